"""The demodulation band, chosen from the data by the fault evidence it shows.

Candidate bands are the cells of a kurtogram tree (Antoni 2007): for window lengths
Nw = 2^k and 1.5·2^k, bands [f_k − fs/Nw, f_k + fs/Nw] centred on f_k = k·fs/Nw, kept when

* width ≥ 2·f_top, f_top = the highest envelope frequency a hypothesis tests (the complex
  envelope of a band B, sampled at B, shows the envelope spectrum up to B/2);
* lower edge ≥ f_top (the band must not hold the fault and shaft lines themselves);
* upper edge ≤ the usable bandwidth: 0.45·fs (Nyquist and the anti-alias transition, the
  same rule at any rate), or less when the sensor chain's bandwidth is stated;
* band power ≥ 1e-6 × the median candidate's (a "dead" band beyond an anti-alias filter
  holds only residue that prewhitening would blow up to full scale).

The chosen band is the one whose prewhitened envelope spectrum gives the smallest fault
p-value over all hypotheses, on a buffer of recent data (a fault-specific "gram", in the
spirit of the IESFOgram of Mauricio et al. 2020); every window test then pays a Bonferroni
factor of the number of candidates for that choice (:mod:`.fault_combs`). The kurtogram's
own criterion — the most impulsive band — was measured and rejected: on the development
records it locks onto impulsive content that is not periodic at any fault rate (MFPT IR:
12-14 kHz, where the BPFI line stands 21× above its neighbours, against 486× in 2-6 kHz)
and finds 25 of 34 faults against 33.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import groupby

import numpy as np

from .envelope_spectrum import band_kurtosis, band_ses, normalise, unit_magnitude
from .fault_combs import comb_evidence


@dataclass(frozen=True)
class BandChoice:
    """The demodulation band (Hz), how many candidates it was chosen among, and its evidence."""

    low: float
    high: float
    candidates: int
    log10p: float


def candidate_bands(fs: float, f_top: float, f_usable: float) -> list[np.ndarray]:
    """Admissible kurtogram cells, as one (m, 2) array of (f_lo, f_hi) per width."""
    f_max = min(0.45 * fs, f_usable)
    out = []
    k = 3
    while True:
        wide_enough = False
        for nw in (2 ** k, 3 * 2 ** (k - 1)):
            if 2 * fs / nw < 2 * f_top:
                continue
            wide_enough = True
            centres = np.arange(0, nw // 2 + 1) * fs / nw
            lo, hi = centres - fs / nw, centres + fs / nw
            ok = (lo >= f_top) & (hi <= f_max)
            if ok.any():
                out.append(np.stack([lo[ok], hi[ok]], axis=1))
        if not wide_enough:
            break
        k += 1
    if not out and f_max > f_top:
        out.append(np.array([[f_top, f_max]]))
    return out


def _band_power(cumulative: np.ndarray, df: float, bands: np.ndarray) -> np.ndarray:
    """Mean power of each band from the cumulative power spectrum (bin width ``df`` Hz)."""
    i0 = np.clip(np.rint(bands[:, 0] / df).astype(int), 0, cumulative.size - 1)
    i1 = np.clip(np.rint(bands[:, 1] / df).astype(int), 0, cumulative.size - 1)
    return (cumulative[i1] - cumulative[i0]) / np.maximum(i1 - i0, 1)


def live_bands(raw: np.ndarray, n: int, fs: float, f_top: float, f_usable: float) -> list[np.ndarray]:
    """The admissible candidates (:func:`candidate_bands`) that hold band power, from ``raw``, the rfft of
    ``n`` samples: at least 1e-6 × the median candidate's (module docstring)."""
    groups = candidate_bands(fs, f_top, f_usable)
    if not groups:
        return []
    cumulative = np.concatenate([[0.0], np.cumsum(np.abs(raw) ** 2)])
    power = [_band_power(cumulative, fs / n, g) for g in groups]
    floor = 1e-6 * float(np.median(np.concatenate(power)))
    return [g[p > floor] for g, p in zip(groups, power) if np.any(p > floor)]


def choose_band(x: np.ndarray, fs: float, f_top: float, f_usable: float, fr: float, terms: dict,
                rho: tuple[float, float], prewhiten: bool = True, mask_shaft: bool = True,
                criterion: str = "evidence", exclude=()) -> BandChoice | None:
    """The candidate band of buffer ``x`` (fs Hz) with the strongest fault evidence; None if none fits.

    ``f_top`` and ``fr`` in Hz, ``terms`` and ``rho`` as in :func:`.fault_combs.comb_evidence`.
    ``criterion="kurtogram"``: the most impulsive band instead (Antoni's kurtogram, the
    textbook choice; the window tests then pay no factor for it). ``exclude``: frequencies (Hz) another
    explanation holds (the machine's own lines), as in :func:`.fault_combs.comb_evidence`.
    """
    raw = np.fft.rfft(x - x.mean())
    groups = live_bands(raw, x.size, fs, f_top, f_usable)
    n_candidates = sum(len(g) for g in groups)
    if not n_candidates:
        return None
    spectrum = unit_magnitude(raw) if prewhiten else raw
    bands = np.concatenate(groups)
    if criterion == "kurtogram":
        best = bands[int(np.argmax(np.concatenate([band_kurtosis(spectrum, x.size, fs, g) for g in groups])))]
        return BandChoice(float(best[0]), float(best[1]), 1, 0.0)
    ses = [band_ses(spectrum, x.size, fs, g, f_top)[0] for g in groups]
    score = []
    for _, run in groupby(ses, key=lambda s: s.shape[1]):  # all bands of one SES length in one pass
        evidence = comb_evidence(normalise(np.concatenate(list(run))), fs / x.size, fr, terms, rho, mask_shaft,
                                 exclude=exclude)
        score.append(np.min([e[0] for e in evidence.values()], axis=0))
    score = np.concatenate(score)
    i = int(np.argmin(score))
    return BandChoice(float(bands[i, 0]), float(bands[i, 1]), n_candidates, float(score[i]))
