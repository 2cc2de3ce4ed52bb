"""The textbook squared-envelope-spectrum statistic of the fold front end (``--method envelope``).

The reference the folding statistic is measured against: the spectrum of one window's
energy envelope, read at the fault harmonics and CFAR-normalised by the same decoy
frequencies as the folding (:mod:`.decoys`), so that only the statistic differs.
"""

from __future__ import annotations

import numpy as np


def squared_envelope_spectrum(env: np.ndarray, envelope_rate: float, pad: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Magnitude of the squared envelope spectrum (SES) of one window.

    ``env`` is the block-averaged squared band-passed signal ((m/s²)²), i.e. the squared
    envelope low-passed by the block average.  Mean removed, Hann window, zero-padded
    ``pad``×.  Returns (frequencies Hz, |SES|).
    """
    e = np.asarray(env, float)
    e = (e - e.mean()) * np.hanning(e.size)
    nfft = int(2 ** np.ceil(np.log2(max(8, e.size * pad))))
    spec = np.abs(np.fft.rfft(e, nfft))
    return np.fft.rfftfreq(nfft, 1.0 / envelope_rate), spec


def ses_harmonic_peaks(freq: np.ndarray, spec: np.ndarray, f0: np.ndarray, search: float = 0.03,
                       harmonics=(1, 2)) -> np.ndarray:
    """SES maximum within k·f0·(1 ± search) for each f0 (rows) and k in ``harmonics`` (columns)."""
    f0 = np.atleast_1d(np.asarray(f0, float))
    df = freq[1] - freq[0]
    out = np.zeros((f0.size, len(harmonics)))
    for i, f in enumerate(f0):
        for j, k in enumerate(harmonics):
            lo = int(np.floor(k * f * (1 - search) / df))
            hi = int(np.ceil(k * f * (1 + search) / df)) + 1
            if lo < spec.size:
                out[i, j] = spec[lo:min(hi, spec.size)].max()
    return out


def cfar_ses(env: np.ndarray, envelope_rate: float, fault_hz: float, decoys_hz: np.ndarray,
             search: float = 0.03, harmonics=(1, 2)) -> tuple[float, float, float]:
    """Classical envelope-spectrum detector, CFAR-normalised like :func:`.folding.cfar_periodicity`.

    For each harmonic k, the SES peak within k·BPFO (or BPFI) · (1 ± search) is divided by
    the median of the peaks at k × the decoy frequencies; the statistic is the largest of
    these per-harmonic ratios (a fault may show mainly at its fundamental, as CWRU 105
    does, or at its harmonics, as the simulator's IR, whose impact sign follows the
    shaft angle).  Returns ``(ratio, fault_peak_at_best_harmonic, best_hz)``.
    """
    freq, spec = squared_envelope_spectrum(env, envelope_rate)
    pk = ses_harmonic_peaks(freq, spec, np.concatenate([[fault_hz], decoys_hz]), search, harmonics)
    ref = np.median(pk[1:], axis=0)
    ratios = np.where(ref > 0, pk[0] / np.where(ref > 0, ref, 1.0), 0.0)
    j = int(np.argmax(ratios))
    df = freq[1] - freq[0]
    lo, hi = int(fault_hz * (1 - search) / df), int(np.ceil(fault_hz * (1 + search) / df)) + 1
    best = freq[lo + int(np.argmax(spec[lo:hi]))] if hi <= spec.size else fault_hz
    return float(ratios[j]), float(pk[0, j]), float(best)
