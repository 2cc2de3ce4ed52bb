"""General system identification: output-error and Hammerstein-Wiener fits (thesis section 2.4, app. C).

* :func:`oe_fit` — linear output-error model ``x = q^-nk B/F u``: Steiglitz-McBride
  iterations (prefiltered least squares), then simulation-error minimisation;
* :func:`hw_fit` — Hammerstein-Wiener model ``y = g(q^-nk B/F u)`` with a strictly
  increasing piecewise-linear output nonlinearity ``g`` (``g(0) = 0``, geometric-mean slope
  1: the normalisation that removes the scale ambiguity between ``B`` and ``g``), by
  minimising the simulation error with ``scipy.optimize.least_squares``;
* F is parametrised by reflection coefficients ``tanh(rho_i)`` (:func:`reflection_to_poly`),
  so every iterate is stable;
* :func:`fit_percent` — MATLAB ``compare``'s fit: ``100 (1 - |y - yhat| / |y - mean(y)|)`` (%).

Nothing here knows about bearings; :mod:`.fault_identification` prepares the data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, signal

from .piecewise_linear import MonotonePiecewiseLinear, evaluate_piecewise_linear

#: Bound on the reflection-coefficient parameters: |k| <= tanh(4.5) = 0.99975, so the
#: poles of B/F stay strictly inside the unit circle.
RHO_MAX = 4.5
#: Output-nonlinearity breakpoints.
N_BREAKPOINTS = 7


def fit_percent(y, yhat) -> float:
    """MATLAB ``compare`` fit (%): ``100 (1 - |y - yhat| / |y - mean(y)|)``."""
    y = np.asarray(y, dtype=float)
    yhat = np.asarray(yhat, dtype=float)
    dev = y - y.mean()
    den = math.sqrt(float(np.sum(dev * dev)))  # (np.linalg.norm goes through BLAS dot)
    if den == 0.0:
        return float("nan")
    err = y - yhat
    return float(100.0 * (1.0 - math.sqrt(float(np.sum(err * err))) / den))


# ---------------------------------------------------------------------------------------
# Stable parametrisation of F (reflection coefficients)
# ---------------------------------------------------------------------------------------
def reflection_to_poly(rho: np.ndarray) -> np.ndarray:
    """Monic F from unconstrained ``rho`` (reflection coefficients ``tanh(rho)``): stable."""
    a = np.array([1.0])
    for k in np.tanh(np.asarray(rho, dtype=float)):
        a = np.concatenate([a, [0.0]]) + k * np.concatenate([[0.0], a[::-1]])
    return a


def poly_to_reflection(f: np.ndarray) -> np.ndarray:
    """Inverse of :func:`reflection_to_poly` for a stable monic F (roots inside |z| < 1)."""
    a = np.asarray(f, dtype=float).copy()
    n = a.size - 1
    ks = np.zeros(n)
    for m in range(n, 0, -1):
        k = float(np.clip(a[m], -0.999999, 0.999999))
        ks[m - 1] = k
        a = (a[:m] - k * a[m:0:-1]) / (1.0 - k * k)
    return np.arctanh(ks)


def stabilise(f: np.ndarray, radius: float = 0.999) -> np.ndarray:
    """Reflect roots of F outside the unit circle inside (``r -> 1/conj(r)``, which keeps
    the magnitude response up to a gain) and clip them to ``radius``."""
    f = np.asarray(f, dtype=float)
    if f.size <= 1:
        return f
    r = np.roots(f)
    if np.all(np.abs(r) < radius):
        return f
    r = np.where(np.abs(r) > 1.0, 1.0 / np.conj(r), r)
    mag = np.abs(r)
    r = np.where(mag >= radius, r / np.maximum(mag, 1e-300) * radius, r)
    return np.real(np.poly(r))


# ---------------------------------------------------------------------------------------
# Linear output-error fit
# ---------------------------------------------------------------------------------------
def _delay(x, nk):
    if nk == 0:
        return x
    return np.concatenate([np.zeros(min(nk, x.size)), x[: max(0, x.size - nk)]])


def _regressors(u, y, nb, nf, nk):
    n = y.size
    cols = []
    for i in range(1, nf + 1):
        cols.append(-_delay(y, i))
    for j in range(nb):
        cols.append(_delay(u, nk + j))
    return np.column_stack(cols) if cols else np.zeros((n, 0))


def oe_fit(u, y, nb: int, nf: int, nk: int, iterations: int = 12):
    """Linear output-error fit ``y = q^-nk B/F u`` (initialisation of the HW fit).

    Steiglitz-McBride iterations (prefiltered least squares), stabilised, then refined by
    minimising the simulation error. Returns ``(b, f)`` with ``f`` monic and stable.
    """
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    if nb < 1 or nf < 0 or nk < 0:
        raise ValueError("need nb >= 1, nf >= 0, nk >= 0")
    f = np.array([1.0])
    b = np.zeros(nb)
    for _ in range(iterations if nf else 1):
        uf = signal.lfilter([1.0], f, u)
        yf = signal.lfilter([1.0], f, y)
        phi = _regressors(uf, yf, nb, nf, nk)
        theta, *_ = np.linalg.lstsq(phi, yf, rcond=None)
        f = stabilise(np.concatenate([[1.0], theta[:nf]]))
        b = theta[nf:]
    rho0 = poly_to_reflection(f)

    def resid(p):
        bb = p[:nb]
        ff = reflection_to_poly(p[nb:])
        return _delay(signal.lfilter(bb, ff, u), nk) - y

    p0 = np.concatenate([b, rho0])
    try:
        lb = np.concatenate([np.full(nb, -np.inf), np.full(p0.size - nb, -RHO_MAX)])
        p0 = np.clip(p0, -np.concatenate([np.full(nb, np.inf), np.full(p0.size - nb, RHO_MAX - 1e-6)]),
                     np.concatenate([np.full(nb, np.inf), np.full(p0.size - nb, RHO_MAX - 1e-6)]))
        sol = optimize.least_squares(resid, p0, bounds=(lb, -lb), x_scale="jac",
                                     max_nfev=20 * (p0.size + 1))
        if np.sum(sol.fun ** 2) < np.sum(resid(p0) ** 2):
            p0 = sol.x
    except (ValueError, np.linalg.LinAlgError):
        pass
    return p0[:nb].copy(), reflection_to_poly(p0[nb:])


# ---------------------------------------------------------------------------------------
# HW fit
# ---------------------------------------------------------------------------------------
@dataclass
class HWFit:
    """Result of :func:`hw_fit`: blocks and fit on the identification data."""

    b: np.ndarray
    f: np.ndarray
    nk: int
    g: MonotonePiecewiseLinear
    fit_linear: float
    fit: float
    nfev: int = 0


def _g_from_params(knots, theta, i0):
    slopes = np.exp(theta - theta.mean())
    vals = np.zeros(knots.size)
    d = np.diff(knots) * slopes
    vals[i0 + 1:] = np.cumsum(d[i0:])
    vals[:i0] = -np.cumsum(d[:i0][::-1])[::-1]
    return vals


def _hat_basis(knots, x):
    """Piecewise-linear (hat) basis at ``knots`` evaluated at ``x`` (linear extrapolation)."""
    m = knots.size
    i = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, m - 2)
    t = (x - knots[i]) / (knots[i + 1] - knots[i])
    phi = np.zeros((x.size, m))
    rows = np.arange(x.size)
    phi[rows, i] = 1.0 - t
    phi[rows, i + 1] += t
    return phi


def _fit_monotone_g(knots, i0, x, y):
    """Least-squares strictly increasing g through ``(knots, v)`` with ``v[i0] = 0``."""
    m = knots.size
    phi = _hat_basis(knots, x)
    # v = T d, d >= 0 (increments), v[i0] = 0
    T = np.zeros((m, m - 1))
    for j in range(m):
        if j > i0:
            T[j, i0:j] = 1.0
        elif j < i0:
            T[j, j:i0] = -1.0
    d, _ = optimize.nnls(phi @ T, y)
    floor = 1e-3 * max(float(np.mean(d)), 1e-12)
    d = np.maximum(d, floor)
    return T @ d


def _normalise(knots, vals, b):
    """Rescale so that g has geometric-mean slope 1 (x -> s x, b -> s b)."""
    slopes = np.diff(vals) / np.diff(knots)
    s = float(np.exp(np.mean(np.log(slopes))))
    return knots * s, vals, b * s


def hw_fit(u, y, nb: int, nf: int, nk: int, n_breakpoints: int = N_BREAKPOINTS,
           max_nfev: int | None = None, alternations: int = 4) -> HWFit:
    """Hammerstein-Wiener fit by simulation-error minimisation.

    Initialisation: linear OE fit, then ``alternations`` rounds of (monotone least-squares
    fit of ``g`` on the linear output; OE fit of the linear block to ``g^-1(y)``), keeping
    the best. Then all parameters together by ``scipy.optimize.least_squares``.

    Parameters
    ----------
    u : ndarray, shape (n,)
        Input (impulse train, dimensionless).
    y : ndarray, shape (n,)
        Output (m/s²).
    nb, nf, nk : int
        Orders of B, F and the pure delay (samples).
    n_breakpoints : int
        Breakpoints of ``g`` (< 3 means ``g`` is the identity).

    Returns
    -------
    HWFit
    """
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    b0, f0 = oe_fit(u, y, nb, nf, nk)
    x0 = _delay(signal.lfilter(b0, f0, u), nk)
    fit_lin = fit_percent(y, x0)
    if n_breakpoints < 3:
        g = MonotonePiecewiseLinear.identity(max(1.0, float(np.max(np.abs(y)))))
        return HWFit(b0, f0, nk, g, fit_lin, fit_lin)

    def make_knots(x):
        lo, hi = float(x.min()), float(x.max())
        span = max(hi - lo, 1e-12)
        lo, hi = min(lo - 0.05 * span, -1e-6 * span), max(hi + 0.05 * span, 1e-6 * span)
        k = np.linspace(lo, hi, n_breakpoints - 1)
        k = np.unique(np.concatenate([k[np.abs(k) > 1e-3 * span], [0.0]]))
        return k, int(np.flatnonzero(k == 0.0)[0])

    best = (fit_lin, b0, f0, None, None)
    b, f = b0, f0
    for _ in range(alternations):
        x = _delay(signal.lfilter(b, f, u), nk)
        knots, i0 = make_knots(x)
        vals = _fit_monotone_g(knots, i0, x, y)
        g = MonotonePiecewiseLinear(knots, vals)
        fit_now = fit_percent(y, g(x))
        if fit_now > best[0] or best[3] is None:
            best = (fit_now, b, f, knots, vals)
        knots_n, vals_n, _ = _normalise(knots, vals, b)
        z = MonotonePiecewiseLinear(knots_n, vals_n).inverse(y)
        b, f = oe_fit(u, z, nb, nf, nk)
    _, b, f, knots, vals = best
    knots, vals, b = _normalise(knots, vals, b)
    i0 = int(np.flatnonzero(knots == 0.0)[0])
    ng = knots.size - 1
    nrho = f.size - 1
    slopes = np.diff(vals) / np.diff(knots)
    th0 = np.log(slopes)

    def unpack(p):
        return p[:nb], reflection_to_poly(p[nb:nb + nrho]), p[nb + nrho:]

    def predict(p):
        bb, ff, th = unpack(p)
        v = _g_from_params(knots, th, i0)
        x = _delay(signal.lfilter(bb, ff, u), nk)
        return evaluate_piecewise_linear(knots, v, x)

    def resid(p):
        return predict(p) - y

    p0 = np.concatenate([b, poly_to_reflection(f), th0 - th0.mean()])
    lb = np.concatenate([np.full(nb, -np.inf), np.full(nrho, -RHO_MAX), np.full(ng, -6.0)])
    ub = -lb
    p0 = np.clip(p0, lb + 1e-9, ub - 1e-9)
    nfev = 0
    try:
        sol = optimize.least_squares(resid, p0, bounds=(lb, ub), x_scale="jac",
                                     max_nfev=max_nfev or 30 * (p0.size + 1))
        nfev = int(sol.nfev)
        p = sol.x if np.sum(sol.fun ** 2) <= np.sum(resid(p0) ** 2) else p0
    except (ValueError, np.linalg.LinAlgError):
        p = p0
    bb, ff, th = unpack(p)
    g = MonotonePiecewiseLinear(knots, _g_from_params(knots, th, i0))
    fit = fit_percent(y, g(_delay(signal.lfilter(bb, ff, u), nk)))
    return HWFit(bb.copy(), ff, nk, g, fit_lin, fit, nfev)

