"""StopSignals: a signal sets the flag (no KeyboardInterrupt); later ones are ignored, also after the block."""

import os
import signal

import pytest

from bearing_common.stop_signals import StopSignals


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


def test_handlers_are_restored_when_no_stop_was_requested():
    with StopSignals():
        assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
