"""StopSignals: a signal sets the flag (no KeyboardInterrupt); later ones are ignored, also after the block;
a stop that stalls ends the process with the stacks printed."""

import os
import signal
import subprocess
import sys
import time

import pytest

from bearing_common.stop_signals import StopRequested, StopSignals


@pytest.fixture(autouse=True)
def default_handlers():
    yield
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def test_first_signal_is_recorded_and_later_ones_ignored():
    with StopSignals() as stop:
        assert not stop
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGINT)
        assert stop and stop.signal == signal.SIGTERM
    assert signal.getsignal(signal.SIGINT) is signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    os.kill(os.getpid(), signal.SIGINT)  # stopping is under way: no KeyboardInterrupt
    assert stop.signal == signal.SIGTERM


def test_a_signal_while_abort_is_set_raises_once():
    with StopSignals() as stop:
        stop.abort = True
        with pytest.raises(StopRequested):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the handler runs here at the latest
        os.kill(os.getpid(), signal.SIGTERM)  # a later signal while stopping only is ignored
        assert stop.signal == signal.SIGINT


def test_handlers_are_restored_when_no_stop_was_requested():
    with StopSignals():
        assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


STALLING_PROCESS = """
import os, signal, sys, time
from bearing_common.stop_signals import StopRequested, StopSignals
with StopSignals(stall_s=0.5) as stop:
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(0.05)
    os.kill(os.getpid(), signal.SIGINT)  # a second signal (Ctrl-C under ros2 launch): still quiet
    time.sleep(float(sys.argv[1]))  # the clean-up: hangs (10 s) or is quick (0 s)
print("left", bool(stop))
"""


@pytest.mark.parametrize("cleanup_s, code", [(10.0, 1), (0.0, 0)])
def test_a_stop_that_stalls_prints_the_stacks_and_exits_1(cleanup_s, code):
    start = time.monotonic()
    run = subprocess.run([sys.executable, "-c", STALLING_PROCESS, str(cleanup_s)], capture_output=True, text=True,
                         timeout=30)
    assert run.returncode == code, run.stderr
    if code:
        assert time.monotonic() - start < 5.0
        assert "most recent call first" in run.stderr
        assert "left" not in run.stdout
    else:
        assert run.stdout.strip() == "left True" and not run.stderr


HELD_IN_C = """
import os, signal, sys, time
from bearing_common.node_main import process_stop_signals
with process_stop_signals("probe") as stop:
    # the main thread as in one long C call (LLVM compiling a kernel): Python's handler cannot run
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    os.kill(os.getpid(), getattr(signal, sys.argv[1]))
    time.sleep(10.0)
print("not stopped")
"""


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_a_start_held_in_c_code_is_ended_by_the_watcher(signame):
    """A stop signal while the start-up is held in C: the watcher thread ends the process as a stop
    (one line, exit 0) START_GRACE_S later, long before the stall watchdog."""
    from bearing_common.stop_signals import START_GRACE_S

    start = time.monotonic()
    run = subprocess.run([sys.executable, "-c", HELD_IN_C, signame], capture_output=True, text=True, timeout=30)
    took = time.monotonic() - start
    assert run.returncode == 0, run.stderr
    assert run.stderr == f"probe: {signame} while starting: stopped\n" and not run.stdout
    assert START_GRACE_S <= took < 4.0


STARTING = """
import os, signal, time
from bearing_common.node_main import process_stop_signals
with process_stop_signals("probe") as stop:
    with stop.aborting():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(10.0)  # Python code: the handler raises StopRequested here at once
print("not stopped")
"""


def test_a_start_in_python_code_ends_at_the_signal():
    start = time.monotonic()
    run = subprocess.run([sys.executable, "-c", STARTING], capture_output=True, text=True, timeout=30)
    assert run.returncode == 0 and run.stderr == "probe: SIGTERM while starting: stopped\n", run.stderr
    assert time.monotonic() - start < 3.0


def test_a_stop_raised_inside_a_finalizer_prints_nothing_and_stays_pending(monkeypatch):
    """A signal whose handler runs inside a ``__del__`` (numba's LLVM objects collected during a first
    compile): Python cannot raise StopRequested there and would print it as "Exception ignored"; it is
    kept from the unraisable hook, and the stop stays pending (the watcher ends a start-up still
    running; here: the flag is set). Other unraisable exceptions still reach the hook."""
    reported = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: reported.append(u.exc_type))

    class Collected:
        def __init__(self, error=None):
            self.error = error

        def __del__(self):
            if self.error:
                raise self.error
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.2)  # the handler runs here, inside the finalizer

    with StopSignals() as stop:
        stop.abort = True
        Collected()  # collected at once: its finalizer runs the handler
        assert stop.signal == signal.SIGINT
        Collected(ValueError("other"))
    assert reported == [ValueError]


HALF_DONE = """
import os, signal, time
from bearing_common.node_main import process_stop_signals

class Collected:  # an LLVM object of numba's, collected during a first compile
    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)  # the handler runs here: its StopRequested is swallowed

with process_stop_signals("probe") as stop:
    with stop.aborting():
        Collected()
        raise RuntimeError("no compiled object yet")  # the compile, interrupted, fails on its own
print("not stopped")
"""


def test_a_start_up_that_fails_after_its_stop_was_swallowed_ends_as_a_stop():
    """The stop came inside a finalizer (swallowed there), and the start-up, cut in the middle, then
    raised an error of its own (numba's cache save: "no compiled object yet"): a stop, exit 0 and one
    line, not a traceback. An error with no stop before it stays an error (next test)."""
    run = subprocess.run([sys.executable, "-c", HALF_DONE], capture_output=True, text=True, timeout=30)
    assert run.returncode == 0 and run.stderr == "probe: SIGINT while starting: stopped\n", run.stderr
    assert not run.stdout


def test_a_start_up_error_without_a_stop_is_an_error():
    run = subprocess.run([sys.executable, "-c", HALF_DONE.replace("        Collected()\n", "")],
                         capture_output=True, text=True, timeout=30)
    assert run.returncode == 1 and "RuntimeError: no compiled object yet" in run.stderr
