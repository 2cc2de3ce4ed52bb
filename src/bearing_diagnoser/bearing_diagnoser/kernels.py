"""Compiled inner loops of the decision (numba).

Each replaces a chain of small NumPy calls that ran once per chunk or per window (a 48 kHz
stream has 100 of each per second) by one pass over the data. Strict IEEE arithmetic (no
fastmath), operations in NumPy's order: each kernel names the NumPy formulation it
reproduces bit for bit — sums in NumPy's pairwise order (:func:`pairwise_sum`), the
band-pass in ``scipy.signal.sosfilt``'s.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: NumPy's block length of pairwise summation (``PW_BLOCKSIZE``).
_PW_BLOCK = 128


@njit(cache=True)
def _block_sum(a: np.ndarray, lo: int, n: int) -> float:
    """:func:`pairwise_sum` of at most 128 terms (one block, no recursion)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        j = lo + i
        r0 += a[j]
        r1 += a[j + 1]
        r2 += a[j + 2]
        r3 += a[j + 3]
        r4 += a[j + 4]
        r5 += a[j + 5]
        r6 += a[j + 6]
        r7 += a[j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True)
def pairwise_sum(a: np.ndarray, lo: int, n: int) -> float:
    """Sum of ``a[lo:lo + n]`` in the order of ``np.add.reduce`` on a contiguous axis.

    NumPy's pairwise summation: below 8 terms in sequence; up to 128 with eight
    interleaved accumulators combined as ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7)),
    then the remainder in sequence; above, the two halves (the first a multiple of 8)
    summed the same way and added. Bit-identical to ``a[lo:lo + n].sum()``. The halving
    runs on an explicit stack (numba cannot cache a recursive function).
    """
    if n <= _PW_BLOCK:
        return _block_sum(a, lo, n)
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
        v = _block_sum(a, los[sp], ns[sp])
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
            out[j, k] = pairwise_sum(t[j + 2 - band], 0, d)
        for j in range(band):
            out[j, k] /= d


def warm_up() -> None:
    """Compile (first run after an install) or load from numba's cache every kernel, with the
    argument types the decision uses, so that no window waits for a compile."""
    z = np.zeros(16)
    sos_filter(np.array([[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]]), np.zeros((1, 2)), z, np.zeros(16))
    block_sums(z, z, z, z, 4, np.zeros((7, 4)))
