"""The continued fraction of the upper incomplete gamma function, compiled: the far tail where Q < 1e-280.

:func:`.significance.log10_gamma_sf` takes log10 Q(a, x) from the continued fraction of Q
(modified Lentz) where scipy's value underflows. :func:`lentz_product` is its loop, compiled
(numba, strict IEEE: no fused multiply-add, no reassociation), the same operations in the same
order as the NumPy formulation it replaced, so its products are bit-identical: each group of
elements (a call of the NumPy loop) iterates until every element of the group has converged,
the elements that converged first included.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Iterations at most (the NumPy loop's ``range(1, 200)``).
MAX_TERMS = 200

#: A step this close to 1 (relative) ends the fraction.
TOLERANCE = 1e-12

#: Floor of |d| and |c| (Lentz's guard against division by zero).
TINY = 1e-300


@njit(cache=True)
def lentz_product(a: np.ndarray, x: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """h = the continued fraction of Q(a, x)·Γ(a)·e^x·x^-a per element of ``a`` and ``x`` (1-d, x > a),
    groups ``bounds[g]:bounds[g + 1]`` each iterated until all its elements converged (relative step
    below :data:`TOLERANCE`), at most :data:`MAX_TERMS` − 1 terms."""
    h = np.empty_like(x)
    for g in range(bounds.size - 1):
        lo, hi = bounds[g], bounds[g + 1]
        n = hi - lo
        b = np.empty(n)
        c = np.empty(n)
        d = np.empty(n)
        for e in range(n):
            b[e] = x[lo + e] + 1.0 - a[lo + e]
            c[e] = 1e300
            d[e] = 1.0 / b[e]
            h[lo + e] = d[e]
        for i in range(1, MAX_TERMS):
            converged = True
            for e in range(n):
                an = float(-i) * (float(i) - a[lo + e])
                b[e] = b[e] + 2.0
                de = an * d[e] + b[e]
                if abs(de) < TINY:
                    de = TINY
                ce = b[e] + an / c[e]
                if abs(ce) < TINY:
                    ce = TINY
                c[e] = ce
                d[e] = 1.0 / de
                step = d[e] * ce
                h[lo + e] = h[lo + e] * step
                if not abs(step - 1.0) < TOLERANCE:
                    converged = False
            if converged:
                break
    return h
