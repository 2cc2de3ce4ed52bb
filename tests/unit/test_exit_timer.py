"""exit_after: a process whose main thread is held in C with the GIL (as in rclpy's destroy_node) still
ends at the deadline, with the line and the exit code; a block that ends in time cancels it."""

import subprocess
import sys
import time

import pytest

PROCESS = """
import ctypes, sys, time
from bearing_common.exit_timer import exit_after
with exit_after(0.3, int(sys.argv[1]), "probe: ended by the timer"):
    if sys.argv[2] == "held":
        ctypes.PyDLL(None).sleep(10)  # one C call that keeps the GIL: no Python thread can run
print("left the block", flush=True)
time.sleep(0.5)  # past the deadline: the timers were cancelled
"""


@pytest.mark.parametrize("code", [0, 3])
def test_a_process_held_in_c_with_the_gil_ends_at_the_deadline(code):
    started = time.monotonic()
    run = subprocess.run([sys.executable, "-c", PROCESS, str(code), "held"], capture_output=True, text=True,
                         timeout=20)
    assert run.returncode == code
    assert run.stdout == "probe: ended by the timer\n"
    assert time.monotonic() - started < 5.0  # not the 10 s of the C call


def test_leaving_the_block_in_time_cancels_the_exit():
    run = subprocess.run([sys.executable, "-c", PROCESS, "3", "quick"], capture_output=True, text=True, timeout=20)
    assert run.returncode == 0
    assert run.stdout == "left the block\n"
