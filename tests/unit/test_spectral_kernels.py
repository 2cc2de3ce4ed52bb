"""The spectral decision's exact shortcuts against the plain formulations they replace, bit for bit.

The compiled continued fraction of the gamma tail (:mod:`bearing_diagnoser.spectral.gamma_tail`), the
onset's runs tested at once (:func:`.fault_combs.recent_run_evidence`), the kept term bins
(:func:`.fault_combs.term_bins`) and the long horizon's rows left out when they cannot hold the
smallest p-value (:func:`.fault_combs.smallest_log10p`), the running-median normalisation without
``np.pad``, ``sliding_window_view``, ``np.partition`` and a ``np.interp`` per row (:func:`.envelope_spectrum.normalise`,
compiled in :mod:`bearing_diagnoser.spectral.running_median`), the bands' bins sliced rather than gathered
(:func:`.envelope_spectrum.band_bins`) and the compiled reads of the single-window p-value table
(:mod:`bearing_diagnoser.spectral.comb_table`) promise the very numbers the decision computed before; the
references below are those computations.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal
from scipy.special import gammaincc, gammaln

from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_diagnoser.spectral.accumulation import CombGeometry
from bearing_diagnoser.spectral.envelope_spectrum import N_MED, band_bins, normalise
from bearing_diagnoser.spectral.fault_combs import (
    SHAFT_MASK_BINS,
    best_scale,
    comb_evidence,
    comb_sums,
    comb_terms,
    log10p_k,
    recent_run_evidence,
    rho_range,
    scales,
    term_bins,
)
from bearing_diagnoser.spectral.significance import (
    _TABLE,
    J_MAX,
    S_MAX,
    S_STEP,
    averaged_comb_log10p,
    averaged_comb_log10p_rows,
    averaged_median,
    comb_log10p,
    log10_gamma_sf,
)

RNG = np.random.default_rng(26)


def plain_log10_gamma_sf(a, x) -> np.ndarray:
    """log10 Q(a, x) as the decision computed it before: the continued fraction in NumPy, all elements
    iterated until every one converged."""
    a, x = np.broadcast_arrays(np.asarray(a, float), np.asarray(x, float))
    q = gammaincc(a, x)
    out = np.log10(np.maximum(q, 1e-300))
    tiny = q < 1e-280
    if np.any(tiny):
        at, xt = a[tiny], x[tiny]
        b = xt + 1.0 - at
        c = np.full_like(xt, 1e300)
        d = 1.0 / b
        h = d.copy()
        for i in range(1, 200):
            an = -i * (i - at)
            b = b + 2.0
            d = an * d + b
            d = np.where(np.abs(d) < 1e-300, 1e-300, d)
            c = b + an / c
            c = np.where(np.abs(c) < 1e-300, 1e-300, c)
            d = 1.0 / d
            step = d * c
            h = h * step
            if np.all(np.abs(step - 1.0) < 1e-12):
                break
        out[tiny] = (-xt + at * np.log(xt) - gammaln(at) + np.log(h)) / np.log(10.0)
    return out


def tail_arguments(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    """(a, x) of comb p-values deep in the tail and around its edge: a = J·K, x up to 40 a."""
    a = RNG.integers(1, 16, size=(rows, 1)) * RNG.integers(1, 33, size=(rows, 1)).astype(float)
    x = a * RNG.uniform(0.5, 40.0, size=(rows, cols))
    return a, x


def test_gamma_tail_matches_the_numpy_loop():
    a, x = tail_arguments(40, 128)
    assert (gammaincc(np.broadcast_to(a, x.shape), x) < 1e-280).mean() > 0.2  # the tail is exercised
    assert_array_equal(log10_gamma_sf(a, x), plain_log10_gamma_sf(a, x))
    assert_array_equal(log10_gamma_sf([3.0], [900.0]), plain_log10_gamma_sf([3.0], [900.0]))


def test_gamma_tail_per_row_is_each_row_alone():
    a, x = tail_arguments(25, 60)
    rows = np.stack([plain_log10_gamma_sf(a[r], x[r]) for r in range(a.shape[0])])
    assert_array_equal(log10_gamma_sf(a, x, per_row=True), rows)


def geometry(fr: float = 29.95, fs: float = 12000.0, window: int = 4096) -> CombGeometry:
    return CombGeometry(fs, fr, 0.01 * fr, window, rho_range(0.005), comb_terms(CATALOG["6205"]), 600.0)


def plain_recent_run_evidence(z, df, g, hypothesis, mask_shaft=True) -> np.ndarray:
    """The onset's evidence as the decision computed it before: one run length at a time."""
    t = g.terms[hypothesis]
    rhos, n_cells = scales(t, g.rho, df, g.fr)
    s, j = comb_sums(z, df, g.fr, t, rhos, mask_shaft, ())
    out = np.empty(z.shape[0])
    for r in range(z.shape[0]):
        best = best_scale(s[r:r + 1], j, r + 1)[0, 0]
        out[r] = min(0.0, log10p_k(s[r:r + 1, best], j[best:best + 1], r + 1)[0] + np.log10(n_cells))
    return out


@pytest.mark.parametrize("hypothesis", [FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL])
@pytest.mark.parametrize("line", [0.0, 3.0, 40.0])
def test_recent_runs_at_once_match_one_at_a_time(hypothesis, line):
    g = geometry()
    df = g.fs / g.window
    runs = 32
    z = RNG.exponential(size=(runs, 400)) * np.log(2.0)
    bins = np.rint(np.outer(np.arange(1, 4), [g.terms[hypothesis][0, 0] * g.fr * 0.99 / df])).astype(int).ravel()
    z[:, bins] += line * np.linspace(0.2, 1.0, runs)[:, None]  # from no evidence to the deep tail
    z = np.cumsum(z, axis=0) / np.arange(1, runs + 1)[:, None]
    got = recent_run_evidence(z, df, g, hypothesis)
    assert_array_equal(got, plain_recent_run_evidence(z, df, g, hypothesis))
    assert_array_equal(np.signbit(got), np.signbit(plain_recent_run_evidence(z, df, g, hypothesis)))
    one = z[:1]
    assert_array_equal(recent_run_evidence(one, df, g, hypothesis), plain_recent_run_evidence(one, df, g, hypothesis))


def test_term_bins_are_kept_and_read_only():
    g = geometry()
    t = g.terms[FaultState.INNER_RACE]
    rhos = np.linspace(0.97, 1.02, 50)
    df = g.fs / g.window
    idx, active = term_bins(df, g.fr, t, rhos, 300, True, (181.0,))
    f = (t[None, :, 0] * rhos[:, None] + t[None, :, 1]) * g.fr
    plain = np.rint(f / df).astype(int)
    expected = (plain >= 1) & (plain < 300)
    order = np.rint(f / g.fr)
    expected &= ~((order >= 1) & (np.abs(f - order * g.fr) < SHAFT_MASK_BINS * df))
    expected &= np.abs(f - 181.0) >= SHAFT_MASK_BINS * df
    assert_array_equal(idx, np.clip(plain, 0, 299))
    assert_array_equal(active, expected)
    again = term_bins(df, g.fr, t.copy(), rhos.copy(), 300, True, [181.0])
    assert again[0] is idx and again[1] is active  # the same arguments: the arrays kept
    assert not idx.flags.writeable and not active.flags.writeable
    assert averaged_median(2)[0].size == 128


def comb_rows(rows: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(S, J) of ``rows`` combs over k averaged windows: no terms, noise, and lines from weak to the far tail."""
    j = RNG.integers(0, 10, size=rows)
    s = np.where(j > 0, j * RNG.uniform(0.3, 1.5, size=rows), 0.0)
    strong = RNG.random(rows) < 0.3
    s[strong] *= RNG.uniform(1.0, 60.0, size=int(strong.sum()))
    assert (log10_gamma_sf(j * k, k * s) < -280).any()  # some rows reach the continued fraction
    return s, j


@pytest.mark.parametrize("k", [2, 7, 32])
def test_averaged_p_values_of_some_rows_are_those_of_all(k):
    s, j = comb_rows(60, k)
    rows = RNG.random(60) < 0.4
    got = averaged_comb_log10p_rows(s, j, k, rows)
    assert_array_equal(got[rows], averaged_comb_log10p(s, j, k)[rows])
    assert np.isnan(got[~rows]).all()


@pytest.mark.parametrize("k", [2, 5, 16])
@pytest.mark.parametrize("line", [0.0, 0.6, 3.0])
def test_rows_left_out_cannot_hold_the_smallest_p_value(k, line):
    g = geometry()
    df = g.fs / g.window
    z = RNG.gamma(k, 1.0 / k, size=(40, 400)) * np.log(2.0)
    bins = np.rint(np.arange(1, 4) * g.terms[FaultState.OUTER_RACE][0, 0] * g.fr * 0.99 / df).astype(int)
    z[:, bins] += line * RNG.uniform(0.0, 1.0, size=(40, 1))  # rows from noise to a clear comb
    args = (z, df, g.fr, g.terms, g.rho, True, 40, k)
    plain, pruned = comb_evidence(*args), comb_evidence(*args, prune=True)
    left_out = 0
    for h in plain:
        lp, got = plain[h][0], pruned[h][0]
        best = int(np.argmin(lp))
        assert int(np.argmin(got)) == best and np.signbit(got[best]) == np.signbit(lp[best])
        kept = np.isfinite(got)
        assert_array_equal(got[kept], lp[kept])
        assert (lp[~kept] > lp[best]).all()
        left_out += int((~kept).sum())
        for a, b in zip(plain[h][1:], pruned[h][1:]):
            assert_array_equal(a, b)
    if line >= 3.0:
        assert left_out > 0  # a clear comb leaves the noise rows out


def plain_normalise(ses: np.ndarray, stride: int = 8, level: float = np.log(2.0)) -> np.ndarray:
    """The running-median normalisation as the decision computed it before."""
    ses = np.atleast_2d(ses)
    n = ses.shape[-1]
    padded = np.pad(ses, ((0, 0), (N_MED, N_MED)), mode="reflect" if n > N_MED else "edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * N_MED + 1, axis=-1)[:, ::stride]
    centres = np.arange(0, n, stride)[: windows.shape[1]]
    medians = np.partition(windows, N_MED, axis=-1)[..., N_MED]
    if centres[-1] != n - 1:
        centres = np.append(centres, n - 1)
        last = np.partition(padded[:, n - 1:n + 2 * N_MED], N_MED, axis=-1)[:, N_MED]
        medians = np.concatenate([medians, last[:, None]], axis=1)
    grid = np.arange(n)
    med = np.stack([np.interp(grid, centres, row) for row in medians])
    return level * ses / np.maximum(med, 1e-300)


@pytest.mark.parametrize("n", [1, 2, 9, 50, 51, 52, 101, 102, 107, 600, 1001, 4097])
@pytest.mark.parametrize("stride", [1, 5, 8, 150])
def test_normalise_matches_the_plain_running_median(n, stride):
    ses = RNG.exponential(size=(5, n)) * RNG.uniform(0.01, 100.0, size=(5, 1))
    ses[1, : n // 3] = 0.0  # ties and a zero median
    ses[2] = np.round(ses[2] / ses[2].mean() * 4.0)  # a few levels: ties everywhere
    ses[3] = np.sort(ses[3])  # rising: the median moves by a whole stride of ranks at each centre
    ses[4] = np.sort(ses[4])[::-1]  # falling
    for level in (np.log(2.0), 0.93):
        assert_array_equal(normalise(ses, stride, level), plain_normalise(ses, stride, level))
    assert_array_equal(normalise(ses[0], stride), plain_normalise(ses[0], stride))


def test_band_bins_are_the_gathered_bins():
    n, fs = 4000, 12000.0
    X = np.fft.rfft(RNG.normal(size=n))
    df = fs / n
    inside = np.array([[600.0, 1800.0], [1500.0, 2700.0], [4800.0, 6000.0]])  # up to Nyquist, no clipping
    beyond = np.array([[-30.0, 1170.0], [5400.0, 6600.0]])  # below 0 and beyond Nyquist: clipped
    for bands in (inside, beyond, inside[:1]):
        first = np.rint(bands[:, 0] / df).astype(int)
        width = int(np.rint((bands[0, 1] - bands[0, 0]) / df))
        gathered = X[np.clip(first[:, None] + np.arange(width)[None, :], 0, X.size - 1)]
        got = band_bins(X, n, fs, bands)
        assert_array_equal(got, gathered)
        assert got.flags.c_contiguous and got.dtype == X.dtype


def plain_comb_log10p(s, j) -> np.ndarray:
    """The single-window table read as the decision computed it before, in NumPy."""
    s = np.clip(np.asarray(s, float), 0.0, S_MAX)
    j = np.clip(np.asarray(j, int), 0, J_MAX)
    pos = s / S_STEP
    i = np.minimum(pos.astype(int), _TABLE.shape[1] - 2)
    w = pos - i
    return _TABLE[j, i] * (1 - w) + _TABLE[j, i + 1] * w


def plain_best_scale(s, j, starts) -> np.ndarray:
    """:func:`.fault_combs.best_scale` of single windows as the decision computed it before."""
    score = plain_comb_log10p(s, j[None, :])
    starts = np.asarray(starts, int)
    low = np.minimum.reduceat(score, starts, axis=1)
    sizes = np.diff(np.r_[starts, score.shape[1]])
    at_low = score == np.repeat(low, sizes, axis=1)
    return np.minimum.reduceat(np.where(at_low, np.arange(score.shape[1]), score.shape[1]), starts, axis=1)


def test_table_reads_match_the_numpy_lookup():
    s = np.r_[RNG.uniform(-5.0, S_MAX + 50.0, 2000), 0.0, S_MAX, S_MAX - S_STEP / 3, 12.35, -0.0]
    j = RNG.integers(-1, J_MAX + 3, s.size)
    assert_array_equal(comb_log10p(s, j), plain_comb_log10p(s, j))
    grid = s.reshape(1, -1)[:, :1000].reshape(40, 25)
    assert_array_equal(comb_log10p(grid, j[:25][None, :]), plain_comb_log10p(grid, j[:25][None, :]))
    assert comb_log10p(3.7, 2) == plain_comb_log10p(3.7, 2)


@pytest.mark.parametrize("starts", [(0,), (0, 7, 8, 30)])
def test_best_scales_of_single_windows_match_the_numpy_search(starts):
    s = np.round(RNG.uniform(0.0, 40.0, (25, 41)), 0)  # whole values: ties between scales
    j = RNG.integers(0, 10, 41)
    assert_array_equal(best_scale(s, j, 1, starts), plain_best_scale(s, j, starts))
    empty = (0, 7, 7, 30)  # a run without scales: the NumPy search's own rule
    assert_array_equal(best_scale(s, j, 1, empty), plain_best_scale(s, j, empty))
