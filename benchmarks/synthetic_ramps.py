"""A machine changing speed, synthetic: shaft lines and bearing impacts that follow the shaft angle, a
resonance that stays put in Hz (as on a real machine, unlike a warped recording: benchmarks/speed_ramps).

The 6205 at fs = 12 kHz along a :class:`bearing_common.shaft_angle.SpeedProfile`: the shaft's harmonic series
(k = 1..8 at 0.5/k m/s²), white sensor noise (0.5 m/s² RMS), and with an outer-race fault impacts every
1/BPFO revolution (1 % slip), each ringing at 3 kHz (decay 1.5 ms, peak ``amplitude`` m/s²).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import fftconvolve

from bearing_common.bearings import CATALOG
from bearing_common.shaft_angle import SpeedProfile

RATE = 12000.0
BEARING = CATALOG["6205"]
RING_HZ, RING_DECAY_S, SLIP = 3000.0, 1.5e-3, 0.01


def ramp_signal(profile: SpeedProfile, duration: float, amplitude: float = 0.0,
                seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(acceleration m/s², shaft speed rad/s) per sample for ``duration`` s along ``profile``; outer-race
    impacts of peak ``amplitude`` (0: healthy)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(RATE * duration)) / RATE
    phi = profile.angle(t)
    x = sum(0.5 / k * np.sin(k * phi + k) for k in range(1, 9)) + 0.5 * rng.standard_normal(t.size)
    if amplitude > 0:
        order = BEARING.orders().bpfo * (1 - SLIP)
        hits = profile.time_at_angle(np.arange(0.0, phi[-1], 2 * np.pi / order) + 0.1)
        train = np.zeros(t.size)
        np.add.at(train, np.minimum((hits * RATE).astype(int), t.size - 1), 1.0)
        k = np.arange(int(8 * RING_DECAY_S * RATE)) / RATE
        x += amplitude * fftconvolve(train, np.exp(-k / RING_DECAY_S) * np.sin(2 * np.pi * RING_HZ * k))[:t.size]
    return x, profile.omega(t)
