"""Parameters of the ``simulator`` node and how they become a simulation (no rclpy).

The node (``node.py``) declares ``PARAMETERS``; ``build_run`` turns their values
into a validated SimulationConfig and schedule. ``rpm``, ``noise_density`` and
``realtime`` can change while the node runs (applied at the next chunk, see
:mod:`.sim_stream` and :mod:`.pacer`); the others are read-only. Topic names and QoS
come from :mod:`bearing_common.topics`.
"""

import math
from dataclasses import dataclass

from bearing_common.parameters import ParameterSpec, non_negative, positive

from .schedule import parse_schedule, scenario, speed_profile
from .simulator import MAX_RPM, SimulationConfig

ENDLESS_SEGMENT_S = 3600.0  #: s; normal operation without a schedule: hour-long segments, repeated


def _rpm_check(value):
    return None if 0 < value <= MAX_RPM else f"must be in (0, {MAX_RPM:g}] rev/min, got {value:g}"


def _noise_check(value):
    return None if 0 <= value < math.inf else f"must be a finite number >= 0, got {value}"


PARAMETERS = (
    ParameterSpec("scenario", "", "thesis case: normal, or, ir, or-ir, ir-or, or-normal, normal-or, "
                  "ir-normal, normal-ir; empty (with empty schedule) = normal operation without end"),
    ParameterSpec("schedule", "", "segments 'fault:seconds,...' e.g. 'normal:0.1,outer_race:0.2' "
                  "(overrides scenario)"),
    ParameterSpec("segment_duration", 0.2, "seconds per scenario segment", positive),
    ParameterSpec("rpm", 1800.0, "shaft speed (rev/min); a change restarts the simulation at the new speed "
                  "from the next chunk on, stamps continuing", _rpm_check, dynamic=True),
    ParameterSpec("rpm_profile", "", "changing speed 'T0:RPM0,T1:RPM1,...' (seconds:rev/min, piecewise linear "
                  "from the start of the run, held after its last point, replayed on every repeat), e.g. a "
                  "run-up '0:900,10:1800'; empty = the constant rpm (a live rpm change replaces it)",
                  lambda v: _check_speed(v, "")),
    ParameterSpec("speed_wobble", "", "slow speed wobble 'FRACTION:PERIOD': the speed times "
                  "1 + FRACTION*sin(2*pi*t/PERIOD s), e.g. '0.02:1.5'; empty = none",
                  lambda v: _check_speed("", v)),
    ParameterSpec("speed_rate", 100.0, "shaft_speed messages per second of signal time, stamped at multiples "
                  "of 1/speed_rate s with the speed at that instant (rad/s)", positive),
    ParameterSpec("tachometer", False, "also publish tachometer pulses (bearing_msgs/Tachometer) on "
                  "shaft_pulses, one message per chunk"),
    ParameterSpec("tachometer_pulses", 1, "tachometer pulses per shaft revolution", positive),
    ParameterSpec("tachometer_jitter", 1e-5, "standard deviation of the tachometer pulse times' error (s), "
                  "Gaussian truncated at 5 sigma; below a tenth of the pulse period",
                  lambda v: None if 0 <= v <= 1e-3 else f"must be in [0, 0.001] s, got {v}"),
    ParameterSpec("sample_rate", 48000.0, "output sample rate of vibration/drive_end (Hz), 4 kHz-1 MHz", positive),
    ParameterSpec("chunk_duration", 0.01, "seconds of signal per published chunk", positive),
    ParameterSpec("realtime", True, "pace publishing to wall-clock real time (false: as fast as possible)",
                  dynamic=True),
    ParameterSpec("repeat", False, "restart the scenario/schedule when it ends instead of exiting 0"),
    ParameterSpec("noise_density", 0.0, "measurement noise density ((m/s^2)/sqrt(Hz)); 0 = off", _noise_check,
                  dynamic=True),
    ParameterSpec("seed", 0, "random seed of the measurement noise"),
    ParameterSpec("variant", "default", "model variant (see bearing_sim.model_parameters)"),
    ParameterSpec("publish_clock", False, "publish /clock with the simulation time (for use_sim_time consumers)"),
    ParameterSpec("frame_id", "drive_end", "frame_id of vibration/drive_end (sensor location)"),
    ParameterSpec("wait_for_subscribers", "", "before publishing, wait until these topics have these many "
                  "subscribers, 'topic:count,...' e.g. 'vibration/drive_end:2' (the graph's "
                  "consumers are ready), at most subscriber_timeout s; empty = start at once",
                  lambda v: _check_wait_spec(v)),
    ParameterSpec("subscriber_timeout", 30.0, "seconds to wait for subscribers before starting anyway", positive),
    ParameterSpec("linger", 1.0, "seconds to keep serving after the last chunk has been acknowledged (late joiners of "
                  "the latched topics)",
                  non_negative),
)

def parse_wait_spec(spec: str) -> list:
    """``'topic:count,...'`` -> [(topic, count)]; ValueError on a malformed entry."""
    pairs = []
    for item in filter(None, (part.strip() for part in spec.split(","))):
        topic, sep, count = item.rpartition(":")
        if not sep or not topic or not count.isdigit():
            raise ValueError(f"expected 'topic:count', got {item!r}")
        pairs.append((topic, int(count)))
    return pairs


def _check_speed(profile: str, wobble: str):
    try:
        speed_profile(1800.0, profile, wobble, 1.0)
    except ValueError as exc:
        return str(exc)
    return None


def _check_wait_spec(spec: str):
    try:
        parse_wait_spec(spec)
    except ValueError as exc:
        return str(exc)
    return None


SOURCE = "simulator"


@dataclass(frozen=True)
class SimulationRun:
    """What the node simulates: config, schedule (None = normal operation without end), chunk size,
    shaft_speed messages per second (Hz), tachometer pulses per revolution (0 = no tachometer) and
    their timing jitter (s)."""

    config: SimulationConfig
    schedule: object
    chunk_samples: int
    speed_rate: float = 100.0
    tacho_pulses: int = 0
    tacho_jitter: float = 0.0


def build_run(values: dict) -> SimulationRun:
    """Validated run from node parameter values; ValueError with the reason otherwise."""
    if values["schedule"]:
        schedule = parse_schedule(values["schedule"])
    elif values["scenario"]:
        schedule = scenario(values["scenario"], float(values["segment_duration"]))
    else:
        schedule = None
    duration = ENDLESS_SEGMENT_S if schedule is None else sum(seconds for _, seconds in schedule)
    profile = speed_profile(float(values["rpm"]), values["rpm_profile"], values["speed_wobble"], duration)
    config = SimulationConfig(rpm=float(values["rpm"]), sample_rate=float(values["sample_rate"]),
                              noise_density=float(values["noise_density"]), seed=int(values["seed"]),
                              variant=values["variant"], speed_profile=profile)
    chunk_samples = max(1, int(round(float(values["chunk_duration"]) * config.sample_rate)))
    pulses = int(values["tachometer_pulses"]) if values["tachometer"] else 0
    return SimulationRun(config, schedule, chunk_samples, float(values["speed_rate"]), pulses,
                         float(values["tachometer_jitter"]))
