"""When the simulator node publishes (no rclpy): the start gate and wall-clock pacing.

* :class:`SubscriberGate` — ``wait_for_subscribers``: hold the start until every listed
  topic has its count of subscribers (published chunks are not latched), at most
  ``subscriber_timeout`` s.
* :class:`Pacer` — keeps the simulated time in step with wall-clock time when
  ``realtime`` (switchable while running) and accounts the compute real-time factor.

Times are monotonic wall-clock seconds passed in by the caller, so tests need no clock.
"""

from __future__ import annotations

from collections.abc import Callable


class SubscriberGate:
    """Open once each ``(topic, count)`` of ``wanted`` is matched, or ``timeout`` s after ``now``."""

    def __init__(self, wanted: list, timeout: float, now: float):
        self.wanted = list(wanted)
        self.deadline = now + timeout

    def missing(self, count: Callable[[str], int]) -> list:
        """[(topic, wanted, have)] not yet matched; ``count(topic)`` gives the subscriber count."""
        have = [(topic, n, count(topic)) for topic, n in self.wanted]
        return [entry for entry in have if entry[2] < entry[1]]

    def is_open(self, count: Callable[[str], int], now: float) -> bool:
        return now >= self.deadline or not self.missing(count)


class Pacer:
    """Simulated time against wall-clock time, and the compute spent on it.

    ``ahead(now)`` is how far the published signal runs ahead of real time (s; wait
    that long before the next chunk), 0 when not paced. Switching ``realtime`` on
    restarts the pacing from that instant: no catch-up burst, no long wait.
    The compute real-time factor is simulated seconds per CPU second spent producing
    them (not lowered by other processes sharing the cores).
    """

    def __init__(self, realtime: bool, report_period: float = 5.0):
        self.realtime = realtime
        self.report_period = report_period  # s between reports
        self.simulated = 0.0  # s of signal produced
        self.busy = 0.0  # CPU s spent producing it
        self._origin = (0.0, 0.0)  # (wall s, simulated s) at which pacing (re)started
        self._last_report = 0.0

    def start(self, now: float) -> None:
        self._origin = (now, self.simulated)
        self._last_report = now

    def set_realtime(self, realtime: bool, now: float) -> None:
        self.realtime = realtime
        self._origin = (now, self.simulated)

    def chunk_done(self, seconds: float, busy: float) -> None:
        """Account a chunk of ``seconds`` of signal that took ``busy`` CPU seconds."""
        self.simulated += seconds
        self.busy += busy

    def ahead(self, now: float) -> float:
        if not self.realtime:
            return 0.0
        wall0, sim0 = self._origin
        return (self.simulated - sim0) - (now - wall0)

    @property
    def realtime_factor(self) -> float:
        return self.simulated / max(self.busy, 1e-9)

    def report(self, now: float) -> str | None:
        """A progress line once per ``report_period``, else None."""
        if now - self._last_report < self.report_period:
            return None
        self._last_report = now
        return f"simulated {self.simulated:.2f} s; compute real-time factor {self.realtime_factor:.2f}"
