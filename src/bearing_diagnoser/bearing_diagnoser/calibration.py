"""Thresholds derived from a stated false-alarm probability on white noise.

Under noise only, the CFAR periodicity (:mod:`.periodicity`) is a ratio of two
statistics of the same stream, so its distribution does not depend on the noise level;
it depends on the window length, sample rate, band and bins.  :func:`calibrate` runs the
exact decision front end on white Gaussian noise (non-overlapping windows), fits a
normal law to log(c) (the upper tail of log c is close to normal; the empirical quantile
is used when the sample holds at least 10 exceedances) and returns the (1 − pfa)
quantile.  The kurtosis threshold of the band-passed window is derived the same way.
Both are per window and per hypothesis; the k-of-n hysteresis lowers the rate of state
changes further (see :mod:`.diag_benchmarks` for measured false alarms per hour).
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import numpy as np
from scipy import stats

N_WINDOWS = 600  #: noise windows per calibration (per hypothesis)
SEED = 20150101


def _tail_quantile(x: np.ndarray, pfa: float) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x) & (x > 0)]
    if x.size * pfa >= 10:
        return float(np.quantile(x, 1.0 - pfa))
    lx = np.log(x)
    return float(np.exp(lx.mean() + stats.norm.isf(pfa) * lx.std(ddof=1)))


@lru_cache(maxsize=32)
def _calibrate(cfg, sample_rate: float, diagnoser_cls) -> dict:
    from bearing_common.bearings import CATALOG, fault_frequency
    DRIVE_END_6205 = CATALOG["6205"]  # TODO(issue 11): bearing as input
    from bearing_common.states import FaultState
    HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE)
    c = replace(cfg, hop_s=cfg.window_s, threshold=2.0, kurtosis_threshold=1e9, k_of_n=(1, 1), rms_floor=0.0)
    dg = diagnoser_cls(c, model_set="calibration")
    dg.keep_history = False
    rng = np.random.default_rng(SEED)
    n = int(round((N_WINDOWS + 1) * cfg.window_s * sample_rate))
    y = rng.standard_normal(n)
    cf, ku = [], []
    chunk = int(sample_rate * 0.1)
    for i in range(0, n, chunk):
        for h in HYPOTHESES:
            f = fault_frequency(DRIVE_END_6205, h, cfg.nominal_rpm)
            for d in dg.update(h, i, sample_rate, y[i:i + chunk], None, None, f):
                cf += [d.scores[f"{x.label}_cfar"] for x in HYPOTHESES]
                ku.append(d.scores["kurtosis"])
    cf, ku = np.asarray(cf), np.asarray(ku)
    return {"threshold": _tail_quantile(cf, cfg.pfa), "kurtosis_threshold": _tail_quantile(ku, cfg.pfa),
            "n_windows": int(ku.size), "cfar_median": float(np.median(cf)),
            "cfar_p99": float(np.quantile(cf, 0.99)), "kurtosis_median": float(np.median(ku))}


def calibrate(cfg, sample_rate: float, diagnoser_cls) -> dict:
    """Thresholds for ``cfg`` at ``sample_rate`` (Hz) from ``cfg.pfa`` on white noise.

    Returns a dict: ``threshold`` (CFAR periodicity), ``kurtosis_threshold``,
    ``n_windows`` used, and the noise medians / 99 % points for documentation.
    Deterministic (fixed seed); cached per (configuration, rate).
    """
    key = replace(cfg, threshold=None, kurtosis_threshold=None)
    return dict(_calibrate(key, float(sample_rate), diagnoser_cls))
