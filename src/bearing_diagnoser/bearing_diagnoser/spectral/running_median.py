"""The running median of the SES normalisation, compiled: sorted windows slid bin by bin, no partition per centre.

:func:`.envelope_spectrum.normalise` divides each SES bin by the median of the 2·half + 1 bins
around it, evaluated every ``stride`` bins and interpolated linearly between. :func:`median_line`
computes that line for every row: it keeps the window sorted and slides it from centre to centre,
the bins that leave taken out and those that enter merged in (one pass over the window), instead of
copying and partitioning every window (``np.partition`` of a strided view: 101/8 times the spectrum's
size copied, the bulk of the band choice's time at 48 kHz). The median is an order statistic, so it
is the very value ``np.partition`` finds; the interpolation is ``np.interp``'s arithmetic, compiled
(strict IEEE: no fused multiply-add), so the line is bit-identical to the NumPy formulation.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _sorted_copy(src: np.ndarray, lo: int, hi: int, dst: np.ndarray) -> None:
    """``dst[:hi - lo]`` = ``src[lo:hi]`` sorted (insertion sort: a stride's few values)."""
    for i in range(hi - lo):
        v = src[lo + i]
        j = i
        while j > 0 and dst[j - 1] > v:
            dst[j] = dst[j - 1]
            j -= 1
        dst[j] = v


@njit(cache=True)
def _slide(window: np.ndarray, leaving: np.ndarray, entering: np.ndarray, d: int, out: np.ndarray) -> None:
    """``out`` = the sorted ``window`` without the ``d`` sorted values ``leaving`` (one element each) and
    with the ``d`` sorted values ``entering``: one merge."""
    k = e = o = 0
    for i in range(window.size):
        v = window[i]
        if k < d and v == leaving[k]:
            k += 1
            continue
        while e < d and entering[e] < v:
            out[o] = entering[e]
            o += 1
            e += 1
        out[o] = v
        o += 1
    while e < d:
        out[o] = entering[e]
        o += 1
        e += 1


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
    for r in range(rows):
        row = padded[r]
        window = np.sort(row[:width])
        spare = np.empty(width)
        leaving = np.empty(width)
        entering = np.empty(width)
        pos = 0
        for c in range(m):
            target = int(xp[c])
            if target - pos >= width:
                window = np.sort(row[target:target + width])
            elif target > pos:
                _sorted_copy(row, pos, target, leaving)
                _sorted_copy(row, pos + width, target + width, entering)
                _slide(window, leaving, entering, target - pos, spare)
                window, spare = spare, window
            pos = target
            med[c] = window[half]
        for c in range(m - 1):
            slope = (med[c + 1] - med[c]) / (xp[c + 1] - xp[c])
            for x in range(int(xp[c]), int(xp[c + 1])):
                out[r, x] = slope * (float(x) - xp[c]) + med[c]
        for c in range(m):
            out[r, int(xp[c])] = med[c]
    return out
