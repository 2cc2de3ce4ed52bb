"""NumPy's pairwise summation as compiled code: sums bit-identical to ``x.sum()`` inside numba loops.

The decision's compiled kernels (block sums, fold profiles, window sums) add many short runs
of numbers; each sum must equal the NumPy formulation it replaces bit for bit, so that a
compiled kernel changes no decision. NumPy sums a contiguous axis pairwise: below 8 terms
in sequence; up to 128 with eight interleaved accumulators; above, the two halves (the
first a multiple of 8) recursively. Strict IEEE arithmetic (no fastmath).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: NumPy's block length of pairwise summation (``PW_BLOCKSIZE``).
PW_BLOCK = 128


@njit(cache=True)
def block_sum(a: np.ndarray, row: int, lo: int, n: int) -> float:
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
def halved_sum(a: np.ndarray, row: int, lo: int, n: int) -> float:
    """:func:`row_sum` of more than 128 terms: NumPy's recursive halving, on an explicit stack
    (numba cannot cache a recursive function)."""
    los = np.empty(64, np.int64)  # 2**64 terms would not fit any array
    ns = np.empty(64, np.int64)
    left = np.empty(64)
    stage = np.zeros(64, np.int64)  # 0: not split yet, 1: left half pending, 2: right half pending
    sp, los[0], ns[0] = 0, lo, n
    while True:
        if ns[sp] > PW_BLOCK and stage[sp] == 0:  # split: descend into the left half
            half = ns[sp] // 2
            stage[sp] = 1
            sp += 1
            los[sp], ns[sp], stage[sp] = los[sp - 1], half - half % 8, 0
            continue
        v = block_sum(a, row, los[sp], ns[sp])
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
    many short sums call :func:`block_sum` themselves (calling this function there kept
    numba from optimising the loop: 3x slower).
    """
    if n <= PW_BLOCK:
        return block_sum(a, row, lo, n)
    half = n // 2
    half -= half % 8
    if n - half <= PW_BLOCK:  # two blocks (up to 264 terms: a fold window) without the stack
        return block_sum(a, row, lo, half) + block_sum(a, row, lo + half, n - half)
    return halved_sum(a, row, lo, n)
