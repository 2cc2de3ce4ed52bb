"""Shaft speed from the vibration itself: the 1× line and its harmonics in the raw spectrum.

On a buffer (Hann, one rfft) the power spectrum is normalised like the envelope spectrum
(ln 2 · P / running median, ≈ Exp(1) per bin over a smooth background) and a bin is a
*line* when it exceeds ln(N_bins / 0.01) (a 1 % chance that noise puts one line anywhere in
the spectrum). For each candidate shaft rate on a grid (step df/(2K)) the harmonics
k = 1..K (K = 10) that hit a line (±1 bin) are counted and scored by Σ_k max(0, ln z_k).
A candidate must have its own 1× line and lines at ≥ half of its first K harmonics; among
those the largest score wins. The rate is then the least-squares slope through the origin
of the interpolated line peaks, f̂ = Σ k·f_k / Σ k², with the residual scatter (floored at
the bin quantisation) as its standard uncertainty.

Use it to refine a speed that is told (a tachometer, the file, a nameplate) inside its
tolerance. Without any prior it is not reliable: measured on the development recordings,
the strongest harmonic comb in the raw spectrum is often not the shaft's — 2× on CWRU
(60 Hz mains), ½× on the HIT-SM rig at 1200 rpm, the BPFO comb itself on every HIT-SM
outer-race record — and only 13 of 34 fault records were then diagnosed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .envelope_spectrum import hanning, normalise

#: Harmonics of the shaft rate examined.
N_HARMONICS = 10

#: Chance that noise alone puts one line anywhere in the spectrum.
LINE_FALSE_ALARM = 0.01


@dataclass(frozen=True)
class SpeedEstimate:
    """Shaft rate (Hz), its standard uncertainty (Hz) and the number of harmonic lines it rests on."""

    hz: float
    sigma: float
    lines: int


def estimate_speed(x: np.ndarray, fs: float, f_lo: float, f_hi: float, min_lines: int = 3) -> SpeedEstimate | None:
    """Shaft rate in [f_lo, f_hi] Hz from buffer ``x`` (fs Hz); None when no harmonic series is found."""
    n = x.size
    power = np.abs(np.fft.rfft((x - x.mean()) * hanning(n))) ** 2
    df = fs / n
    nb = min(power.size, int(min(0.45 * fs, (N_HARMONICS + 1) * f_hi) / df) + 1)
    if nb < 8 or f_hi <= f_lo:
        return None
    z = normalise(power[:nb])[0]
    line = z > np.log(nb / LINE_FALSE_ALARM)
    near_line = line.copy()
    near_line[1:] |= line[:-1]
    near_line[:-1] |= line[1:]
    grid = np.arange(f_lo, f_hi, df / (2 * N_HARMONICS))
    k = np.arange(1, N_HARMONICS + 1)
    idx = np.rint(grid[:, None] * k[None, :] / df).astype(int)
    valid = (idx < nb - 1) & (idx > 2)
    hits = np.where(valid, near_line[np.clip(idx, 0, nb - 1)], False)
    count = hits.sum(axis=1)
    if not count.size or count.max() < min_lines:
        return None
    z_near = z.copy()
    z_near[1:] = np.maximum(z_near[1:], z[:-1])
    z_near[:-1] = np.maximum(z_near[:-1], z[1:])
    score = np.where(valid, np.log(np.maximum(z_near[np.clip(idx, 0, nb - 1)], 1.0)), 0.0).sum(axis=1)
    shaft_like = hits[:, 0] & (count >= np.maximum(min_lines, 0.5 * valid.sum(axis=1)))
    candidates = shaft_like if shaft_like.any() else count == count.max()
    f0 = grid[int(np.argmax(np.where(candidates, score, -np.inf)))]
    log_power = np.log(np.maximum(power[:nb], 1e-300))
    orders, peaks = [], []
    for kk in k:
        b = int(np.rint(kk * f0 / df))
        if b < 3 or b >= nb - 2:
            continue
        j = b - 1 + int(np.argmax(z[b - 1:b + 2]))
        if not line[j]:
            continue
        a, c, e = log_power[j - 1], log_power[j], log_power[j + 1]
        curvature = a - 2 * c + e
        offset = 0.5 * (a - e) / curvature if curvature < 0 else 0.0
        orders.append(kk)
        peaks.append((j + np.clip(offset, -0.5, 0.5)) * df)
    orders, peaks = np.asarray(orders, float), np.asarray(peaks)
    if orders.size < min_lines:
        return None
    s2 = float(np.sum(orders ** 2))
    hz = float(np.sum(orders * peaks) / s2)
    if not f_lo <= hz <= f_hi:  # the interpolated peaks moved the fit out of the searched range
        return None
    floor = df / np.sqrt(12.0) / np.sqrt(s2)
    scatter = float(np.sqrt(np.sum((peaks - orders * hz) ** 2) / (orders.size - 1) / s2)) if orders.size > 1 else 0.0
    return SpeedEstimate(hz, max(scatter, floor), int(orders.size))
