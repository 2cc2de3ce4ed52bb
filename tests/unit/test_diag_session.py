"""The diagnoser session's health (what /diagnostics says), without ROS."""

import numpy as np
import pytest

from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_node_config import LEVEL_OK, LEVEL_STALE, LEVEL_WARN, PARAMETERS
from bearing_diagnoser.diagnoser_session import SPEED_UNKNOWN, DiagnoserSession

FS = 12000.0


def session(**values):
    logged = []
    v = {p.name: p.default for p in PARAMETERS} | values
    return DiagnoserSession(v, lambda level, text: logged.append((level, text))), logged


def feed(s, seconds=0.5, now=0.0):
    """Gaussian noise as both observers' pass-through residuals (model set none)."""
    x = np.random.default_rng(1).normal(0.0, 1.0, int(seconds * FS))
    for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE):
        s.on_residual(h, 0.0, 0, FS, x, np.zeros_like(x), np.zeros_like(x), 100.0, "none", now)


def test_stale_before_any_residual():
    s, _ = session()
    assert s.health(0.0).level == LEVEL_STALE


def test_unknown_speed_is_warned_once_and_clears_when_a_speed_is_told():
    s, logged = session(rpm=0.0)
    feed(s)
    health = s.health(0.1)
    assert health.level == LEVEL_WARN and SPEED_UNKNOWN in health.message
    assert logged.count(("warning", SPEED_UNKNOWN)) == 1
    s.on_speed(1800.0 * 2 * np.pi / 60.0)
    assert s.health(0.1).level == LEVEL_OK


@pytest.mark.parametrize("values", [dict(rpm=1797.0, rpm_tolerance=0.02), dict(rpm=0.0, model_set="sim_12k")])
def test_no_speed_warning_with_a_precise_speed_or_a_simulator_model_set(values):
    s, logged = session(**values)
    feed(s)
    assert s.health(0.1).level == LEVEL_OK
    assert not any(SPEED_UNKNOWN in text for _, text in logged)


def test_a_nameplate_speed_the_vibration_does_not_confirm_is_tested_and_warned():
    """Noise has no 1x line: a speed told within 10 % stays unconfirmed; the windows are tested over that
    whole range (paid for: noise stays NORMAL), and /diagnostics says that the speed is unconfirmed."""
    s, _ = session(rpm=1797.0)
    rng = np.random.default_rng(1)
    out = [r for i in range(8) for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE) for r in
           s.on_residual(h, 0.5 * i, int(0.5 * FS) * i, FS, rng.normal(0.0, 1.0, int(0.5 * FS)),
                         None, None, 100.0, "none", 0.0)]
    assert out and all(r.state == FaultState.NORMAL for r in out)
    health = s.health(0.1)
    assert health.level == LEVEL_WARN and "shaft speed not confirmed: told 1797 rpm ± 10 %" in health.message


def test_a_restarted_producer_whose_outer_race_residuals_come_late_raises_no_false_state():
    """The simulator restarted (indices and stamps back to 0); the OR observer's first residuals of
    the new run were lost (its DDS match came late), so only IR arrives for 2 s (the decision's
lag allowance is 1 s). The restarted
    folding decision must wait for the OR stream it knows is deployed, not decide without it
    (found by test_graph_restart: NORMAL, UNKNOWN, INNER_RACE on an outer-race signal)."""
    from bearing_common.bearings import CATALOG, fault_frequency
    from bearing_diagnoser.synthetic import burst_train, white_noise
    fs, o, i = 48000.0, FaultState.OUTER_RACE, FaultState.INNER_RACE
    s, _ = session(rpm=1800.0)
    y = burst_train(3.0, fs, fault_frequency(CATALOG["6205"], o, 1800.0), amplitude=10.0,
                    rng=np.random.default_rng(2)) + white_noise(3.0, fs, 4.5e-3)
    f = {h: fault_frequency(CATALOG["6205"], h, 1800.0) for h in (o, i)}

    def run(start, late, stamp0):
        out = []
        for k in range(start, y.size, 480):
            for h in (o, i):
                if h == o and k < late:
                    continue
                c = y[k:k + 480]
                out += s.on_residual(h, stamp0 + k / fs, k, fs, c, np.zeros_like(c), np.zeros_like(c), f[h],
                                     "sim_48k", now=0.0)
        return out

    run(0, 0, 100.0)  # a first run of 3 s with both streams
    assert s.last_report.state == o
    after = run(0, 96000, 0.0)  # the new run: OR residuals only from 2 s on
    assert after and {r.state for r in after} == {o}, sorted({(r.state.name, r.detail) for r in after})
    assert all("decided without" not in r.detail for r in after)


def test_an_observer_known_to_be_deployed_is_waited_for_at_start():
    """The node saw both observers' publishers matched, but the OR residuals' first 2 s were lost:
    the decision holds instead of deciding without OR."""
    from bearing_common.bearings import CATALOG, fault_frequency
    from bearing_diagnoser.synthetic import burst_train, white_noise
    fs, o, i = 48000.0, FaultState.OUTER_RACE, FaultState.INNER_RACE
    y = burst_train(3.0, fs, fault_frequency(CATALOG["6205"], o, 1800.0), amplitude=10.0,
                    rng=np.random.default_rng(3)) + white_noise(3.0, fs, 4.5e-3)
    for expected, ok in (({o, i}, True), (set(), False)):
        s, _ = session(rpm=1800.0)
        s.expect(expected)
        out = []
        for k in range(0, y.size, 480):
            for h in (o, i) if k >= 96000 else (i,):
                c = y[k:k + 480]
                out += s.on_residual(h, k / fs, k, fs, c, np.zeros_like(c), np.zeros_like(c),
                                     fault_frequency(CATALOG["6205"], h, 1800.0), "sim_48k", now=0.0)
        assert out and ({r.state for r in out} == {o}) == ok, sorted({(r.state.name, r.detail) for r in out})


def test_each_front_end_takes_the_false_alarm_budget_it_states():
    """false_alarm_rate (per hour) shapes the spectral decision, false_alarm_probability (per window)
    the fold decision; neither silently sets the other's, and the log line says the one in use."""
    s, logged = session(rpm=1797.0, false_alarm_rate=0.01, false_alarm_probability=1e-3)
    spectral = s.decision_config("none")
    assert spectral.front_end.false_alarm_rate == 0.01
    fold = s.decision_config("sim_12k")
    assert fold.pfa == 1e-3 and fold.front_end == fold.front_end.with_false_alarm_rate(0.01)
    feed(s)
    assert any("0.01 per hour" in text for _, text in logged)
    default, _ = session()
    assert default.decision_config("none").front_end.false_alarm_rate == 1e-3


def test_a_measured_speed_beyond_the_told_tolerance_is_used_and_warned():
    """A shaft running 12 % faster than its nameplate (within twice the 10 % tolerance, plainly
    measured from its 1x line and harmonics; 15 % would put it at a quarter of the ball comb's
    2·BSF, which is never taken for the shaft): the scores carry both speeds, /diagnostics warns."""
    fr = 1.12 * 1797.0 / 60.0
    t = np.arange(int(4.0 * FS)) / FS
    x = sum(np.sin(2 * np.pi * k * fr * t + k) / k for k in range(1, 7))
    x = x + np.random.default_rng(2).normal(0.0, 0.05, t.size)
    s, logged = session(rpm=1797.0)
    reports = [r for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE) for r in
               s.on_residual(h, 0.0, 0, FS, x, None, None, 100.0, "none", 0.0)]
    last = reports[-1].scores.as_dict()
    assert abs(last["speed_hz"] - fr) < 0.01 * fr and last["told_speed_hz"] == pytest.approx(1797.0 / 60.0)
    assert last["speed_disagrees"] == 1.0
    health = s.health(0.1)
    assert health.level == LEVEL_WARN and "disagrees with the told 1797.0 rpm" in health.message
    assert any(level == "warning" and "disagrees" in text for level, text in logged)
