"""Compiled inner loop of :func:`bearing_observer.impulse_trains._render` (numba).

Adds the rectangular pulses to the sampled trains impact by impact; a train has only a
few impacts per thousand samples, so a loop over the pulses' samples replaces some twenty
small NumPy array operations per call. Strict IEEE arithmetic (no fastmath): the sums are
the same, in the same order, as the NumPy formulation in the docstring of
:func:`add_pulses`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def add_pulses(out: np.ndarray, a: np.ndarray, b: np.ndarray, weights: np.ndarray,
               span: int) -> None:
    """Add unit-height pulses over ``[a[k], b[k])`` (in samples) times ``weights[:, k]``.

    For pulse ``k`` and sample ``i = floor(a[k]) + s``, ``s = 0..span``, the overlap of
    ``[i, i + 1)`` with ``[a[k], b[k])`` (fraction of a sample) times ``weights[j, k]`` is
    added to ``out[j, i]`` when ``0 <= i < n`` and the overlap is positive, in order of
    ``k`` then ``s`` (the order of ``np.bincount`` over the flattened (k, s) grid).

    Parameters
    ----------
    out : ndarray, shape (m, n)
        Trains to add to (dimensionless), modified in place.
    a, b : ndarray, shape (K,)
        Pulse start and end positions (samples from ``out[:, 0]``), ``b >= a``.
    weights : ndarray, shape (m, K)
        Pulse heights per train (dimensionless).
    span : int
        Samples after ``floor(a)`` that a pulse can reach, ``>= ceil(b - a)``.
    """
    n = out.shape[1]
    for k in range(a.size):
        first = np.int64(np.floor(a[k]))
        for s in range(span + 1):
            i = first + s
            fi = np.float64(i)
            ov = min(fi + 1.0, b[k]) - max(fi, a[k])
            if ov > 0.0 and 0 <= i < n:
                for j in range(out.shape[0]):
                    out[j, i] += ov * weights[j, k]
