"""The envelope spectrum a report shows for a stretch of a recording, with the fault frequencies to mark.

Computed with the decision's own functions (:mod:`bearing_diagnoser.spectral.envelope_spectrum`:
prewhitening, band-pass demodulation, normalisation by the running median) over the band
the decision chose, then averaged over the stretch's non-overlapping windows: each window's
normalised squared envelope spectrum has median ≈ 1 where there is only noise, and the mean
of K windows scatters √K times less about it (Welch 1967), while a fault's lines stay. A
window is as long as the decision's, and at least 4 cage periods (the resolution the ball
hypothesis' sidebands need). Without a band from the decision (the folding front end) the
condition indicators' default band is used (:func:`.health.indicators.default_envelope_band`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..health.indicators import default_envelope_band, fault_lines_top
from ..spectral.envelope_spectrum import band_ses, normalise, window_spectrum

#: Most windows averaged for one view (evenly spread over a longer stretch).
MAX_WINDOWS = 64

#: Cage periods a window spans at least.
CAGE_PERIODS = 4.0


@dataclass
class EnvelopeView:
    """``f`` (Hz) and ``z``, the mean normalised squared envelope spectrum of ``windows`` windows of
    ``window_s`` s in ``band`` (Hz) over ``start``-``end`` (s); ``band_source`` says whose band it is;
    ``prewhitened`` whether the spectrum was levelled first (as the decision does)."""

    f: np.ndarray
    z: np.ndarray
    windows: int
    window_s: float
    band: tuple
    band_source: str
    start: float
    end: float
    prewhitened: bool


def top_frequency(orders: dict, speed_hz: float) -> float:
    """Highest envelope frequency (Hz) worth showing: 3 × the highest fault rate, its sidebands, and a margin."""
    return 1.1 * (3.0 * max(orders["bpfo"], orders["bpfi"], 2.0 * orders["bsf"]) + 1.0) * speed_hz


def envelope_view(x: np.ndarray, fs: float, start: float, end: float, speed_hz: float, orders: dict,
                  band: tuple | None, bearing, prewhiten: bool, decision_window_s: float) -> EnvelopeView | None:
    """The view (module docstring) of ``x`` (m/s² at ``fs`` Hz) over ``start``-``end`` (s), or None when
    the stretch is too short for one window of 8 envelope bins at the shown top frequency."""
    window_s = max(decision_window_s, CAGE_PERIODS / (orders["ftf"] * speed_hz))
    source = "the decision's"
    if band is None:
        band = default_envelope_band(fs, fault_lines_top(bearing, 60.0 * speed_hz))
        source = "the default (fs/8 to 3fs/8, above the fault lines)"
        if band is None:
            return None
    i0, i1 = max(0, int(round(start * fs))), min(x.size, int(round(end * fs)))
    n = min(int(round(window_s * fs)), i1 - i0)
    f_top = top_frequency(orders, speed_hz)
    if n < 2 or fs / n > f_top / 8:
        return None
    starts = np.arange(i0, i1 - n + 1, n)
    if starts.size > MAX_WINDOWS:
        starts = starts[np.linspace(0, starts.size - 1, MAX_WINDOWS).round().astype(int)]
    total = None
    for s in starts:
        ses, df = band_ses(window_spectrum(x[s:s + n], prewhiten), n, fs, np.array([band], float), f_top)
        z = normalise(ses)[0]
        total = z if total is None else total + z
    f = np.arange(total.size) * df
    keep = f <= f_top
    return EnvelopeView(f[keep], total[keep] / starts.size, int(starts.size), n / fs, tuple(map(float, band)),
                        source, i0 / fs, i1 / fs, prewhiten)


def fault_markers(orders: dict, speed_hz: float, f_top: float) -> dict:
    """{hypothesis label: [(frequency Hz, is_carrier)]} up to ``f_top`` Hz: k·BPFO; k·BPFI ± fr; 2k·BSF ± FTF,
    k = 1, 2, ... at ``speed_hz`` (kinematic, eqs. 2.51-2.54)."""
    fr = speed_hz
    k_max = int(f_top / (min(orders["bpfo"], orders["bpfi"], 2.0 * orders["bsf"]) * fr)) + 1
    ks = range(1, k_max + 1)
    out = {"outer_race": [(k * orders["bpfo"] * fr, True) for k in ks],
           "inner_race": [(k * orders["bpfi"] * fr + s * fr, s == 0) for k in ks for s in (-1, 0, 1)],
           "ball": [(2 * k * orders["bsf"] * fr + s * orders["ftf"] * fr, s == 0) for k in ks for s in (-1, 0, 1)]}
    return {h: [(f, c) for f, c in lines if 0 < f <= f_top and math.isfinite(f)] for h, lines in out.items()}
