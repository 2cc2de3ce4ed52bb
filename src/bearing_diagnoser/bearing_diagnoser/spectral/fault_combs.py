"""Fault evidence in the normalised envelope spectrum: harmonic and sideband combs, slip search.

Each hypothesis is a comb of terms, in orders of the shaft rate fr (thesis eqs. 2.51-2.54 via
:meth:`bearing_common.bearings.Bearing.orders`); a term's frequency is (c·ρ + d)·fr:

* OUTER_RACE: carriers k·BPFO, k = 1..H;
* INNER_RACE: carriers k·BPFI and the shaft-rate sidebands k·BPFI ± fr (the defect turns
  with the shaft through the load zone, eq. 2.58; the sideband offset does not slip);
* BALL: carriers 2k·BSF (a ball defect strikes both races once per spin revolution) and
  the cage-rate sidebands 2k·BSF ± FTF (the ball travels with the cage through the load
  zone; they slip with ρ).

H = 3 harmonics. ρ, one scale per hypothesis for all its terms (impacts are periodic, so
their harmonics are exact multiples of one rate), is searched on [1 − 2.5 % − 2u,
1 + 1 % + 2u], u = the relative standard uncertainty of the shaft speed: rolling elements
slip 1-2 % (Randall & Antoni 2011; measured 1-2 % on CWRU, about 1 % on MFPT) with 0.5 %
margin, and +1 % covers geometry tolerance and cage slip, which raises BPFI = n(fr − FTF).

Ambiguity: terms of two hypotheses closer (relatively) than the ρ-search width could be
matched by either. Carrier-carrier and sideband-sideband collisions drop the term from
both (6205: 3·BPFO and 2·BPFI lie 0.7 % apart); in a carrier-sideband collision only the
sideband is dropped (a sideband exists only with its carrier).

Shaft-line mask: at each ρ, a term within 1.5 bins of a shaft harmonic m·fr is not used
(the Hann main lobe is ±1 bin at −6 dB): healthy machines put shaft harmonics into the
envelope spectrum, and they must never count as fault evidence.

Statistic at ρ: S(ρ) = sum of the active terms' normalised bins, J(ρ) active terms,
log10 p(ρ) from :func:`.significance.comb_log10p`. The hypothesis p-value pays for the
searches it made (Bonferroni): p_h = min(1, n_bands · n_cells · min_ρ p(ρ)), n_cells =
distinct bins the highest term visits over the ρ range, n_bands = candidate bands when the
band was chosen by this same evidence.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.special import gammaincc

from bearing_common.bearings import Bearing
from bearing_common.states import FaultState

from .significance import (
    TAIL,
    averaged_comb_log10p,
    averaged_comb_log10p_rows,
    averaged_median,
    comb_log10p,
    first_best_scale,
    log10_gamma_sf,
    logsumexp_rows,
)

#: The fault hypotheses the envelope spectrum tests.
HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL)

#: Harmonics per hypothesis.
N_HARMONICS = 3

#: Slip range below / above the kinematic frequency (fractions).
SLIP_BELOW, SLIP_ABOVE = 0.025, 0.01


@dataclass(frozen=True)
class CombEvidence:
    """The best match of one hypothesis' comb in one window."""

    log10p: float  # corrected for the ρ search and the band choice
    rho: float  # scale of the kinematic frequencies where the comb matched best
    statistic: float  # S, sum of the normalised bins
    terms: int  # J, terms used


def comb_terms(bearing: Bearing, harmonics: int = N_HARMONICS, fundamental_only: bool = False) -> dict:
    """{hypothesis: (J, 3) array of (c, d, is_carrier)}: term frequency = (c·ρ + d)·fr."""
    o = bearing.orders()
    ks = [1] if fundamental_only else list(range(1, harmonics + 1))
    outer = [(k * o.bpfo, 0.0, 1) for k in ks]
    inner = [(k * o.bpfi, 0.0, 1) for k in ks]
    ball = [(2 * k * o.bsf, 0.0, 1) for k in ks]
    if not fundamental_only:
        inner += [(k * o.bpfi, s, 0) for k in ks for s in (-1.0, 1.0)]
        ball += [(2 * k * o.bsf + s * o.ftf, 0.0, 0) for k in ks for s in (-1.0, 1.0)]
    return {FaultState.OUTER_RACE: np.asarray(outer, float), FaultState.INNER_RACE: np.asarray(inner, float),
            FaultState.BALL: np.asarray(ball, float)}


def drop_ambiguous(terms: dict, tolerance: float) -> dict:
    """Terms without a term of another hypothesis closer than ``tolerance`` (relative)."""
    out = {}
    for h, own in terms.items():
        f = own[:, 0] + own[:, 1]
        keep = np.ones(len(own), bool)
        for g, other in terms.items():
            if g == h or len(other) == 0:
                continue
            fo = other[:, 0] + other[:, 1]
            close = np.abs(f[:, None] / fo[None, :] - 1.0) < tolerance
            carrier_over_sideband = (own[:, 2][:, None] == 1) & (other[:, 2][None, :] == 0)
            keep &= ~(close & ~carrier_over_sideband).any(axis=1)
        out[h] = own[keep]
    return out


#: Bins a sideband must lie from its carrier to be told from it: the spacing the analysis window is
#: designed for (4 cage periods put the cage sideband 4 bins off, twice the Hann main lobe's half-width).
RESOLVED_BINS = 4.0

#: Bins within which a shaft harmonic masks a term (:func:`comb_evidence`).
SHAFT_MASK_BINS = 1.5


def untestable(terms: dict, fr: float, df: float, mask_shaft: bool = True, series: bool = True) -> dict:
    """{hypothesis: why} for the combs a spectrum of bin width ``df`` (Hz) cannot test at shaft rate ``fr``
    (Hz): those whose sidebands lie fewer than :data:`RESOLVED_BINS` bins from their carriers (they are
    what tells the inner race, turning with the shaft, and the ball, travelling with the cage, from the
    others), and, with the shaft-harmonic mask, those whose every carrier lies within
    :data:`SHAFT_MASK_BINS` of a shaft harmonic, or (``series``: evidence must be a series,
    :mod:`.distinct_evidence`) that keep fewer than two terms clear of them (at the kinematic
    frequencies). A window of the analysis length (4 cage periods) tests every hypothesis of a
    6205; a short snapshot may not."""
    out = {}
    for h, t in terms.items():
        carriers = t[t[:, 2] == 1, 0] * fr
        sides = (t[t[:, 2] == 0, 0] + t[t[:, 2] == 0, 1]) * fr
        if not carriers.size:
            out[h] = "no carrier term left"
            continue
        if sides.size:
            offset = float(np.min(np.abs(sides[:, None] - carriers[None, :]))) / df
            if offset < RESOLVED_BINS:
                out[h] = f"sidebands {offset:.1f} bins from their carriers, {RESOLVED_BINS:g} needed"
                continue
        if mask_shaft:
            _, clear = term_bins(df, fr, t, np.array([1.0]), np.iinfo(np.int32).max, True, ())
            if not clear[0, t[:, 2] == 1].any():
                out[h] = f"every carrier within {SHAFT_MASK_BINS:g} bins of a shaft harmonic"
            elif series and clear.sum() < 2:
                out[h] = f"one term clear of the shaft harmonics ({SHAFT_MASK_BINS:g} bins): no series to test"
    return out


def rho_range(u: float, slip_search: bool = True) -> tuple[float, float]:
    """(ρ_lo, ρ_hi) for speed uncertainty ``u`` (relative); ±2u only without the slip search."""
    if not slip_search:
        return 1.0 - 2 * u, 1.0 + 2 * u
    return 1.0 - SLIP_BELOW - 2 * u, 1.0 + SLIP_ABOVE + 2 * u


def comb_evidence(z: np.ndarray, df: float, fr: float, terms: dict, rho: tuple[float, float],
                  mask_shaft: bool = True, n_bands: int = 1, k: int = 1, exclude=(), prune: bool = False) -> dict:
    """Per hypothesis, per row of ``z`` (m, n_bins) of normalised SES: the best comb match.

    Returns {hypothesis: (log10 p (m,), ρ (m,), S (m,), J (m,))} arrays; ``df`` = bin width
    (Hz), ``fr`` = shaft rate (Hz). ``k``: the spectra are averages of k windows
    (:func:`.significance.averaged_comb_log10p`; each row's best ρ is found with the p-value at
    the normalising median's median, then its p-value computed exactly). ``exclude``:
    frequencies (Hz) another explanation holds; a term within 1.5 bins of one is not used. ``prune``
    (k > 1): log10 p only where it can be the smallest of the rows, +inf elsewhere
    (:func:`smallest_log10p`; the smallest, its row and its ties exact).
    """
    z = np.atleast_2d(z)
    out = {}
    for h, t in terms.items():
        if len(t) == 0:
            out[h] = (np.zeros(z.shape[0]), np.ones(z.shape[0]), np.zeros(z.shape[0]), np.zeros(z.shape[0], int))
            continue
        rhos, n_cells = scales(t, rho, df, fr)
        s, j = comb_sums(z, df, fr, t, rhos, mask_shaft, exclude)
        best = best_scale(s, j, k)[:, 0]
        s_best = s[np.arange(z.shape[0]), best]
        c = np.log10(n_cells * n_bands)
        lp = smallest_log10p(s_best, j[best], k, c) if prune and k > 1 else np.minimum(0.0, log10p_k(s_best, j[best], k)
                                                                                        + c)
        out[h] = (lp, rhos[best], s_best, j[best])
    return out


#: Decades by which a row's bounds must clear the others' to be left out (:func:`smallest_log10p`): far
#: above the p-values' rounding.
PRUNE_MARGIN = 1e-6


def smallest_log10p(s: np.ndarray, j: np.ndarray, k: int, c: float) -> np.ndarray:
    """min(0, log10 p + ``c``) of comb sums S with J terms over k > 1 averaged windows, per row, exactly as
    :func:`comb_evidence` gives it at every row that holds or ties the smallest; +inf at the others. The
    mean over the normalising median's nodes of Q lies between its largest term (the first node) and a
    :data:`.significance.averaged_median` node count's fraction of it: rows whose bound from below
    clears the best bound from above by :data:`PRUNE_MARGIN` are not computed, nor rows surely at 0."""
    nodes, med = averaged_median(k)
    jf = np.asarray(j, float)
    q0 = gammaincc(jf * k, k * np.maximum(s, 0.0) / med * nodes[0])
    lq0 = np.log10(np.maximum(q0, 1e-300))
    tail = q0 < TAIL
    upper = np.where(jf > 0, np.minimum(np.where(tail, np.log10(TAIL), lq0), 0.0), 0.0)
    lower = np.where(jf > 0, np.where(tail, -np.inf, np.minimum(lq0 - np.log10(nodes.size), 0.0)), 0.0)
    zero = lower + c > PRUNE_MARGIN
    need = ~zero & (np.minimum(0.0, lower + c) <= np.minimum(0.0, upper + c).min() + PRUNE_MARGIN)
    out = np.where(zero, 0.0, np.inf)
    if np.any(need):
        out[need] = np.minimum(0.0, averaged_comb_log10p_rows(s, j, k, need)[need] + c)
    return out


def recent_run_evidence(z: np.ndarray, df: float, geometry, hypothesis: FaultState, mask_shaft: bool = True
                        ) -> np.ndarray:
    """log10 p of ``hypothesis``' comb (at ``geometry``, :class:`.accumulation.CombGeometry`) in each row
    r of ``z``: the normalised mean SES of the last r + 1 windows (no band-choice factor). Every row is
    tested as :func:`comb_evidence` tests a spectrum of r + 1 windows, the rows of two windows and more
    at once (:func:`averaged_run_log10p`)."""
    t = geometry.terms[hypothesis]
    rhos, n_cells = scales(t, geometry.rho, df, geometry.fr)
    s, j = comb_sums(z, df, geometry.fr, t, rhos, mask_shaft, ())
    best = best_scale(s[:1], j, 1)[0, 0]
    lp = np.r_[log10p_k(s[0, best:best + 1], j[best:best + 1], 1), averaged_run_log10p(s[1:], j)]
    lp = lp + np.log10(n_cells)
    return np.where(lp < 0.0, lp, 0.0)


def averaged_run_log10p(s: np.ndarray, j: np.ndarray) -> np.ndarray:
    """log10 p of the best scale of each row r of S (rows, scales) with J (scales), row r from spectra
    averaged over k = r + 2 windows: per row bit for bit :func:`best_scale` and
    :func:`.significance.averaged_comb_log10p` with that k (one call for all rows, not one per row)."""
    if not s.shape[0]:
        return np.empty(0)
    ks = np.arange(2, s.shape[0] + 2)[:, None]
    nodes = np.stack([averaged_median(int(k))[0] for k in ks[:, 0]])
    med = np.array([averaged_median(int(k))[1] for k in ks[:, 0]])[:, None]
    mid = nodes[:, nodes.shape[1] // 2:nodes.shape[1] // 2 + 1]
    score = np.where(j[None, :] > 0, log10_gamma_sf(j[None, :] * ks, ks * s * mid / med, per_row=True), 0.0)
    best = np.argmin(score, axis=1)  # the first of equals
    s_best, j_best = s[np.arange(s.shape[0]), best], np.asarray(j[best], float)[:, None]
    lq = log10_gamma_sf(j_best * ks, ks * np.maximum(s_best[:, None], 0.0) / med * nodes, per_row=True)
    out = (logsumexp_rows(lq * np.log(10.0)) - np.log(nodes.shape[1])) / np.log(10.0)
    return np.where(j_best[:, 0] > 0, np.minimum(out, 0.0), 0.0)


def scales(t: np.ndarray, rho: tuple[float, float], df: float, fr: float) -> tuple[np.ndarray, int]:
    """The scales ρ searched for comb ``t`` (half a bin apart at its highest term) and the distinct
    bins that term visits (the search's Bonferroni count)."""
    top = t[:, 0].max()
    step = 0.5 * df / (top * fr)
    rhos = np.arange(rho[0], rho[1] + step / 2, step) if rho[1] > rho[0] else np.array([rho[0]])
    return rhos, int(np.ceil((rho[1] - rho[0]) * top * fr / df)) + 1


def term_bins(df: float, fr: float, t: np.ndarray, rhos: np.ndarray, nb: int, mask_shaft: bool, exclude
              ) -> tuple[np.ndarray, np.ndarray]:
    """Bin (n_rho, J) of each term of comb ``t`` at each scale of ``rhos`` in a spectrum of ``nb`` bins, and
    whether it counts: inside the spectrum, not on a shaft harmonic (with ``mask_shaft``), not within
    1.5 bins of a frequency of ``exclude`` (Hz). Read-only arrays, kept for the next window that asks
    with the same arguments (the geometry changes rarely)."""
    t, rhos = np.asarray(t, float), np.asarray(rhos, float)
    exclude = tuple(np.atleast_1d(np.asarray(exclude, float)).tolist())
    return _term_bins(float(df), float(fr), t.tobytes(), t.shape, rhos.tobytes(), int(nb), bool(mask_shaft), exclude)


@lru_cache(maxsize=256)
def _term_bins(df: float, fr: float, t_bytes: bytes, t_shape: tuple, rhos_bytes: bytes, nb: int, mask_shaft: bool,
               exclude: tuple) -> tuple[np.ndarray, np.ndarray]:
    """:func:`term_bins` of the arrays given as bytes (hashable)."""
    t = np.frombuffer(t_bytes).reshape(t_shape)
    rhos = np.frombuffer(rhos_bytes)
    f = (t[None, :, 0] * rhos[:, None] + t[None, :, 1]) * fr  # (n_rho, J)
    idx = np.rint(f / df).astype(int)
    active = (idx >= 1) & (idx < nb)
    if mask_shaft:
        order = np.rint(f / fr)
        active &= ~((order >= 1) & (np.abs(f - order * fr) < SHAFT_MASK_BINS * df))
    for g in exclude:
        active &= np.abs(f - g) >= SHAFT_MASK_BINS * df
    idx = np.clip(idx, 0, nb - 1)
    idx.setflags(write=False)
    active.setflags(write=False)
    return idx, active


def comb_sums(z: np.ndarray, df: float, fr: float, t: np.ndarray, rhos: np.ndarray, mask_shaft: bool,
              exclude) -> tuple[np.ndarray, np.ndarray]:
    """S (rows of ``z``, scales) and J (scales) of comb ``t`` at every scale of ``rhos``."""
    idx, active = term_bins(df, fr, t, rhos, z.shape[1], mask_shaft, exclude)
    values = np.where(active[None], z[:, idx], 0.0)  # (m, n_rho, J)
    return values.sum(axis=2), active.sum(axis=1)


def best_scale(s: np.ndarray, j: np.ndarray, k: int, starts=(0,)) -> np.ndarray:
    """Index of the best scale per row of S (rows, scales) with J (scales), in each run of scales
    beginning at ``starts`` ((rows, runs); the first of equals): by the tabulated p-value for
    single windows (compiled where no run is empty: :func:`.significance.first_best_scale`), for k
    averaged ones by the p-value at the normalising median's median."""
    starts = np.asarray(starts, int)
    sizes = np.diff(np.append(starts, s.shape[1]))
    if k == 1 and sizes.min() > 0:
        return first_best_scale(s, j, starts)
    if k == 1:
        score = comb_log10p(s, j[None, :])
    else:
        nodes, med = averaged_median(k)
        score = np.where(j[None, :] > 0, log10_gamma_sf(j[None, :] * k, k * s * nodes[nodes.size // 2] / med), 0.0)
    low = np.minimum.reduceat(score, starts, axis=1)
    at_low = score == np.repeat(low, sizes, axis=1)
    return np.minimum.reduceat(np.where(at_low, np.arange(score.shape[1]), score.shape[1]), starts, axis=1)


def log10p_k(s: np.ndarray, j: np.ndarray, k: int) -> np.ndarray:
    """log10 p of comb sums S with J terms over spectra averaged from k windows, elementwise."""
    return comb_log10p(s, j) if k == 1 else averaged_comb_log10p(s, j, k)

def term_frequencies(terms: dict, hypothesis: FaultState, rho: float, fr: float) -> np.ndarray:
    """Frequencies (Hz) of ``hypothesis``' comb at scale ``rho`` and shaft rate ``fr``."""
    t = terms[hypothesis]
    return (t[:, 0] * rho + t[:, 1]) * fr


def highest_term(terms: dict, rho_hi: float) -> float:
    """Highest term frequency in orders (at ρ = ``rho_hi``): the top of the envelope band tested."""
    rows = np.concatenate([t for t in terms.values() if len(t)])
    return float((rows[:, 0] * rho_hi + rows[:, 1]).max())
