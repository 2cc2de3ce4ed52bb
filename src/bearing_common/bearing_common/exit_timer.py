"""End the process after a delay from a native timer thread, whatever its threads are doing (no rclpy).

A Python thread cannot end a process whose main thread is held in a C call that keeps the GIL
(rclpy's pybind11 calls do not release it, e.g. ``Node.destroy_node`` while rmw deletes the DDS
participant): it never gets the GIL back. glibc's POSIX timers with ``SIGEV_THREAD`` call a C
function with one argument in a thread of their own; with ``puts`` (one line on stdout) and then
``_exit`` (the exit code) as those functions, the process says why and ends, GIL held or not.
Linux (glibc), 64-bit.
"""

from __future__ import annotations

import contextlib
import ctypes

CLOCK_MONOTONIC = 1
SIGEV_THREAD = 2
_IOLBF = 1  #: setvbuf: line-buffered
MESSAGE_LEAD_S = 0.05  #: s between the message and the exit (its own timer thread writes it)


class _SigEvent(ctypes.Structure):
    """glibc's ``struct sigevent`` (64 bytes) as SIGEV_THREAD uses it."""

    _fields_ = [("value", ctypes.c_void_p), ("signo", ctypes.c_int), ("notify", ctypes.c_int),
                ("function", ctypes.c_void_p), ("attribute", ctypes.c_void_p), ("pad", ctypes.c_int * 8)]


class _TimeSpec(ctypes.Structure):
    _fields_ = [("sec", ctypes.c_long), ("nsec", ctypes.c_long)]


class _ITimerSpec(ctypes.Structure):
    _fields_ = [("interval", _TimeSpec), ("value", _TimeSpec)]


_libc = ctypes.CDLL(None, use_errno=True)
_libc.timer_create.argtypes = [ctypes.c_int, ctypes.POINTER(_SigEvent), ctypes.POINTER(ctypes.c_void_p)]
_libc.timer_settime.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(_ITimerSpec), ctypes.c_void_p]
_libc.timer_delete.argtypes = [ctypes.c_void_p]
_libc.setvbuf.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_size_t]


def _start_timer(function, argument: int | None, seconds: float) -> ctypes.c_void_p:
    """A one-shot timer calling the C ``function(argument)`` in a new thread after ``seconds``."""
    event = _SigEvent(value=argument, notify=SIGEV_THREAD, function=ctypes.cast(function, ctypes.c_void_p).value)
    timer = ctypes.c_void_p()
    if _libc.timer_create(CLOCK_MONOTONIC, ctypes.byref(event), ctypes.byref(timer)) != 0:
        raise OSError(ctypes.get_errno(), "timer_create failed")
    whole = int(seconds)
    spec = _ITimerSpec(value=_TimeSpec(whole, int((seconds - whole) * 1e9)))
    if _libc.timer_settime(timer, 0, ctypes.byref(spec), None) != 0:
        _libc.timer_delete(timer)
        raise OSError(ctypes.get_errno(), "timer_settime failed")
    return timer


@contextlib.contextmanager
def exit_after(seconds: float, code: int, message: str):
    """While the block runs: ``seconds`` after entering it, print ``message`` (one line, stdout) and
    end the process with ``code`` (no clean-up, no flush of Python's buffers: flush them before).
    Leaving the block in time cancels both."""
    line = ctypes.create_string_buffer(message.encode())  # C memory the timer thread reads: alive till the end
    _libc.setvbuf(ctypes.c_void_p.in_dll(_libc, "stdout"), None, _IOLBF, 0)  # puts' line leaves at once
    timers = [_start_timer(_libc.puts, ctypes.addressof(line), seconds),
              _start_timer(_libc._exit, code, seconds + MESSAGE_LEAD_S)]
    try:
        yield
    finally:
        for timer in timers:
            _libc.timer_delete(timer)
