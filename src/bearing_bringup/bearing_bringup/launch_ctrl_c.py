"""Ctrl-C reaches ``ros2 launch`` however it was started (called by the launch files).

A process started as a background job of a non-interactive shell (``cmd &`` in a script, a
CI runner, a test harness started so) inherits SIGINT *ignored*, and an ignored signal stays
ignored across fork and exec. launch installs no SIGINT handler of its own: it reads the
signals Python's handlers note on a wake-up socket, and an ignored signal never gets there.
Such a launch never hears Ctrl-C, while our nodes, which install their own handlers
(:mod:`bearing_common.stop_signals`), stop on it: launch then respawned the respawnable ones
and kept running (``fleet.launch.py``; ``monitor.launch.py`` hid it, as its simulator's end
shuts the launch down). :func:`hear_ctrl_c` gives launch Python's SIGINT handler back where
it finds SIGINT ignored, so that launch and its nodes stop together, as in a terminal.
"""

import signal


def hear_ctrl_c() -> None:
    """Python's SIGINT handler (KeyboardInterrupt, which launch expects) where SIGINT is ignored."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
