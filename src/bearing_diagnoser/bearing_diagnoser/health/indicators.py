"""Condition indicators of one window or snapshot of acceleration (pure NumPy).

Every indicator is computed on the signal with its mean removed (an accelerometer's offset
is not vibration):

* **RMS** ``sqrt(mean(x²))`` (m/s²), **peak** ``max |x|`` (m/s²), **crest factor**
  peak / RMS (a sine: √2), **kurtosis** ``mean(x⁴) / mean(x²)²`` (Gaussian noise: 3, a sine:
  1.5; impacts raise it);
* **velocity RMS** over 10-1000 Hz (m/s; ISO 20816-3 tables are in mm/s): the acceleration
  spectrum divided by 2πf, integrated in the frequency domain over the band (Hann window,
  power normalised so that Parseval holds). The window spreads what lies at 0 Hz over the
  first two bins, so the lowest bin counted is 2·df (df = 1/T): the band's effective lower
  edge is max(10 Hz, 2/T) — **20 Hz for a 0.1 s snapshot**, 10 Hz from 0.2 s on. What a 0.1 s
  snapshot holds between 10 and 20 Hz (a 600-1200 rpm machine's shaft rate) is not resolved:
  partly lost, partly leaked into the bins above (a 15 Hz tone reads about half its velocity);
  the record states the edge used;
* **envelope RMS** in a demodulation band (m/s²): the RMS of the fluctuation of the band's
  envelope |analytic signal| about its mean — what impacts modulate; its mean is the band's
  carrier level, which RMS already tracks (Gaussian noise: 0.655 × the band's RMS).
  :func:`default_envelope_band` is the band when none is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: ISO 20816-3 velocity band (Hz), machines above 600 r/min.
VELOCITY_BAND = (10.0, 1000.0)

#: Fewest samples an indicator is computed from.
MIN_SAMPLES = 16


@dataclass(frozen=True)
class ConditionIndicators:
    """The condition indicators of one window or snapshot (units in the attribute docs).

    Attributes
    ----------
    rms, peak : float
        m/s².
    crest_factor, kurtosis : float
        Dimensionless.
    velocity_rms : float
        m/s over ``velocity_band`` (NaN when the window cannot resolve the band at all).
    velocity_band : (float, float)
        Hz, the band actually integrated (lower edge max(10 Hz, 2/T)).
    envelope_rms : float
        m/s² in ``envelope_band`` (NaN without a band).
    envelope_band : (float, float) or None
        Hz.
    duration : float
        s.
    sample_rate : float
        Hz.
    """

    rms: float
    peak: float
    crest_factor: float
    kurtosis: float
    velocity_rms: float
    velocity_band: tuple
    envelope_rms: float
    envelope_band: tuple | None
    duration: float
    sample_rate: float

    def trended(self) -> dict:
        """The indicators the trend follows, by name (:data:`.trend.TRENDED`)."""
        return {"rms": self.rms, "kurtosis": self.kurtosis, "envelope_rms": self.envelope_rms,
                "velocity_rms": self.velocity_rms}

    def to_json(self) -> dict:
        """JSON form, units in the key names (velocity in mm/s, the unit of ISO 20816 tables)."""
        out = {"rms_m_s2": self.rms, "peak_m_s2": self.peak, "crest_factor": self.crest_factor,
               "kurtosis": self.kurtosis, "velocity_rms_mm_s": self.velocity_rms * 1e3,
               "velocity_band_hz": list(self.velocity_band), "envelope_rms_m_s2": self.envelope_rms,
               "envelope_band_hz": None if self.envelope_band is None else list(self.envelope_band)}
        return {k: (_finite_or_none(v) if isinstance(v, float) else v) for k, v in out.items()}


def _finite_or_none(v: float):
    return v if math.isfinite(v) else None


def default_envelope_band(fs: float, f_top: float = 0.0) -> tuple | None:
    """The demodulation band (Hz) used when none is given: [fs/8, 3·fs/8].

    An octave and a half centred on fs/4: clear of the shaft and fault lines of ordinary
    machines below, of the anti-alias transition above (0.375·fs, inside the 0.45·fs the
    spectral decision admits); 3.2-9.6 kHz at 25.6 kHz (PRONOSTIA's accelerometers are flat
    to 10 kHz), 1.5-4.5 kHz at 12 kHz. ``f_top`` (Hz), the highest envelope frequency of
    interest (e.g. the third harmonic of the highest fault rate), raises the lower edge to
    it; None when nothing is left.
    """
    lo, hi = max(fs / 8.0, f_top), 3.0 * fs / 8.0
    return (lo, hi) if hi > lo else None


def fault_lines_top(bearing, rpm: float | None) -> float:
    """3 × the highest fault impact rate + the shaft rate (Hz) of ``bearing``
    (:class:`bearing_common.bearings.Bearing`) at ``rpm`` rev/min: the ``f_top`` of
    :func:`default_envelope_band` that keeps the fault and shaft lines out of the demodulation
    band; 0 when the speed is unknown."""
    if not rpm:
        return 0.0
    f = bearing.frequencies(rpm)
    return 3.0 * max(f.bpfo, f.bpfi, f.ball) + f.shaft


def condition_indicators(x, fs: float, envelope_band: tuple | None = None) -> ConditionIndicators:
    """Indicators of acceleration ``x`` (m/s², shape (n,)) sampled at ``fs`` Hz.

    ``envelope_band`` (Hz): the demodulation band, e.g. the spectral decision's choice;
    default :func:`default_envelope_band`. Raises ValueError on fewer than
    :data:`MIN_SAMPLES` samples or non-finite ones.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < MIN_SAMPLES:
        raise ValueError(f"need a 1-D window of at least {MIN_SAMPLES} samples, got shape {x.shape}")
    if not np.isfinite(x).all():
        raise ValueError("the window holds non-finite samples")
    x = x - x.mean()
    n = x.size
    ms = float(np.dot(x, x) / n)
    rms = math.sqrt(ms)
    peak = float(np.max(np.abs(x)))
    crest = peak / rms if rms > 0 else math.nan
    kurt = float(np.mean(x ** 4) / ms ** 2) if ms > 0 else math.nan
    spectrum = np.fft.rfft(x)
    freqs = np.fft.rfftfreq(n, 1.0 / fs)
    vel, vband = _velocity_rms(x, fs, freqs)
    band = envelope_band if envelope_band is not None else default_envelope_band(fs)
    env = _envelope_rms(spectrum, freqs, n, band) if band is not None else math.nan
    return ConditionIndicators(rms, peak, crest, kurt, vel, vband, env, band, n / fs, float(fs))


def _velocity_rms(x: np.ndarray, fs: float, freqs: np.ndarray) -> tuple:
    """RMS velocity (m/s) over the ISO band as far as the window resolves it, and that band (Hz)."""
    n = x.size
    w = np.hanning(n)
    psd = np.abs(np.fft.rfft(x * w)) ** 2 * (2.0 / (fs * np.dot(w, w)))  # one-sided, (m/s²)²/Hz
    df = fs / n
    lo, hi = max(VELOCITY_BAND[0], 2.0 * df), min(VELOCITY_BAND[1], fs / 2.0)
    sel = (freqs >= lo - 1e-9 * df) & (freqs <= hi + 1e-9 * df)
    sel[-1] &= n % 2 == 1  # the Nyquist bin of an even window has no one-sided twin
    if not sel.any():
        return math.nan, (lo, hi)
    v2 = psd[sel] / (2.0 * math.pi * freqs[sel]) ** 2
    return math.sqrt(float(v2.sum() * df)), (lo, hi)


def _envelope_rms(spectrum: np.ndarray, freqs: np.ndarray, n: int, band: tuple) -> float:
    """RMS of the band's envelope about its mean (m/s²); FFT band-pass and analytic signal."""
    sel = (freqs >= band[0]) & (freqs <= band[1])
    if sel.sum() < 2:
        return math.nan
    full = np.zeros(n, dtype=complex)
    full[: freqs.size][sel] = 2.0 * spectrum[sel]
    envelope = np.abs(np.fft.ifft(full))
    return float(np.std(envelope))
