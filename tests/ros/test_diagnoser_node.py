"""The diagnoser node through real DDS: fault states, health, /diagnostics, a silent observer, staleness."""

import time

import numpy as np
import pytest

from bearing_common import topics
from bearing_common.bearings import CATALOG
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_msgs.msg import FaultState, Residual

pytestmark = pytest.mark.ros

FS = 48000.0
N = 480
PACE_S = 0.002  # between chunks: 5x faster than real time, like a fast replay (queues hold 50 chunks)
BPFO = CATALOG["6205"].bpfo(30.0)
BPFI = CATALOG["6205"].bpfi(30.0)


def residual_msg(hypothesis, i, y, fault_hz):
    msg = Residual(sample_rate=FS, first_sample_index=i * N, fault_hypothesis=hypothesis,
                   model_set="sim_48k", fault_frequency=fault_hz)
    t = i * N / FS
    msg.header.stamp.sec = int(t)
    msg.header.stamp.nanosec = int(round((t - int(t)) * 1e9))
    msg.residual = [float(v) for v in y]  # a model-free residual: estimate 0, so y = residual
    msg.estimate = [0.0] * len(y)
    msg.impulse_train = [0.0] * len(y)
    return msg


def signal_normal_then_or(duration=0.4, change=0.2):
    noise = white_noise(duration, FS, 4.5e-3)
    bursts = burst_train(duration, FS, BPFO, amplitude=30.0, start=change)
    return noise + bursts


def test_states_and_diagnostics_follow_the_residuals(ros_graph):
    states = ros_graph.subscribe(topics.FAULT_STATE)
    diags = ros_graph.subscribe(topics.DIAGNOSTICS)
    health = ros_graph.subscribe(topics.HEALTH)
    pub_or = ros_graph.publisher(topics.RESIDUAL_OUTER_RACE)
    pub_ir = ros_graph.publisher(topics.RESIDUAL_INNER_RACE)
    node = ros_graph.start("bearing_diagnoser", "diagnoser", params={"stale_timeout": 1.0, "diagnostics_period": 0.2,
                                                                     "health_period": 0.1})
    ros_graph.wait_until(lambda: pub_or.get_subscription_count() and pub_ir.get_subscription_count(),
                         30.0, "the diagnoser to subscribe")
    y = signal_normal_then_or()
    for i in range(len(y) // N):
        pub_or.publish(residual_msg(1, i, y[i * N:(i + 1) * N], BPFO))
        pub_ir.publish(residual_msg(2, i, y[i * N:(i + 1) * N], BPFI))
        time.sleep(PACE_S)
    ros_graph.wait_until(lambda: states and states[-1].state == FaultState.OUTER_RACE, 30.0,
                         "OUTER_RACE to be published")
    first_or = next(m for m in states if m.state == FaultState.OUTER_RACE)
    onset = first_or.onset.sec + first_or.onset.nanosec * 1e-9
    decided = first_or.header.stamp.sec + first_or.header.stamp.nanosec * 1e-9
    assert 0.17 <= onset <= 0.25 and decided - 0.2 <= 0.05
    assert all(m.state == FaultState.NORMAL for m in states[:states.index(first_or)])
    assert "outer_race" in list(first_or.hypotheses) and 0.0 <= first_or.confidence <= 1.0
    # health: one message per 0.1 s of the measurement (both streams carry it: counted once), stamped at
    # the window's first sample, the indicators of that window, the fault evidence or why there is none.
    ros_graph.wait_until(lambda: len(health) >= 4, 10.0, "four health messages")
    assert [m.header.stamp.nanosec for m in health[:4]] == [0, 100_000_000, 200_000_000, 300_000_000]
    y32 = y.astype(np.float32).astype(float)  # the residual travels as float32 (msg/Residual.msg)
    assert [m.rms for m in health[:4]] == pytest.approx([np.std(y32[k * 4800:(k + 1) * 4800]) for k in range(4)],
                                                        rel=1e-9)
    assert health[3].rms > 3 * health[0].rms and health[3].kurtosis > 3 * health[0].kurtosis  # the bursts
    assert all(list(m.hypotheses) or m.evidence_problem for m in health[:4]) and health[0].learning
    # /diagnostics: ERROR for the fault while residuals flow; STALE once they stop.
    ros_graph.wait_until(lambda: any(s.level == b"\x03" for d in diags for s in d.status), 10.0,
                         "/diagnostics to go STALE")
    levels = [s.level for d in diags for s in d.status]
    assert b"\x02" in levels[:levels.index(b"\x03")]  # ERROR while the fault was current
    stale = next(s for d in diags for s in d.status if s.level == b"\x03")
    assert "no residuals" in stale.message
    values = {kv.key: kv.value for kv in stale.values}
    assert values["condition"] == "learning the baseline" and float(values["rms (m/s^2)"]) == pytest.approx(
        health[-1].rms, rel=1e-3)
    assert node.returncode is None


def test_a_diagnoser_started_late_decides_from_the_residuals_history(ros_graph):
    """Residuals are transient local (keep last 50): a diagnoser whose reader matches after the
    observers began publishing (a cold start's late DDS match, a restart) still gets their last
    0.5 s and dates the fault from the stream's start."""
    states = ros_graph.subscribe(topics.FAULT_STATE)
    pub_or = ros_graph.publisher(topics.RESIDUAL_OUTER_RACE, depth=50)
    pub_ir = ros_graph.publisher(topics.RESIDUAL_INNER_RACE, depth=50)
    y = signal_normal_then_or()
    for i in range(len(y) // N):  # 40 chunks, all before the diagnoser exists
        pub_or.publish(residual_msg(1, i, y[i * N:(i + 1) * N], BPFO))
        pub_ir.publish(residual_msg(2, i, y[i * N:(i + 1) * N], BPFI))
    ros_graph.start("bearing_diagnoser", "diagnoser")
    ros_graph.wait_until(lambda: any(m.state == FaultState.OUTER_RACE for m in states), 30.0,
                         "OUTER_RACE from the history")
    first_or = next(m for m in states if m.state == FaultState.OUTER_RACE)
    assert 0.17 <= first_or.onset.sec + first_or.onset.nanosec * 1e-9 <= 0.25
    assert states[0].state == FaultState.NORMAL  # the first window, at the stream's start, was decided


def test_one_silent_observer_is_reported_and_decisions_continue(ros_graph):
    states = ros_graph.subscribe(topics.FAULT_STATE)
    diags = ros_graph.subscribe(topics.DIAGNOSTICS)
    pub_or = ros_graph.publisher(topics.RESIDUAL_OUTER_RACE)
    ros_graph.start("bearing_diagnoser", "diagnoser", params={"diagnostics_period": 0.2})
    ros_graph.wait_until(lambda: pub_or.get_subscription_count(), 30.0, "the diagnoser to subscribe")
    y = signal_normal_then_or(duration=3.0, change=1.5)  # decided 1 s behind (max_lag_s) without inner_race
    half = len(y) // N // 2
    for i in range(len(y) // N):
        pub_or.publish(residual_msg(1, i, y[i * N:(i + 1) * N], BPFO))
        time.sleep(PACE_S)
        if i == half:  # NORMAL decided with one observer silent: wait for a status of it
            ros_graph.wait_until(lambda: any(s.message.startswith("NORMAL") for d in diags for s in d.status), 10.0,
                                 "a status while NORMAL")
    ros_graph.wait_until(lambda: states and states[-1].state == FaultState.OUTER_RACE, 30.0,
                         "OUTER_RACE from the OR stream alone")
    ros_graph.wait_until(lambda: any(s.level == b"\x02" and "waiting for residual/inner_race" in s.message
                                     for d in diags for s in d.status), 10.0, "an ERROR naming the silent observer")
    statuses = [s for d in diags for s in d.status]
    normal = [s for s in statuses if s.message.startswith("NORMAL")]
    assert normal and all(s.level == b"\x01" for s in normal), [(s.level, s.message) for s in statuses]  # WARN
    assert all("waiting for residual/inner_race" in s.message for s in normal)


def test_tachometer_pulses_give_the_speed_and_the_decision_follows_them(ros_graph):
    """shaft_pulses (as the simulator publishes them, one message per 0.01 s chunk) on a run-up: the
    diagnoser takes the speed from the pulses, ignores a wrong shaft_speed and follows the change."""
    from bearing_common.shaft_angle import SpeedProfile, pulse_times
    from bearing_common.stamps import to_stamp
    from bearing_msgs.msg import ShaftSpeed, Tachometer

    fs, n, seconds = 12000.0, 120, 2.0
    run_up = SpeedProfile.parse("0:900,10:1800")  # +18 % by 2 s
    diags = ros_graph.subscribe(topics.DIAGNOSTICS)
    pub_or = ros_graph.publisher(topics.RESIDUAL_OUTER_RACE)
    pub_tacho = ros_graph.publisher(topics.TACHOMETER)
    pub_speed = ros_graph.publisher(topics.SHAFT_SPEED)
    node = ros_graph.start("bearing_diagnoser", "diagnoser", params={"model_set": "none", "diagnostics_period": 0.2})
    ros_graph.wait_until(lambda: pub_or.get_subscription_count() and pub_tacho.get_subscription_count(),
                         30.0, "the diagnoser to subscribe")
    times = pulse_times(run_up, 0.0, seconds)
    y = white_noise(seconds, fs, 0.1)
    for i in range(int(seconds * fs) // n):
        t0 = i * n / fs
        inside = (times >= t0) & (times < t0 + n / fs)
        tacho = Tachometer(duration=n / fs, first_pulse_index=int(np.searchsorted(times, t0)), pulses_per_revolution=1,
                           source="test")
        tacho.header.stamp = to_stamp(t0)
        tacho.pulse_offsets = (times[inside] - t0).tolist()
        pub_tacho.publish(tacho)
        speed = ShaftSpeed(angular_velocity=3000.0 * 2 * np.pi / 60)  # 3000 rpm: wrong, the pulses win
        speed.header.stamp = to_stamp(t0)
        pub_speed.publish(speed)
        msg = Residual(sample_rate=fs, first_sample_index=i * n, fault_hypothesis=1, model_set="none",
                       fault_frequency=100.0)
        msg.header.stamp = to_stamp(t0)
        msg.residual = y[i * n:(i + 1) * n].tolist()
        pub_or.publish(msg)
        time.sleep(n / fs)  # real time: the angle domain's resampling keeps up, no queue overflows

    def status():
        return [{kv.key: kv.value for kv in s.values} for d in list(diags) for s in d.status]

    chunks = int(seconds * fs) // n
    ros_graph.wait_until(lambda: any(f"accepted {chunks}" in v.get("residual/outer_race chunks", "")
                                     for v in status()), 20.0, "every chunk to be taken")
    last = next(v for v in status() if f"accepted {chunks}" in v.get("residual/outer_race chunks", ""))
    assert last["speed domain"].startswith("shaft angle")  # the decision follows the changing speed
    assert last["shaft speed from"] == topics.TACHOMETER.name
    assert float(last["shaft speed (rpm)"]) == pytest.approx(run_up.rpm(seconds), rel=0.02)
    assert any("shaft speed from the tachometer pulses" in line for line in node.lines), ros_graph.output()
