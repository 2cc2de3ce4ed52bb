"""Squared envelope spectrum (SES) of one window, by frequency-domain band-pass and decimation.

One FFT of the window gives both the prewhitened spectrum and the band-pass:

* **cepstral prewhitening** (Borghesani et al. 2013): every spectral magnitude set to one,
  X/|X|, phase kept. It removes the discrete lines (shaft harmonics, electrical lines)
  and the resonance colouring at once, has no order or parameter to choose, and costs
  nothing here because the band-pass uses the same FFT. Chosen over the residual of a
  linear-prediction model of the healthy machine (an observer in the thesis' sense), which
  needs a model order, a fit buffer and a healthy reference that a machine never seen does
  not have;
* the positive-frequency bins of the band [f_lo, f_hi] are inverse-transformed on their
  own: the complex envelope of the band, decimated to B = f_hi − f_lo samples per second;
* SES = |rfft(Hann · (|c|² − mean))|², bin width 1/T (T = window length), no zero
  padding, so the bins are nearly independent.

Normalisation: each bin × ln 2 / the running median over 2·N_MED + 1 = 101 bins. Under
Gaussian noise an SES bin is exponential, so the normalised bin is Exp(1) up to the
median's own scatter (accounted for exactly in :mod:`.significance`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .running_median import median_line

#: Half-width (bins) of the running median that normalises the SES.
N_MED = 50


@lru_cache(maxsize=128)
def hanning(n: int) -> np.ndarray:
    """``np.hanning(n)``, read-only and cached (the speed and band buffers reuse a few lengths)."""
    w = np.hanning(n)
    w.setflags(write=False)
    return w


@lru_cache(maxsize=128)
def hann(n: int) -> np.ndarray:
    """Hann taper of ``n`` points without its zero end points (read-only, cached)."""
    w = np.hanning(n + 2)[1:-1]
    w.setflags(write=False)
    return w


def unit_magnitude(X: np.ndarray) -> np.ndarray:
    """Cepstral prewhitening of a spectrum: X/|X|, phase kept, zeros stay zero."""
    mag = np.abs(X)
    return np.where(mag > 0, X / np.where(mag > 0, mag, 1.0), 0.0)


def window_spectrum(x: np.ndarray, prewhiten: bool = True) -> np.ndarray:
    """rfft of the mean-removed window, prewhitened (:func:`unit_magnitude`) when ``prewhiten``."""
    X = np.fft.rfft(x - x.mean())
    return unit_magnitude(X) if prewhiten else X


def band_bins(X: np.ndarray, n: int, fs: float, bands: np.ndarray) -> np.ndarray:
    """The bins of each band of ``bands`` ((m, 2) (f_lo, f_hi) in Hz, one width, at least 8 bins) in
    the window spectrum ``X`` (rfft of ``n`` samples), one row each (m, width): from the bin of f_lo on,
    indices beyond X's ends clipped to them. Rows inside X are sliced (a copy each), not gathered."""
    df_x = fs / n
    first = np.rint(bands[:, 0] / df_x).astype(int)
    width = max(8, int(np.rint((bands[0, 1] - bands[0, 0]) / df_x)))
    if first.min() < 0 or first.max() + width > X.size:
        return X[np.clip(first[:, None] + np.arange(width)[None, :], 0, X.size - 1)]
    out = np.empty((first.size, width), dtype=X.dtype)
    for row, k in enumerate(first):
        out[row] = X[k:k + width]
    return out


def band_ses(X: np.ndarray, n: int, fs: float, bands: np.ndarray, f_max: float | None = None):
    """SES of bands of equal width from one window spectrum ``X`` (rfft of ``n`` samples).

    ``bands``: (m, 2) array of (f_lo, f_hi) in Hz, all of one width. Returns
    ``(ses (m, n_bins), df)`` with df = fs/n the SES bin width (Hz); bins above ``f_max``
    (plus the median's half-width) are dropped.
    """
    bands = np.atleast_2d(bands)
    df_x = fs / n
    env = np.abs(np.fft.ifft(band_bins(X, n, fs, bands), axis=1)) ** 2
    width = env.shape[1]
    env -= env.mean(axis=1, keepdims=True)
    spectrum = np.fft.rfft(env * hann(width), axis=1)
    if f_max is not None:  # cut before squaring: the bins dropped are not worth their magnitude
        spectrum = spectrum[:, : int(np.ceil(f_max / df_x)) + N_MED + 2]
    return np.abs(spectrum) ** 2, df_x


def band_kurtosis(X: np.ndarray, n: int, fs: float, bands: np.ndarray) -> np.ndarray:
    """Spectral kurtosis of each band's complex envelope, <|c|⁴>/<|c|²>² − 2 (0 for Gaussian noise;
    the kurtogram's criterion, Antoni 2007), from one window spectrum as in :func:`band_ses`."""
    env = np.abs(np.fft.ifft(band_bins(X, n, fs, np.atleast_2d(bands)), axis=1)) ** 2
    mean = env.mean(axis=1)
    return (env ** 2).mean(axis=1) / np.maximum(mean, 1e-300) ** 2 - 2.0


def normalise(ses: np.ndarray, stride: int = 8, level: float = np.log(2.0)) -> np.ndarray:
    """``level`` · SES / running median over 2·N_MED + 1 bins (last axis), shape kept.

    ``level`` is the median of one bin's null law, so that a normalised bin has median ≈ 1:
    ln 2 for a window's SES (Exp(1)), med_K for the average of K windows' (Gamma(K, 1/K),
    :func:`.significance.averaged_median`).

    The median is evaluated every ``stride`` bins (each a median of 101 neighbouring
    bins, the same law as the exact running median) and interpolated linearly, by
    :func:`.running_median.median_line` (compiled, sliding a sorted window: the values
    ``np.partition`` and ``np.interp`` gave, bit for bit). The ends are padded by reflection
    (:func:`_reflect`).
    """
    ses = np.atleast_2d(ses)
    n = ses.shape[-1]
    padded = _reflect(ses) if n > N_MED else np.pad(ses, ((0, 0), (N_MED, N_MED)), mode="edge")
    line = median_line(np.ascontiguousarray(padded, dtype=float), n, stride, N_MED)
    return level * ses / np.maximum(line, 1e-300)


def _reflect(ses: np.ndarray) -> np.ndarray:
    """``np.pad(ses, ((0, 0), (N_MED, N_MED)), mode="reflect")`` (more than N_MED bins), without its
    general machinery."""
    return np.concatenate([ses[:, N_MED:0:-1], ses, ses[:, -2:-N_MED - 2:-1]], axis=1)
