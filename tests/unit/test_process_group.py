"""ProcessGroup: prefixed output, clean stop, no orphans (children of children included)."""

import os
import sys
import time

from bearing_bringup.process_group import ProcessGroup

SLEEPER = "import signal, sys, time; print('ready', flush=True); time.sleep(60)"
# A child that ignores SIGINT and SIGTERM and starts a grandchild: needs SIGKILL of the whole group.
STUBBORN = ("import signal, subprocess, sys, time; signal.signal(signal.SIGINT, signal.SIG_IGN); "
            "signal.signal(signal.SIGTERM, signal.SIG_IGN); "
            "p = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)']); "
            "print(p.pid, flush=True); time.sleep(60)")


def wait_for_line(member, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not member.lines and time.monotonic() < deadline:
        time.sleep(0.02)
    assert member.lines, "child printed nothing"


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_output_is_prefixed_and_interleaved(capsys):
    group = ProcessGroup()
    m = group.start("talker", [sys.executable, "-c", "print('hello'); print('world')"])
    m.process.wait()
    group.stop()
    out = capsys.readouterr().out.splitlines()
    assert out == ["[talker    ] hello", "[talker    ] world"]


def test_stop_interrupts_then_reaps():
    group = ProcessGroup(echo=False)
    m = group.start("sleeper", [sys.executable, "-c", SLEEPER])
    wait_for_line(m)
    codes = group.stop(grace=5.0)
    assert codes["sleeper"] is not None and not alive(m.process.pid)


def test_stubborn_child_and_grandchild_are_killed():
    group = ProcessGroup(echo=False)
    m = group.start("stubborn", [sys.executable, "-c", STUBBORN])
    wait_for_line(m)
    grandchild = int(m.lines[0])
    start = time.monotonic()
    group.stop(grace=0.5)
    assert time.monotonic() - start < 10.0
    time.sleep(0.2)
    assert not alive(m.process.pid)
    assert not alive(grandchild) or open(f"/proc/{grandchild}/stat").read().split()[2] == "Z"


def test_wait_any_exit_reports_the_first_to_end():
    with ProcessGroup(echo=False) as group:
        group.start("long", [sys.executable, "-c", SLEEPER])
        short = group.start("short", [sys.executable, "-c", "pass"])
        assert group.wait_any_exit(timeout=10.0) is short
