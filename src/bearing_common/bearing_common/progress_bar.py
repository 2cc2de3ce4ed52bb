"""A progress line for long batches on stderr: redrawn in place on a terminal, a line per tenth in a log."""

from __future__ import annotations

import time


def _clock(seconds: float) -> str:
    """``seconds`` as h:mm:ss or m:ss."""
    m, s = divmod(int(round(seconds)), 60)
    h, m = divmod(m, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class ProgressBar:
    """Progress of ``total`` items on ``stream``, prefixed ``label``.

    ``live`` (a terminal): one line redrawn in place, cleared by :meth:`clear` before other
    output is written and drawn again by :meth:`draw`; otherwise a plain line each time another
    tenth of the items is done. The line tells items done (and failed), seconds of signal
    read, time elapsed and an estimate of the time left (from the mean time per item so far).
    """

    WIDTH = 24

    def __init__(self, total: int, stream, label: str, live: bool):
        self.total, self.stream, self.label, self.live = int(total), stream, label, live
        self.done = self.failed = 0
        self.signal_s = 0.0
        self._start = time.monotonic()
        self._tenth = 0
        self._shown = False

    def text(self) -> str:
        """The progress line (without any terminal control)."""
        frac = self.done / self.total if self.total else 1.0
        elapsed = time.monotonic() - self._start
        left = f", ~{_clock(elapsed / self.done * (self.total - self.done))} left" if 0 < self.done < self.total else ""
        failed = f" ({self.failed} failed)" if self.failed else ""
        bar = "#" * int(self.WIDTH * frac)
        return (f"{self.label} [{bar:<{self.WIDTH}}] {self.done}/{self.total} files{failed}, "
                f"{self.signal_s:.0f} s of signal, {_clock(elapsed)} elapsed{left}")

    def advance(self, signal_s: float = 0.0, failed: bool = False) -> None:
        """One more item done (``failed``: it failed), holding ``signal_s`` seconds of signal."""
        self.done += 1
        self.failed += bool(failed)
        self.signal_s += signal_s
        if self.live:
            self.draw()
        elif self.total and self.done * 10 // self.total > self._tenth:
            self._tenth = self.done * 10 // self.total
            self.stream.write(self.text() + "\n")
            self.stream.flush()

    def draw(self) -> None:
        """Draw the line again (a terminal only)."""
        if self.live:
            self.stream.write("\r" + self.text() + "\033[K")
            self.stream.flush()
            self._shown = True

    def clear(self) -> None:
        """Erase the line, so that other output starts at the line's place (a terminal only)."""
        if self.live and self._shown:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self._shown = False
