"""The running median of the SES normalisation, compiled: each centre's median found from the previous one.

:func:`.envelope_spectrum.normalise` divides each SES bin by the median of the 2·half + 1 bins
around it, evaluated every ``stride`` bins and interpolated linearly between. :func:`median_line`
computes that line for every row from the previous centre's median: a slide of ``stride`` bins moves
the median by at most ``stride`` ranks, so one pass counts the window's values below and equal to the
previous median, and a second selects the few values between (the k nearest beyond it, k ≤ stride),
instead of copying and partitioning every window (``np.partition`` of a strided view: 101/8 times the
spectrum's size copied, the bulk of the band choice's time at 48 kHz). The median is an order statistic, so it
is the very value ``np.partition`` finds; the interpolation is ``np.interp``'s arithmetic, compiled
(strict IEEE: no fused multiply-add), so the line is bit-identical to the NumPy formulation.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _kth_beyond(values: np.ndarray, pivot: float, k: int, above: bool, near: np.ndarray, top: np.ndarray) -> float:
    """The ``k``-th value of ``values`` counted from ``pivot`` outwards: the k-th smallest of those above
    it (``above``), else the k-th largest of those below it. ``near``, ``top``: scratch of the values' size
    (those beyond the pivot gathered without branches, then the k nearest kept, the farthest first)."""
    held = 0
    if above:
        for v in values:
            near[held] = v
            held += v > pivot
    else:
        for v in values:
            near[held] = -v
            held += v < pivot
        pivot = -pivot
    for i in range(k):  # the first k, sorted descending (the farthest first)
        v = near[i]
        j = i
        while j > 0 and top[j - 1] < v:
            top[j] = top[j - 1]
            j -= 1
        top[j] = v
    for i in range(k, held):
        v = near[i]
        if v >= top[0]:
            continue
        j = 0
        while j + 1 < k and top[j + 1] > v:
            top[j] = top[j + 1]
            j += 1
        top[j] = v
    return top[0] if above else -top[0]


@njit(cache=True)
def _median_near(values: np.ndarray, half: int, guess: float, near: np.ndarray, top: np.ndarray) -> float:
    """The order statistic ``half`` (0-based) of ``values``, found from ``guess``, a value near it in rank
    (the previous window's median: a slide of d bins moves it by at most d ranks): counted around the
    guess, then the few values between selected (:func:`_kth_beyond`)."""
    below = 0
    equal = 0
    for v in values:
        below += v < guess
        equal += v == guess
    if below > half:
        return _kth_beyond(values, guess, below - half, False, near, top)
    if below + equal > half:
        return guess
    return _kth_beyond(values, guess, half + 1 - below - equal, True, near, top)


@njit(cache=True)
def median_line(padded: np.ndarray, n: int, stride: int, half: int) -> np.ndarray:
    """Per row of ``padded`` (rows, n + 2·half; a spectrum of ``n`` finite bins padded by ``half`` at each
    end): the median of the 2·half + 1 padded bins centred on bins 0, stride, 2·stride, … < n and on
    n − 1, interpolated linearly to every bin (rows, n)."""
    rows = padded.shape[0]
    width = 2 * half + 1
    count = (n - 1) // stride + 1
    m = count + (1 if (count - 1) * stride != n - 1 else 0)
    xp = np.empty(m)
    for c in range(count):
        xp[c] = c * stride
    xp[m - 1] = n - 1
    out = np.empty((rows, n))
    med = np.empty(m)
    near = np.empty(width)
    top = np.empty(width)
    for r in range(rows):
        row = padded[r]
        for c in range(m):
            target = int(xp[c])
            values = row[target:target + width]
            med[c] = np.sort(values)[half] if c == 0 else _median_near(values, half, med[c - 1], near, top)
        for c in range(m - 1):
            slope = (med[c + 1] - med[c]) / (xp[c + 1] - xp[c])
            for x in range(int(xp[c]), int(xp[c + 1])):
                out[r, x] = slope * (float(x) - xp[c]) + med[c]
        for c in range(m):
            out[r, int(xp[c])] = med[c]
    return out
