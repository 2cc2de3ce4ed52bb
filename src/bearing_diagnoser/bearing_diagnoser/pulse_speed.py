"""Shaft speed from tachometer pulses as they arrive (the ``shaft_pulses`` topic), without rclpy.

Each ``bearing_msgs/Tachometer`` message holds the pulses of one interval of signal time, numbered
from ``first_pulse_index``. :class:`PulseSpeed` keeps the last pulses of the stream and gives, for
each new pulse, the shaft speed there (rad/s) at the pulse's smoothed time: the local quadratic fit
of :func:`bearing_common.shaft_angle.fit_pulses` over the pulse's neighbours (the newest pulses have
only earlier ones, so their fit is one-sided). A lost message (its first pulse not the one expected),
pulses that do not follow on in time or another number of pulses per revolution begin the history
again.
"""

from __future__ import annotations

import numpy as np

from bearing_common.shaft_angle import PULSE_FIT_HALF_WIDTH, fit_pulses

#: Pulses kept behind the newest: one whole fit window.
KEPT_PULSES = 2 * PULSE_FIT_HALF_WIDTH + 1

_NONE = (np.zeros(0), np.zeros(0))


class PulseSpeed:
    """The speed at each tachometer pulse of one stream (see the module docstring).

    ``breaks`` counts the times the history began again (lost messages, times going back, another
    number of pulses per revolution).
    """

    def __init__(self):
        self._times = np.zeros(0)  # the last pulses' times (s), increasing
        self._next: int | None = None  # number of the next pulse expected
        self._per_rev: int | None = None
        self.breaks = 0

    def add(self, stamp: float, offsets, first_index: int, pulses_per_rev: int) -> tuple[np.ndarray, np.ndarray]:
        """One message: pulses at ``stamp`` + ``offsets`` (s), the first numbered ``first_index``,
        ``pulses_per_rev`` per revolution. Returns (smoothed pulse times s, speed rad/s) of its pulses
        (none until the stream has two)."""
        times = float(stamp) + np.asarray(offsets, dtype=float).ravel()
        per_rev = max(int(pulses_per_rev), 1)
        follows = self._next is None or (first_index == self._next and per_rev == self._per_rev)
        if not follows or (self._times.size and times.size and times[0] <= self._times[-1]):
            self.breaks += 1
            self._times = np.zeros(0)
        self._next, self._per_rev = int(first_index) + times.size, per_rev
        if not times.size:
            return _NONE
        if not (np.all(np.isfinite(times)) and np.all(np.diff(times) > 0.0)):
            self.breaks += 1
            self._times = np.zeros(0)
            return _NONE
        joined = np.concatenate([self._times, times])
        self._times = joined[-KEPT_PULSES:]
        if joined.size < 2:
            return _NONE
        fit_t, fit_w = fit_pulses(joined[-(KEPT_PULSES + times.size):], per_rev)
        return fit_t[-times.size:], fit_w[-times.size:]
