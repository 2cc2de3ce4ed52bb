"""The envelope_spectrum topic without ROS: max-hold decimation, the message's contents, the decision's hook.

Exact answers on analytic inputs (a ramp, an isolated line, a known view), and the hook checked
against the decision it comes from: the view of a window is the spectrum that window was decided
on (its comb scales are the verdict's), and its strongest line sits on the fault's harmonics.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearing_common.bearings import CATALOG, DEFAULT_BEARING
from bearing_common.stamps import to_seconds
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser import Diagnoser
from bearing_diagnoser.diagnoser_node_config import PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.spectral.envelope_view import EnvelopeView
from bearing_diagnoser.spectral.fault_combs import comb_terms
from bearing_diagnoser.spectrum_message import (
    FIRST_BIN,
    MAX_VALUES,
    decimated_spectrum,
    fill_spectrum_message,
    max_hold,
)
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_msgs.msg import EnvelopeSpectrum, FaultLines

O, I, B = FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL
FS, FR = 48000.0, 30.0
BEARING = CATALOG[DEFAULT_BEARING]


def test_max_hold_of_a_ramp():
    held, centres, p = max_hold(np.arange(10.0), 4)
    assert p == 3  # ceil(10 / 4)
    assert held.tolist() == [2.0, 5.0, 8.0, 9.0]  # runs [0-2], [3-5], [6-8], [9]
    assert centres.tolist() == [1.0, 4.0, 7.0, 9.0]  # the last run is one bin: its centre is that bin


@pytest.mark.parametrize("n", [1, 99, 100, 101, 180, 231, 1000, 12345])
def test_max_hold_keeps_at_most_max_values_with_the_shortest_runs(n):
    held, centres, p = max_hold(np.zeros(n), MAX_VALUES)
    assert len(held) == len(centres) <= MAX_VALUES
    assert p == 1 or math.ceil(n / (p - 1)) > MAX_VALUES  # one bin shorter runs would be too many


@pytest.mark.parametrize("n, max_values", [(231, 100), (180, 100), (100, 100), (57, 10)])
def test_max_hold_never_loses_a_line_and_places_it_within_half_a_run(n, max_values):
    for k in range(n):  # an isolated line in every bin in turn
        values = np.zeros(n)
        values[k] = 1.0
        held, centres, p = max_hold(values, max_values)
        assert held.tolist().count(1.0) == 1 and held.sum() == 1.0
        assert abs(centres[np.argmax(held)] - k) <= (p - 1) / 2


def test_max_hold_refuses_what_it_cannot_decimate():
    with pytest.raises(ValueError, match="non-empty 1-D"):
        max_hold(np.array([]))
    with pytest.raises(ValueError, match="non-empty 1-D"):
        max_hold(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="max_values must be >= 1"):
        max_hold(np.zeros(3), 0)


def view(told_hz=FR, shaft_hz=FR * 1.004, line_bin=36, n_bins=240, df=2.976) -> EnvelopeView:
    """A view of 6205 combs with noise at 1 and one line of 300 at ``line_bin``."""
    ses = np.ones(n_bins)
    ses[line_bin] = 300.0
    terms = comb_terms(BEARING)
    return EnvelopeView(end=96000, length=16128, sample_rate=FS, ses=ses, bin_width=df, band=(2000.0, 6000.0),
                        f_top=531.99, shaft_hz=shaft_hz, shaft_source="refined", told_hz=told_hz, terms=terms,
                        rho={O: 0.99, I: 1.0, B: 1.01})


def test_the_shown_range_is_from_bin_2_to_the_highest_line_tested():
    v = view()
    freq, mag, p = decimated_spectrum(v)
    n = math.ceil(v.f_top / v.bin_width) + 1 - FIRST_BIN  # bins 2 .. 179: 178
    assert p == math.ceil(n / MAX_VALUES) == 2 and len(freq) == math.ceil(n / p) == 89
    assert freq[0] == pytest.approx(2.5 * v.bin_width)  # the run of bins 2 and 3
    assert freq[-1] == pytest.approx((FIRST_BIN + n - 1.5) * v.bin_width)
    assert mag.max() == 300.0 and abs(freq[np.argmax(mag)] - 36 * v.bin_width) <= v.bin_width / 2


def test_the_message_holds_the_view_decimated_with_the_lines_at_both_speeds():
    v = view()
    msg = fill_spectrum_message(EnvelopeSpectrum(), v, 2.0, "drive_end", FaultLines)
    freq, mag, p = decimated_spectrum(v)
    assert to_seconds(msg.header.stamp) == 2.0 and msg.header.frame_id == "drive_end"
    assert msg.window_duration == 16128 / FS and msg.bin_width == v.bin_width
    assert msg.bins_per_value == p and msg.frequency_resolution == pytest.approx(p * v.bin_width)
    assert (msg.band_low, msg.band_high) == (2000.0, 6000.0)
    assert (msg.told_shaft_rate, msg.shaft_rate, msg.shaft_rate_source) == (FR, FR * 1.004, "refined")
    assert np.allclose(msg.frequency, freq, rtol=1e-7) and np.allclose(msg.magnitude, mag, rtol=1e-7)  # float32
    assert len(msg.frequency) <= MAX_VALUES
    o = BEARING.orders()
    lines = {entry.hypothesis: entry for entry in msg.lines}
    assert list(lines) == ["outer_race", "inner_race", "ball"]
    assert lines["outer_race"].told.tolist() == pytest.approx([k * o.bpfo * FR for k in (1, 2, 3)], rel=1e-12)
    assert lines["outer_race"].measured.tolist() == pytest.approx([k * o.bpfo * FR * 1.004 for k in (1, 2, 3)],
                                                                  rel=1e-12)
    inner = lines["inner_race"]  # carriers, then the ±fr sidebands of each
    assert inner.carrier == [True] * 3 + [False] * 6
    assert inner.told[3:5].tolist() == pytest.approx([o.bpfi * FR - FR, o.bpfi * FR + FR], rel=1e-12)
    ball = lines["ball"]  # carriers 2k·BSF, sidebands ± FTF
    assert ball.measured[0] == pytest.approx(2 * o.bsf * FR * 1.004, rel=1e-12)
    assert ball.measured[3] == pytest.approx((2 * o.bsf - o.ftf) * FR * 1.004, rel=1e-12)
    assert (lines["outer_race"].rho, lines["ball"].rho) == (0.99, 1.01)


def test_without_a_told_speed_the_told_lines_are_empty_and_the_rate_nan():
    msg = fill_spectrum_message(EnvelopeSpectrum(), view(told_hz=None), 1.0, "", FaultLines)
    assert math.isnan(msg.told_shaft_rate)
    assert all(len(entry.told) == 0 and len(entry.measured) == len(entry.carrier) > 0 for entry in msg.lines)


def test_the_hook_holds_the_spectrum_each_window_was_decided_on():
    """A simulated outer-race fault through the decision core: after every window the view is that
    window's (its end and its comb scales are the verdict's), and its strongest line is a harmonic
    of BPFO at the speed the decision used."""
    rng = np.random.default_rng(5)
    y = burst_train(2.0, FS, BEARING.orders().bpfo * FR, amplitude=3.0, jitter=0.01, rng=rng)
    y = y + white_noise(2.0, FS, 4.5e-3, rng)
    core = Diagnoser(config_for("none"), "none", BEARING, FS)
    core.tell_speed(60.0 * FR)
    assert core.envelope_view() is None  # nothing tested yet
    chunk, views = 480, []
    for i in range(0, y.size, chunk):
        for d in core.update(O, i, FS, y[i:i + chunk], fault_frequency=BEARING.orders().bpfo * FR):
            v = core.envelope_view()
            views.append(v)
            assert v.end == round(d.window_end * FS) and v.length / FS == pytest.approx(d.window_end - d.window_start)
            assert v.rho == d.scores.rho
    assert len(views) >= 8 and d.state == O
    freq, mag, p = decimated_spectrum(views[-1])
    peak = freq[np.argmax(mag)]
    bpfo = BEARING.orders().bpfo * views[-1].shaft_hz
    assert abs(peak - round(peak / bpfo) * bpfo) <= (p / 2 + 1) * views[-1].bin_width


def test_the_fold_front_end_publishes_no_spectrum():
    core = Diagnoser(config_for("sim_48k"), "sim_48k", BEARING, FS)
    y = burst_train(0.2, FS, BEARING.orders().bpfo * FR)
    for h in (O, I):
        core.update(h, 0, FS, y, fault_frequency=100.0)
    assert core.envelope_view() is None


def test_the_session_hands_out_each_window_spectrum_once_at_its_stamp():
    """take_envelope: the last tested window's view with the stamp of its end on the chunks' clock
    (stamp of index 0 + end / rate), once; None until the next window."""
    values = {p.name: p.default for p in PARAMETERS} | {"model_set": "none", "rpm": 60.0 * FR}
    session = DiagnoserSession(values, lambda level, text: None, keep_history=True)
    rng = np.random.default_rng(5)
    y = burst_train(1.0, FS, BEARING.orders().bpfo * FR, amplitude=3.0, jitter=0.01, rng=rng)
    y = y + white_noise(1.0, FS, 4.5e-3, rng)
    t0, chunk, taken = 100.0, 480, []
    for i in range(0, y.size, chunk):
        seen = len(session.history)
        session.on_residual(O, t0 + i / FS, i, FS, y[i:i + chunk], None, None, 107.0, "none", 0.0)
        got = session.take_envelope()
        if len(session.history) > seen:  # windows decided (published or not: a window's spectrum shows either way)
            assert got is not None and got[0] == pytest.approx(t0 + session.history[-1].window_end, abs=1e-9)
            taken.append(got)
        else:
            assert got is None
    assert len(taken) >= 3 and len({id(v) for _, v in taken}) == len(taken)
    assert session.take_envelope() is None
