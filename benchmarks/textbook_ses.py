"""The textbook squared envelope spectrum (SES) of a whole record: the reference for the decision's cost.

What the published CWRU benchmark calls the plain SES (Smith & Randall 2015; diagnosis-notes.md,
round 2), on the whole record at once: in each of three fixed bands (:data:`BANDS`, all below
12 kHz' Nyquist frequency) a 4th-order Butterworth band-pass run forwards and backwards, the
analytic signal (``scipy.signal.hilbert``), the squared envelope less its mean, and its power
spectrum (one FFT). A hypothesis scores, per band, the mean over harmonics 1-3 of its fault
frequency of the peak within ±3 % of the line divided by the median within ±20 %; the best
band's score counts. No slip search beyond the ±3 %, no sidebands, no significance: the least
a diagnosis from the SES does, and so the cost a decision is compared with
(:mod:`benchmarks.decision_cost`).
"""

from __future__ import annotations

import numpy as np
from scipy import fft, signal

from bearing_common.bearings import Bearing, fault_frequency
from bearing_common.states import FaultState

#: The fixed bands (Hz).
BANDS = ((500.0, 2500.0), (2000.0, 4000.0), (3500.0, 5500.0))

#: The hypotheses scored, and their harmonics.
HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL)
HARMONICS = 3

#: Half-widths (relative) of the peak search and of the floor around each line.
PEAK, FLOOR = 0.03, 0.20


def squared_envelope_spectrum(x: np.ndarray, fs: float, band: tuple[float, float]) -> tuple[np.ndarray, float]:
    """(power spectrum of the squared envelope of ``x`` band-passed to ``band`` (Hz), its bin width (Hz))."""
    sos = signal.butter(4, band, btype="bandpass", fs=fs, output="sos")
    n = fft.next_fast_len(x.size)
    envelope = np.abs(signal.hilbert(signal.sosfiltfilt(sos, x), N=n)[:x.size]) ** 2
    spectrum = np.abs(fft.rfft(envelope - envelope.mean(), n)) ** 2
    return spectrum, fs / n


def line_ratio(spectrum: np.ndarray, df: float, line_hz: float) -> float:
    """Mean over harmonics 1-3 of ``line_hz`` of the peak within ±3 % divided by the median within ±20 %."""
    ratios = []
    for k in range(1, HARMONICS + 1):
        f = k * line_hz
        peak = spectrum[int(f * (1 - PEAK) / df):int(np.ceil(f * (1 + PEAK) / df)) + 1]
        floor = spectrum[int(f * (1 - FLOOR) / df):int(np.ceil(f * (1 + FLOOR) / df)) + 1]
        ratios.append(peak.max() / max(float(np.median(floor)), 1e-300))
    return float(np.mean(ratios))


def textbook_ses(x: np.ndarray, fs: float, rpm: float, bearing: Bearing) -> dict:
    """{hypothesis: its best band's line ratio} of the record ``x`` (m/s² at ``fs`` Hz), shaft at ``rpm``."""
    x = np.asarray(x, float)
    lines = {h: fault_frequency(bearing, h, rpm) for h in HYPOTHESES}
    best = dict.fromkeys(HYPOTHESES, 0.0)
    for band in BANDS:
        spectrum, df = squared_envelope_spectrum(x, fs, band)
        for h, f in lines.items():
            best[h] = max(best[h], line_ratio(spectrum, df, f))
    return best
