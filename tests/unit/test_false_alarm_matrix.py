"""The false-alarm matrix on a few cells (benchmarks/false_alarm_matrix.py, issue 25 item 5), and its two constructions.

Cells: a healthy recording, a bearing, the speed told, a variant (as recorded, the 1x family
notched out, a foreign stationary line in the envelope) and our decision as ``bearing-diagnose``
runs it; none may raise an alarm. The constructions are checked on the recording itself: the
notches leave no 1x family to the decision's own speed measurement and nothing else changes;
the foreign line stands where and as high as stated, where the recording had none. Skips with
the reason when the recordings are absent.
"""

from __future__ import annotations

import numpy as np
import pytest
from data_paths import data_dir

from bearing_common.states import FaultState
from bearing_diagnoser.spectral.fault_combs import SHAFT_MASK_BINS, comb_terms
from bearing_diagnoser.spectral.shaft_speed import estimate_speed
from benchmarks import healthy_variants as hv
from benchmarks.false_alarm_matrix import GEOMETRIES, Cell, Outcome, cells, machine, markdown, run_cell
from benchmarks.healthy_data import CONTINUOUS

EIGHT_BALLS = "8 balls d/D 0.25 (BPFO 3x, BPFI 5x)"
CWRU_DE = "CWRU 097 drive end"

@pytest.fixture(scope="module", autouse=True)
def recordings():
    missing = [h.path for h in CONTINUOUS if not h.path.is_file()]
    if missing:
        pytest.skip(f"{len(missing)} recordings not found under {data_dir()} (provided beside the repository "
                    "as ../shared/data in CI; set BEARING_DATA_DIR to use another copy)")


@pytest.mark.parametrize("source, geometry, speed, variant", [
    (CWRU_DE, EIGHT_BALLS, "own speed", "as recorded"),
    (CWRU_DE, EIGHT_BALLS, "told 7 % low", "as recorded"),
    (CWRU_DE, EIGHT_BALLS, "told 7 % high", "as recorded"),
    (CWRU_DE, EIGHT_BALLS, "own speed", "1x family notched"),
    (CWRU_DE, EIGHT_BALLS, "own speed", "foreign line"),
    ("HIT-SM Normal_1200", "6205", "own speed", "as recorded"),
    ("HIT-SM Normal_1200", "6205", "own speed", "foreign line"),
    ("HIT-SM Normal_1200", EIGHT_BALLS, "own speed", "as recorded"),  # these three alarmed before issue 25
    # these two alarmed (INNER_RACE) when two lines of a 1 s buffer confirmed the speed: 2 x 10.55 Hz and
    # 2 x 20.19 Hz, a bin apart, passed for 1x and 2x of 20.41 Hz, and the 12th shaft harmonic escaped the mask
    ("HIT-SM Normal_1200", "6205", "own speed", "1x family notched"),
    ("HIT-SM Normal_1200", "9 balls d/D 1/3 (BPFO 3x, BPFI 6x)", "told 7 % high", "1x family notched"),
    ("HIT-SM Normal_900", "femto", "own speed", "as recorded"),
    ("HIT-SM Normal_600", "9 balls d/D 1/3 (BPFO 3x, BPFI 6x)", "told 7 % low", "as recorded"),
])
def test_no_alarm_from_our_decision(source, geometry, speed, variant):
    out = run_cell(Cell(source, geometry, speed, variant, "ours"))
    assert not out.error
    assert out.windows > 0
    assert out.calls == (), (out.calls, out.change)
    assert sum(out.not_diagnosed.values()) < 0.5 * out.windows, out.not_diagnosed  # a verdict, not silence


@pytest.mark.parametrize("source, geometry, variant", [
    (CWRU_DE, EIGHT_BALLS, "as recorded"),
    (CWRU_DE, EIGHT_BALLS, "foreign line"),  # the line is in the reference too: the machine's own
    ("HIT-SM Normal_1200", EIGHT_BALLS, "as recorded"),
    ("HIT-SM Normal_600", "6205", "1x family notched"),
])
def test_no_alarm_with_the_machines_own_reference(source, geometry, variant):
    out = run_cell(Cell(source, geometry, "own speed", variant, "ours, with reference"))
    assert not out.error and not out.unbuilt
    assert out.windows > 0
    assert out.calls == (), (out.calls, out.change)
    assert sum(out.not_diagnosed.values()) < 0.5 * out.windows, out.not_diagnosed


def test_snapshots_have_no_with_reference_cells():
    modes = {(c.source.startswith("FEMTO"), c.mode) for c in cells()}
    assert (True, "ours, with reference") not in modes and (False, "ours, with reference") in modes
    assert (True, "ours") in modes


def _speeds(x, fs, nominal_hz):
    """The decision's speed measurement on 2 s buffers (half overlapping), over ±10 % of the nominal rate."""
    n = int(2 * fs)
    return [estimate_speed(x[i:i + n], fs, 0.9 * nominal_hz, 1.1 * nominal_hz)
            for i in range(0, x.size - n + 1, n // 2)]


@pytest.mark.parametrize("source", [CWRU_DE, "HIT-SM Normal_1200"])
def test_the_notches_take_the_1x_family_away_and_nothing_else(source):
    m = machine(source)
    x = m.pieces[0]
    y = hv.without_shaft_family(x, m.fs, m.fr)
    assert all(s is not None for s in _speeds(x, m.fs, m.rpm / 60))  # the recording shows its 1x family
    assert all(s is None for s in _speeds(y, m.fs, m.rpm / 60))
    n = 8 * x.size  # the whole record's spectrum, Hann, interpolated 8x
    before, after = (np.abs(np.fft.rfft((s - s.mean()) * np.hanning(s.size), n)) ** 2 for s in (x, y))
    f = np.fft.rfftfreq(n, 1 / m.fs)
    above = f > (hv.NOTCHED_HARMONICS + 2) * m.fr
    assert after[above].sum() == pytest.approx(before[above].sum(), rel=1e-3)  # nothing else changed
    floor = np.median(before[(np.abs(f - m.fr) > 0.03 * m.fr) & (np.abs(f - m.fr) < 0.1 * m.fr)])
    at = np.abs(f - m.fr) <= m.fs / x.size  # within one bin of the record
    assert before[at].max() > 20 * floor and after[at].max() < floor  # the 1x line: gone


def test_the_foreign_line_is_where_and_as_strong_as_stated():
    m = machine(CWRU_DE)
    bearing = GEOMETRIES[EIGHT_BALLS]
    line = hv.place_foreign_line(list(m.pieces), m.fs, bearing, m.fr)
    # 2.5 % below 2·BPFO = 5.85x, the line the issue measured on a healthy 8-ball rig
    assert (line.hypothesis, line.harmonic, line.offset) == (FaultState.OUTER_RACE, 2, -0.025)
    assert line.hz == pytest.approx(5.85 * m.fr, rel=1e-9)
    bin_hz = bearing.ftf(m.fr) / hv.WINDOW_CAGE_PERIODS
    assert abs(line.hz - 6 * m.fr) > SHAFT_MASK_BINS * bin_hz  # not a shaft line by the decision's own mask
    kinematic = np.concatenate([t[:, 0] + t[:, 1] for t in comb_terms(bearing).values()]) * m.fr
    assert np.min(np.abs(kinematic - line.hz)) > SHAFT_MASK_BINS * bin_hz  # nor a part's
    top = hv.envelope_top(bearing, m.fr)
    assert hv.line_strength(list(m.pieces), m.fs, line.hz, top) < hv.LINE_STRENGTH_RANGE[0]  # none there before
    y = hv.modulated(m.pieces[0], m.fs, line.hz, line.depth)
    assert hv.line_strength([y], m.fs, line.hz, top) == pytest.approx(hv.LINE_STRENGTH, abs=hv.STRENGTH_TOLERANCE)
    assert 0.0 < line.depth < 0.2  # a weak modulation: the signal's level is that of the recording
    # the line stands at its frequency: in 0.5 s windows of the widest band the height peaks there
    n = int(hv.STRENGTH_WINDOW_S * m.fs)
    z = np.mean([_ses(y[i:i + n], m.fs, top) for i in range(0, y.size - n + 1, n)], axis=0)
    df = 1 / hv.STRENGTH_WINDOW_S
    near = np.arange(int((line.hz - 10 * df) / df), int((line.hz + 10 * df) / df) + 1)
    assert abs(near[np.argmax(z[near])] * df - line.hz) <= df


def _ses(x, fs, f_top):
    """Normalised squared envelope spectrum of ``x`` over [f_top, 0.45·fs] without prewhitening."""
    from bearing_diagnoser.spectral.envelope_spectrum import band_ses, normalise, window_spectrum
    ses, _ = band_ses(window_spectrum(x, prewhiten=False), x.size, fs, np.array([[f_top, 0.45 * fs]]), 2 * f_top)
    return normalise(ses)[0]


def test_the_floor_measures_one():
    """White noise: the normalised envelope spectrum's floor has mean 1 wherever it is read (each band
    and view: the mean of 10 windows' Exp(1) bins), and a modulation brings the line to its height."""
    rng = np.random.default_rng(7)
    fs = 20000.0
    x = rng.standard_normal(int(5 * fs))
    heights = hv.line_heights([x], fs, 175.0, 200.0)
    assert heights.size > 20 and np.mean(heights) == pytest.approx(1.0, abs=0.1)
    depth, strength = hv.modulation_depth([x], fs, 175.0, 200.0)
    assert strength == pytest.approx(hv.LINE_STRENGTH, abs=hv.STRENGTH_TOLERANCE) and depth < 0.2


def test_the_report_counts_refusals_and_cells_not_built_apart_from_alarms():
    cell = Cell("S", "6205", "own speed", "foreign line", "ours")
    outcomes = [Outcome(cell, "R", ("ball",), 10), Outcome(cell, "R", (), 10, error="too short"),
                Outcome(cell, "R", unbuilt="no place for a foreign line")]
    text = markdown(outcomes, 1.0, quick=True)
    assert "| all | 1/2 (ball 1), 0 %, exit 2: 1, not built: 1 |" in text
    assert "| S | 6205 | own speed | foreign line | ours | not built | no place for a foreign line |" in text
