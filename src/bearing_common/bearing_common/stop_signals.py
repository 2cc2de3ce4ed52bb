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

With ``stall_s`` (a process's main: a stop is its end), a process still running
``stall_s`` seconds after the stop signal arrived prints the stack of every thread on
stderr and exits with code 1 (``faulthandler``): a clean-up, a callback or the
interpreter's exit that hangs says where, instead of waiting for SIGKILL. The clock starts
when the signal arrives, even while the main thread is blocked in C code where Python's
handler cannot run yet (a thread waits on the signal wake-up descriptor), and keeps
running after the ``with`` block, through the process's exit.

While ``abort`` is true (a node's start-up: imports, JIT warm-up, seconds of CPU; set it with
:meth:`StopSignals.aborting`), the first signal also raises :class:`StopRequested` in the main
thread, so that the start-up ends instead of running on past the stall watchdog. Python runs
that handler only between bytecodes of the main thread: one C call (numba's LLVM compile of
a large kernel, an extension module's import) can hold it off for seconds under load. With
``stuck_start``, the watcher thread then ends the start-up itself: if the main thread is still
in the abortable section ``START_GRACE_S`` after the signal, it calls ``stuck_start(signum)``,
which must end the process (nothing of a start-up needs cleaning up but rclpy's context, which
the process's end takes with it). A StopRequested raised inside a finalizer is swallowed there;
the start-up, cut in the middle, may then fail on its own (numba's cache save after an interrupted
compile): :attr:`StopSignals.aborted` tells the caller that this failure is the stop's doing.
"""

from __future__ import annotations

import contextlib
import faulthandler
import os
import signal
import sys
import threading
import time
from collections.abc import Callable

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
START_GRACE_S = 1.0  #: s the main thread has to leave an abortable section after a stop signal


class StopRequested(BaseException):
    """A stop signal arrived while :attr:`StopSignals.abort` was set (not an error: no ``except Exception``)."""


class StopSignals:
    """True once SIGINT or SIGTERM arrived (``signal`` says which came first)."""

    def __init__(self, stall_s: float | None = None, stuck_start: Callable[[int], None] | None = None):
        self.signal: int | None = None
        self.arrived: float | None = None  #: time.monotonic() s when the first stop signal arrived
        self.abort = False  #: the first signal raises StopRequested (see the module's docstring)
        self.aborted = False  #: the first signal came while ``abort`` was set (a start-up was interrupted)
        self._old = {}
        self._stall_s = stall_s
        self._stuck_start = stuck_start
        self._wakeup: tuple[int, int] | None = None
        self._old_wakeup_fd = -1

    def __enter__(self) -> StopSignals:
        if self._stall_s is not None:  # the watcher first: a signal may come (and raise) once a handler is in
            self._wakeup = os.pipe()
            os.set_blocking(self._wakeup[1], False)
            self._old_wakeup_fd = signal.set_wakeup_fd(self._wakeup[1], warn_on_full_buffer=False)
            threading.Thread(target=self._watch, args=(self._wakeup[0],), name="stop-stall", daemon=True).start()
        for sig in STOP_SIGNALS:
            self._old[sig] = signal.signal(sig, self._handle)
        self._old_unraisable = sys.unraisablehook
        sys.unraisablehook = self._unraisable
        return self

    def _unraisable(self, unraisable) -> None:
        """A StopRequested raised where Python cannot raise it (a finalizer, ``__del__``, that the
        garbage collector ran while the signal came: numba's LLVM objects during a first compile) is
        swallowed there; the stop stays pending, and the watcher ends a start-up still running
        :data:`START_GRACE_S` later (:meth:`_end_stuck_start`). Say nothing of it; pass on the rest."""
        if not isinstance(unraisable.exc_value, StopRequested):
            self._old_unraisable(unraisable)

    def _watch(self, fd: int) -> None:
        """Arm the stall timer when the first stop signal's number arrives on the wake-up pipe;
        drain the pipe until its write end closes (a later signal must find a reader)."""
        armed = False
        try:
            while byte := os.read(fd, 1):
                if byte[0] in STOP_SIGNALS and not armed:
                    self.arrived = self.arrived or time.monotonic()  # this thread runs while the main one is held in C
                    faulthandler.dump_traceback_later(self._stall_s, exit=True)
                    armed = True
                    if self.abort and self._stuck_start is not None:
                        threading.Timer(START_GRACE_S, self._end_stuck_start, args=(byte[0],)).start()
        finally:
            os.close(fd)

    def _end_stuck_start(self, signum: int) -> None:
        if self.abort:  # the main thread has not left the abortable section: blocked in C code
            self._stuck_start(signum)

    @contextlib.contextmanager
    def aborting(self):
        """A section (start-up work: imports, compiles) that a stop signal ends with StopRequested."""
        self.abort = True
        try:
            yield self
        finally:
            self.abort = False

    def _handle(self, signum, _frame) -> None:
        if self.signal is None:
            self.signal = signum
            self.arrived = self.arrived or time.monotonic()
            if self.abort:
                self.aborted = True
                raise StopRequested(signum)

    def __exit__(self, *exc) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old if self.signal is None else signal.SIG_IGN)
        sys.unraisablehook = self._old_unraisable
        if self._wakeup is not None:
            signal.set_wakeup_fd(self._old_wakeup_fd)
            os.close(self._wakeup[1])  # the watcher's read returns: it ends
            self._wakeup = None

    def __bool__(self) -> bool:
        return self.signal is not None
