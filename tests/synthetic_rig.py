"""A synthetic rig whose fault orders are shaft harmonics, with a healthy machine's own lines (issue 25).

The bearing has 8 balls with d/D = 0.25: BPFO = 3.00× and BPFI = 5.00× the shaft rate. The
healthy machine's envelope carries the shaft's modulation at 1× and 2× and one foreign
stationary line at 5.85× (2.5 % below 2·BPFO, inside the outer-race comb's slip range) in a
1-2.5 kHz resonance; its raw spectrum a weak 1x family (1× and 2× only). A fault adds impacts
ringing at 4 kHz at its slipped rate: the outer race's, the inner race's modulated by the
shaft, the ball's (2·BSF) modulated by the cage.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, sosfiltfilt

from bearing_common.bearings import Bearing

RIG_BEARING = Bearing("8 balls, d/D 0.25", 8, 0.01, 0.04)
RIG_RATE = 20000.0
#: The foreign line's order and its modulation depth (about 7x the envelope floor in 0.5 s windows).
FOREIGN_ORDER, FOREIGN_DEPTH = 5.85, 0.3
#: The slip of each fault's impacts (fraction below the kinematic rate).
SLIP = {"outer_race": 0.015, "inner_race": 0.01, "ball": 0.01}


def rig_signal(rpm: float, duration: float, fault: str | None = None, seed: int = 0) -> np.ndarray:
    """``duration`` seconds of the rig at ``rpm`` (true speed), healthy or with ``fault`` (a state label)."""
    rng = np.random.default_rng(seed)
    n = int(RIG_RATE * duration)
    t = np.arange(n) / RIG_RATE
    fr = rpm / 60.0
    carrier = sosfiltfilt(butter(4, [1000.0, 2500.0], "bandpass", fs=RIG_RATE, output="sos"), rng.standard_normal(n))
    am = (1 + 0.35 * np.cos(2 * np.pi * fr * t) + 0.25 * np.cos(2 * np.pi * 2 * fr * t + 1)
          + FOREIGN_DEPTH * np.cos(2 * np.pi * FOREIGN_ORDER * fr * t))
    x = 0.5 * carrier / carrier.std() * am + 0.6 * rng.standard_normal(n)
    x += 3.0 * np.sin(2 * np.pi * fr * t + 1) + 1.2 * np.sin(2 * np.pi * 2 * fr * t + 2)
    if fault:
        o = RIG_BEARING.orders()
        order = {"outer_race": o.bpfo, "inner_race": o.bpfi, "ball": 2 * o.bsf}[fault] * (1 - SLIP[fault])
        times = np.arange(0.0, duration, 1.0 / (order * fr))
        times = times + rng.normal(0.0, 5e-4, times.size)
        amp = np.ones(times.size)
        if fault == "inner_race":
            amp = 1 + 0.8 * np.cos(2 * np.pi * fr * times)
        elif fault == "ball":
            amp = 1 + 0.8 * np.cos(2 * np.pi * o.ftf * fr * times)
        idx = np.clip((times * RIG_RATE).astype(int), 0, n - 1)
        impulses = np.zeros(n)
        np.add.at(impulses, idx, amp)
        k = np.arange(200)
        x += 1.5 * np.convolve(impulses, np.exp(-k / 25.0) * np.sin(2 * np.pi * 4000.0 * k / RIG_RATE))[:n]
    return x
