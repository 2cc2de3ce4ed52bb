"""The thesis' own blocks, measured on every window and reported, not decided on (section 3.2).

* ``explained`` — how much of the measurement the train-driven observer removes,
  1 − ‖r‖²/‖y − ȳ‖² (thesis 3.2.3: an observer injecting impulses of its own in NORMAL
  operation gives a negative value);
* ``xcorr`` — the thesis-literal statistic: the cross-correlation of |residual| with the
  impulse train (Figs. 3.7-3.12), per window as the best Pearson correlation over short
  lags (:func:`train_correlation`), and over a whole record for the figures
  (:func:`train_cross_correlation`, with the train's autocorrelation as reference).

The feasibility study (``diagnosis-notes.md``) measured 0/56 with the literal statistic
alone; both front ends report these blocks beside their own decision.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import signal

#: Lags 0..this (s) of the thesis-literal correlation of |r| with the train: the observer's
#: impulse response follows its impulse within a couple of milliseconds.
XCORR_LAG_S = 2e-3


def explained_fraction(sum_y: float, sum_y2: float, sum_r2: float, n: int) -> float:
    """1 − Σr² / Σ(y − ȳ)² over ``n`` samples from the sums of y, y² and r² (0 when y is constant)."""
    var_y = sum_y2 - sum_y * sum_y / n
    return float(1.0 - sum_r2 / var_y) if var_y > 0 else 0.0


def train_autocorrelation(train: np.ndarray) -> np.ndarray:
    """Autocorrelation of the impulse train (thesis Figs. 3.7-3.8), FFT-based, full length.

    Returns 2·N − 1 values, lag −(N−1)..N−1, normalised to 1 at lag 0.
    """
    u = np.asarray(train, dtype=float)
    ac = signal.correlate(u, u, mode="full", method="fft")
    peak = ac[u.size - 1]
    return ac / peak if peak > 0 else ac


def train_cross_correlation(residual: np.ndarray, train: np.ndarray) -> np.ndarray:
    """Cross-correlation of |residual| with the impulse train (thesis section 3.2, Figs. 3.9-3.12).

    FFT-based, full length (lag −(N−1)..N−1), normalised by ‖|r|‖·‖u‖ so a residual made
    of the train itself gives the train autocorrelation (dimensionless).
    """
    a = np.abs(np.asarray(residual, dtype=float))
    u = np.asarray(train, dtype=float)
    xc = signal.correlate(a, u, mode="full", method="fft")
    norm = np.linalg.norm(a) * np.linalg.norm(u)
    return xc / norm if norm > 0 else xc


def train_correlation(abs_residual_blocks: np.ndarray, train_blocks: np.ndarray, max_lag: float) -> float:
    """Thesis-literal score of one window: max Pearson correlation of |r| with u over lags.

    Both inputs are per-block sums (same blocks as the envelope); lags 0..``max_lag``
    blocks (at most n − 3) with |r| lagging u (the observer's impulse response follows the
    impulse): x = a[k:], z = u[:n − k]. Returns a value in [−1, 1] (0 when the train is
    empty; lags where either part is constant are skipped; floored at 0 when lag 0 is).
    """
    a = np.ascontiguousarray(abs_residual_blocks, dtype=float)
    u = np.ascontiguousarray(train_blocks, dtype=float)
    n = min(a.size, u.size)
    last = min(int(max(0, max_lag)), n - 3)
    if last < 0:
        return 0.0
    return float(_train_correlation(a[:n], u[:n], last))


@njit(cache=True)
def _train_correlation(a: np.ndarray, u: np.ndarray, max_lag: int) -> float:
    """Max Pearson correlation of ``a[k:]`` with ``u[:n − k]`` over lags k = 0..``max_lag``
    (:func:`train_correlation`; the lagged products summed in sequence).

    Lags where either variance is at most 1e-12 × the largest square (floored at 1e-300) are
    skipped; without a valid lag, 0; a best found without lag 0 is floored at 0.
    """
    n = a.size
    ca, ca2, cu, cu2 = np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1)
    top = 1e-300
    for i in range(n):
        ca[i + 1] = ca[i] + a[i]
        ca2[i + 1] = ca2[i] + a[i] * a[i]
        cu[i + 1] = cu[i] + u[i]
        cu2[i + 1] = cu2[i] + u[i] * u[i]
        top = max(top, a[i] * a[i], u[i] * u[i])
    tiny = 1e-12 * top
    best = -np.inf
    found = False
    valid0 = False
    for k in range(max_lag + 1):
        m = n - k
        mx = (ca[n] - ca[k]) / m
        mz = cu[n - k] / m
        vx = (ca2[n] - ca2[k]) / m - mx * mx
        vz = cu2[n - k] / m - mz * mz
        if not (vx > tiny and vz > tiny):
            continue
        sxz = 0.0
        for i in range(m):
            sxz += a[i + k] * u[i]
        c = (sxz / m - mx * mz) / np.sqrt(vx * vz)
        best = max(best, c)
        found = True
        valid0 = valid0 or k == 0
    if not found:
        return 0.0
    return best if valid0 else max(0.0, best)
