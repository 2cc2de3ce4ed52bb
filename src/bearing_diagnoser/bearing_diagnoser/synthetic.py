"""Synthetic test signals with known answers: decaying-resonance bursts in white noise.

A bearing defect excites a structural resonance once per fault period (BPFO, BPFI;
thesis section 2.2, eqs. 2.53-2.54); the measured acceleration is a train of decaying
sinusoids.  These generators give inputs whose correct diagnosis is known exactly.
Units: seconds, Hz, m/s².
"""

from __future__ import annotations

import numpy as np


def burst_train(duration: float, sample_rate: float, fault_hz: float, amplitude: float = 10.0,
                resonance_hz: float = 3000.0, decay_s: float = 4e-4, jitter: float = 0.0,
                shaft_hz: float | None = None, start: float = 0.0, stop: float | None = None,
                rng: np.random.Generator | None = None, times: np.ndarray | None = None,
                depth: float = 1.0) -> np.ndarray:
    """Decaying resonance bursts at ``fault_hz`` (or at explicit ``times``), m/s².

    ``jitter`` = standard deviation of each impact time relative to the period
    (real impacts wander 0.1-0.7 ms); ``shaft_hz`` modulates the amplitude by
    (1 + cos 2π·shaft·t)/2 as an inner-race defect passing through the load zone does
    (eq. 2.58).  Bursts only between ``start`` and ``stop`` (s).
    """
    rng = rng or np.random.default_rng(0)
    n = int(round(duration * sample_rate))
    x = np.zeros(n)
    stop = duration if stop is None else stop
    if times is None:
        times = np.arange(start, stop, 1.0 / fault_hz)
        times = times + jitter / fault_hz * rng.standard_normal(times.size)
    klen = int(8 * decay_s * sample_rate)
    tk = np.arange(klen) / sample_rate
    kern = np.exp(-tk / decay_s) * np.sin(2 * np.pi * resonance_hz * tk)
    for t0 in times:
        if not start <= t0 < stop:
            continue
        i = int(round(t0 * sample_rate))
        a = amplitude
        if shaft_hz is not None:
            a *= 1.0 - depth * 0.5 * (1.0 - np.cos(2 * np.pi * shaft_hz * t0))
        seg = kern[: max(0, min(klen, n - i))]
        x[i:i + seg.size] += a * seg
    return x


def white_noise(duration: float, sample_rate: float, density: float,
                rng: np.random.Generator | None = None) -> np.ndarray:
    """White noise of one-sided density ``density`` ((m/s²)/√Hz): RMS = density·√(fs/2)."""
    rng = rng or np.random.default_rng(1)
    n = int(round(duration * sample_rate))
    return density * np.sqrt(sample_rate / 2.0) * rng.standard_normal(n)
