"""Accuracy on every development recording in ../shared/data (CWRU 12 and 48 kHz, MFPT, HIT-SM), same settings for all.

The totals reached are asserted, so a regression fails: the race faults diagnosed (all of them
but two 48 kHz CWRU records: 174, whose file labels the shaft 11 % too fast over only 1.33 s,
too short to measure the speed, and 201, whose envelope lines at BPFO stand no higher than in
the healthy record 097; and HIT-SM's OR8_600, whose outer-race comb keeps one term clear of the
shaft harmonics in a 1.3 s window at 600 rpm, and 5 s do not hold one block of the fine lane:
one term is no series), no ball record called a race fault (but 226, below), no alarm on any
healthy record, the method at least as good as the textbook envelope baseline (with the same
accumulation) on every data set, and the published confidence of a fault state a lower bound of how often it
was right. Skips with the reason when the recordings are absent.
"""

from __future__ import annotations

import pytest
from data_paths import REPO_ROOT, data_dir

from bearing_common.states import FaultState
from bearing_diagnoser.accuracy import calibration, load_manifest, markdown, run, totals
from bearing_diagnoser.recording_diagnosis import diagnose_recording

MANIFEST = REPO_ROOT / "benchmarks" / "shared_data.yaml"

#: Reached on the development recordings: (faults right, fault records, healthy clean, healthy).
EXPECTED = {"CWRU": (2, 3, 2, 2), "MFPT": (14, 14, 0, 0), "HIT-SM": (17, 18, 3, 3), "CWRU-48k": (8, 13, 0, 0)}

#: The ball-fault record whose envelope holds an inner-race series: BPFI and its harmonics with shaft-rate
#: sidebands, at one common slip, growing steadily over the record (the long horizon names it after 4.7 s);
#: the label and the signal disagree, as on several CWRU ball records (Smith & Randall 2015 found many of
#: them undiagnosable as ball faults). :func:`test_the_ball_record_226_holds_an_inner_race_series` shows it.
BPFI_IN_A_BALL_RECORD = "226"


@pytest.fixture(scope="module")
def results():
    records = load_manifest(MANIFEST, root=data_dir())
    missing = [r.path for r in records if not r.path.is_file()]
    if missing:
        pytest.skip(f"{len(missing)} recordings not found under {data_dir()} (provided beside the repository "
                    "as ../shared/data in CI; set BEARING_DATA_DIR to use another copy)")
    return run(records)


def test_every_fault_but_the_undiagnosable_ball_record_and_no_alarm(results):
    got = totals([r for r in results if r.method == "model"])
    for dataset, (right, faults, _clean, healthy) in EXPECTED.items():
        t = got[dataset]
        assert (t["faults"], t["healthy"]) == (faults, healthy)
        assert t["faults_right"] >= right, (dataset, t, markdown(results))
        assert t["healthy_clean"] == healthy and t["alarm_windows"] == 0, (dataset, t)
    for ball in (r for r in results if r.method == "model" and r.record.truth == FaultState.BALL):
        if ball.record.name != BPFI_IN_A_BALL_RECORD:
            assert ball.state not in (FaultState.OUTER_RACE, FaultState.INNER_RACE), ball.record.name  # wrong part


def test_the_ball_record_226_holds_an_inner_race_series(results):
    """What :data:`BPFI_IN_A_BALL_RECORD` is called on: the inner-race comb's own evidence, every check of
    distinctness passed (a series at one slip, its shaft-rate sidebands, above its decoys), decisive
    at the end of the record, with no ball evidence beside it."""
    r = next(r for r in results if r.method == "model" and r.record.name == BPFI_IN_A_BALL_RECORD)
    assert r.state == FaultState.INNER_RACE
    last = diagnose_recording(r.record.load()).decisions[-1].scores.as_dict()
    assert last["inner_race"] > 1.0 and last["ball"] < 1.0 and last["outer_race"] < 1.0


def test_at_least_as_good_as_the_textbook_envelope_spectrum(results):
    ours, baseline = (totals([r for r in results if r.method == m]) for m in ("model", "envelope"))
    for dataset in EXPECTED:
        assert ours[dataset]["faults_right"] >= baseline[dataset]["faults_right"]
        assert baseline[dataset]["healthy_clean"] == baseline[dataset]["healthy"]  # a fair, quiet baseline
    # in total no fewer; the trust work traded one HIT-SM record (600 rpm, see EXPECTED) for no alarm on healthy
    # machines told 7 % off or with bearings whose fault orders are near-integers, where the baseline alarms
    # (the false-alarm matrix, docs/results.md)
    assert sum(t["faults_right"] for t in ours.values()) >= sum(t["faults_right"] for t in baseline.values())


def test_fault_confidence_is_a_lower_bound_of_being_right(results):
    """On the race-fault and healthy records. The confidence is the posterior of the part given
    the hypotheses the combs stand for; two 48 kHz ball-fault records (122, 226) carry plain
    race-fault line families (BPFO lines in 122, a BPFI harmonic series in 226: any envelope
    method sees them), which name a race late in the record: reported in docs/results.md, not here."""
    rows = calibration([r for r in results if r.method == "model" and r.record.truth != FaultState.BALL],
                       faults=True)
    assert sum(n for _lo, _hi, n, _s in rows) > 400
    for lo, _hi, n, share in rows:
        if n >= 20:
            assert share >= lo, rows


def test_correct_records_are_decided_within_six_windows(results):
    """A window is 4 cage periods (0.34 s at 1800 rpm, 1 s at 600 rpm); a nameplate speed needs
    about 2 s of signal to be confirmed by the 1x line at 600 rpm."""
    for r in results:
        if r.method == "model" and r.correct and r.record.truth != FaultState.NORMAL:
            rpm = r.record.rpm or 1800.0
            assert r.decided_at is not None and r.decided_at <= 6 * 10.0 / (rpm / 60.0), (r.record.name, r.decided_at)
