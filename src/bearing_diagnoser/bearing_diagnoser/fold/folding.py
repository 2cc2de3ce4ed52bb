"""Folding periodicity, the fold front end's statistic (diagnosis-notes.md, "what carried the discrimination").

The band-passed energy envelope (:class:`bearing_diagnoser.decision.stream_blocks.EnergyEnvelope`)
of one window is folded at a candidate period: envelope sample t falls in phase bin
floor(frac(t·f)·bins); the profile is the bin means, smoothed over adjacent bins (an impact
may straddle two). Peakiness = (max − mean)/mean of the profile (the maximum over bins is
the phase search); the period is searched ±3 % for slip and speed error
(:func:`period_grid`). :func:`cfar_periodicity` divides the best peakiness at the fault
frequency by the median of the same at "decoy" frequencies where no bearing line lies
(:mod:`.decoys`): a constant-false-alarm-rate normalisation, ≈ 1 on noise. Explain-away:
:func:`impact_phase_mask` and :func:`explain_away` mask one hypothesis' impact phases
before the other is tested (IR impacts fold into three phase clusters at the OR period,
2·BPFI ≈ 3·BPFO).

The inner loops are compiled (numba, strict IEEE), each reproducing the NumPy formulation it
names bit for bit.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit

from ..decision.pairwise_sum import PW_BLOCK, block_sum, halved_sum


def period_grid(fault_hz: float, window_s: float, bins: int, search: float = 0.03) -> np.ndarray:
    """Relative frequency factors searched around a nominal frequency (dimensionless).

    The step keeps the phase drift over the window below one bin: step = 1/(bins · N)
    with N = fault_hz · window_s periods in the window; the grid spans ±``search``
    (default 3 %, slip 1-2 % plus speed error).  The same factors are used at the decoy
    frequencies so fault and decoy statistics see the same number of trials.
    """
    n_periods = max(1.0, fault_hz * window_s)
    step = 1.0 / (bins * n_periods)
    half = max(1, int(np.ceil(search / step)))
    return 1.0 + np.linspace(-search, search, 2 * half + 1)


@lru_cache(maxsize=64)
def _fold_table(freqs: tuple, n: int, envelope_rate: float, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Phase bins of ``n`` envelope samples at each frequency: the folding, precomputed.

    Sample t (t / envelope_rate s from the window's first sample) falls at frequency f (Hz)
    in bin floor(frac(t·f)·bins). Returns ``offsets`` (n, len(freqs)): row f's bin plus
    f · bins (uint16 when that fits: the table stays in the L1 cache), and ``inv``
    (len(freqs) · bins,): 1 / the samples per bin (1 for an empty bin). Phase is measured
    from the window's first sample: the maximum over bins (the phase search) does not
    depend on the origin, and the table serves window after window while the frequencies
    stay the same.
    """
    f = np.asarray(freqs, float)
    t = np.arange(n) / envelope_rate
    idx = np.minimum(((np.outer(f, t) % 1.0) * bins).astype(np.int64), bins - 1)
    rows = idx + (np.arange(f.size) * bins)[:, None]
    inv = 1.0 / np.maximum(np.bincount(rows.ravel(), minlength=f.size * bins).astype(float), 1.0)
    offsets = np.ascontiguousarray(rows.T.astype(np.uint16 if f.size * bins <= 1 << 16 else np.int64))
    offsets.setflags(write=False)
    inv.setflags(write=False)
    return offsets, inv


def folded_peakiness(env: np.ndarray, envelope_rate: float, freqs: np.ndarray,
                     first_block: int = 0, bins: int = 16, smooth: int = 2) -> np.ndarray:
    """Peakiness of the envelope folded at each frequency in ``freqs``.

    For each f, envelope sample n (time t = n / rate from the window start) goes to bin
    floor(frac(t·f)·bins); the profile is the bin means, circularly averaged over
    ``smooth`` adjacent bins (an impact may straddle two bins).  Peakiness =
    (max − mean)/mean of the profile: 0 for a flat profile, ≈ bins/smooth − 1 for one
    impact per period.  The maximum over bins is the phase search.  ``first_block`` is
    accepted for symmetry with absolute-time callers and does not change the result
    beyond the bin origin.

    Returns an array of shape (len(freqs),), dimensionless.
    """
    env = np.ascontiguousarray(env, dtype=float)
    freqs = np.atleast_1d(np.asarray(freqs, dtype=float))
    if env.size == 0:
        return np.zeros(freqs.size)
    offsets, inv = _fold_table(tuple(np.round(freqs, 9)), env.size, float(envelope_rate), int(bins))
    return fold_peakiness(env, offsets, inv, int(bins), int(smooth))


class FoldBank:
    """The CFAR periodicity of windows of ``n`` envelope samples at one fault frequency.

    Fault and decoy frequencies (Hz) times the relative ``grid`` are folded with one
    precomputed table (:func:`_fold_table`), so that a window costs one compiled pass
    (:func:`cfar_fold`). See :func:`cfar_periodicity`.
    """

    def __init__(self, fault_hz: float, decoys_hz: np.ndarray, grid: np.ndarray, n: int, envelope_rate: float,
                 bins: int = 16):
        freqs = np.concatenate([[fault_hz], np.asarray(decoys_hz, float)])
        allf = (freqs[:, None] * grid[None, :]).ravel()
        self.fault_hz, self.grid, self.bins = fault_hz, grid, int(bins)
        self._offsets, self._inv = _fold_table(tuple(np.round(allf, 9)), n, float(envelope_rate), self.bins)

    def cfar(self, env: np.ndarray) -> tuple[float, float, float]:
        """``(ratio, fault_peakiness, best_hz)`` of one window's envelope, a contiguous float
        array (:func:`cfar_periodicity`)."""
        ratio, peak, j = cfar_fold(env, self._offsets, self._inv, self.grid.size, self.bins, 2)
        return ratio, peak, float(self.fault_hz * self.grid[j])


def cfar_periodicity(env: np.ndarray, envelope_rate: float, fault_hz: float,
                     decoys_hz: np.ndarray, grid: np.ndarray, first_block: int = 0,
                     bins: int = 16) -> tuple[float, float, float]:
    """CFAR-normalised periodicity at ``fault_hz``.

    Returns ``(ratio, fault_peakiness, best_hz)``: ratio = max over the grid of the
    peakiness (:func:`folded_peakiness`) at ``fault_hz · grid`` divided by the median over
    decoys of the same max at ``decoy · grid`` (dimensionless, ≈ 1 on noise, ≫ 1 for
    impacts at the fault period; 0 when that median is not positive); best_hz = the
    searched frequency that maximised the peakiness.
    """
    env = np.ascontiguousarray(env, dtype=float)
    return FoldBank(fault_hz, decoys_hz, grid, env.size, envelope_rate, bins).cfar(env)


def impact_phase_mask(env: np.ndarray, envelope_rate: float, freq: float, first_block: int = 0,
                      bins: int = 16, smooth: int = 2, margin: int = 1) -> np.ndarray:
    """Boolean mask of the envelope samples at the impact phase of period 1/``freq``.

    Folds ``env`` at ``freq``, finds the peak of the (smoothed) profile and marks every
    sample whose phase lies in the peak's ``smooth`` bins widened by ``margin`` bins on
    each side.  Used to "explain away" one hypothesis before testing the other: IR
    impacts folded at the OR period fall into three phase clusters (BPFI/BPFO ≈ 1.51, so
    2·BPFI ≈ 3·BPFO, 0.7 % apart) and would otherwise look periodic at BPFO too.
    """
    return _impact_phase_mask(np.ascontiguousarray(env, dtype=float), float(envelope_rate), float(freq),
                                     int(bins), int(smooth), int(margin))


def explain_away(env: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Copy of ``env`` with the masked samples replaced by the median of the others."""
    return _explain_away(np.ascontiguousarray(env, dtype=float), np.ascontiguousarray(mask, dtype=bool))


@njit(cache=True)
def fold_peakiness(env: np.ndarray, offsets: np.ndarray, inv: np.ndarray, bins: int, smooth: int) -> np.ndarray:
    """Peakiness of the envelope folded at each frequency of a folding table.

    Row ``f``: profile ``prof[f, b] = Σ_{t in bin b} inv[f, b] · env[t]``, summed in order of
    t (as the sparse matrix product did), smoothed circularly over ``smooth`` bins
    (``sum(np.roll(prof, -k) for k in range(smooth)) / smooth``), peakiness
    ``(max − mean) / mean`` (0 when the mean is not positive). Samples run in the outer
    loop and frequencies in the inner one: consecutive additions go to different bins, so
    none waits for the previous one (a quarter faster than frequency by frequency); the
    neighbour index wraps without a modulo (an integer division per bin cost as much as
    the fold).

    Parameters
    ----------
    env : ndarray, shape (n,)
        Envelope ((m/s²)²).
    offsets : ndarray of int, shape (n, F)
        ``f · bins + (phase bin of sample t at frequency f)``.
    inv : ndarray, shape (F · bins,)
        1 / (samples in the bin), 1 for an empty bin, at the same offsets.

    Returns
    -------
    ndarray, shape (F,)
        Dimensionless.
    """
    n_rows = offsets.shape[1]
    prof = np.zeros(n_rows * bins)
    for t in range(env.size):
        e = env[t]
        for f in range(n_rows):
            o = offsets[t, f]
            prof[o] += inv[o] * e
    out = np.empty(n_rows)
    smoothed = np.empty((1, bins))
    for f in range(n_rows):
        top = -np.inf
        for b in range(bins):
            s = prof[f * bins + b]
            j = b
            for _ in range(1, smooth):
                j += 1
                if j == bins:
                    j = 0
                s += prof[f * bins + j]
            v = s / smooth
            smoothed[0, b] = v
            if v > top:
                top = v
        mean = (block_sum(smoothed, 0, 0, bins) if bins <= PW_BLOCK else halved_sum(smoothed, 0, 0, bins)) / bins
        out[f] = (top - mean) / mean if mean > 0 else 0.0
    return out


@njit(cache=True)
def median(x: np.ndarray) -> float:
    """``np.median`` of a finite 1-D array: the middle order statistic, or the mean of the two
    (NaN when empty)."""
    if x.size == 0:
        return np.nan
    s = np.sort(x)
    m = s.size // 2
    return s[m] if s.size % 2 else (s[m - 1] + s[m]) / 2


@njit(cache=True)
def cfar_fold(env: np.ndarray, offsets: np.ndarray, inv: np.ndarray, n_grid: int, bins: int, smooth: int):
    """CFAR ratio of the first frequency's best peakiness to the median of the others'.

    The table's rows are frequencies × grid factors, row ``i·n_grid + g``; frequency 0 is the
    fault, the rest decoys. Returns ``(ratio, best peakiness of frequency 0, grid index of
    that best)``: ``best[0] / median(best[1:])`` (0 when the median is not positive), with
    ``best`` the maximum over the grid (:func:`cfar_periodicity`).
    """
    pk = fold_peakiness(env, offsets, inv, bins, smooth)
    n_freqs = pk.size // n_grid
    best = np.empty(n_freqs)
    arg = 0
    for i in range(n_freqs):
        best[i] = pk[i * n_grid]
        for g in range(1, n_grid):
            if pk[i * n_grid + g] > best[i]:
                best[i] = pk[i * n_grid + g]
                if i == 0:
                    arg = g
    ref = median(best[1:])
    return (best[0] / ref if ref > 0 else 0.0), best[0], arg


@njit(cache=True)
def phase_bins(n: int, envelope_rate: float, freq: float, bins: int) -> np.ndarray:
    """Phase bin ``min(floor(frac(t·freq)·bins), bins − 1)`` of envelope samples t = 0..n−1 / rate."""
    out = np.empty(n, np.int64)
    for i in range(n):
        out[i] = min(np.int64((((i / envelope_rate) * freq) % 1.0) * bins), bins - 1)
    return out


@njit(cache=True)
def _impact_phase_mask(env: np.ndarray, envelope_rate: float, freq: float, bins: int, smooth: int,
                       margin: int) -> np.ndarray:
    """:func:`impact_phase_mask`: the samples in the peak's ``smooth`` bins ± ``margin``.

    Profile = ``np.bincount(b, env) / max(np.bincount(b), 1)``, smoothed as in
    :func:`fold_peakiness`; the peak is its first maximum.
    """
    b = phase_bins(env.size, envelope_rate, freq, bins)
    sums = np.zeros(bins)
    counts = np.zeros(bins, np.int64)
    for t in range(env.size):
        sums[b[t]] += env[t]
        counts[b[t]] += 1
    peak, top = 0, -np.inf
    for k in range(bins):
        s = sums[k] / max(counts[k], 1)
        for j in range(1, smooth):
            s += sums[(k + j) % bins] / max(counts[(k + j) % bins], 1)
        s = s / smooth
        if s > top:
            peak, top = k, s
    sel = np.zeros(bins, np.bool_)
    for k in range(-margin, smooth + margin):
        sel[(peak + k) % bins] = True
    mask = np.empty(env.size, np.bool_)
    for t in range(env.size):
        mask[t] = sel[b[t]]
    return mask


@njit(cache=True)
def _explain_away(env: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Copy of ``env`` with the masked samples replaced by the median of the others (when
    there are both)."""
    out = env.copy()
    kept = env[~mask]
    if kept.size and kept.size < env.size:
        m = median(kept)
        for t in range(env.size):
            if mask[t]:
                out[t] = m
    return out
