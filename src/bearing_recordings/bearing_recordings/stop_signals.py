"""Stop a long-running tool cleanly on SIGINT (Ctrl-C) or SIGTERM."""

from __future__ import annotations

import signal


class StopSignals:
    """True once SIGINT or SIGTERM arrived; the handlers are installed inside the ``with`` block."""

    def __init__(self):
        self.signal: int | None = None
        self._old = {}

    def __enter__(self):
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._old[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, _frame):
        self.signal = signum

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)

    def __bool__(self):
        return self.signal is not None
