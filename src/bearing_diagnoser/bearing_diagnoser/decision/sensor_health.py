"""Is the accelerometer signal fit to diagnose at all? Sensor problems, per analysis window.

A dead, disconnected, clipped or coarsely quantised sensor gives a signal that envelope
analysis would read as a healthy bearing (a flat line has no impacts) or as a faulty one (a
clipped or square-wave signal is all "impacts"). Such windows are reported as a sensor
problem and not diagnosed. The checks are scale-free (no units needed):

* **non-finite** — any sample NaN or infinite (an acquisition that marks dropouts or
  overflows so; no spectrum is defined);
* **flat** — the window's standard deviation is zero, or below 1e-9 of its mean level
  (a stuck or disconnected channel, an ADC holding one code);
* **quantised** — fewer than :data:`MIN_LEVELS` distinct values: with 16 levels the
  quantisation noise is already -24 dB of a full-scale sine and impacts are lost in it;
* **clipped** — more than :data:`MAX_CLIPPED` of the samples sit exactly at the window's
  maximum or minimum (a real signal touches its extreme once; a saturated amplifier sits
  there for runs of samples; a rail-to-rail square wave almost always).

:class:`SensorWatch` keeps a measurement's recent samples for a front end that decides from
reduced blocks (the fold), so that its windows get the same check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bearing_common.chunk_stream import StreamCursor
from bearing_common.indexed_buffer import IndexedBuffer

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
    n = x.size
    if n == 0:
        return SensorCheck("no samples", 0.0, 0, 0.0)
    s = np.sort(x)  # one sort gives the extremes, their counts and the levels (NaN sorts last, -inf first)
    lo, hi = float(s[0]), float(s[-1])
    if not (math.isfinite(lo) and math.isfinite(hi)):
        bad = int(np.count_nonzero(~np.isfinite(s)))
        return SensorCheck(f"{bad} of {n} samples not finite (NaN or infinite): acquisition fault", math.nan, 0, 0.0)
    mean = float(np.mean(x))
    std = float(np.std(x))
    rms = float(np.sqrt(mean * mean + std * std))
    levels = 1 + int(np.count_nonzero(s[1:] != s[:-1]))
    at_rails = int(np.searchsorted(s, lo, "right")) + n - int(np.searchsorted(s, hi, "left"))
    clipped = float((at_rails - (n if hi == lo else 0)) / n)
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


class SensorWatch:
    """The recent samples of one measurement, by stream index, to check the windows decided on it.

    Every observer stream carries the same measurement y = r + ŷ: the first stream to bring a
    sample wins, a later copy of it is skipped. A start or a gap begins afresh (a window that
    reaches before it can no longer be checked).
    """

    def __init__(self):
        self._samples = IndexedBuffer()
        self._cursor = StreamCursor()

    def push(self, first_index: int, y: np.ndarray) -> None:
        """Samples ``y`` from stream index ``first_index``."""
        offset = self._cursor.offset(first_index)
        if offset is None or offset > 0:
            self._samples.clear(first=first_index)
        elif offset < 0:  # seen already, in part or whole
            y, first_index = y[-offset:], first_index - offset
        if y.size:
            self._samples.append(y)
            self._cursor.advance(first_index, y.size)

    def check(self, i0: int, i1: int) -> SensorCheck | None:
        """:func:`check_window` of samples [i0, i1); None when they are not all held."""
        x = self._samples.view(i0, i1)
        return None if x is None else check_window(x[0])

    def trim(self, keep_from: int) -> None:
        """Forget the samples before index ``keep_from``."""
        self._samples.trim(keep_from)
