"""Strictly monotone piecewise-linear functions (the HW blocks f and g, thesis section 2.4).

The thesis restricts both nonlinearities to monotone piecewise-linear maps so that the
output nonlinearity can be inverted in the observer (Fig. 3.1, ``g^-1``); appendix E
evaluates them with ``piecelin`` / ``Inverse_for_piecelin``. Here the breakpoint values
must be *strictly* increasing, so the inverse exists everywhere, and the function is
extended beyond the outer breakpoints with the end slopes (the appendix E code does the
same), so both the function and its inverse are defined on the whole real line.
"""

from __future__ import annotations

import numpy as np
from numba import njit


class MonotonePiecewiseLinear:
    """Strictly increasing piecewise-linear function through ``(x[i], y[i])``.

    Parameters
    ----------
    x, y : array_like, shape (m,), m >= 2
        Breakpoints; both strictly increasing and finite (units of the input / output).
    """

    def __init__(self, x, y):
        x = np.asarray(x, dtype=float).ravel()
        y = np.asarray(y, dtype=float).ravel()
        if x.shape != y.shape or x.size < 2:
            raise ValueError("need x and y of equal length >= 2")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise ValueError("breakpoints must be finite")
        if np.any(np.diff(x) <= 0) or np.any(np.diff(y) <= 0):
            raise ValueError("breakpoints must be strictly increasing in x and in y")
        self.x = x
        self.y = y
        self.slopes = np.diff(y) / np.diff(x)  #: segment slopes (units of y per unit of x)
        self._inverse_slopes = np.diff(x) / np.diff(y)

    @classmethod
    def identity(cls, scale: float = 1.0) -> MonotonePiecewiseLinear:
        """The map ``v -> v`` as two breakpoints at ``-scale`` and ``+scale``."""
        return cls([-scale, scale], [-scale, scale])

    @classmethod
    def gain(cls, k: float) -> MonotonePiecewiseLinear:
        """The map ``v -> k v`` (k > 0) as breakpoints at -1 and 1."""
        if not k > 0:
            raise ValueError(f"gain must be > 0, got {k}")
        return cls([-1.0, 1.0], [-k, k])

    def __call__(self, v):
        """Evaluate ``g(v)`` (vectorised, any shape)."""
        return _evaluate(self.x, self.y, self.slopes, v)

    def inverse(self, w):
        """Evaluate ``g^-1(w)`` (vectorised, any shape)."""
        return _evaluate(self.y, self.x, self._inverse_slopes, w)

    def slope_at(self, v: float) -> float:
        """Local slope dg/dv at ``v`` (right derivative)."""
        i = int(np.clip(np.searchsorted(self.x, v, side="right") - 1, 0, self.x.size - 2))
        return float(self.slopes[i])

    def is_identity(self, tol: float = 1e-12) -> bool:
        """True when the function is ``v -> v`` within ``tol``."""
        return bool(np.allclose(self.x, self.y, rtol=0, atol=tol))

    def to_dict(self) -> dict:
        return {"x": [float(v) for v in self.x], "y": [float(v) for v in self.y]}

    @classmethod
    def from_dict(cls, d: dict) -> MonotonePiecewiseLinear:
        return cls(d["x"], d["y"])

    def __repr__(self):
        return f"MonotonePiecewiseLinear({self.x.size} breakpoints)"


def evaluate_piecewise_linear(x, y, v) -> np.ndarray:
    """Piecewise-linear function through ``(x, y)`` (``x`` strictly increasing), extended
    beyond the outer breakpoints with the end slopes, at ``v`` (any shape)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return _evaluate(x, y, np.diff(y) / np.diff(x), v)


def _evaluate(x, y, slopes, v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    out = np.empty(v.shape)
    interp_extended(x, y, slopes, np.ascontiguousarray(v).reshape(-1), out.reshape(-1))
    return out


# compiled inner loop (numba; strict IEEE arithmetic, no fastmath)
@njit(cache=True)
def interp_extended(x: np.ndarray, y: np.ndarray, slopes: np.ndarray, v: np.ndarray,
                    out: np.ndarray) -> None:
    """Piecewise-linear interpolation through ``(x, y)``, extended with the end slopes.

    ``out[i] = slopes[j] * (v[i] - x[j]) + y[j]`` with ``j`` the segment of ``v[i]``
    (clamped to the first / last segment outside ``[x[0], x[-1]]``): the formula of
    ``np.interp`` inside the breakpoints. The segment search starts from the previous
    sample's segment, so smooth signals cost O(1) per sample.

    Parameters
    ----------
    x, y : ndarray, shape (m,), m >= 2
        Breakpoints, ``x`` strictly increasing.
    slopes : ndarray, shape (m - 1,)
        ``(y[j + 1] - y[j]) / (x[j + 1] - x[j])``.
    v : ndarray, shape (n,)
        Points to evaluate (NaN gives NaN).
    out : ndarray, shape (n,)
        Result, written in place.
    """
    last = x.size - 2
    j = 0
    for i in range(v.size):
        vi = v[i]
        while j > 0 and vi < x[j]:
            j -= 1
        while j < last and vi >= x[j + 1]:
            j += 1
        out[i] = slopes[j] * (vi - x[j]) + y[j]
