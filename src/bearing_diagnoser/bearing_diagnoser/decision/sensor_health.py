"""Is the accelerometer signal fit to diagnose at all? Sensor problems, per analysis window.

A dead, disconnected, clipped or coarsely quantised sensor gives a signal that envelope
analysis would read as a healthy bearing (a flat line has no impacts) or as a faulty one (a
clipped or square-wave signal is all "impacts"). Such windows are reported as a sensor
problem and not diagnosed. The checks are scale-free (no units needed):

* **flat** — the window's standard deviation is zero, or below 1e-9 of its mean level
  (a stuck or disconnected channel, an ADC holding one code);
* **quantised** — fewer than :data:`MIN_LEVELS` distinct values: with 16 levels the
  quantisation noise is already -24 dB of a full-scale sine and impacts are lost in it;
* **clipped** — more than :data:`MAX_CLIPPED` of the samples sit exactly at the window's
  maximum or minimum (a real signal touches its extreme once; a saturated amplifier sits
  there for runs of samples; a rail-to-rail square wave almost always).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Fewest distinct sample values a diagnosable window holds.
MIN_LEVELS = 16

#: Largest share of samples allowed at the window's extreme values.
MAX_CLIPPED = 0.01


@dataclass(frozen=True)
class SensorCheck:
    """Result of :func:`check_window`: ``problem`` is "" when the signal is fit to diagnose."""

    problem: str
    rms: float
    levels: int
    clipped: float

    @property
    def ok(self) -> bool:
        return not self.problem


def check_window(x: np.ndarray) -> SensorCheck:
    """Check one window of raw samples (any unit) for a sensor problem."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return SensorCheck("no samples", 0.0, 0, 0.0)
    mean = float(np.mean(x))
    std = float(np.std(x))
    rms = float(np.sqrt(mean * mean + std * std))
    levels = int(np.unique(x).size)
    hi, lo = float(np.max(x)), float(np.min(x))
    clipped = float(np.count_nonzero((x == hi) | (x == lo)) / x.size)
    if std == 0.0 or std < 1e-9 * abs(mean):
        problem = f"flat signal (standard deviation {std:.3g}, level {mean:.3g}): sensor dead or disconnected"
    elif clipped >= 0.5:
        problem = (f"signal at its rails: {100 * clipped:.0f} % of the samples at {lo:.3g} or {hi:.3g} "
                   "(saturated sensor or a square wave, not vibration)")
    elif levels < MIN_LEVELS and x.size >= 4 * MIN_LEVELS:
        problem = f"signal quantised to {levels} levels (fewer than {MIN_LEVELS}): gain or ADC resolution too low"
    elif clipped > MAX_CLIPPED:
        problem = (f"signal clipped: {100 * clipped:.1f} % of the samples at its extremes "
                   f"({lo:.3g}, {hi:.3g}): sensor or amplifier saturated")
    else:
        problem = ""
    return SensorCheck(problem, rms, levels, clipped)
