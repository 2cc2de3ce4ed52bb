"""Stop a process cleanly on SIGINT (Ctrl-C) or SIGTERM (no rclpy).

The handlers only record the first signal; the process's loops poll the flag and
wind down in their own time, so no KeyboardInterrupt or context shutdown strikes
in the middle of a publish or a clean-up. Further signals while stopping are
ignored: a terminal Ctrl-C under ``ros2 launch`` reaches a node twice (from the
terminal and from launch), and the second must not cut the clean-up short. For
the same reason, once a stop was requested, leaving the ``with`` block makes the
signals ignored until the process exits (Python resets its own handlers to the
default, deadly, action while it finalizes; an ignored signal stays ignored);
without a stop the previous handlers return.
"""

from __future__ import annotations

import signal

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopSignals:
    """True once SIGINT or SIGTERM arrived (``signal`` says which came first)."""

    def __init__(self):
        self.signal: int | None = None
        self._old = {}

    def __enter__(self) -> StopSignals:
        for sig in STOP_SIGNALS:
            self._old[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, _frame) -> None:
        if self.signal is None:
            self.signal = signum

    def __exit__(self, *exc) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old if self.signal is None else signal.SIG_IGN)

    def __bool__(self) -> bool:
        return self.signal is not None
