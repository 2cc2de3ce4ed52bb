"""The trend statistic's null distribution, and limits with a stated false-alarm rate per day.

The null model of one log-indicator ``y`` of a healthy machine is a stationary Gaussian AR(1)
sequence, ``y_t − μ = φ (y_{t−1} − μ) + e_t``, Var(e) = σ_e², fitted on the baseline
(:func:`fit_ar1`). The statistic the trend tests (:mod:`.trend`) is

    D_t = z_t − μ̂,   z_t = EWMA_λ(m_t),   m_t = median(y_{t−2}, y_{t−1}, y_t),

μ̂ the baseline's (winsorised) mean. Relative to the marginal variance σ² = σ_e²/(1 − φ²):

* Var(z)/σ² and the lag-1 correlation of z depend on (φ, λ) only; the running median has no
  closed form, so they are measured on a long simulated null sequence (:func:`simulated_moments`,
  4·10⁶ steps, fixed seed; shipped for the default λ in :mod:`.null_table`, simulated on
  demand for another λ; relative error below 0.5 %);
* Var(μ̂)/σ² is that of the mean of n AR(1) values, in closed form (:func:`mean_variance`).

μ̂'s error is shared by every D_t, so Var(D) = Var(z) + Var(μ̂) and the lag-1 correlation ρ
of D is (ρ_z Var(z) + Var(μ̂)) / Var(D) (the covariance of the baseline and the early
monitored snapshots is left out: it would only lower Var(D)). For a Gaussian pair the
probability that the standardised statistic crosses a limit u upwards at a given step is
exactly

    P(s_{t−1} < u ≤ s_t) = 2·T(u, √((1 − ρ)/(1 + ρ)))            (Owen's T function),

since Φ₂(u, u; ρ) = Φ(u) − 2T(u, a). The statistic is standardised with the baseline's own
estimates, so :func:`crossing_probability` averages this over their errors: σ̂_e/σ_e ~
√(χ²_ν/ν) with ν = n − 3, and the true φ over its confidence distribution given φ̂
(:func:`phi_confidence`, from the estimator's simulated sampling distribution: short AR(1)
samples underestimate φ, and an underestimated φ means too narrow limits). A warning or an
alarm begins only at such a crossing, so the expected number of false ones per day is at
most crossings per step × steps per day × indicators (:func:`limit_for_rate`).

How well this holds with a baseline of 30 snapshots is measured (``tests/unit/test_health_trend.py``,
docs/health.md): exact when φ is known; with φ estimated, conservative
for uncorrelated indicators and somewhat liberal for strongly correlated ones (φ = 0.8), the
more so the deeper in the tail: 30 correlated values cannot pin down the long-run variance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

#: Largest AR(1) coefficient the model uses: beyond it a baseline of tens of snapshots cannot
#: tell a slow wander from a trend, and the model would claim variances it has not seen.
PHI_MAX = 0.9

#: Step of the grid of AR(1) coefficients the EWMA's moments are tabulated at (linear in between).
PHI_STEP = 0.01

#: Smallest innovation standard deviation of a log-indicator (1 %): a constant baseline (a
#: synthetic signal) must not make every later change infinitely significant.
SIGMA_MIN = 0.01

#: Length of each simulated null sequence behind :func:`simulated_moments`.
SIMULATION_STEPS = 4_000_000

#: Gauss-Laguerre nodes of the average over the uncertainty of σ_e.
SCALE_NODES = 40


@dataclass(frozen=True)
class Ar1Fit:
    """Baseline fit of one log-indicator.

    Attributes
    ----------
    centre : float
        μ̂, the winsorised mean (log units).
    sigma_e : float
        Innovation sd σ̂_e at φ̂ (log units, ≥ :data:`SIGMA_MIN`).
    phi : float
        AR(1) coefficient φ̂ (bias-corrected, in [0, :data:`PHI_MAX`]).
    n : int
        Baseline values the fit used.
    weights : ndarray, shape (len(phi_grid()),)
        Confidence weights of the grid φ given φ̂ (:func:`phi_confidence`).
    """

    centre: float
    sigma_e: float
    phi: float
    n: int
    weights: np.ndarray

    @property
    def sigma(self) -> float:
        """Marginal sd σ̂ = σ̂_e / √(1 − φ̂²)."""
        return self.sigma_e / math.sqrt(1.0 - self.phi ** 2)


def fit_ar1(y: np.ndarray) -> Ar1Fit:
    """Robust AR(1) fit of a baseline ``y`` (shape (n,), n ≥ 6).

    Values beyond median ± 3.5 robust sd (1.4826·MAD) are winsorised first (one glitch must
    not set the level or the scale; Gaussian values are left alone). μ̂ is their mean. φ̂ and
    σ̂_e come from the values with their least-squares line removed (:func:`phi_estimate`): a
    drift through the baseline — a new bearing running in, a machine warming up — is not
    short-term variation, and taken for it would make φ̂ → 1 and the limits far too wide.
    φ̂ is the lag-1 regression coefficient with Kendall's bias correction, clipped to
    [0, :data:`PHI_MAX`]; σ̂_e² the residual variance (n − 3 dof).
    """
    y = np.asarray(y, dtype=float)
    n = y.size
    if n < 6:
        raise ValueError(f"a baseline needs at least 6 values, got {n}")
    med = float(np.median(y))
    mad = 1.4826 * float(np.median(np.abs(y - med)))
    if mad > 0:
        y = np.clip(y, med - 3.5 * mad, med + 3.5 * mad)
    phi_c = float(phi_estimate(y[None, :])[0])
    phi = min(max(phi_c, 0.0), PHI_MAX)
    d = _detrended(y[None, :])[0]
    resid = d[1:] - phi * d[:-1]
    sigma_e = max(math.sqrt(float(np.dot(resid, resid)) / (n - 3)), SIGMA_MIN)
    return Ar1Fit(float(y.mean()), sigma_e, phi, n, phi_confidence(phi_c, n))


def _detrended(y: np.ndarray) -> np.ndarray:
    """Each row of ``y`` (m, n) minus its least-squares line."""
    n = y.shape[1]
    t = np.arange(n) - (n - 1) / 2.0
    d = y - y.mean(axis=1, keepdims=True)
    return d - np.outer(d @ t / (t @ t), t)


def phi_estimate(y: np.ndarray) -> np.ndarray:
    """Kendall-corrected lag-1 regression coefficient r + (1 + 3r)/n of each detrended row of
    ``y`` (shape (m, n)), not clipped (0 for a constant row)."""
    d = _detrended(y)
    n = y.shape[1]
    den = np.einsum("ij,ij->i", d[:, :-1], d[:, :-1])
    raw = np.where(den > 0, np.einsum("ij,ij->i", d[:, :-1], d[:, 1:]) / np.where(den > 0, den, 1.0), 0.0)
    return raw + (1.0 + 3.0 * raw) / n


#: Simulated baselines per grid φ behind :func:`phi_confidence`.
CONFIDENCE_REPLICATES = 2000


#: Longest baseline whose estimator is simulated; beyond, its large-sample law N(φ, (1 − φ²)/n).
CONFIDENCE_SIMULATED_MAX = 200


@lru_cache(maxsize=16)
def _phi_sampling(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and sd of the estimate φ̂* (:func:`phi_estimate`) of simulated stationary AR(1)
    baselines of length ``n`` at each grid φ (:data:`CONFIDENCE_REPLICATES` each, seed 0)."""
    from scipy.signal import lfilter
    grid = phi_grid()
    if n > CONFIDENCE_SIMULATED_MAX:
        return grid.copy(), np.sqrt(np.maximum(1.0 - grid ** 2, 1e-4) / n)
    rng = np.random.default_rng(0)
    e = rng.standard_normal((CONFIDENCE_REPLICATES, n + 100))
    est = np.array([phi_estimate(lfilter([1.0], [1.0, -phi], e, axis=1)[:, 100:]) for phi in grid])
    return est.mean(axis=1), est.std(axis=1)


def phi_confidence(phi_hat: float, n: int) -> np.ndarray:
    """Confidence distribution of the true φ on the grid given the (unclipped) estimate
    ``phi_hat`` (:func:`phi_estimate`) from ``n`` values.

    C(φ) = P_φ(φ̂* ≥ φ̂), φ̂* normal with the mean and sd of the estimator's simulated sampling
    distribution at φ (the bias and the spread of short AR(1) samples); the weights are its
    increments over the grid, the mass below the first grid point put on it and the mass
    above :data:`PHI_MAX` on the last.
    """
    from scipy.special import ndtr
    mean, sd = _phi_sampling(int(n))
    c = np.maximum.accumulate(ndtr((mean - phi_hat) / sd))
    w = np.diff(np.concatenate([[0.0], c]))
    w[-1] += 1.0 - c[-1]
    return w


def median_of_3(y: np.ndarray) -> np.ndarray:
    """Median of each value and the two before it (the first value repeated at the start): one
    outlying snapshot never moves it."""
    y = np.asarray(y, dtype=float)
    a = np.concatenate([y[:1], y[:1], y[:-2]]) if y.size > 2 else y
    b = np.concatenate([y[:1], y[:-1]]) if y.size > 1 else y
    return median_of_3_rows(a, b, y)


def median_of_3_rows(a, b, c):
    """Element-wise median of three arrays, max(min(a, b), min(max(a, b), c))."""
    return np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c))


def ewma(x: np.ndarray, lam: float, z0: float | None = None) -> np.ndarray:
    """z_t = (1 − λ) z_{t−1} + λ x_t, started at ``z0`` (default x_0)."""
    from scipy.signal import lfilter
    x = np.asarray(x, dtype=float)
    z0 = x[0] if z0 is None else z0
    out, _ = lfilter([lam], [1.0, lam - 1.0], x, zi=[(1.0 - lam) * z0])
    return out


def simulated_moments(phi: float, lam: float, steps: int = SIMULATION_STEPS, seed: int = 0) -> tuple:
    """(Var(z)/σ², corr(z_t, z_{t−1})) of z = EWMA_λ(median_of_3(y)) for unit-variance AR(1) ``y``."""
    from scipy.signal import lfilter
    rng = np.random.default_rng(seed)
    burn = 5000
    e = rng.standard_normal(steps + burn) * math.sqrt(1.0 - phi * phi)
    y = lfilter([1.0], [1.0, -phi], e)[burn:]
    z = ewma(median_of_3(y), lam)[burn:]
    z = z - z.mean()
    zz = float(np.dot(z, z))
    return zz / z.size, float(np.dot(z[1:], z[:-1])) / zz


@lru_cache(maxsize=8)
def moments_table(lam: float) -> tuple[np.ndarray, np.ndarray]:
    """(Var(z)/σ², ρ_z) on the φ grid 0, :data:`PHI_STEP`, ..., :data:`PHI_MAX` for EWMA weight
    ``lam`` (shipped in :mod:`.null_table` for the default weights, simulated otherwise)."""
    from . import null_table
    if lam in null_table.MOMENTS:
        var_z, rho_z = null_table.MOMENTS[lam]
        return np.asarray(var_z), np.asarray(rho_z)
    grid = phi_grid()
    rows = [simulated_moments(float(p), lam) for p in grid]
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])


def phi_grid() -> np.ndarray:
    """The φ values the moments are tabulated at."""
    return np.round(np.arange(0.0, PHI_MAX + PHI_STEP / 2, PHI_STEP), 10)


def mean_variance(phi, n: int):
    """Var(mean of n consecutive AR(1) values) / σ²: (1/n²)[n + 2 Σ_{k<n} (n − k) φ^k]."""
    phi = np.asarray(phi, dtype=float)
    k = np.arange(1, n)
    return (n + 2.0 * np.sum((n - k) * phi[..., None] ** k, axis=-1)) / n ** 2


def d_moments(phi, lam: float, n: int) -> tuple:
    """(Var(D)/σ_e², lag-1 correlation of D) at AR(1) coefficient(s) ``phi``, EWMA ``lam``, baseline ``n``."""
    var_z_tab, rho_z_tab = moments_table(lam)
    grid = phi_grid()
    phi = np.clip(np.asarray(phi, dtype=float), 0.0, PHI_MAX)
    var_z, rho_z = np.interp(phi, grid, var_z_tab), np.interp(phi, grid, rho_z_tab)
    var_c = mean_variance(phi, n)
    var_d = var_z + var_c
    return var_d / (1.0 - phi ** 2), (rho_z * var_z + var_c) / var_d


@lru_cache(maxsize=64)
def _laguerre(dof: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights (summing to 1) of the generalised Gauss-Laguerre rule for x^α e^(−x)/Γ(α+1),
    α = dof/2 − 1, from the eigen-decomposition of its Jacobi matrix (Golub-Welsch): no Γ(α+1) is formed,
    which overflows beyond about 340 degrees of freedom (a baseline of 340 windows or more made the
    limits NaN and the trend raised)."""
    from scipy.linalg import eigh_tridiagonal
    alpha = dof / 2.0 - 1.0
    k = np.arange(SCALE_NODES, dtype=float)
    x, v = eigh_tridiagonal(2.0 * k + alpha + 1.0, np.sqrt(k[1:] * (k[1:] + alpha)))
    return x, v[0] ** 2


def crossing_probability(u: float, fit: Ar1Fit, lam: float) -> float:
    """Probability per step that the standardised statistic of a baseline fitted as ``fit`` crosses
    ``u`` upwards under the null, averaged over the baseline's estimation errors.

    The statistic is standardised by sd(D) = σ̂_e √g(φ̂) (g = Var(D)/σ_e²); at a true φ a
    crossing of u by s is a crossing of h = u·(σ̂_e/σ_e)·√(g(φ̂)/g(φ)) by the true standard
    score, whose probability is 2·T(h, a(φ)). σ̂_e/σ_e ~ √(χ²_ν/ν), ν = n − 3 (generalised
    Gauss-Laguerre with the Gaussian tail factored out: exact to about 1e-8 for these smooth
    integrands); φ is averaged over its confidence distribution ``fit.weights``.
    """
    from scipy.special import owens_t
    keep = fit.weights > 1e-7  # a node below this changes the probability by less than 1e-7 x its own
    phis, wp = phi_grid()[keep], fit.weights[keep]
    g_true, rho = d_moments(phis, lam, fit.n)
    g_hat, _ = d_moments(fit.phi, lam, fit.n)
    a = np.sqrt((1.0 - rho) / (1.0 + rho))
    nu = fit.n - 3
    x, w = _laguerre(nu)
    h0 = u * np.sqrt(g_hat / g_true)  # at σ̂_e = σ_e
    c = h0 ** 2 / nu  # exp(−h²/2) = exp(−c·x) with h² = h0²·X/ν, X = 2x
    y = x[None, :] / (1.0 + c[:, None])
    h = h0[:, None] * np.sqrt(2.0 * y / nu)
    f = 2.0 * owens_t(h, a[:, None]) * np.exp(c[:, None] * y)
    per_phi = (1.0 + c) ** (-(nu / 2.0)) * (f @ w)
    return float(np.dot(wp, per_phi) / wp.sum())


def limit_for_rate(p_step: float, fit: Ar1Fit, lam: float) -> float:
    """The limit u ≥ 0 whose upward-crossing probability per step is ``p_step`` (0 when even
    u = 0 is crossed less often: such a rate asks for every departure above the baseline; inf
    when no u up to 10⁴ is rare enough: a baseline too short to say anything that certain)."""
    from scipy.optimize import brentq
    if not p_step > 0.0:
        raise ValueError(f"crossing probability per step must be positive, got {p_step!r}")
    if crossing_probability(0.0, fit, lam) <= p_step:
        return 0.0

    def excess(u):
        return math.log(max(crossing_probability(u, fit, lam), 1e-300)) - math.log(p_step)

    hi = 40.0
    while excess(hi) > 0.0:
        if hi >= 1e4:
            return math.inf
        hi *= 4.0
    return float(brentq(excess, 0.0, hi, xtol=1e-5))
