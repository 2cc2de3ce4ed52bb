"""When windows are due: a sliding window over stream indices, not over chunks.

Windows are [end − window, end) with ends at origin + window + k·hop, in the stream's own
index (samples, or envelope blocks), so that the same signal gives the same windows however
it is chunked. A front end owns one schedule: the fold's never changes size and jumps over
what no stream holds; the spectral one resizes with the shaft speed and restarts at a gap.
"""

from __future__ import annotations


class WindowSchedule:
    """The next window's end, for windows of ``window`` indices every ``hop``, from ``origin``.

    ``next_end`` is None until :meth:`start` (the spectral schedule starts once a speed is known).
    """

    def __init__(self, origin: int = 0, window: int = 0, hop: int = 0):
        self.origin = origin
        self.window = window
        self.hop = hop
        self.next_end: int | None = None

    def restart(self, origin: int) -> None:
        """A new schedule from ``origin`` (a gap, a restarted stream), not started yet."""
        self.origin = origin
        self.next_end = None

    def start(self) -> None:
        """The first window ends one window after the origin."""
        self.next_end = self.origin + self.window

    @property
    def next_start(self) -> int:
        """Start of the next window."""
        return self.next_end - self.window

    def advance(self) -> None:
        """The window ending at ``next_end`` was decided: the next ends one hop later."""
        self.next_end += self.hop

    def skip_to(self, first: int) -> None:
        """Go to the first window starting at or after index ``first`` (nothing before it is held)."""
        k = -(-(first - self.origin) // self.hop)
        self.next_end = self.origin + k * self.hop + self.window
