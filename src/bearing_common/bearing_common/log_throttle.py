"""Say each kind of repeatable message at most once per period.

A node that rejects a bad chunk does it again for every following chunk; the first time is
news, the hundredth is noise. rclpy's own throttle is per call site, so one warning call
site shared by several kinds of message would let one kind silence the others: the kind is
the key here.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable


class LogThrottle:
    """``throttle(kind, level, text)`` forwards to ``log(level, text)`` at most once per ``period`` s per kind."""

    def __init__(self, log: Callable[[str, str], None], period: float = 5.0,
                 clock: Callable[[], float] = time.monotonic):
        self._log = log
        self.period = float(period)
        self._clock = clock
        self._last: dict[str, float] = {}

    def __call__(self, kind: str, level: str, text: str) -> bool:
        """Log unless ``kind`` was logged less than ``period`` ago; True when logged."""
        now = self._clock()
        if now - self._last.get(kind, -math.inf) < self.period:
            return False
        self._last[kind] = now
        self._log(level, text)
        return True
