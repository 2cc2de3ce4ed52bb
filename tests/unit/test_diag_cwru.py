"""Real CWRU recordings through ``bearing-diagnose``'s pipeline, thresholds from white noise only.

105 (IR) -> inner_race, 130 (OR at 6:00) -> outer_race, 97 (normal, 48 kHz; as given and
decimated to 12 kHz beforehand) -> normal, with the model method and with the envelope
reference.  118 (ball, 0.007 in; Smith & Randall: not diagnosable by any method) is run
and reported, not asserted: there is no ball model, and nothing is tuned to make it pass.
Skips with the reason when the recordings (../shared/data/cwru or $BEARING_CWRU_DIR) are
absent.
"""

from __future__ import annotations

import functools

import pytest

from bearing_common.states import FaultState
from bearing_diagnoser.cwru_report import RECORDS, load_record, markdown, summarise
from bearing_diagnoser.offline import diagnose_recording


@functools.cache
def _diagnose(directory: str, file: str, rate: float, method: str):
    rec = load_record(directory, file, rate)
    return diagnose_recording(rec, method=method, quiet=True)


CASES = [(f, r, t) for f, r, t, _n in RECORDS if t != FaultState.BALL]


@pytest.mark.parametrize("method", ["model", "envelope"])
@pytest.mark.parametrize("file, rate, truth", CASES, ids=[f"{f[:3]}@{int(r)}" for f, r, _t in CASES])
def test_cwru_record_is_diagnosed(cwru_record, file, rate, truth, method):
    res = _diagnose(str(cwru_record(file).parent), file, rate, method)
    s = summarise(res)
    assert res.model_set == "cwru_de_6205"
    assert s["state"] == truth, [(x.state.label, round(x.start, 2), round(x.end, 2)) for x in res.segments]
    assert s["share"] >= 0.9  # of the record's duration
    assert s["decided_at"] <= 1.0  # s
    if truth == FaultState.NORMAL:
        assert len(res.segments) == 1  # never an alarm on the normal record


def test_cwru_ball_record_is_reported_honestly(cwru_record, capsys):
    """118: run both methods; print what they give (expected: not ball — no ball model)."""
    file, rate = "118_B007_0hp_DE12k.mat", 12000.0
    directory = str(cwru_record(file).parent)  # skips with the reason when absent
    rows = []
    for method in ("model", "envelope"):
        s = summarise(_diagnose(directory, file, rate, method))
        assert s["state"] != FaultState.BALL  # reserved state: nothing produces it yet
        rows.append((method, s["state"].label, round(s["share"], 3)))
    with capsys.disabled():
        print(f"\nCWRU 118 (ball, not diagnosable per Smith & Randall): {rows}")


def test_cwru_table_markdown_shape():
    row = {"record": "105", "note": "n", "truth": "inner_race",
           "model": {"state": FaultState.INNER_RACE, "confidence": 0.5, "share": 1.0, "decided_at": 0.2, "segments": 1},
           "envelope": {"state": FaultState.NORMAL, "confidence": 0.9, "share": 1.0, "decided_at": 0.2, "segments": 1}}
    text = markdown([row])
    lines = text.splitlines()
    assert len(lines) == 3 and lines[2].count("|") == lines[0].count("|")
    assert "inner_race (0.50, 100 %, 1 segment)" in lines[2] and "normal ✗" in lines[2]
