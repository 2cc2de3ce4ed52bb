"""The diagnoser node's session, without rclpy: residual chunks in, fault states and health out.

What the node does between ROS and the decision core:

* every residual chunk passes :class:`bearing_common.chunk_stream.ChunkStream` (empty, huge,
  non-finite, wrong-rate, out-of-order chunks are rejected and counted);
* snapshots (``input_mode``: a snapshot sensor's chunks, each a short waveform with a pause
  before it; ``auto`` recognises them from the pauses): each is a snapshot, not a broken
  stream — no gap is counted or logged, and the stale timeout stretches to the snapshots'
  interval. The decision core places each at its stamp (sensors number their snapshots'
  samples as they like) and scores it alone, its evidence accumulating across the pauses
  (:meth:`.diagnoser.Diagnoser.update`);
* condition: the measurement y = r + ŷ goes to :class:`.health.health_session.HealthSession`
  (indicators and trend per 1 s window of a stream or per snapshot, with the decision's comb
  evidence), drained by :meth:`DiagnoserSession.take_health` (the ``health`` topic);
* the spectrum the spectral decision tested in its last window, for plotting, from
  :meth:`DiagnoserSession.take_envelope` (the ``envelope_spectrum`` topic);
* restart rule: the decision core (:class:`.diagnoser.Diagnoser`) restarts when a stream that
  already fed it restarts (a restarted observer or sensor: index back to 0, a new rate) —
  its stream is then a new one —, when the residuals name another model set (observers
  reconfigured), or when a parameter that shapes the decision changes;
* time: a decision's stamp is the time of its window's end, from the chunk stamps
  (stamp of sample index 0 + index / rate), never from arrival;
* health: the /diagnostics level and key-values — STALE when no residual arrived within
  the stale timeout, WARN when one observer is silent, when the sensor signal is unusable
  (:mod:`.decision.sensor_health`), when a real machine's shaft speed is unknown (estimated blind
  from the vibration, which misses most faults: ``bearing-accuracy`` ablation) or the state
  is UNKNOWN, ERROR for a fault, OK for NORMAL; at least WARN for a condition WARNING, ERROR
  for a condition ALARM (the trend, with its indicators, since when and slope, in the
  key-values; the message says when the last window's shaft speed changed and its indicators were
  held out of the trend, without raising the level) —, named ``bearing_monitor/<motor>/drive_end``
  with the motor as hardware id, so that ``diagnostic_aggregator`` groups a fleet's statuses
  (``config/diagnostic_aggregator.yaml``).
"""

from __future__ import annotations

import math
import socket
from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np

from bearing_common import topics
from bearing_common.bearings import Bearing, load_bearing
from bearing_common.chunk_stream import ChunkStream
from bearing_common.log_throttle import LogThrottle
from bearing_common.model_set_info import NONE, SHIPPED_SETS
from bearing_common.states import FaultState

from .decision.config import DiagnoserConfig
from .decision.not_diagnosed import NotDiagnosed
from .decision.scores import WindowScores
from .decision.state_tracker import Decision
from .diagnoser import STREAMS, Diagnoser
from .diagnoser_node_config import LEVEL_STALE, LEVEL_WARN, RESTART_ON, STATE_LEVEL, TREND_LEVEL, health_settings
from .front_ends import MODEL_SET_DEFAULTS, NO_REFERENCE, config_for, takes_reference, with_reference
from .health.health_session import DecidedWindow, HealthSession
from .health.indicators import fault_lines_top
from .health.monitor import HealthRecord
from .pulse_speed import PulseSpeed
from .reference_session import ReferenceSession
from .warm_up import warm_up

#: Snapshot intervals a snapshot sensor may stay silent before /diagnostics reports it stale.
SNAPSHOT_STALE_INTERVALS = 2.5

#: Parameters of the condition trend (a change applies to the next record, or begins the trend again).
HEALTH_PARAMETERS = ("machine_class", "baseline", "baseline_min_duration", "health_period")

#: Fastest plausible shaft (rev/min): anything above is a broken speed source.
MAX_RPM = 1e6

#: Relative departure of the measured shaft speed from the one a decision began with beyond which it
#: follows the speed in the angle domain (:mod:`.spectral.angle_domain`): a tachometer's tolerance, to
#: which the constant-speed decision holds a measured speed (``SpectralSettings.told_tolerance``).
FOLLOW_BEYOND = 0.02

#: Seconds of measured speed kept behind the newest residual (the angle domain needs the speed of the
#: samples it has not resampled yet: a chunk and the interpolation kernel's reach).
SPEED_KEPT_S = 2.0

#: Seconds of signal time past the tachometer's last interval during which ``shaft_speed`` messages are
#: ignored: the pulses give the speed (a speed message may come before the pulses of its instant).
PULSES_PREFERRED_S = 1.0

SPEED_CHANGING_HELD = "speed changing: condition indicators held out of the trend"

SPEED_UNKNOWN = ("shaft speed unknown: estimated from the vibration, which misses most faults; "
                 "set the rpm parameter or publish shaft_speed")

#: /diagnostics status names: ``STATUS_PREFIX/<motor>/SENSOR_LOCATION``.
STATUS_PREFIX = "bearing_monitor"
SENSOR_LOCATION = "drive_end"


def motor_name(parameter: str, namespace: str) -> str:
    """The motor a diagnoser watches (its /diagnostics hardware id): the ``motor`` parameter,
    else the node's namespace without the leading slash, else (root namespace) the host's name."""
    return parameter or namespace.strip("/") or socket.gethostname()


def status_name(motor: str) -> str:
    """The /diagnostics status name of ``motor``'s bearing, e.g. ``bearing_monitor/motor_3/drive_end``."""
    return f"{STATUS_PREFIX}/{motor}/{SENSOR_LOCATION}"


@dataclass(frozen=True)
class StateReport:
    """A fault state to publish: times in seconds of the streams' stamps."""

    state: FaultState
    confidence: float
    stamp: float
    onset: float
    scores: WindowScores
    model_set: str
    detail: str
    changed: bool


@dataclass
class Health:
    """The /diagnostics status: level (0-3), one-line message, key-values."""

    level: int
    message: str
    values: dict = field(default_factory=dict)


class DiagnoserSession:
    """Session state of one diagnoser (see the module docstring).

    Parameters
    ----------
    values : dict
        The node's parameter values (:data:`.diagnoser_node_config.PARAMETERS`), kept current
        by the node.
    log : callable(level, text)
        Where to say what happened (``"info"``, ``"warning"``); repeatable per-chunk messages
        (rejections, bad speeds, "cannot decide") at most once per ``log_period`` s each.
    bearing : Bearing, optional
        The monitored bearing, parsed already (offline runs); default: the ``bearing`` parameter's.
    config : DiagnoserConfig, optional
        The decision's configuration as it is, instead of the one the parameters derive from
        the model set (offline runs: the textbook baseline, the ablations).
    keep_history : bool
        Keep every window's decision in :attr:`history` and every health record in
        ``condition.history`` (offline runs).
    """

    def __init__(self, values: dict, log, log_period: float = 5.0, bearing: Bearing | None = None,
                 config: DiagnoserConfig | None = None, keep_history: bool = False):
        self.values = values
        self._log = log
        self._log_repeatable = LogThrottle(log, log_period)
        self._config = config
        self.bearing = bearing or load_bearing(values["bearing"])
        self.history: list[Decision] | None = [] if keep_history else None
        self.streams = {h: ChunkStream(topics.residual_topic(h).name, input_mode=values["input_mode"])
                        for h in STREAMS}
        self.condition = HealthSession(health_settings(values), log, keep_history)
        # the machine's healthy reference (:mod:`.reference_session`); offline runs give theirs in ``config``
        self.reference = ReferenceSession(values, log) if config is None else None
        self._learn_from: FaultState | None = None  # the stream the reference learns from
        self._health_out: list[HealthRecord] = []
        self._lines_top: tuple = (None, 0.0)  # ((bearing, rpm), its fault_lines_top) for the condition trend
        self._envelope_taken = None  # the last spectrum handed out by take_envelope
        self.last_health: HealthRecord | None = None
        self.snapshots = False  # whether the last accepted chunk was a snapshot sensor's
        self._snapshot_arrivals = {h: deque(maxlen=2) for h in STREAMS}  # node times of the last snapshots
        self._placed = False  # whether the core places chunks at their stamps (it has seen a snapshot)
        self._next_index: dict = {}  # per stream, the core's index of its next sample
        self.core: Diagnoser | None = None
        self._fed: set = set()  # streams that fed the current core
        self.deployed: set = set()  # streams known to be deployed (fed a core, or publisher matched)
        self.time_offset = 0.0  # stamp of sample index 0 (s)
        self.last_heard = {h: None for h in STREAMS}
        self.shaft_rpm: float | None = None
        # the measured speed over time (stamps s, rad/s), and how many of its points the core has
        self._speed_t, self._speed_w, self._speed_given = np.zeros(0), np.zeros(0), 0
        self.follow: tuple[float, float] | None = None  # deciding in the angle domain: (nominal, top rpm)
        self._core_rpm: float | None = None  # the measured speed the current core began with
        self.last_report: StateReport | None = None
        self.not_diagnosed: NotDiagnosed | None = None  # why the last window was not diagnosed (sensor, speed, ...)
        self.untested: dict = {}  # {hypothesis: why} the last window could not test
        self.speed_warning = ""  # the last window's measured speed disagreed with the told one
        self.decision_problem = ""  # why the last chunk could not be decided on (cleared by a good one)
        self.last_refusal = ""  # why the last refused chunk was refused
        self.rejected_speeds = 0
        self.pulses = PulseSpeed()  # the speed at each tachometer pulse (shaft_pulses)
        self._pulses_until: float | None = None  # end (s) of the tachometer's last interval

    def warm_up(self) -> None:
        """Compute now what the first windows would otherwise stall on: the p-value tables, the
        compiled kernels (numba: from its cache, or 15 s to compile after an install) and what
        the front ends of the model sets with defaults of their own prepare (the folding
        thresholds of the simulator sets, about 1 s each)."""
        warm_up()
        for name, cfg in MODEL_SET_DEFAULTS.items():
            if self.values["model_set"] in ("", name):
                Diagnoser(cfg, name, self.bearing, SHIPPED_SETS[name].sample_rate).warm_up()

    # -- configuration -----------------------------------------------------------------
    def configure(self, changed: dict) -> None:
        """Parameters changed (already applied to ``values``): restart the decision if they shape it."""
        if "bearing" in changed:
            self.bearing = load_bearing(self.values["bearing"])
        if any(k in HEALTH_PARAMETERS for k in changed):
            self.condition.configure(health_settings(self.values))
        if self.core is not None and any(k in RESTART_ON for k in changed):
            self._log("info", f"{', '.join(sorted(changed))} changed; the decision restarts with the next chunk")
            self.core = None

    def decision_config(self, model_set: str) -> DiagnoserConfig:
        """The decision's configuration for residuals of ``model_set``: the one given at construction,
        else the defaults of the ``model_set`` parameter (or of the residuals' set) with the
        ``false_alarm_rate``, ``false_alarm_probability``, ``window`` and ``sensor_bandwidth``
        parameters applied (each front end takes the false-alarm budget it states)."""
        if self._config is not None:
            return self._config
        v = self.values
        cfg = config_for(v["model_set"] or model_set)
        if v["false_alarm_probability"] > 0:
            cfg = replace(cfg, pfa=float(v["false_alarm_probability"]))
        front_end = cfg.front_end.with_window(float(v["window"])).with_false_alarm_rate(float(v["false_alarm_rate"]))
        cfg = replace(cfg, usable_bandwidth=float(v["sensor_bandwidth"]), front_end=front_end)
        learnt = self.reference.reference if self.reference is not None else None
        return with_reference(cfg, learnt) if takes_reference(cfg) else cfg

    def _make_core(self, model_set: str, sample_rate: float) -> Diagnoser:
        name = self.values["model_set"] or model_set
        cfg = self.decision_config(model_set)
        core = Diagnoser(cfg, name, self.bearing, sample_rate)
        core.keep_history = False
        core.expected = set(self.deployed)
        self._tell_speed(core)
        self._core_rpm, self._speed_given = self.shaft_rpm, 0
        if self.follow is not None and core.follows_speed:
            core.follow_speed(*self.follow)
        self._log("info", f"deciding with the {cfg.method} front end ({name or 'no'} model set), bearing "
                          f"{core.bearing.name}, {cfg.front_end.describe_window()}, "
                          f"{cfg.front_end.describe_false_alarms(cfg.pfa)}"
                          + (f", in the shaft-angle domain at {self.follow[0]:.0f} rpm nominal"
                             if self.follow is not None and core.follows_speed else ""))
        if self.speed_unknown_for(cfg):
            self._log("warning", SPEED_UNKNOWN)
        return core

    def _tell_speed(self, core: Diagnoser) -> None:
        if self.shaft_rpm is not None:
            core.tell_speed(self.shaft_rpm)  # a measured speed: the default 2 % tolerance
        elif self.values["rpm"] > 0:
            core.tell_speed(float(self.values["rpm"]), float(self.values["rpm_tolerance"]))
        else:
            core.tell_speed(None)

    def expect(self, hypotheses) -> None:
        """Streams whose observer is deployed (the node saw their publisher matched): the folding
        decision holds for them instead of deciding without them while their first chunks are
        still on their way (a late DDS match at start or after a restart)."""
        new = set(hypotheses) - self.deployed
        if new:
            self.deployed |= new
            if self.core is not None:
                self.core.expected |= new

    # -- inputs ------------------------------------------------------------------------
    def on_speed(self, rad_s: float, stamp: float | None = None) -> None:
        """A ``shaft_speed`` message (rad/s) stamped ``stamp`` (s; None: not placed in time, so it
        cannot be followed in the angle domain); not finite, not positive or above 10⁶ rpm is refused."""
        if self._pulses_until is not None and (stamp is None or stamp <= self._pulses_until + PULSES_PREFERRED_S):
            return  # the tachometer's pulses give the speed
        rpm = rad_s * 60.0 / (2.0 * math.pi)
        if not (math.isfinite(rpm) and 0.0 < rpm <= MAX_RPM):
            self.rejected_speeds += 1
            self._log_repeatable("bad speed", "warning", f"ignoring shaft speed {rad_s!r} rad/s")
            return
        if stamp is not None:
            self._add_speed([float(stamp)], [float(rad_s)])
        self.measured_speed(rpm)

    def on_pulses(self, stamp: float, duration: float, offsets, first_index: int, pulses_per_rev: int) -> None:
        """A ``shaft_pulses`` message (tachometer pulses at ``stamp`` + ``offsets`` s, in the interval of
        ``duration`` s from ``stamp``): the speed at each pulse (:mod:`.pulse_speed`), stamped, as
        ``shaft_speed`` would give it; from then on ``shaft_speed`` is ignored while pulses keep coming."""
        if self._pulses_until is None:
            self._log("info", f"shaft speed from the tachometer pulses on {topics.TACHOMETER.name}")
        self._pulses_until = float(stamp) + float(duration)
        t, w = self.pulses.add(stamp, offsets, first_index, pulses_per_rev)
        ok = np.isfinite(w) & (w > 0.0) & (w * 60.0 / (2.0 * math.pi) <= MAX_RPM)
        if not ok.all():
            self.rejected_speeds += int((~ok).sum())
            self._log_repeatable("bad speed", "warning", f"ignoring {int((~ok).sum())} speed(s) from tachometer "
                                                          "pulses")
            t, w = t[ok], w[ok]
        if t.size:
            self._add_speed(t, w)
            self.measured_speed(float(w[-1]) * 60.0 / (2.0 * math.pi))

    def follow_speed(self, nominal_rpm: float, top_rpm: float) -> None:
        """Decide in the shaft-angle domain from the start (a recording whose measured speed changes,
        told by :meth:`speed_samples`): as if the shaft turned at ``nominal_rpm``, up to ``top_rpm``
        (:meth:`.diagnoser.Diagnoser.follow_speed`)."""
        self.follow = (float(nominal_rpm), float(top_rpm))
        self.core = None

    def speed_samples(self, stamp: float, sample_rate: float, rad_s) -> None:
        """A recorded speed channel's chunk: ``rad_s`` (rad/s) per sample from ``stamp`` (s) at
        ``sample_rate`` Hz (offline runs: the speed of the vibration chunk with that stamp)."""
        w = np.asarray(rad_s, dtype=float)
        self._add_speed(stamp + np.arange(w.size) / float(sample_rate), w)

    def _add_speed(self, stamps, rad_s) -> None:
        self.condition.speed(stamps, rad_s)
        self._speed_t, self._speed_w = np.r_[self._speed_t, stamps], np.r_[self._speed_w, rad_s]
        if self.follow is None:  # nothing given to a core yet: what a restart in the angle domain needs
            old = max(0, int(np.searchsorted(self._speed_t, self._speed_t[-1] - SPEED_KEPT_S)) - 1)
            self._speed_t, self._speed_w, self._speed_given = self._speed_t[old:], self._speed_w[old:], 0

    def measured_speed(self, rpm: float) -> None:
        """A measured shaft speed (rev/min: a tachometer, a recording's own): it overrides ``rpm``.
        A speed that leaves the one the decision began with by more than :data:`FOLLOW_BEYOND`,
        when its messages are stamped, makes the decision follow it in the shaft-angle domain
        (restarted at the next chunk)."""
        if self.shaft_rpm is None or abs(rpm / self.shaft_rpm - 1.0) > 1e-3:
            if self.shaft_rpm is None:
                self._log("info", f"shaft speed {rpm:.1f} rpm from {self.speed_source}")
            self.shaft_rpm = rpm
            if self.follow is not None:
                return  # (the angle domain takes the speed as it comes, from the stamped points)
            if self.core is not None and self._core_rpm is None:
                self._core_rpm = rpm  # the decision began on a told speed: the first measured one is the start
            if self.core is not None and self._core_rpm is not None and self._speed_t.size \
                    and self.core.follows_speed and abs(rpm / self._core_rpm - 1.0) > FOLLOW_BEYOND:
                self._log("info", f"shaft speed changed from {self._core_rpm:.1f} to {rpm:.1f} rpm, beyond "
                                  f"{100 * FOLLOW_BEYOND:g} %: the decision restarts in the shaft-angle domain")
                self.follow = (self._core_rpm, self._core_rpm)
                self.core = None
            elif self.core is not None:
                self._tell_speed(self.core)

    def on_residual(self, hypothesis: FaultState, stamp: float, first_index: int, sample_rate: float,
                    residual, estimate, train, fault_hz: float, model_set: str, now: float) -> list[StateReport]:
        """One residual chunk; returns the fault states to publish.

        ``estimate`` and ``train`` are as long as ``residual``, or None when the stream carries
        none (a model-free stream: y = r; no impulse train).
        """
        self.last_heard[hypothesis] = now
        r = np.asarray(residual, dtype=float)
        stream = self.streams[hypothesis]
        verdict = stream.check(stamp, first_index, sample_rate, r)
        if verdict.accepted and not all(a is None or len(a) == r.size for a in (estimate, train)):
            stream.counts["rejected"] += 1
            return self._refused(f"{stream.name}: array lengths differ")
        if not verdict.accepted:
            return self._refused(verdict.reason)
        if verdict.snapshot != self.snapshots and verdict.reason:
            self._log("info", verdict.reason)  # auto input mode recognised snapshots, or a stream again
        self.snapshots = verdict.snapshot
        if verdict.snapshot and verdict.resync:
            self._snapshot_arrivals[hypothesis].append(now)
        switched = self.core is not None and not self.values["model_set"] and model_set != self.core.model_set
        if self.core is None or (verdict.restart and hypothesis in self._fed) or switched:
            if self.core is not None:
                why = f"residuals now from model set {model_set!r}" if switched else verdict.reason
                self._log("info", f"{why}; restarting the decision")
            self.core = self._make_core(model_set, sample_rate)
            self._fed = set()
            self.time_offset = stamp - first_index / sample_rate
            self._placed, self._next_index = False, {}
        self._fed.add(hypothesis)
        self.deployed.add(hypothesis)
        index = self._core_index(hypothesis, verdict, stamp, first_index, sample_rate, r.size)
        if self.follow is not None and self.core.follows_speed:
            self._give_speed(sample_rate, stamp + r.size / sample_rate)
        e = _array(estimate)
        try:
            decisions = self.core.update(hypothesis, index, sample_rate, r, e, _array(train), fault_hz,
                                         snapshot=verdict.snapshot)
        except ValueError as exc:
            stream.counts["rejected by decision"] += 1
            self.decision_problem = str(exc)
            self._log_repeatable("cannot decide", "warning", f"cannot decide: {exc}")
            decisions = None
        else:
            self.decision_problem = ""
        self._feed_condition(stamp, sample_rate, r if e is None else r + e, verdict, decisions or [])
        out = [] if decisions is None else self._published(decisions)
        self._learn(hypothesis, index, sample_rate, r if e is None else r + e, verdict.snapshot)
        return out

    def _give_speed(self, sample_rate: float, newest: float) -> None:
        """The measured speed points the core has not had yet, at its sample indices; forget those
        :data:`SPEED_KEPT_S` behind ``newest`` (s)."""
        t, w = self._speed_t[self._speed_given:], self._speed_w[self._speed_given:]
        if t.size:
            self.core.tell_speed_points((t - self.time_offset) * sample_rate, w)
        old = int(np.searchsorted(self._speed_t, newest - SPEED_KEPT_S)) - 1
        old = max(0, min(old, self._speed_t.size - 1))
        self._speed_t, self._speed_w = self._speed_t[old:], self._speed_w[old:]
        self._speed_given = self._speed_t.size

    def _core_index(self, hypothesis: FaultState, verdict, stamp: float, first_index: int, sample_rate: float,
                    n: int) -> int:
        """The core's index of the chunk's first sample: the stream's own, until the core has seen a
        snapshot; from then on a chunk that begins a stretch is placed at its stamp (a snapshot sensor
        numbers its snapshots' samples as it likes), one that continues it follows on."""
        self._placed = self._placed or verdict.snapshot
        if not self._placed:
            return first_index
        if verdict.resync or hypothesis not in self._next_index:
            index = int(round((stamp - self.time_offset) * sample_rate))
        else:
            index = self._next_index[hypothesis]
        self._next_index[hypothesis] = index + n
        return index

    def _feed_condition(self, stamp: float, sample_rate: float, y: np.ndarray, verdict,
                        decisions: list[Decision]) -> None:
        """The measurement to the condition trend, with the windows just decided."""
        self.condition.decided([DecidedWindow(self.time_offset + d.window_end, d.scores, d.not_diagnosed)
                                for d in decisions])
        rpm = self.shaft_rpm or (float(self.values["rpm"]) or None)
        no_evidence = self.decision_problem and f"cannot decide: {self.decision_problem}"
        if not no_evidence and self.speed_unknown:
            no_evidence = SPEED_UNKNOWN
        if self._lines_top[0] != (self.bearing, rpm):  # (per chunk: computed when the bearing or speed changes)
            self._lines_top = ((self.bearing, rpm), fault_lines_top(self.bearing, rpm))
        records = self.condition.push(stamp, sample_rate, y, verdict.snapshot, self._lines_top[1],
                                   verdict.restart, no_evidence)
        if records:
            self._health_out.extend(records)
            self.last_health = records[-1]

    def _learn(self, hypothesis: FaultState, index: int, sample_rate: float, y: np.ndarray, snapshot: bool) -> None:
        """The measurement to the machine reference while it learns (one stream's); once learnt, the
        decision restarts judging against it."""
        if self.reference is None or not self.reference.learning or not takes_reference(self.core.config):
            return
        self._learn_from = self._learn_from or hypothesis
        if hypothesis != self._learn_from:
            return
        settings = self.core.config.front_end
        told, tolerance = (self.shaft_rpm, settings.told_tolerance) if self.shaft_rpm is not None else (
            float(self.values["rpm"]) or None, float(self.values["rpm_tolerance"]))
        if self.reference.push(index, sample_rate, y, snapshot, self.bearing, told, tolerance, settings) is not None:
            self._log("info", "the decision restarts with the machine reference")
            self.core = None

    def take_envelope(self):
        """``(stamp s, view)``: the spectrum the decision tested in its last window
        (:class:`.spectral.envelope_view.EnvelopeView`, the ``envelope_spectrum`` topic) and the stamp
        of that window's end, when it is new since the last call; else None (none new, or a front end
        that computes none)."""
        view = None if self.core is None else self.core.envelope_view()
        if view is None or view is self._envelope_taken:
            return None
        self._envelope_taken = view
        return self.time_offset + view.end / view.sample_rate, view

    def take_health(self) -> list[HealthRecord]:
        """The condition records completed since the last call (oldest first), for the ``health`` topic."""
        out, self._health_out = self._health_out, []
        return out

    def flush(self) -> list[StateReport]:
        """End of data (a recording's): decide every window that can still be decided."""
        return self._published(self.core.flush()) if self.core is not None else []

    def _refused(self, reason: str) -> list[StateReport]:
        self.last_refusal = reason
        self._log_repeatable("rejected", "warning", f"rejected residual chunk: {reason}")
        return []

    def _published(self, decisions: list[Decision]) -> list[StateReport]:
        if self.history is not None:
            self.history.extend(decisions)
        return [self._report(d) for d in decisions if self._account(d)]

    def _account(self, d: Decision) -> bool:
        """Remember why a window was not diagnosed, if it was not; True when its state is to be published."""
        self.not_diagnosed, self.untested = d.not_diagnosed, d.scores.untested
        self.speed_warning = d.scores.speed_warning()
        if self.speed_warning:
            unconfirmed = getattr(d.scores, "speed_unconfirmed", 0.0)  # (the spectral front end's scores)
            self._log_repeatable("speed not confirmed" if unconfirmed else "speed disagrees", "warning",
                                 self.speed_warning)
        return d.diagnosed

    def _report(self, d: Decision) -> StateReport:
        report = StateReport(d.state, d.confidence, self.time_offset + d.time, self.time_offset + d.onset,
                             d.scores, self.core.model_set, d.detail, d.changed)
        self.last_report = report
        return report

    # -- health ------------------------------------------------------------------------
    def health(self, now: float) -> Health:
        """The /diagnostics status at node time ``now`` (s)."""
        timeout = float(self.values["stale_timeout"])
        interval = self.snapshot_interval
        if self.snapshots and interval:
            timeout = max(timeout, SNAPSHOT_STALE_INTERVALS * interval)
        silent = [topics.residual_topic(h).name for h, t in self.last_heard.items() if t is None or now - t > timeout]
        report = self.last_report
        state = report.state if report else FaultState.NORMAL
        values = {"state": state.name}
        if report is not None:
            values.update({"confidence": f"{report.confidence:.3f}", "onset (s)": f"{report.onset:.4f}",
                           "decided at (s)": f"{report.stamp:.4f}", "model set": report.model_set})
            values.update({k: f"{v:.4g}" for k, v in report.scores.as_dict().items()})
        if self.core is not None:
            values["bearing"] = self.core.bearing.name
        if self.shaft_rpm is not None:
            values["shaft speed (rpm)"] = f"{self.shaft_rpm:.1f}"
            values["shaft speed from"] = self.speed_source
        if self.pulses.breaks:
            values["tachometer breaks"] = str(self.pulses.breaks)
        for stream in self.streams.values():
            values[f"{stream.name} chunks"] = ", ".join(f"{k} {v}" for k, v in sorted(stream.counts.items()))
        if self.rejected_speeds:
            values["rejected shaft speeds"] = str(self.rejected_speeds)
        if self.follow is not None and self.core is not None and self.core.follows_speed:
            values["speed domain"] = f"shaft angle, nominal {self.follow[0]:.1f} rpm (the speed changes)"
            if self.core.model_set not in ("", NONE):
                values["observer models"] = ("identified at one speed: their impulse trains follow the shaft speed, "
                                             "their models do not")
        values["input"] = f"snapshots, one every {interval:.3g} s" if self.snapshots and interval else (
            "snapshots" if self.snapshots else "stream")
        if self.untested:
            values["untested"] = "; ".join(f"{h.label}: {why}" for h, why in self.untested.items())
        values.update(self._condition_values())
        if self.reference is not None:
            fold = self.core is not None and not takes_reference(self.core.config)
            values["machine reference"] = f"none: {NO_REFERENCE}" if fold else self.reference.status()
        if len(silent) == len(self.last_heard):
            return Health(LEVEL_STALE, "no residuals: " + ", ".join(silent), values)
        level, message = STATE_LEVEL[state], state.name
        if self.decision_problem:
            level, message = max(level, LEVEL_WARN), f"cannot decide: {self.decision_problem}"
        elif self.not_diagnosed is not None:
            level, message = max(level, LEVEL_WARN), f"not diagnosed: {self.not_diagnosed}"
            values["not diagnosed"] = self.not_diagnosed.kind
        elif self.speed_unknown:
            level, message = max(level, LEVEL_WARN), f"{message} ({SPEED_UNKNOWN})"
        elif self.speed_warning:
            level, message = max(level, LEVEL_WARN), f"{message} ({self.speed_warning})"
        if silent:
            level = max(level, LEVEL_WARN)
            message += " (waiting for " + ", ".join(silent) + ")"
        condition = self.last_health.trend if self.last_health is not None else None
        if condition is not None and not condition.learning:
            level = max(level, TREND_LEVEL[condition.state])
            message += f"; condition {condition.state.name}"
        if self.last_health is not None and self.last_health.speed_changing:
            message += f"; {SPEED_CHANGING_HELD}"
        return Health(level, message, values)

    @property
    def snapshot_interval(self) -> float | None:
        """Node seconds between a snapshot sensor's last two snapshots (None: fewer seen)."""
        gaps = [b - a for a, b in (tuple(d) for d in self._snapshot_arrivals.values() if len(d) == 2)]
        return max(gaps) if gaps else None

    def _condition_values(self) -> dict:
        """/diagnostics key-values of the condition: the trend (state, since when, slope) and the
        indicators of the last record."""
        rec = self.last_health
        if rec is None:
            return {}
        trend, ind = rec.trend, rec.indicators
        t0 = rec.t - trend.t  # the record's trend's first window (a trend begun again has its own)
        b = self.condition.monitor.tracker.baseline if self.condition.monitor is not None else None
        out = {"condition": "learning the baseline" if trend.learning else trend.state.name,
               "condition since (s)": f"{t0 + trend.since:.3f}"}
        if rec.speed_changing:
            out["condition"] += f" ({SPEED_CHANGING_HELD})"
        held = self.condition.counts["speed changing"]
        if held:
            out["condition windows held out (speed changing)"] = str(held)
        if trend.moved:
            out["condition moved"] = trend.moved
            out["condition level (x baseline)"] = f"{trend.level.get(trend.moved, math.nan):.3g}"
        slope = trend.slope.get(trend.moved) if trend.moved else None
        if slope is not None and math.isfinite(slope):
            out["condition slope (1/h)"] = f"{slope:+.3g}"
        if b is not None:
            out["condition baseline"] = f"{b.snapshots} windows or snapshots to {t0 + b.end:.3f} s"
        out.update({"rms (m/s^2)": f"{ind.rms:.4g}", "peak (m/s^2)": f"{ind.peak:.4g}",
                    "crest factor": f"{ind.crest_factor:.4g}", "kurtosis": f"{ind.kurtosis:.4g}",
                    "velocity rms (mm/s)": f"{ind.velocity_rms * 1e3:.4g}",
                    "iso 20816-3 zone": f"{rec.iso_zone or 'unknown'} ({self.condition.settings.machine})",
                    "envelope rms (m/s^2)": f"{ind.envelope_rms:.4g}"})
        if rec.evidence is not None and rec.evidence.problem:
            out["condition fault evidence"] = rec.evidence.problem
        return out

    @property
    def speed_source(self) -> str:
        """The topic the measured speed comes from: the tachometer's once it has published, else ``shaft_speed``."""
        return topics.TACHOMETER.name if self._pulses_until is not None else topics.SHAFT_SPEED.name

    @property
    def speed_unknown(self) -> bool:
        """True when the decision needs a shaft speed it is not told (no shaft_speed, rpm 0): it is
        then estimated blind from the vibration."""
        return self.core is not None and self.speed_unknown_for(self.core.config)

    def speed_unknown_for(self, config: DiagnoserConfig) -> bool:
        return config.front_end.NEEDS_SPEED and self.shaft_rpm is None and not self.values["rpm"] > 0

    def final_health(self, now: float) -> Health:
        """The last status, sent when the node stops."""
        last = self.health(now)
        return Health(LEVEL_STALE, "diagnoser stopped", last.values)


def _array(values) -> np.ndarray | None:
    """``values`` as a float array; None stays None (the stream carries none)."""
    return None if values is None else np.asarray(values, dtype=float)
