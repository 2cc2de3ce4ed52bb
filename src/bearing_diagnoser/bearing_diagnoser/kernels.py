"""Compiled inner loops of the decision (numba).

Each replaces a chain of small NumPy calls that ran once per chunk or per window (a 48 kHz
stream has 100 of each per second) by one pass over the data. Strict IEEE arithmetic (no
fastmath), operations in NumPy's order: each kernel names the NumPy formulation it
reproduces bit for bit — sums in NumPy's pairwise order (:func:`row_sum`), the
band-pass in ``scipy.signal.sosfilt``'s. The one exception, said where it applies: the
lagged products of :func:`train_correlation` (NumPy computes them with a BLAS dot, whose
summation order depends on the BLAS build; the score is reported, never decided on).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: NumPy's block length of pairwise summation (``PW_BLOCKSIZE``).
_PW_BLOCK = 128


@njit(cache=True)
def _block_sum(a: np.ndarray, row: int, lo: int, n: int) -> float:
    """:func:`row_sum` of at most 128 terms of ``a[row]`` (one block, no halving)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[row, lo + i]
        return res
    r0, r1, r2, r3 = a[row, lo], a[row, lo + 1], a[row, lo + 2], a[row, lo + 3]
    r4, r5, r6, r7 = a[row, lo + 4], a[row, lo + 5], a[row, lo + 6], a[row, lo + 7]
    i = 8
    while i < n - n % 8:
        j = lo + i
        r0 += a[row, j]
        r1 += a[row, j + 1]
        r2 += a[row, j + 2]
        r3 += a[row, j + 3]
        r4 += a[row, j + 4]
        r5 += a[row, j + 5]
        r6 += a[row, j + 6]
        r7 += a[row, j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[row, lo + i]
        i += 1
    return res


@njit(cache=True)
def _halved_sum(a: np.ndarray, row: int, lo: int, n: int) -> float:
    """:func:`row_sum` of more than 128 terms: NumPy's recursive halving, on an explicit stack
    (numba cannot cache a recursive function)."""
    los = np.empty(64, np.int64)  # 2**64 terms would not fit any array
    ns = np.empty(64, np.int64)
    left = np.empty(64)
    stage = np.zeros(64, np.int64)  # 0: not split yet, 1: left half pending, 2: right half pending
    sp, los[0], ns[0] = 0, lo, n
    while True:
        if ns[sp] > _PW_BLOCK and stage[sp] == 0:  # split: descend into the left half
            half = ns[sp] // 2
            stage[sp] = 1
            sp += 1
            los[sp], ns[sp], stage[sp] = los[sp - 1], half - half % 8, 0
            continue
        v = _block_sum(a, row, los[sp], ns[sp])
        while sp > 0:  # hand v to the parents: a left half waits for its right, a right half completes
            sp -= 1
            if stage[sp] == 1:
                left[sp], stage[sp] = v, 2
                half = ns[sp] // 2
                half -= half % 8
                sp += 1
                los[sp], ns[sp], stage[sp] = los[sp - 1] + half, ns[sp - 1] - half, 0
                break
            v = left[sp] + v
        if sp == 0 and stage[0] != 1:
            return v


@njit(cache=True)
def row_sum(a: np.ndarray, row: int, lo: int, n: int) -> float:
    """Sum of ``a[row, lo:lo + n]`` in the order of ``np.add.reduce`` on a contiguous axis.

    NumPy's pairwise summation: below 8 terms in sequence; up to 128 with eight
    interleaved accumulators combined as ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7)),
    then the remainder in sequence; above, the two halves (the first a multiple of 8)
    summed the same way and added. Bit-identical to ``a[row, lo:lo + n].sum()``. Rows are
    addressed by index because a view per call would cost more than a short sum; loops of
    many short sums call :func:`_block_sum` themselves (calling this function there kept
    numba from optimising the loop: 3x slower).
    """
    if n <= _PW_BLOCK:
        return _block_sum(a, row, lo, n)
    half = n // 2
    half -= half % 8
    if n - half <= _PW_BLOCK:  # two blocks (up to 264 terms: a fold window) without the stack
        return _block_sum(a, row, lo, half) + _block_sum(a, row, lo + half, n - half)
    return _halved_sum(a, row, lo, n)


@njit(cache=True)
def sos_filter(sos: np.ndarray, zi: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """Cascaded second-order sections, transposed direct form II: ``scipy.signal.sosfilt``.

    Parameters
    ----------
    sos : ndarray, shape (S, 6)
        Sections (b0, b1, b2, 1, a1, a2).
    zi : ndarray, shape (S, 2)
        Section states before ``x[0]``; updated in place to the states after ``x[-1]``.
    x, out : ndarray, shape (n,)
        Input and output (same unit).
    """
    for i in range(x.size):
        cur = x[i]
        for s in range(sos.shape[0]):
            new = sos[s, 0] * cur + zi[s, 0]
            zi[s, 0] = sos[s, 1] * cur - sos[s, 4] * new + zi[s, 1]
            zi[s, 1] = sos[s, 2] * cur - sos[s, 5] * new
            cur = new
        out[i] = cur


@njit(cache=True)
def block_sums(y: np.ndarray, r: np.ndarray, u: np.ndarray, b: np.ndarray, d: int, out: np.ndarray) -> None:
    """Per block of ``d`` samples, the rows of :meth:`.periodicity.EnergyEnvelope.blocks`.

    Column ``k`` of ``out`` gets, over samples ``k·d .. k·d + d − 1``: when ``out`` has 7
    rows, mean(b²) and mean(b⁴) of the band-passed ``b``; then Σy, Σy², Σr², Σ|r|, Σu — each
    ``x.reshape(-1, d).sum(axis=1)`` (or ``.mean``) of the elementwise products, bit for bit.

    Parameters
    ----------
    y, r, u, b : ndarray, shape (n,), n >= (columns of ``out``) · d
        Measurement, residual, train, band-passed measurement (``b`` unused for 5 rows).
    d : int
        Block length (samples).
    out : ndarray, shape (7 or 5, n // d)
        Written in place, rows in the order above.
    """
    band = out.shape[0] - 5
    t = np.empty((7, d))
    short = d <= _PW_BLOCK
    for k in range(out.shape[1]):
        o = k * d
        for i in range(d):
            b2 = b[o + i] * b[o + i]
            t[0, i] = b2
            t[1, i] = b2 * b2
            t[2, i] = y[o + i]
            t[3, i] = y[o + i] * y[o + i]
            t[4, i] = r[o + i] * r[o + i]
            t[5, i] = abs(r[o + i])
            t[6, i] = u[o + i]
        for j in range(out.shape[0]):
            out[j, k] = _block_sum(t, j + 2 - band, 0, d) if short else _halved_sum(t, j + 2 - band, 0, d)
        for j in range(band):
            out[j, k] /= d


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
        mean = (_block_sum(smoothed, 0, 0, bins) if bins <= _PW_BLOCK else _halved_sum(smoothed, 0, 0, bins)) / bins
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
    ``best`` the maximum over the grid (:func:`.periodicity.cfar_periodicity`).
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
def window_sums(env: np.ndarray, b4: np.ndarray, y: np.ndarray, y2: np.ndarray, r2: np.ndarray, q: int):
    """The sums a fold window's scores need, each ``x.sum()`` bit for bit (:func:`row_sum`).

    Returns ``(Σy, Σy², Σr², Σenv, Σenv[:-q], Σenv[-q:], Σb4)`` over the window's blocks,
    ``q`` >= 1 the newest blocks (all of them when q >= the window; the older part is then
    empty, sum 0).
    """
    w = env.size
    e = env.reshape(1, w)
    tail = min(q, w)
    return (row_sum(y.reshape(1, w), 0, 0, w), row_sum(y2.reshape(1, w), 0, 0, w),
            row_sum(r2.reshape(1, w), 0, 0, w), row_sum(e, 0, 0, w), row_sum(e, 0, 0, w - tail),
            row_sum(e, 0, w - tail, tail), row_sum(b4.reshape(1, w), 0, 0, w))


@njit(cache=True)
def all_finite(x: np.ndarray) -> bool:
    """``np.all(np.isfinite(x))``."""
    for v in x:
        if not np.isfinite(v):
            return False
    return True


@njit(cache=True)
def phase_bins(n: int, envelope_rate: float, freq: float, bins: int) -> np.ndarray:
    """Phase bin ``min(floor(frac(t·freq)·bins), bins − 1)`` of envelope samples t = 0..n−1 / rate."""
    out = np.empty(n, np.int64)
    for i in range(n):
        out[i] = min(np.int64((((i / envelope_rate) * freq) % 1.0) * bins), bins - 1)
    return out


@njit(cache=True)
def impact_phase_mask(env: np.ndarray, envelope_rate: float, freq: float, bins: int, smooth: int,
                      margin: int) -> np.ndarray:
    """:func:`.periodicity.impact_phase_mask`: the samples in the peak's ``smooth`` bins ± ``margin``.

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
def explain_away(env: np.ndarray, mask: np.ndarray) -> np.ndarray:
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


@njit(cache=True)
def train_correlation(a: np.ndarray, u: np.ndarray, max_lag: int) -> float:
    """Max Pearson correlation of ``a[k:]`` with ``u[:n − k]`` over lags k = 0..``max_lag``
    (:func:`.periodicity.train_correlation`; the lagged products summed in sequence).

    Lags where either variance is at most 1e-12 × the largest square (floored at 1e-300) are
    skipped; without a valid lag, 0; a best found without lag 0 is floored at 0.
    """
    n = a.size
    ca, ca2, cu, cu2 = np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1)
    top = 1e-300
    for i in range(n):
        ca[i + 1] = ca[i] + a[i]
        ca2[i + 1] = ca2[i] + a[i] * a[i]
        cu[i + 1] = cu[i] + u[i]
        cu2[i + 1] = cu2[i] + u[i] * u[i]
        top = max(top, a[i] * a[i], u[i] * u[i])
    tiny = 1e-12 * top
    best = -np.inf
    found = False
    valid0 = False
    for k in range(max_lag + 1):
        m = n - k
        mx = (ca[n] - ca[k]) / m
        mz = cu[n - k] / m
        vx = (ca2[n] - ca2[k]) / m - mx * mx
        vz = cu2[n - k] / m - mz * mz
        if not (vx > tiny and vz > tiny):
            continue
        sxz = 0.0
        for i in range(m):
            sxz += a[i + k] * u[i]
        c = (sxz / m - mx * mz) / np.sqrt(vx * vz)
        best = max(best, c)
        found = True
        valid0 = valid0 or k == 0
    if not found:
        return 0.0
    return best if valid0 else max(0.0, best)


def warm_up() -> None:
    """Compile (first run after an install) or load from numba's cache every kernel, with the
    argument types the decision uses (folding tables are read-only uint16 offsets and float
    weights), so that no window waits for a compile."""
    z = np.zeros(16)
    sos_filter(np.array([[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]]), np.zeros((1, 2)), z, np.zeros(16))
    block_sums(z, z, z, z, 4, np.zeros((7, 4)))
    block_sums(z, z, z, z, 4, np.zeros((7, 8))[:, 4:])  # into a stream's block store (strided)
    offsets, inv = np.zeros((16, 4), np.uint16), np.ones(64)
    offsets.setflags(write=False)
    inv.setflags(write=False)
    fold_peakiness(z, offsets, inv, 16, 2)
    cfar_fold(z, offsets, inv, 2, 16, 2)
    explain_away(z, impact_phase_mask(z, 4000.0, 100.0, 16, 2, 1))
    train_correlation(z, z, 2)
    window_sums(z, z, z, z, z, 4)
    all_finite(z)
