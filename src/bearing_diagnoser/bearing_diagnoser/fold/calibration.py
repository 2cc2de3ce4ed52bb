"""Thresholds derived from a stated false-alarm probability on white noise.

Under noise only, the CFAR periodicity (:mod:`.folding`) is a ratio of two
statistics of the same stream, so its distribution does not depend on the noise level;
it depends on the window length, sample rate, band and bins.  :func:`calibrate` runs the
exact decision front end on white Gaussian noise (non-overlapping windows), fits a
normal law to log(c) (the upper tail of log c is close to normal; the empirical quantile
is used when the sample holds at least 10 exceedances) and returns the (1 − pfa)
quantile.  The kurtosis threshold of the band-passed window is derived the same way.
Both are per window and per hypothesis; the k-of-n hysteresis lowers the rate of state
changes further (``benchmarks/diag_benchmarks.py`` measures false alarms per hour).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from scipy import stats

from bearing_common.bearings import Bearing, fault_frequency

from ..decision.stream_blocks import EnergyEnvelope, StreamBlocks
from .scoring import HYPOTHESES, FoldScorer
from .settings import FoldSettings

N_WINDOWS = 600  #: noise windows per calibration (per hypothesis)
SEED = 20150101


def _tail_quantile(x: np.ndarray, pfa: float) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x) & (x > 0)]
    if x.size * pfa >= 10:
        return float(np.quantile(x, 1.0 - pfa))
    lx = np.log(x)
    return float(np.exp(lx.mean() + stats.norm.isf(pfa) * lx.std(ddof=1)))


@dataclass(frozen=True)
class Calibration:
    """Thresholds of the folding front end and the noise statistics they came from."""

    threshold: float  # CFAR periodicity
    kurtosis_threshold: float
    n_windows: int
    cfar_median: float
    cfar_p99: float
    kurtosis_median: float


@lru_cache(maxsize=32)
def _calibrate(settings: FoldSettings, pfa: float, sample_rate: float, bearing: Bearing) -> Calibration:
    scorer = FoldScorer(settings, bearing, (2.0, 1e9))
    streams = {h: StreamBlocks(EnergyEnvelope(sample_rate, settings.band)) for h in HYPOTHESES}
    fault_hz = {h: fault_frequency(bearing, h, settings.nominal_rpm) for h in HYPOTHESES}
    rng = np.random.default_rng(SEED)
    y = rng.standard_normal(int(round((N_WINDOWS + 1) * settings.window_s * sample_rate)))
    for st in streams.values():
        st.push(0, y, y, np.zeros_like(y))
    env = next(iter(streams.values())).env
    fe = env.envelope_rate
    w = max(1, int(round(settings.window_s * fe)))
    cf, ku = [], []
    for b0 in range(0, min(st.n_blocks for st in streams.values()) - w + 1, w):
        wins = {h: st.window(b0, b0 + w) for h, st in streams.items()}
        scores = scorer.scores(wins, fault_hz, dict.fromkeys(HYPOTHESES, False), env.decimation, b0, fe)
        cf += [scores.cfar[h] for h in HYPOTHESES]
        ku.append(scores.kurtosis)
    cf, ku = np.asarray(cf), np.asarray(ku)
    return Calibration(_tail_quantile(cf, pfa), _tail_quantile(ku, pfa), int(ku.size), float(np.median(cf)),
                       float(np.quantile(cf, 0.99)), float(np.median(ku)))


def calibrate(settings: FoldSettings, pfa: float, sample_rate: float, bearing: Bearing) -> Calibration:
    """Thresholds of ``settings`` at ``sample_rate`` (Hz) for false-alarm probability ``pfa``
    per window and hypothesis on white noise. Deterministic (fixed seed); cached."""
    key = replace(settings, threshold=None, kurtosis_threshold=None)
    return _calibrate(key, float(pfa), float(sample_rate), bearing)
