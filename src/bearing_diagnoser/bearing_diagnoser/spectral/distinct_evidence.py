"""Whether a comb's evidence is this fault's and no other explanation's: the one home of the checks
that the short horizon (:mod:`.evidence_stream`) and the long horizon (:mod:`.accumulation`) share.

The p-values of :mod:`.fault_combs` test the combs against Gaussian noise. A real machine's
envelope spectrum carries lines of its own — shaft harmonics, other periodicities, stationary
lines present from the day it was installed — and any of them may fall into one term's slip
range. Evidence counts for a hypothesis only when it is distinct:

1. **Explain-away**: each hypothesis but the strongest is tested again without the bins the
   strongest one's comb occupies (a line that both explain does not decide between them).
2. **A series** (:func:`series_holds`): a fault's impacts are periodic, so its evidence is
   several terms at one common scale ρ. At the comb's best ρ, the comb without its strongest
   term, and its carriers alone, must each still be significant at :data:`SERIES_LEVEL` (one
   test each, no search): one foreign line inside one term's slip range is not a series.
3. **It stands out** (:func:`stands_out`): the comb searched over its slip range beats the
   same comb searched over decoy ranges where its fault does not lie (another periodicity's
   family of lines, a dense comb of a machine's own lifts those as much).
4. **Its part's sidebands** (:func:`sidebands_carry`): an inner-race defect turns with the
   shaft through the load zone (shaft-rate sidebands), a ball travels with the cage (cage-rate
   sidebands); a family of lines without them is another machine's (measured: HIT-SM's
   healthy 600 rpm record holds a stationary family at 60.6 Hz that an inner-race comb of a
   9-ball bearing, BPFI = 6.0×, matched as a series). They are tested at :data:`SIDEBAND_LEVEL`
   = 1e-2, a line's worth of evidence shared by several terms: on HIT-SM's inner-race records
   at 600 and 900 rpm the sidebands stay below 1e-3.

:data:`SERIES_LEVEL` = 1e-3: one test per check and hypothesis, at the level of a single
clear line (a bin 10× the median floor has p ≈ 1e-3 in one window); it is a condition on top
of the comb's own significance, which pays the false-alarm budget, so it only ever removes
evidence.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bearing_common.states import FaultState

from .fault_combs import best_scale, comb_sums, log10p_k, scales, term_bins, term_frequencies

#: log10 of the level each distinctness check must reach on its own (module docstring).
SERIES_LEVEL = -3.0

#: log10 of the level a comb's sidebands must reach on their own (one test at the comb's scale).
SIDEBAND_LEVEL = -2.0

#: Decoy searches a comb must beat: this many scale ranges as wide as its slip search, the nearest
#: ones either side of it whose terms keep clear of the comb's own (in widths: 2, 3, ... up to 12).
N_DECOYS = 8


def explain_away(found: dict, terms: dict, fr: float, retest: Callable) -> dict:
    """``found`` {hypothesis: evidence with ``log10p`` and ``rho``} with every hypothesis but the strongest
    replaced by ``retest(h, held)``, its evidence without the frequencies ``held`` (Hz) of the strongest
    one's comb (kept as it was when ``retest`` gives None)."""
    if len(found) < 2:
        return found
    strongest = min(found, key=lambda h: found[h].log10p)
    held = term_frequencies(terms, strongest, found[strongest].rho, fr)
    return {h: e if h == strongest else (retest(h, held) or e) for h, e in found.items()}


def distinct(z: np.ndarray, df: float, fr: float, hypothesis: FaultState, terms: np.ndarray,
             rho: tuple[float, float], best_rho: float, log10p: float, mask_shaft: bool = True, k: int = 1,
             series: bool = True, exclude=()) -> bool:
    """Whether ``hypothesis``' comb ``terms``, best at scale ``best_rho`` of the slip range ``rho`` with
    ``log10p`` (without the band choice's factor), is distinct evidence on the normalised SES row ``z``
    (k windows averaged; module docstring). ``series``: the comb has harmonics to test as a series
    (not the textbook baseline's fundamentals); ``exclude``: frequencies (Hz) another explanation holds."""
    z = np.atleast_1d(z)
    if series and not series_holds(z, df, fr, terms, best_rho, mask_shaft, k, exclude):
        return False
    if hypothesis in (FaultState.INNER_RACE, FaultState.BALL) and not sidebands_carry(
            z, df, fr, terms, best_rho, mask_shaft, k, exclude):
        return False
    return stands_out(z, df, fr, terms, rho, log10p, mask_shaft, k)


def _term_values(z: np.ndarray, df: float, fr: float, terms: np.ndarray, rho: float, mask_shaft: bool,
                 exclude) -> tuple[np.ndarray, np.ndarray]:
    """Each term's normalised bin at scale ``rho`` on row ``z``, and whether it counts (:func:`.term_bins`)."""
    idx, active = term_bins(df, fr, terms, np.array([rho]), z.size, mask_shaft, exclude)
    return np.where(active[0], z[idx[0]], 0.0), active[0]


def _significant(values: np.ndarray, use: np.ndarray, k: int, level: float = SERIES_LEVEL) -> bool:
    """Whether the terms ``use`` of ``values`` together reach ``level`` (log10 p, one test)."""
    n = int(use.sum())
    return n > 0 and float(log10p_k(np.array([values[use].sum()]), np.array([n]), k)[0]) < level


def series_holds(z: np.ndarray, df: float, fr: float, terms: np.ndarray, rho: float, mask_shaft: bool = True,
                 k: int = 1, exclude=()) -> bool:
    """Whether comb ``terms`` at scale ``rho`` is a series (module docstring, 2): at least two terms count,
    and without its strongest term, and with its carriers alone, it is significant at :data:`SERIES_LEVEL`."""
    values, active = _term_values(z, df, fr, terms, rho, mask_shaft, exclude)
    if active.sum() < 2:
        return False
    rest = active.copy()
    rest[int(np.argmax(values))] = False
    return _significant(values, rest, k) and _significant(values, active & (terms[:, 2] == 1), k)


def sidebands_carry(z: np.ndarray, df: float, fr: float, terms: np.ndarray, rho: float, mask_shaft: bool = True,
                    k: int = 1, exclude=()) -> bool:
    """Whether the sideband terms (``is_carrier`` 0) of one comb at scale ``rho`` on the normalised SES row
    ``z`` (k windows averaged) are significant on their own at :data:`SIDEBAND_LEVEL` (one test, no search);
    True for a comb without sidebands (the textbook baseline's fundamentals)."""
    side = terms[:, 2] == 0
    if not side.any():
        return True
    values, active = _term_values(z, df, fr, terms, rho, mask_shaft, exclude)
    return _significant(values, active & side, k, SIDEBAND_LEVEL)


def decoy_ranges(terms: np.ndarray, rho: tuple[float, float], df: float, fr: float) -> list[tuple[float, float]]:
    """Up to :data:`N_DECOYS` scale ranges for :func:`stands_out`: as wide as ``rho``, nearest first,
    alternating sides, each one's terms clear (by 1.5 bins) of every term of the comb itself over
    ``rho`` (an IR comb's carrier shifted by a fifth lands on its own shaft sideband)."""
    width = max(rho[1] - rho[0], 0.01)
    centre = 0.5 * (rho[0] + rho[1])
    c, d = terms[:, 0], terms[:, 1]
    own = np.sort(np.stack([(c * r + d) * fr for r in rho], axis=-1), axis=-1)  # (J, 2) Hz
    m = np.repeat(np.arange(2, 13), 2)
    lo = centre + np.tile([-1.0, 1.0], 11) * m * width - 0.5 * width  # nearest first, alternating sides
    lo = lo[lo > 0.2]
    span = np.stack([(c * lo[:, None] + d) * fr, (c * (lo[:, None] + width) + d) * fr], axis=-1)  # (n, J, 2)
    a1, b1 = span[:, :, None, 0], span[:, :, None, 1]
    a2, b2 = own[None, None, :, 0], own[None, None, :, 1]
    clear = ((b1 + 1.5 * df < a2) | (b2 + 1.5 * df < a1)).all(axis=(1, 2))
    return [(float(x), float(x + width)) for x in lo[clear][:N_DECOYS]]


def stands_out(z: np.ndarray, df: float, fr: float, terms: np.ndarray, rho: tuple[float, float], log10p: float,
               mask_shaft: bool = True, k: int = 1) -> bool:
    """Whether a comb's best match (``log10p``, over the slip range ``rho``, without the band choice's
    factor) beats the same comb searched over the decoy ranges (:func:`decoy_ranges`) on the same
    spectrum row ``z``.

    A family of lines that is not this fault's — harmonics of another periodicity, a dense comb
    of a machine's own — lifts the comb at scales where no line of this fault lies as much as
    at the fault's: the fault's comb must stand out from all of them (eight decoys: one chance
    in nine under any exchangeable null). Decoys that land on another hypothesis' lines only
    make the test stricter: evidence another hypothesis explains does not decide.
    """
    decoys = [scales(terms, r, df, fr) for r in decoy_ranges(terms, rho, df, fr)]
    if not decoys:
        return True
    s, j = comb_sums(np.atleast_2d(z), df, fr, terms, np.concatenate([r for r, _ in decoys]), mask_shaft, ())
    best = best_scale(s, j, k, np.cumsum([0] + [r.size for r, _ in decoys[:-1]]))[0]
    lp = log10p_k(s[0, best], j[best], k)
    lp = np.minimum(0.0, lp + np.log10([n for _, n in decoys]))
    return bool(np.all(lp > log10p))
