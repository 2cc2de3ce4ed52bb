"""Signal statistics of the decision: energy envelope, folding periodicity, thesis cross-correlation.

Three blocks, each usable on its own (thesis section 3.2 and ``diagnosis-notes.md``):

* :class:`EnergyEnvelope` — streaming band-pass (Butterworth, order 4) of the
  measurement, squared and block-averaged to an envelope rate near 4 kHz.  Units: the
  envelope is a mean square, (m/s²)².  Block sums of y, y², y⁴, r², |r|·u, ... are kept
  alongside so a window's RMS, kurtosis and "model explains" fraction cost nothing.
* :func:`folded_peakiness` / :func:`cfar_periodicity` — the decision statistic: the
  envelope folded at a candidate period (phase searched implicitly by the bins, period
  searched ±3 % for slip and speed error), peakiness = (max − mean)/mean of the folded
  profile, divided by the mean peakiness at "decoy" periods where no bearing line lies
  (CFAR normalisation).  Dimensionless; ≈ 1 on noise.
* :func:`train_cross_correlation` / :func:`train_autocorrelation` — the thesis' literal
  statistic (section 3.2, Figs. 3.7-3.12): cross-correlation of |residual| with the
  impulse train, FFT-based, with the train's autocorrelation as reference.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import signal

from . import kernels

#: Target envelope sample rate (Hz): enough for folding at BPFI (≈ 162 Hz) with 16 bins.
ENVELOPE_RATE = 4000.0

#: Lags 0..this (s) of the thesis-literal correlation of |r| with the train: the observer's
#: impulse response follows its impulse within a couple of milliseconds.
XCORR_LAG_S = 2e-3


def envelope_decimation(sample_rate: float, envelope_rate: float = ENVELOPE_RATE) -> int:
    """Integer block length D so that sample_rate / D is close to ``envelope_rate``."""
    return max(1, int(round(sample_rate / envelope_rate)))


class EnergyEnvelope:
    """Streaming band-pass energy envelope with per-block sums.

    Parameters
    ----------
    sample_rate : float
        Input rate (Hz).
    band : (lo, hi) or None
        Pass band (Hz) of the order-4 Butterworth band-pass; ``hi`` is clipped below
        0.45 · sample_rate. None: no envelope, only the block sums.
    decimation : int, optional
        Block length D (samples) of the envelope; default from :func:`envelope_decimation`.

    Each call to :meth:`push` returns a dict of arrays, one entry per completed block
    (:attr:`keys`): ``env`` = mean of the squared band-passed signal ((m/s²)²), ``b4`` = mean
    of its fourth power, and the raw sums ``y``, ``y2``, ``r2``, ``ar``, ``u`` (of y, y², r²,
    |r|, u) used for RMS, the model-explains fraction and the thesis-literal correlation.
    Samples that do not fill a block are carried over.
    """

    SUMS = ("y", "y2", "r2", "ar", "u")

    def __init__(self, sample_rate: float, band: tuple[float, float] | None, decimation: int | None = None):
        if sample_rate <= 0:
            raise ValueError(f"sample_rate must be > 0, got {sample_rate}")
        self.sample_rate = float(sample_rate)
        self.decimation = int(decimation or envelope_decimation(sample_rate))
        self.band = None
        self._sos = None
        if band is not None:
            lo, hi = float(band[0]), min(float(band[1]), 0.45 * sample_rate)
            if not 0 < lo < hi:
                raise ValueError(f"invalid band {band} at {sample_rate} Hz")
            self.band = (lo, hi)
            self._sos = signal.butter(4, [lo, hi], btype="bandpass", fs=sample_rate, output="sos")
            self._zi = np.zeros((self._sos.shape[0], 2))
        self.keys = (("env", "b4") if self._sos is not None else ()) + self.SUMS
        self._carry: tuple | None = None  # (y, r, u, b) of a partial block, if any

    @property
    def envelope_rate(self) -> float:
        """Envelope (block) rate in Hz."""
        return self.sample_rate / self.decimation

    def fresh(self) -> EnergyEnvelope:
        """A new envelope of the same rate, band and block length (filter and blocks restarted)."""
        return EnergyEnvelope(self.sample_rate, self.band, self.decimation)

    def push(self, y: np.ndarray, residual: np.ndarray | None = None,
             train: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Feed measurement ``y`` (and optionally residual and train, same length)."""
        return dict(zip(self.keys, self.blocks(y, residual, train)))

    def completed(self, n: int) -> int:
        """How many blocks ``n`` more samples complete."""
        return (n + (0 if self._carry is None else self._carry[0].size)) // self.decimation

    def blocks(self, y: np.ndarray, residual: np.ndarray | None = None,
               train: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
        """As :meth:`push`, as one array of shape (len(:attr:`keys`), completed blocks), written
        into ``out`` when given (of that shape, :meth:`completed` blocks)."""
        y = np.asarray(y, dtype=float)
        r = y if residual is None else np.asarray(residual, dtype=float)
        u = np.zeros_like(y) if train is None else np.asarray(train, dtype=float)
        b = y
        if self._sos is not None:
            b = np.empty_like(y)
            kernels.sos_filter(self._sos, self._zi, y, b)
        if self._carry is not None:
            y, r, u, b = (np.concatenate(p) for p in zip(self._carry, (y, r, u, b)))
        d = self.decimation
        n = (y.size // d) * d
        self._carry = (y[n:].copy(), r[n:].copy(), u[n:].copy(), b[n:].copy()) if n < y.size else None
        out = np.empty((len(self.keys), n // d)) if out is None else out
        kernels.block_sums(y, r, u, b, d, out)
        return out


def period_grid(fault_hz: float, window_s: float, bins: int, search: float = 0.03) -> np.ndarray:
    """Relative frequency factors searched around a nominal frequency (dimensionless).

    The step keeps the phase drift over the window below one bin: step = 1/(bins · N)
    with N = fault_hz · window_s periods in the window; the grid spans ±``search``
    (default 3 %, slip 1-2 % plus speed error).  The same factors are used at the decoy
    frequencies so fault and decoy statistics see the same number of trials.
    """
    n_periods = max(1.0, fault_hz * window_s)
    step = 1.0 / (bins * n_periods)
    half = max(1, int(np.ceil(search / step)))
    return 1.0 + np.linspace(-search, search, 2 * half + 1)


@lru_cache(maxsize=64)
def _fold_table(freqs: tuple, n: int, envelope_rate: float, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Phase bins of ``n`` envelope samples at each frequency: the folding, precomputed.

    Sample t (t / envelope_rate s from the window's first sample) falls at frequency f (Hz)
    in bin floor(frac(t·f)·bins). Returns ``offsets`` (n, len(freqs)): row f's bin plus
    f · bins (uint16 when that fits: the table stays in the L1 cache), and ``inv``
    (len(freqs) · bins,): 1 / the samples per bin (1 for an empty bin). Phase is measured
    from the window's first sample: the maximum over bins (the phase search) does not
    depend on the origin, and the table serves window after window while the frequencies
    stay the same.
    """
    f = np.asarray(freqs, float)
    t = np.arange(n) / envelope_rate
    idx = np.minimum(((np.outer(f, t) % 1.0) * bins).astype(np.int64), bins - 1)
    rows = idx + (np.arange(f.size) * bins)[:, None]
    inv = 1.0 / np.maximum(np.bincount(rows.ravel(), minlength=f.size * bins).astype(float), 1.0)
    offsets = np.ascontiguousarray(rows.T.astype(np.uint16 if f.size * bins <= 1 << 16 else np.int64))
    offsets.setflags(write=False)
    inv.setflags(write=False)
    return offsets, inv


def folded_peakiness(env: np.ndarray, envelope_rate: float, freqs: np.ndarray,
                     first_block: int = 0, bins: int = 16, smooth: int = 2) -> np.ndarray:
    """Peakiness of the envelope folded at each frequency in ``freqs``.

    For each f, envelope sample n (time t = n / rate from the window start) goes to bin
    floor(frac(t·f)·bins); the profile is the bin means, circularly averaged over
    ``smooth`` adjacent bins (an impact may straddle two bins).  Peakiness =
    (max − mean)/mean of the profile: 0 for a flat profile, ≈ bins/smooth − 1 for one
    impact per period.  The maximum over bins is the phase search.  ``first_block`` is
    accepted for symmetry with absolute-time callers and does not change the result
    beyond the bin origin.

    Returns an array of shape (len(freqs),), dimensionless.
    """
    env = np.ascontiguousarray(env, dtype=float)
    freqs = np.atleast_1d(np.asarray(freqs, dtype=float))
    if env.size == 0:
        return np.zeros(freqs.size)
    offsets, inv = _fold_table(tuple(np.round(freqs, 9)), env.size, float(envelope_rate), int(bins))
    return kernels.fold_peakiness(env, offsets, inv, int(bins), int(smooth))


class FoldBank:
    """The CFAR periodicity of windows of ``n`` envelope samples at one fault frequency.

    Fault and decoy frequencies (Hz) times the relative ``grid`` are folded with one
    precomputed table (:func:`_fold_table`), so that a window costs one compiled pass
    (:func:`.kernels.cfar_fold`). See :func:`cfar_periodicity`.
    """

    def __init__(self, fault_hz: float, decoys_hz: np.ndarray, grid: np.ndarray, n: int, envelope_rate: float,
                 bins: int = 16):
        freqs = np.concatenate([[fault_hz], np.asarray(decoys_hz, float)])
        allf = (freqs[:, None] * grid[None, :]).ravel()
        self.fault_hz, self.grid, self.bins = fault_hz, grid, int(bins)
        self._offsets, self._inv = _fold_table(tuple(np.round(allf, 9)), n, float(envelope_rate), self.bins)

    def cfar(self, env: np.ndarray) -> tuple[float, float, float]:
        """``(ratio, fault_peakiness, best_hz)`` of one window's envelope, a contiguous float
        array (:func:`cfar_periodicity`)."""
        ratio, peak, j = kernels.cfar_fold(env, self._offsets, self._inv, self.grid.size, self.bins, 2)
        return ratio, peak, float(self.fault_hz * self.grid[j])


def cfar_periodicity(env: np.ndarray, envelope_rate: float, fault_hz: float,
                     decoys_hz: np.ndarray, grid: np.ndarray, first_block: int = 0,
                     bins: int = 16) -> tuple[float, float, float]:
    """CFAR-normalised periodicity at ``fault_hz``.

    Returns ``(ratio, fault_peakiness, best_hz)``: ratio = max over the grid of the
    peakiness (:func:`folded_peakiness`) at ``fault_hz · grid`` divided by the median over
    decoys of the same max at ``decoy · grid`` (dimensionless, ≈ 1 on noise, ≫ 1 for
    impacts at the fault period; 0 when that median is not positive); best_hz = the
    searched frequency that maximised the peakiness.
    """
    env = np.ascontiguousarray(env, dtype=float)
    return FoldBank(fault_hz, decoys_hz, grid, env.size, envelope_rate, bins).cfar(env)


def train_autocorrelation(train: np.ndarray) -> np.ndarray:
    """Autocorrelation of the impulse train (thesis Figs. 3.7-3.8), FFT-based, full length.

    Returns 2·N − 1 values, lag −(N−1)..N−1, normalised to 1 at lag 0.
    """
    u = np.asarray(train, dtype=float)
    ac = signal.correlate(u, u, mode="full", method="fft")
    peak = ac[u.size - 1]
    return ac / peak if peak > 0 else ac


def train_cross_correlation(residual: np.ndarray, train: np.ndarray) -> np.ndarray:
    """Cross-correlation of |residual| with the impulse train (thesis section 3.2, Figs. 3.9-3.12).

    FFT-based, full length (lag −(N−1)..N−1), normalised by ‖|r|‖·‖u‖ so a residual made
    of the train itself gives the train autocorrelation (dimensionless).
    """
    a = np.abs(np.asarray(residual, dtype=float))
    u = np.asarray(train, dtype=float)
    xc = signal.correlate(a, u, mode="full", method="fft")
    norm = np.linalg.norm(a) * np.linalg.norm(u)
    return xc / norm if norm > 0 else xc


def train_correlation(abs_residual_blocks: np.ndarray, train_blocks: np.ndarray, max_lag: float) -> float:
    """Thesis-literal score of one window: max Pearson correlation of |r| with u over lags.

    Both inputs are per-block sums (same blocks as the envelope); lags 0..``max_lag``
    blocks (at most n − 3) with |r| lagging u (the observer's impulse response follows the
    impulse): x = a[k:], z = u[:n − k]. Returns a value in [−1, 1] (0 when the train is
    empty; lags where either part is constant are skipped; floored at 0 when lag 0 is).
    """
    a = np.ascontiguousarray(abs_residual_blocks, dtype=float)
    u = np.ascontiguousarray(train_blocks, dtype=float)
    n = min(a.size, u.size)
    last = min(int(max(0, max_lag)), n - 3)
    if last < 0:
        return 0.0
    return float(kernels.train_correlation(a[:n], u[:n], last))


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
    """Classical envelope-spectrum detector, CFAR-normalised like :func:`cfar_periodicity`.

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


def impact_phase_mask(env: np.ndarray, envelope_rate: float, freq: float, first_block: int = 0,
                      bins: int = 16, smooth: int = 2, margin: int = 1) -> np.ndarray:
    """Boolean mask of the envelope samples at the impact phase of period 1/``freq``.

    Folds ``env`` at ``freq``, finds the peak of the (smoothed) profile and marks every
    sample whose phase lies in the peak's ``smooth`` bins widened by ``margin`` bins on
    each side.  Used to "explain away" one hypothesis before testing the other: IR
    impacts folded at the OR period fall into three phase clusters (BPFI/BPFO ≈ 1.51, so
    2·BPFI ≈ 3·BPFO, 0.7 % apart) and would otherwise look periodic at BPFO too.
    """
    return kernels.impact_phase_mask(np.ascontiguousarray(env, dtype=float), float(envelope_rate), float(freq),
                                     int(bins), int(smooth), int(margin))


def explain_away(env: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Copy of ``env`` with the masked samples replaced by the median of the others."""
    return kernels.explain_away(np.ascontiguousarray(env, dtype=float), np.ascontiguousarray(mask, dtype=bool))
