"""The diagnoser session on a snapshot sensor and on a stream: condition records, fault evidence, /diagnostics.

Without ROS: the session the node runs, fed residual chunks as the observers of model set
``none`` pass the vibration on (y = r).
"""


import numpy as np
import pytest

from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_diagnoser.decision.not_diagnosed import NotDiagnosed
from bearing_diagnoser.decision.scores import WindowScores
from bearing_diagnoser.diagnoser_node_config import LEVEL_ERROR, LEVEL_OK, LEVEL_STALE, PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_diagnoser.health.health_session import DecidedWindow, HealthSession, HealthSettings
from bearing_diagnoser.health.trend import HealthState, TrendConfig
from bearing_diagnoser.spectral.fault_combs import SLIP_ABOVE, SLIP_BELOW, comb_terms, drop_ambiguous, untestable
from bearing_diagnoser.synthetic import burst_train, white_noise

FS = 12000.0
RPM = 1800.0
BEARING = CATALOG["6205"]
BPFO = BEARING.bpfo(RPM / 60.0)
STREAMS = (FaultState.OUTER_RACE, FaultState.INNER_RACE)


def session(**values):
    logged = []
    v = {p.name: p.default for p in PARAMETERS} | {"rpm": RPM, "rpm_tolerance": 0.02} | values
    return DiagnoserSession(v, lambda level, text: logged.append((level, text)), keep_history=True), logged


def feed(s, stamp, first_index, x, now=None):
    """One chunk through both observer streams (pass-through residuals of model set none)."""
    reports = []
    for h in STREAMS:
        reports += s.on_residual(h, stamp, first_index, FS, x, None, None, BPFO, "none", stamp if now is None else now)
    return reports


def or_fault(seconds, seed, amplitude=3.0):
    rng = np.random.default_rng(seed)
    return white_noise(seconds, FS, 4e-3, rng) + burst_train(seconds, FS, BPFO, amplitude=amplitude, jitter=0.05,
                                                             rng=rng)


def feed_snapshots(s, count, seconds, interval=10.0, index="zero", amplitude=3.0, start=0):
    """``count`` snapshots of an outer-race fault, ``seconds`` long, one every ``interval`` s, their
    sample indices numbered from 0 each time (or on, as if sampling never stopped: ``continued``)."""
    reports, records = [], []
    for k in range(start, start + count):
        first = 0 if index == "zero" else int(round(k * interval * FS))
        reports += feed(s, 100.0 + k * interval, first, or_fault(seconds, k, amplitude))
        records += s.take_health()
    return reports, records


def test_a_stream_gives_one_record_a_second_with_the_decisions_evidence():
    s, _ = session()
    x = or_fault(5.5, 0)
    for i in range(0, x.size, 120):
        feed(s, i / FS, i, x[i:i + 120])
    records = s.take_health()
    assert [r.t for r in records] == pytest.approx([0.0, 1.0, 2.0, 3.0, 4.0])  # the other stream's copy skipped
    assert all(r.indicators.duration == pytest.approx(1.0) for r in records)
    assert np.std(x[:12000]) == pytest.approx(records[0].indicators.rms, rel=1e-9)
    last = records[-1].evidence
    assert set(last.significance) == {"outer_race", "inner_race", "ball"} and not last.untested
    assert last.significance["outer_race"] >= 1.0 and last.accumulated["outer_race"] >= 1.0
    assert s.take_health() == [] and s.streams[FaultState.OUTER_RACE].counts["snapshots"] == 0


def test_a_gap_in_a_stream_drops_the_window_it_breaks():
    s, _ = session(input_mode="stream")
    x = white_noise(4.0, FS, 4e-3)
    for i in range(0, x.size, 120):
        if not 1.5 * FS <= i < 1.6 * FS:  # 0.1 s lost
            feed(s, i / FS, i, x[i:i + 120])
    records = s.take_health()
    assert [r.t for r in records] == pytest.approx([0.0, 1.6, 2.6])
    assert s.condition.counts["broken windows"] == 1 and s.streams[FaultState.OUTER_RACE].counts["gaps"] == 1


@pytest.mark.parametrize("mode, index", [("auto", "zero"), ("auto", "continued"), ("snapshot", "zero")])
def test_snapshots_are_snapshots_not_a_broken_stream(mode, index):
    """Half-second snapshots every 10 s: no gap, no restart of the decision, one record per snapshot at
    its own stamp, every hypothesis tested (a snapshot longer than the 0.335 s window), the evidence
    accumulating across the pauses until the fault is named."""
    s, logged = session(input_mode=mode)
    reports, records = feed_snapshots(s, 3, 0.5, index=index)
    core = s.core
    more, late = feed_snapshots(s, 12, 0.5, index=index, start=3)
    reports += more
    assert s.core is core  # not restarted by the snapshots' indices
    for h in STREAMS:
        counts = s.streams[h].counts
        assert counts["gaps"] == 0 and counts["snapshots"] == 15 and counts["rejected"] == 0
    assert not [t for level, t in logged if level == "warning"]
    assert sum("snapshot sensor" in t for _, t in logged) == (1 if mode == "auto" else 0)  # said once
    assert [r.t for r in records + late] == pytest.approx([100.0 + 10.0 * k for k in range(15)])
    assert all(r.indicators.duration == pytest.approx(0.5) and not r.evidence.untested for r in late)
    horizon = [d.scores.horizon_s for d in s.history if d.diagnosed]
    assert max(horizon) > 1.5  # more than one snapshot's windows (0.5 s each) in the long horizon
    assert reports[-1].state == FaultState.OUTER_RACE
    assert late[-1].evidence.accumulated["outer_race"] >= 1.0


def test_a_short_snapshot_tests_what_its_resolution_separates():
    """0.2 s at 1800 rpm (5 Hz bins): the inner race is tested; the ball's cage sidebands (12 Hz off their
    carriers, 2.4 bins) are not resolved; the outer race keeps one term clear of the shaft-harmonic mask
    (2·BPFO lies 4.8 Hz from 7×; 3·BPFO is left out, as 2·BPFI's twin), and one term is no series.
    0.1 s (10 Hz bins) tests nothing: the mask covers every carrier (harmonics 3 bins apart, 1.5 masked
    each side). Untested hypotheses are said so and never called."""
    terms = drop_ambiguous(comb_terms(BEARING), SLIP_BELOW + SLIP_ABOVE)
    untested = untestable(terms, 30.0, 5.0)
    assert set(untested) == {FaultState.BALL, FaultState.OUTER_RACE}
    assert "2.4 bins from their carriers" in untested[FaultState.BALL]
    assert "no series" in untested[FaultState.OUTER_RACE]
    assert set(untestable(terms, 30.0, 10.0)) == set(terms)
    assert untestable(terms, 30.0, 12000.0 / 4096) == {}  # the analysis window tests them all
    s, _ = session(input_mode="snapshot")
    reports, records = feed_snapshots(s, 20, 0.2)
    ev = records[-1].evidence
    assert set(ev.significance) == {"inner_race"} and set(ev.untested) == {"ball", "outer_race"}
    assert s.history[-1].scores.horizon_s == pytest.approx(20 * 0.2, rel=0.01)  # every snapshot accumulated
    assert {r.state for r in reports} == {FaultState.NORMAL}
    s, _ = session(input_mode="snapshot")
    reports, records = feed_snapshots(s, 3, 0.1)
    assert not reports  # not diagnosed: nothing tested
    d = s.history[-1]
    assert not d.diagnosed and d.not_diagnosed.kind == "resolution"
    assert "0.1 s snapshot resolves 10 Hz, too coarse at 1800 rpm" in d.not_diagnosed.reason
    assert "not diagnosed: resolution: a 0.1 s snapshot" in records[-1].evidence.problem
    assert not records[-1].evidence.significance
    assert records[-1].to_json()["evidence"]["not_diagnosed"] == d.not_diagnosed.to_json()  # bearing-trend's line
    health = s.health(120.5)
    assert health.level != LEVEL_STALE and "not diagnosed: resolution: a 0.1 s snapshot" in health.message
    assert health.values["not diagnosed"] == "resolution"
    assert "ball: sidebands" in health.values["untested"]


def test_diagnostics_wait_for_the_next_snapshot_then_go_stale():
    s, _ = session(input_mode="snapshot", stale_timeout=1.0)
    for k in range(3):
        feed(s, 100.0 + 10.0 * k, 0, or_fault(0.1, k), now=100.0 + 10.0 * k)
    assert s.health(125.0).level != LEVEL_STALE  # 5 s after the last of snapshots 10 s apart
    assert s.health(146.0).level == LEVEL_STALE  # 2.5 intervals without one
    assert s.health(125.0).values["input"] == "snapshots, one every 10 s"


def test_the_condition_trend_is_on_diagnostics_and_raises_its_level():
    s, _ = session(input_mode="snapshot", baseline="6", baseline_min_duration=0.0)
    rng = np.random.default_rng(3)
    for k in range(14):
        x = rng.standard_normal(6000) * (1.0 if k < 10 else 6.0)
        feed(s, 60.0 * k, 0, x, now=60.0 * k)
    records = s.take_health()
    assert len(records) == 14 and records[-1].trend.state == HealthState.ALARM
    health = s.health(60.0 * 13 + 1)
    assert health.level == LEVEL_ERROR and "condition ALARM" in health.message
    v = health.values
    assert v["condition"] == "ALARM" and float(v["condition since (s)"]) == pytest.approx(records[-1].trend.since)
    assert v["condition moved"] in ("rms", "envelope_rms", "velocity_rms") and "condition slope (1/h)" in v
    assert float(v["rms (m/s^2)"]) == pytest.approx(records[-1].indicators.rms, rel=1e-3)
    assert v["iso 20816-3 zone"].endswith("(group2-rigid)")
    s.values["machine_class"] = "group1-flexible"  # as the node applies a parameter change
    s.configure({"machine_class": "group1-flexible"})
    assert s.condition.monitor.machine == "group1-flexible"  # applies to the next record, the trend kept
    assert s.condition.monitor.tracker.snapshots == 14


def test_healthy_snapshots_keep_the_diagnostics_ok():
    s, _ = session(input_mode="snapshot", baseline="6", baseline_min_duration=0.0)
    for k in range(12):
        feed(s, 60.0 * k, 0, white_noise(0.5, FS, 4e-3, np.random.default_rng(k)), now=60.0 * k)
    assert s.take_health()[-1].trend.state == HealthState.HEALTHY
    assert s.health(60.0 * 11 + 1).level == LEVEL_OK


def test_the_trend_begins_again_when_a_replay_starts_over_but_not_for_a_lagging_copy():
    logged = []
    h = HealthSession(HealthSettings(TrendConfig(baseline_snapshots=6)), lambda level, t: logged.append(t))
    x = white_noise(1.0, FS, 4e-3)
    for k in range(4):
        h.push(60.0 * k, FS, x, True, 0.0)
    assert h.push(60.0, FS, x, True, 0.0) == [] and h.monitor.tracker.snapshots == 4  # a copy: skipped
    h.push(0.0, FS, x, True, 0.0, restart=True)
    assert "begins again" in logged[-1] and h.monitor.tracker.snapshots == 1


def test_a_records_evidence_is_the_last_decided_window_inside_it():
    h = HealthSession(HealthSettings(period=1.0), lambda *a: None)
    scores = [WindowScores(significance={FaultState.OUTER_RACE: v}) for v in (0.5, 2.0, 7.0)]
    h.decided([DecidedWindow(0.4, scores[0]), DecidedWindow(0.9, scores[1]), DecidedWindow(1.2, scores[2])])
    (rec,) = h.push(0.0, FS, white_noise(1.0, FS, 4e-3), False, 0.0)
    assert rec.evidence.significance == {"outer_race": 2.0}  # ends inside [0, 1]; 1.2 waits for the next
    h.decided([DecidedWindow(1.5, scores[0], NotDiagnosed("speed", "shaft speed not confirmed"))])
    (rec,) = h.push(1.0, FS, white_noise(1.0, FS, 4e-3), False, 0.0)
    assert rec.evidence.problem == "not diagnosed: speed: shaft speed not confirmed"
    assert rec.evidence.not_diagnosed == NotDiagnosed("speed", "shaft speed not confirmed")
    (rec,) = h.push(2.0, FS, white_noise(1.0, FS, 4e-3), False, 0.0, no_evidence="shaft speed unknown")
    assert rec.evidence.problem == "shaft speed unknown"


def test_a_stream_that_follows_a_snapshot_is_cut_into_windows_from_its_first_chunk():
    """Auto mode: a chunk alone, a snapshot 10 s later, then chunks that continue it (a stream again)."""
    s, logged = session(input_mode="auto")
    x = white_noise(3.0, FS, 4e-3)
    feed(s, 0.0, 0, x[:1200])
    feed(s, 10.0, 0, x[:1200])
    for i in range(0, int(2.5 * FS), 1200):
        feed(s, 10.1 + i / FS, 1200 + i, x[i:i + 1200])
    assert [r.t for r in s.take_health()] == pytest.approx([0.0, 10.0, 10.1, 11.1])
    assert any("a stream again" in t for _, t in logged)


def test_diagnostics_between_a_trend_begun_again_and_its_first_record():
    """A restarted simulator (time back to 0): /diagnostics still shows the last record's condition."""
    s, logged = session()
    x = white_noise(2.0, FS, 4e-3)
    for i in range(0, x.size, 1200):
        feed(s, i / FS, i, x[i:i + 1200])
    feed(s, 0.0, 0, x[:1200])
    assert "begins again" in logged[-1][1]
    assert float(s.health(3.0).values["condition since (s)"]) == pytest.approx(0.0)
