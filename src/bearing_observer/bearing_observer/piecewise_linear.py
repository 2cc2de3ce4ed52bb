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
        self._slope_lo = (y[1] - y[0]) / (x[1] - x[0])
        self._slope_hi = (y[-1] - y[-2]) / (x[-1] - x[-2])
        # Tables extended linearly far beyond the breakpoints (1e6 spans each side), so one
        # np.interp pass evaluates f and f^-1 there; only inputs beyond them (absurd for
        # accelerations) take the slower masked path.
        span_x = x[-1] - x[0]
        ext = 1e6
        self._xe = np.concatenate([[x[0] - ext * span_x], x, [x[-1] + ext * span_x]])
        self._ye = np.concatenate([[y[0] - ext * span_x * self._slope_lo], y,
                                   [y[-1] + ext * span_x * self._slope_hi]])

    @classmethod
    def identity(cls, scale: float = 1.0) -> "MonotonePiecewiseLinear":
        """The map ``v -> v`` as two breakpoints at ``-scale`` and ``+scale``."""
        return cls([-scale, scale], [-scale, scale])

    @classmethod
    def gain(cls, k: float) -> "MonotonePiecewiseLinear":
        """The map ``v -> k v`` (k > 0) as breakpoints at -1 and 1."""
        if not k > 0:
            raise ValueError(f"gain must be > 0, got {k}")
        return cls([-1.0, 1.0], [-k, k])

    @staticmethod
    def _eval(x, y, s_lo, s_hi, v):
        v = np.asarray(v, dtype=float)
        out = np.interp(v, x, y)
        lo = v < x[0]
        hi = v > x[-1]
        if lo.any() or hi.any():
            out = np.where(lo, y[0] + (v - x[0]) * s_lo, out)
            out = np.where(hi, y[-1] + (v - x[-1]) * s_hi, out)
        return out

    def __call__(self, v):
        """Evaluate ``g(v)`` (vectorised, any shape)."""
        v = np.asarray(v, dtype=float)
        if v.size and self._xe[0] < v.min() and v.max() < self._xe[-1]:
            return np.interp(v, self._xe, self._ye)
        return self._eval(self.x, self.y, self._slope_lo, self._slope_hi, v)

    def inverse(self, w):
        """Evaluate ``g^-1(w)`` (vectorised, any shape)."""
        w = np.asarray(w, dtype=float)
        if w.size and self._ye[0] < w.min() and w.max() < self._ye[-1]:
            return np.interp(w, self._ye, self._xe)
        return self._eval(self.y, self.x, 1.0 / self._slope_lo, 1.0 / self._slope_hi, w)

    def slope_at(self, v: float) -> float:
        """Local slope dg/dv at ``v`` (right derivative)."""
        i = int(np.clip(np.searchsorted(self.x, v, side="right") - 1, 0, self.x.size - 2))
        return float((self.y[i + 1] - self.y[i]) / (self.x[i + 1] - self.x[i]))

    def is_identity(self, tol: float = 1e-12) -> bool:
        """True when the function is ``v -> v`` within ``tol``."""
        return bool(np.allclose(self.x, self.y, rtol=0, atol=tol))

    def to_dict(self) -> dict:
        return {"x": [float(v) for v in self.x], "y": [float(v) for v in self.y]}

    @classmethod
    def from_dict(cls, d: dict) -> "MonotonePiecewiseLinear":
        return cls(d["x"], d["y"])

    def __repr__(self):
        return f"MonotonePiecewiseLinear({self.x.size} breakpoints)"
