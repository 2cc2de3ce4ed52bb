"""Shaft speed from the vibration itself: the 1× line and its harmonics in the raw spectrum.

On a buffer (Hann, one rfft) the power spectrum is normalised like the envelope spectrum
(ln 2 · P / running median, ≈ Exp(1) per bin over a smooth background) and a bin is a
*line* when it exceeds ln(N_bins / 0.01) (a 1 % chance that noise puts one line anywhere in
the spectrum). The shaft's 1× line is the strongest line of the searched range that carries
a harmonic series (it stands above its own sidebands and the neighbouring lines; the
strongest five are tried in turn). Its harmonics k = 2..K (K = 10) are
then taken in turn, each only where a line peaks within max(¾ bin, 3·k·σ) of k times the
rate fitted so far (a line of another family is not a harmonic however many there are),
and the rate is refitted after each: the least-squares slope through the origin of the
interpolated line peaks, f̂ = Σ k·f_k / Σ k², with the residual scatter (floored at the bin
quantisation) as its standard uncertainty σ. An estimate rests on at least ``min_lines``
lines, the 1× included, and on lines at half of the harmonics the buffer holds (by default).

:func:`confirm_speed` confirms a told speed where that strict series is absent (a machine
whose raw spectrum shows a weak 1x family): two of the shaft rate's first three harmonics
(:data:`CONFIRM_HARMONICS`), in the raw spectrum or in the squared envelope of the demodulation
band (the shaft's own modulation of the machine's noise), inside the told tolerance. Two lines
at exactly 1:2 inside a ±10 % range do not fall there by chance: each is a line at the 1 % level
over the whole spectrum. Higher orders confirm nothing: the k-th harmonic is searched within
3·k·σ of k times a rate that one line fixes, a range that at k = 10 spans some 15 bins, where
another family's line (a belt's, a second shaft's) is found as often as not (HIT-SM at
1200 rpm: a line of a 10.55 Hz family and one near its 10th harmonic "confirmed" 21.05 Hz for a shaft
at 20.19 Hz, and a healthy machine told 7 % fast was called INNER_RACE).

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

#: Lines of the searched range tried as the 1× line, strongest first.
N_CANDIDATES = 5

#: Harmonics that confirm a told speed (:func:`confirm_speed`): the shaft's own low orders.
CONFIRM_HARMONICS = 3

#: Chance that noise alone puts one line anywhere in the spectrum.
LINE_FALSE_ALARM = 0.01


@dataclass(frozen=True)
class SpeedEstimate:
    """Shaft rate (Hz), its standard uncertainty (Hz) and the number of harmonic lines it rests on."""

    hz: float
    sigma: float
    lines: int


def estimate_speed(x: np.ndarray, fs: float, f_lo: float, f_hi: float, min_lines: int = 3,
                   min_share: float = 0.5, harmonics: int = N_HARMONICS) -> SpeedEstimate | None:
    """Shaft rate in [f_lo, f_hi] Hz from buffer ``x`` (fs Hz); None when no harmonic series of at least
    ``min_lines`` lines, and lines at ``min_share`` of the harmonics the spectrum holds, is found among
    its first ``harmonics`` harmonics."""
    n = x.size
    power = np.abs(np.fft.rfft((x - x.mean()) * hanning(n))) ** 2
    df = fs / n
    nb = min(power.size, int(min(0.45 * fs, (N_HARMONICS + 1) * f_hi) / df) + 1)  # (one spectrum for any harmonics)
    if nb < 8 or f_hi <= f_lo:
        return None
    z = normalise(power[:nb])[0]
    line = z > np.log(nb / LINE_FALSE_ALARM)
    i_lo, i_hi = max(3, int(np.ceil(f_lo / df))), min(nb - 2, int(np.floor(f_hi / df)) + 1)
    if i_hi <= i_lo or not line[i_lo:i_hi].any():
        return None  # no 1x line in the range
    log_power = np.log(np.maximum(power[:nb], 1e-300))

    def peak(j: int) -> float:
        """Interpolated frequency (Hz) of the line peaking at bin j (parabola through log power)."""
        a, c, e = log_power[j - 1], log_power[j], log_power[j + 1]
        curvature = a - 2 * c + e
        return (j + float(np.clip(0.5 * (a - e) / curvature if curvature < 0 else 0.0, -0.5, 0.5))) * df

    strongest = i_lo + np.argsort(z[i_lo:i_hi])[::-1]
    for j in strongest[line[strongest]][:N_CANDIDATES]:  # the strongest line with a harmonic series
        found = _harmonic_series(peak(int(j)), z, line, peak, df, nb, min_lines, min_share, harmonics)
        if found is not None and f_lo <= found.hz <= f_hi:
            return found
    return None


def _harmonic_series(f1: float, z: np.ndarray, line: np.ndarray, peak, df: float, nb: int,
                     min_lines: int, min_share: float, harmonics: int) -> SpeedEstimate | None:
    """The shaft rate whose 1× line peaks at ``f1`` Hz, fitted over its harmonics (module docstring);
    None without ``min_lines`` lines and lines at ``min_share`` of the harmonics the spectrum holds."""
    orders, peaks = [1.0], [f1]
    hz, sigma = f1, df / np.sqrt(12.0)
    usable = 1
    for kk in range(2, harmonics + 1):
        b = int(np.rint(kk * hz / df))
        if b < 3 or b >= nb - 2:
            break
        usable += 1
        j = b - 1 + int(np.argmax(z[b - 1:b + 2]))
        f = peak(j)
        if not line[j] or abs(f - kk * hz) > max(0.75 * df, 3.0 * kk * sigma):
            continue
        orders.append(float(kk))
        peaks.append(f)
        o, p = np.asarray(orders), np.asarray(peaks)
        s2 = float(np.sum(o ** 2))
        hz = float(np.sum(o * p) / s2)
        scatter = float(np.sqrt(np.sum((p - o * hz) ** 2) / (o.size - 1) / s2))
        sigma = max(scatter, df / np.sqrt(12.0) / np.sqrt(s2))
    if len(orders) < max(min_lines, min_share * usable):
        return None
    return SpeedEstimate(hz, sigma, len(orders))


def confirm_speed(x: np.ndarray, fs: float, f_lo: float, f_hi: float, band: tuple[float, float] | None
                  ) -> SpeedEstimate | None:
    """Shaft rate in [f_lo, f_hi] Hz from two of its first harmonics, in the raw spectrum of ``x`` or in the squared
    envelope of its band ``band`` (Hz; None: not tried) (module docstring); None without either."""
    found = estimate_speed(x, fs, f_lo, f_hi, min_lines=2, min_share=0.0,
                          harmonics=CONFIRM_HARMONICS)
    if found is not None or band is None:
        return found
    return estimate_speed(squared_envelope(x, fs, band), fs, f_lo, f_hi, min_lines=2, min_share=0.0,
                          harmonics=CONFIRM_HARMONICS)


def squared_envelope(x: np.ndarray, fs: float, band: tuple[float, float]) -> np.ndarray:
    """|analytic signal|² of ``x`` band-passed to ``band`` (Hz), by one FFT (a brick-wall band)."""
    spectrum = np.fft.fft(x - x.mean())
    f = np.fft.fftfreq(x.size, 1.0 / fs)
    spectrum[(f < band[0]) | (f > band[1])] = 0.0  # negative frequencies go too: the analytic signal
    return np.abs(np.fft.ifft(spectrum)) ** 2
