"""Noise statistics of the normalised envelope spectrum: p-values and Bayes-factor bounds.

Under Gaussian noise a normalised SES bin (:mod:`.envelope_spectrum`) is z = ln 2 · X / m̂
with X ~ Exp(1) and m̂ the sample median of 101 Exp(1) bins. The comb statistic of a
hypothesis, S = Σ_{j=1..J} z_j over its J harmonics and sidebands, then has

    P(S > s) = E_m̂[ Q(J, s · m̂ / ln 2) ]        (Q: regularised upper incomplete gamma)

(sharing one m̂ across the J terms is the worst case: the dependence only fattens the
tail, so the p-value is conservative). m̂ is the 51st order statistic of 101 Exp(1), whose
quantiles are exact: P(m̂ ≤ x) = I_{1−e^{−x}}(51, 51) (regularised incomplete beta); the
expectation is taken over 128 quantile nodes. log10 P is tabulated on S ≤ 650 per J ≤ 16,
each row when first needed, and interpolated.

Averaged spectra (the long horizon, :mod:`.accumulation`): the mean of the SES of K
non-overlapping windows has Ȳ ~ Gamma(K, 1/K) per bin under Gaussian noise (independent
windows); normalised the same way, z = med_K · Ȳ / m̂ with med_K the median of
Gamma(K, 1/K) and m̂ the sample median of 101 such bins, so that

    P(S > s) = E_m̂[ Q(J·K, K · s · m̂ / med_K) ]

with m̂'s quantiles F_K⁻¹(I⁻¹(51, 51)) (K = 1 is the case above). These p-values are computed
in the log domain (:func:`log10_gamma_sf`): accumulated evidence reaches far below 1e-300.

A p-value becomes a statement of evidence through the Sellke-Bayarri-Berger bound on the
Bayes factor against noise, BF ≤ 1/(−e · p · ln p) for p < 1/e.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.special import betaincinv, gammaincc, gammaincinv, gammaln

from .comb_table import first_smallest, table_log10p
from .envelope_spectrum import N_MED
from .gamma_tail import lentz_product

J_MAX = 16
S_MAX = 650.0
S_STEP = 0.05

#: Q below this is taken from the continued fraction (:func:`log10_gamma_sf`): scipy's value underflows.
TAIL = 1e-280


@lru_cache(maxsize=1)
def median_nodes(n_nodes: int = 128) -> np.ndarray:
    """Quantile nodes of the sample median of 2·N_MED + 1 Exp(1) variables (exact order statistic)."""
    k = N_MED + 1
    q = (np.arange(n_nodes) + 0.5) / n_nodes
    return -np.log1p(-betaincinv(k, k, q))


def comb_pvalue(s, j: int) -> np.ndarray:
    """P(S > s) for a comb of ``j`` normalised bins under Gaussian noise (exact integral)."""
    s = np.atleast_1d(np.asarray(s, float))
    if j <= 0:
        return np.ones_like(s)
    return gammaincc(float(j), s[:, None] * median_nodes()[None, :] / np.log(2.0)).mean(axis=1)


_GRID = np.arange(0.0, S_MAX + S_STEP, S_STEP)
_TABLE = np.full((J_MAX + 1, _GRID.size), np.nan)
_TABLE[0] = 0.0


#: Whether every row of the table is filled (then no read looks for a missing one).
_TABULATED = [False]


def _rows(js) -> None:
    for j in js:
        if np.isnan(_TABLE[j, 0]):
            _TABLE[j] = np.log10(np.maximum(comb_pvalue(_GRID, int(j)), 1e-300))
    _TABULATED[0] = not np.isnan(_TABLE[:, 0]).any()


def warm_up() -> None:
    """Tabulate every comb size now (about 2 s) and compile or load the tail's continued fraction
    (:mod:`.gamma_tail`), not on a live stream's first windows."""
    _rows(range(1, J_MAX + 1))
    comb_log10p(np.array([1.0]), np.array([1]))
    first_best_scale(np.ones((1, 2)), np.ones(2, int), np.zeros(1, int))
    log10_gamma_sf(np.array([3.0]), np.array([900.0]))


def comb_log10p(s, j) -> np.ndarray:
    """log10 P(S > s) for combs of ``j`` bins (j = 0 gives 0), elementwise, by table lookup
    (:func:`.comb_table.table_log10p`: linear interpolation on S clipped to the table)."""
    s, j = np.asarray(s, float), comb_sizes(j)
    if s.shape != j.shape:
        s, j = np.broadcast_arrays(s, j)
    return table_log10p(_TABLE, np.ascontiguousarray(s).ravel(), np.ascontiguousarray(j).ravel(), S_MAX,
                        S_STEP).reshape(s.shape)[()]


def comb_sizes(j) -> np.ndarray:
    """Comb sizes ``j`` as table rows (int, clipped to 0..:data:`J_MAX`), every one tabulated."""
    j = np.minimum(np.maximum(np.asarray(j, int), 0), J_MAX)
    if not _TABULATED[0]:  # a comb size may not be tabulated yet (before warm_up)
        _rows(np.unique(j))
    return j


def first_best_scale(s: np.ndarray, j: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Per row of comb sums ``s`` (rows, scales) with ``j`` terms (scales), per run of scales from each of
    ``starts`` (increasing, no run empty): the first scale of the smallest tabulated p-value
    (:func:`.comb_table.first_smallest`)."""
    return first_smallest(_TABLE, np.ascontiguousarray(s, dtype=float), comb_sizes(j), starts, S_MAX, S_STEP)


@lru_cache(maxsize=128)
def averaged_median(k: int, n_nodes: int = 128) -> tuple[np.ndarray, float]:
    """(quantile nodes of the sample median of 2·N_MED + 1 Gamma(k, 1/k) bins, the median med_k
    of one such bin)."""
    q = (np.arange(n_nodes) + 0.5) / n_nodes
    nodes = gammaincinv(k, betaincinv(N_MED + 1, N_MED + 1, q)) / k
    nodes.setflags(write=False)
    return nodes, float(gammaincinv(k, 0.5) / k)


def log10_gamma_sf(a, x, per_row: bool = False) -> np.ndarray:
    """log10 Q(a, x), the regularised upper incomplete gamma, without underflow: scipy's value
    where it is above 1e-280, else the continued fraction of Q (Lentz; x > a there;
    :func:`.gamma_tail.lentz_product`), iterated until all those elements converged, or, with
    ``per_row``, those of each row (first axis) of the 2-d broadcast: each row exactly as if alone."""
    a, x = np.broadcast_arrays(np.asarray(a, float), np.asarray(x, float))
    q = gammaincc(a, x)
    out = np.log10(np.maximum(q, 1e-300))
    tiny = q < TAIL
    if np.any(tiny):
        at, xt = a[tiny], x[tiny]
        counts = tiny.reshape(tiny.shape[0], -1).sum(axis=1) if per_row else [at.size]
        h = lentz_product(np.ascontiguousarray(at), np.ascontiguousarray(xt), np.r_[0, np.cumsum(counts)])
        out[tiny] = (-xt + at * np.log(xt) - gammaln(at) + np.log(h)) / np.log(10.0)
    return out


def averaged_comb_log10p(s, j, k: int) -> np.ndarray:
    """log10 P(S > s) for combs of ``j`` bins of a K-window averaged SES (j = 0 gives 0), elementwise
    (module docstring: the exact integral over the normalising median, in the log domain)."""
    s, j = np.broadcast_arrays(np.asarray(s, float), np.asarray(j, float))
    nodes, med = averaged_median(int(k))
    lq = log10_gamma_sf((j * k)[..., None], (k * np.maximum(s, 0.0) / med)[..., None] * nodes)
    out = (logsumexp_rows(lq * np.log(10.0)) - np.log(nodes.size)) / np.log(10.0)
    return np.where(j > 0, np.minimum(out, 0.0), 0.0)


def averaged_comb_log10p_rows(s, j, k: int, rows: np.ndarray) -> np.ndarray:
    """:func:`averaged_comb_log10p` of 1-d ``s`` and ``j`` at the rows ``rows`` (boolean) alone, bit for bit
    (NaN at the others): the other rows take part only in the continued fraction's stopping, which waits
    for every tail element of the call (:func:`log10_gamma_sf`); their tail nodes are found by bisection
    (Q falls with x, and x with the node), a few evaluations of Q per row instead of one per node."""
    s, j = np.broadcast_arrays(np.asarray(s, float), np.asarray(j, float))
    nodes, med = averaged_median(int(k))
    a = np.broadcast_to((j * k)[:, None], (s.size, nodes.size))
    x = (k * np.maximum(s, 0.0) / med)[:, None] * nodes
    q = np.full(x.shape, np.nan)
    q[rows] = gammaincc(a[rows], x[rows])
    lq = np.log10(np.maximum(q, 1e-300))
    tiny = q < TAIL
    tiny[~rows] = _tail_nodes(a[~rows, 0], x[~rows])
    if np.any(tiny):
        at, xt = a[tiny], x[tiny]
        h = lentz_product(np.ascontiguousarray(at), np.ascontiguousarray(xt), np.array([0, at.size]))
        wanted = np.broadcast_to(rows[:, None], x.shape)[tiny]
        at, xt, h = at[wanted], xt[wanted], h[wanted]
        lq[tiny & rows[:, None]] = (-xt + at * np.log(xt) - gammaln(at) + np.log(h)) / np.log(10.0)
    out = np.full(s.shape, np.nan)
    lse = (logsumexp_rows(lq[rows] * np.log(10.0)) - np.log(nodes.size)) / np.log(10.0)
    out[rows] = np.where(j[rows] > 0, np.minimum(lse, 0.0), 0.0)
    return out


def _tail_nodes(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Whether Q(a, x) < :data:`TAIL` at each node of rows of ``x`` (n, nodes; rising along a row) with
    ``a`` (n,), by bisection for each row's first such node."""
    n, m = x.shape
    lo = np.where(gammaincc(a, x[:, -1]) < TAIL, 0, m) if n else np.zeros(0, int)
    hi = np.where(lo == 0, m - 1, m)
    while np.any(lo < hi):
        act = np.flatnonzero(lo < hi)
        mid = (lo[act] + hi[act]) // 2
        below = gammaincc(a[act], x[act, mid]) < TAIL
        hi[act] = np.where(below, mid, hi[act])
        lo[act] = np.where(below, lo[act], mid + 1)
    return np.arange(m)[None, :] >= lo[:, None]


def logsumexp_rows(a: np.ndarray) -> np.ndarray:
    """ln Σ exp(a) over the last axis of ``a``: scipy.special.logsumexp's arithmetic (the
    maxima taken out of the sum, log1p of the rest), without its per-call overhead (a third of a
    long-horizon window's cost). A row holding NaN (a comb of no terms) gives NaN, silently."""
    a_max = a.max(axis=-1, keepdims=True)
    is_max = a == a_max
    m = is_max.sum(axis=-1, keepdims=True).astype(float)
    s = np.exp(np.where(is_max, -np.inf, a) - a_max).sum(axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(s == 0, s, s / m)
        return (np.log1p(s) + np.log(m) + a_max)[..., 0]


def log10_bayes_factor_bound(log10p) -> np.ndarray:
    """log10 of the Sellke-Bayarri-Berger bound 1/(−e·p·ln p) (p < 1/e; else 0: no evidence)."""
    lp = np.asarray(log10p, float)
    lnp = lp * np.log(10.0)
    bound = -(np.log10(np.e) + lp + np.log10(np.maximum(-lnp, 1e-300)))
    return np.where(lnp < -1.0, bound, 0.0)
