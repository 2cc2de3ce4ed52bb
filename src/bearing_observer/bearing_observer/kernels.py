"""Compiled inner loops of the observer package (numba).

Each replaces a chain of small NumPy calls on a hot path (per chunk or per estimate
update) by one pass over the samples. Strict IEEE arithmetic (no fastmath): each kernel
docstring names the NumPy formulation it reproduces bit for bit.
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


@njit(cache=True)
def fold_energy(z: np.ndarray, first_index: int, cycle_base: float, frequency: float,
                sample_rate: float, n_bins: int) -> np.ndarray:
    """Mean of ``z**2`` per bin of the fault cycle (the observer's phase fold).

    Sample ``i`` sits at cycle position ``c = frac(cycle_base + frequency * t_i)`` with
    ``t_i = (first_index + i) / sample_rate`` (s) and falls in bin
    ``min(floor(c * n_bins), n_bins - 1)``; empty bins are 0. Equals
    ``np.bincount(idx, z * z) / np.maximum(np.bincount(idx), 1)``.

    Returns
    -------
    ndarray, shape (n_bins,)
        Mean squared value per bin (units of ``z`` squared).
    """
    prof = np.zeros(n_bins)
    count = np.zeros(n_bins)
    for i in range(z.size):
        c = cycle_base + frequency * (np.float64(first_index + i) / sample_rate)
        c = c - np.floor(c)
        k = min(np.int64(c * n_bins), n_bins - 1)
        prof[k] += z[i] * z[i]
        count[k] += 1.0
    for k in range(n_bins):
        prof[k] /= max(count[k], 1.0)
    return prof


@njit(cache=True)
def run_modes(lam: np.ndarray, bw: np.ndarray, bz: np.ndarray, c: np.ndarray,
              weight: np.ndarray, d: float, w: np.ndarray, z: np.ndarray,
              state: np.ndarray, out: np.ndarray) -> None:
    """Two-input LTI filter in modal form, state carried in ``state``.

    Per mode ``m``: ``xi_m[n+1] = lam[m] xi_m[n] + bw[m] w[n] + bz[m] z[n]``; output
    ``out[n] = d w[n] + sum_m weight[m] Re(c[m] xi_m[n])`` (one complex mode stands for a
    conjugate pair with ``weight`` 2).

    Parameters
    ----------
    lam, bw, bz, c : ndarray of complex, shape (M,)
        Mode poles, input and output coefficients.
    weight : ndarray, shape (M,)
        1 for real modes, 2 for conjugate pairs.
    d : float
        Direct feed-through of ``w``.
    w, z : ndarray, shape (n,)
        The two inputs.
    state : ndarray of complex, shape (M,)
        Mode states at the first sample; updated in place to the state after the last.
    out : ndarray, shape (n,)
        Output, written in place.
    """
    for i in range(w.size):
        acc = d * w[i]
        for m in range(lam.size):
            s = state[m]
            acc += weight[m] * (c[m] * s).real
            state[m] = lam[m] * s + bw[m] * w[i] + bz[m] * z[i]
        out[i] = acc


@njit(cache=True)
def drive_input(comps: np.ndarray, gains: np.ndarray, active: bool, x: np.ndarray, y: np.ndarray,
                slopes: np.ndarray, delay: np.ndarray, u: np.ndarray, w: np.ndarray) -> None:
    """The observer's train input: ``u = gains @ comps``, ``w = q^-nk f(u)`` (thesis Fig. 3.1).

    ``u[i] = sum_j gains[j] comps[j, i]`` (in order of ``j``), ``f`` the piecewise-linear
    input nonlinearity of :func:`interp_extended` through ``(x, y)``, and the pure delay of
    ``nk = delay.size`` samples: ``w[i] = delay[i]`` for ``i < nk``, ``f(u[i - nk])`` after;
    ``delay`` then holds the last ``nk`` values of ``f(u)`` for the next block. Not
    ``active`` (the drive off): ``u = 0`` and ``f(u)`` counts as 0, nothing is injected.

    Parameters
    ----------
    comps : ndarray, shape (p, n)
        Unit regressor trains (dimensionless).
    gains : ndarray, shape (p,)
        Train gains (units of ``u``).
    x, y, slopes : ndarray
        Breakpoints and segment slopes of ``f`` (see :func:`interp_extended`).
    delay : ndarray, shape (nk,)
        ``f(u)`` of the last ``nk`` samples of the previous block; updated in place.
    u, w : ndarray, shape (n,)
        Drive and delayed nonlinear input, written in place.
    """
    n = u.size
    nk = delay.size
    last = x.size - 2
    j = 0
    fu = np.zeros(n)
    for i in range(n if active else 0):
        acc = 0.0
        for k in range(gains.size):
            acc += gains[k] * comps[k, i]
        u[i] = acc
        while j > 0 and acc < x[j]:
            j -= 1
        while j < last and acc >= x[j + 1]:
            j += 1
        fu[i] = slopes[j] * (acc - x[j]) + y[j]
    if not active:
        u[:] = 0.0
    for i in range(n):
        w[i] = delay[i] if i < nk else fu[i - nk]
    if nk:
        if n >= nk:
            delay[:] = fu[n - nk:]
        else:
            delay[:nk - n] = delay[n:].copy()
            delay[nk - n:] = fu


@njit(cache=True)
def iir_filter(b: np.ndarray, a: np.ndarray, x: np.ndarray, zi: np.ndarray, out: np.ndarray) -> None:
    """``B(q)/A(q)`` applied to ``x`` in transposed direct form II, state carried in ``zi``.

    The recursion of ``scipy.signal.lfilter(b, a, x, zi=zi)``: ``b`` and ``a`` of equal length
    ``K >= 2`` (zero-padded), ``a[0] = 1``; ``out[i] = zi[0] + b[0] x[i]``, then
    ``zi[k] = zi[k + 1] + b[k + 1] x[i] - a[k + 1] out[i]`` (``zi[K - 1]`` counting as 0).

    Parameters
    ----------
    b, a : ndarray, shape (K,)
        Numerator and denominator, ``a[0] = 1``.
    x : ndarray, shape (n,)
        Input.
    zi : ndarray, shape (K - 1,)
        Filter state; updated in place.
    out : ndarray, shape (n,)
        Output, written in place.
    """
    m = zi.size
    for i in range(x.size):
        xi = x[i]
        yi = zi[0] + b[0] * xi
        for k in range(m - 1):
            zi[k] = zi[k + 1] + b[k + 1] * xi - a[k + 1] * yi
        zi[m - 1] = b[m] * xi - a[m] * yi
        out[i] = yi


def warm_up() -> None:
    """Compile (first run after an install) or load from numba's cache every kernel, with
    the argument types the observer uses. A node calls this before it subscribes, so that
    no chunk waits for a compile (about a second per kernel) and its queue never
    overflows."""
    z = np.zeros(8)
    out = np.zeros(8)
    add_pulses(np.zeros((2, 8)), np.array([1.5]), np.array([2.5]), np.ones((2, 1)), 2)
    interp_extended(np.array([-1.0, 1.0]), np.array([-1.0, 1.0]), np.array([1.0]), z, out)
    fold_energy(z, 0, 0.0, 100.0, 48000.0, 4)
    f = (np.array([-1.0, 1.0]), np.array([-1.0, 1.0]), np.array([1.0]))
    for comps in (np.zeros((1, 8)), np.zeros((3, 16))[:, 4:12]):  # the train cache's slices: either layout
        drive_input(comps, np.ones(comps.shape[0]), True, *f, np.zeros(1), z, out)
    iir_filter(np.ones(2), np.ones(2), z, np.zeros(1), out)
    modes = np.zeros(1, dtype=complex)
    run_modes(modes, modes, modes, modes, np.ones(1), 0.0, z, z, np.zeros(1, dtype=complex), out)
