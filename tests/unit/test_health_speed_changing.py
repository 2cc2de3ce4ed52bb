"""Health indicators under a changing shaft speed (issue 27): windows whose measured speed spreads by more
than 2 % are held out of the condition trend (not learnt from, not charted), flagged in the records,
in ``bearing-trend``'s JSON and in /diagnostics.

Signals: :mod:`benchmarks.synthetic_ramps` (the 6205 at 12 kHz, shaft lines that follow the shaft angle,
Gaussian noise) along piecewise linear speed profiles.
"""

import json
import math

import numpy as np
import pytest

from bearing_common.shaft_angle import SpeedProfile
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_node_config import PARAMETERS
from bearing_diagnoser.diagnoser_session import SPEED_CHANGING_HELD, DiagnoserSession
from bearing_diagnoser.health.health_session import HealthSession, HealthSettings
from bearing_diagnoser.health.trend import HealthState, HealthTrend, TrendConfig
from bearing_diagnoser.health.trend_cli import main as trend
from bearing_recordings.bag_write import recording_to_bag
from bearing_recordings.recording import Recording
from benchmarks.synthetic_ramps import RATE, ramp_signal

BASELINE = 6
RUN_UP_FIRST = SpeedProfile.parse("0:1800,4:2700")  # windows 0-3 ramp (+50 %), then 2700 rev/min held
STEADY_THEN_RAMP = SpeedProfile.parse("0:1800,8:1800,12:2700")  # windows 8-11 ramp


def _steady(k: int) -> dict:
    """Indicators of a healthy window: 1 ± 5 %."""
    return {"x": 1.0 + 0.05 * math.sin(1.7 * k)}


def test_held_windows_are_not_learnt_from():
    trend = HealthTrend(TrendConfig(baseline_snapshots=BASELINE, indicators=("x",)))
    held = [trend.hold(float(k)) for k in range(3)]  # a run-up's windows first, whatever their values
    assert all(r.learning and not r.level for r in held) and trend.snapshots == 0
    for k in range(3, 3 + BASELINE):
        trend.update(float(k), _steady(k))
    b = trend.baseline
    assert b is not None and b.snapshots == BASELINE and b.end == 3.0 + BASELINE - 1
    assert trend.limits()["x"][0] == pytest.approx(1.0, rel=0.05)  # the steady level: nothing of the run-up


def test_held_windows_are_not_alarmed_on_and_the_state_in_force_stays():
    config = TrendConfig(indicators=("x",))  # the shipped 30-window baseline
    held, charted = HealthTrend(config), HealthTrend(config)
    k0 = config.baseline_snapshots + 10
    for k in range(k0):
        for t in (held, charted):
            t.update(10.0 * k, _steady(k))
    records = [held.hold(10.0 * k) for k in range(k0, k0 + 5)]  # 4x: a run-up's vibration
    assert {r.state for r in records} == {HealthState.HEALTHY} and not any(r.learning for r in records)
    assert all(not r.score and r.moved == "" for r in records)
    assert [charted.update(10.0 * k, {"x": 4.0}).state for k in range(k0, k0 + 5)][-1] == HealthState.ALARM
    after = held.update(10.0 * (k0 + 5), _steady(k0 + 5))  # steady again: charted as before the ramp
    assert after.state == HealthState.HEALTHY and after.level["x"] == pytest.approx(1.0, rel=0.1)


def test_a_stream_s_windows_are_flagged_where_the_stamped_speed_changes():
    x, w = ramp_signal(STEADY_THEN_RAMP, 16.0, seed=2)
    session = HealthSession(HealthSettings(TrendConfig(baseline_snapshots=BASELINE)), lambda *a: None)
    chunk = int(0.01 * RATE)
    records = []
    for i in range(0, x.size, chunk):
        stamp = 50.0 + i / RATE
        session.speed([stamp], [w[i]])  # shaft_speed: one stamped value per 0.01 s
        records += session.push(stamp, RATE, x[i:i + chunk], False, 500.0)
    assert len(records) == 16
    flagged = [k for k, r in enumerate(records) if r.speed_changing]
    assert flagged == [8, 9, 10, 11]
    assert session.counts["speed changing"] == 4
    assert session.monitor.tracker.snapshots == 12  # the steady windows only
    assert all(r.trend.state == records[7].trend.state and not r.trend.level for r in records[8:12])
    assert records[3].to_json()["speed_changing"] is False and records[9].to_json()["speed_changing"] is True


def test_no_measured_speed_flags_nothing():
    x, _ = ramp_signal(STEADY_THEN_RAMP, 12.0, seed=3)
    session = HealthSession(HealthSettings(TrendConfig(baseline_snapshots=BASELINE)), lambda *a: None)
    records = session.push(0.0, RATE, x, False, 500.0)
    assert len(records) == 12 and not any(r.speed_changing for r in records)


def _diagnose(profile: SpeedProfile, seconds: float) -> DiagnoserSession:
    values = {p.name: p.default for p in PARAMETERS} | {"model_set": "none", "baseline": "6",
                                                         "baseline_min_duration": 0.0}
    session = DiagnoserSession(values, lambda level, text: None)
    x, w = ramp_signal(profile, seconds, seed=4)
    chunk = int(0.01 * RATE)
    for i in range(0, x.size, chunk):
        stamp = 10.0 + i / RATE
        session.on_speed(float(w[i]), stamp)
        session.on_residual(FaultState.OUTER_RACE, stamp, i, RATE, x[i:i + chunk], None, None, 100.0, "none",
                            now=stamp)
    return session


def test_diagnostics_say_when_the_indicators_are_held_out():
    ramp = _diagnose(SpeedProfile.parse("0:1800,1:1800,3:2200"), 2.5)  # the last window [1, 2) s ramps
    assert ramp.last_health.speed_changing
    health = ramp.health(12.5)
    assert health.message.endswith(SPEED_CHANGING_HELD), health.message
    assert SPEED_CHANGING_HELD in health.values["condition"]
    assert health.values["condition windows held out (speed changing)"] == "1"
    steady = _diagnose(SpeedProfile.constant(1800.0), 2.5)
    assert not steady.last_health.speed_changing
    assert SPEED_CHANGING_HELD not in steady.health(12.5).message


def _npz(tmp_path, x, w):
    path = tmp_path / "run_up.npz"
    np.savez(path, accel=x, sample_rate=RATE, shaft_speed=w)
    return path


def _bag(tmp_path, x, w):
    rec = Recording(x, RATE, None, "mat", channel="vib", path="run_up")
    rec.set_shaft_speed(w, "run-up")
    recording_to_bag(rec, tmp_path / "bag", chunk_duration=0.01)  # a ShaftSpeed per chunk
    return tmp_path / "bag"


@pytest.mark.parametrize("write", [_npz, _bag], ids=["npz", "bag"])
def test_bearing_trend_flags_each_window_and_learns_after_the_run_up(tmp_path, capsys, write):
    x, w = ramp_signal(RUN_UP_FIRST, 12.0, seed=5)
    path = write(tmp_path, x, w)
    assert trend([str(path), "--json", "--window", "1", "--baseline", str(BASELINE)]) == 0
    *records, last = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["speed_changing"] for r in records] == [True] * 4 + [False] * 8
    assert all(r["trend"]["learning"] for r in records[:4 + BASELINE - 1])
    baseline = last["summary"]["baseline"]
    assert baseline["snapshots"] == BASELINE and baseline["end"] == pytest.approx(4.0 + BASELINE - 1)
