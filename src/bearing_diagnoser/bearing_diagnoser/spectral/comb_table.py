"""The single-window comb p-value table read, compiled: one pass instead of a dozen NumPy calls per read.

:func:`.significance.comb_log10p` reads log10 P(S > s) for a comb of J bins from its table by linear
interpolation; :func:`.fault_combs.best_scale` reads it at every scale of every row and keeps the first
scale of the smallest. The reads are many and small (one per window, band group, hypothesis and
explain-away retest), so NumPy's per-call overhead was most of their cost. These kernels do the
same arithmetic (strict IEEE: no fused multiply-add) in one pass: s clipped to [0, s_max], position
s / step, cell i = min(⌊position⌋, last cell), weight w = position − i, value
table[J, i]·(1 − w) + table[J, i + 1]·w, bit for bit the NumPy formulation's.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _read(table: np.ndarray, s: float, j: int, s_max: float, step: float) -> float:
    """log10 p of comb sum ``s`` with ``j`` terms (0 ≤ j < table rows) from ``table``."""
    if s < 0.0:
        s = 0.0
    elif s > s_max:
        s = s_max
    pos = s / step
    i = min(int(pos), table.shape[1] - 2)
    w = pos - i
    return table[j, i] * (1 - w) + table[j, i + 1] * w


@njit(cache=True)
def table_log10p(table: np.ndarray, s: np.ndarray, j: np.ndarray, s_max: float, step: float) -> np.ndarray:
    """:func:`_read` elementwise over 1-d ``s`` and ``j`` (int, within the table's rows)."""
    out = np.empty(s.size)
    for e in range(s.size):
        out[e] = _read(table, s[e], j[e], s_max, step)
    return out


@njit(cache=True)
def first_smallest(table: np.ndarray, s: np.ndarray, j: np.ndarray, starts: np.ndarray, s_max: float,
                   step: float) -> np.ndarray:
    """Per row of ``s`` (rows, scales) with ``j`` (scales; int, within the table's rows), per run of scales
    from each of ``starts`` (increasing, each run non-empty) to the next: the first scale of the smallest
    :func:`_read` (rows, runs)."""
    rows, n = s.shape
    out = np.empty((rows, starts.size), np.int64)
    for r in range(rows):
        for q in range(starts.size):
            hi = starts[q + 1] if q + 1 < starts.size else n
            best = starts[q]
            low = _read(table, s[r, best], j[best], s_max, step)
            for c in range(best + 1, hi):
                v = _read(table, s[r, c], j[c], s_max, step)
                if v < low:
                    low, best = v, c
            out[r, q] = best
    return out
