"""CPU starvation for stop tests: busy processes and the graph's processes pinned to one core.

A process whose threads all run on one core beside ``n`` busy loops gets at most
1 / (n + its neighbours) of that core, whatever the machine's core count, so a stop that
needs a given amount of CPU takes a predictable multiple of it in wall time.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys

BUSY_LOOP = "import os, sys\nos.sched_setaffinity(0, {int(sys.argv[1])})\nwhile True:\n    pass\n"


def one_core() -> int:
    """The highest-numbered core this process may run on (the test runner keeps the others)."""
    return max(os.sched_getaffinity(0))


def pin(pid: int, core: int) -> None:
    """Every thread of process ``pid`` onto ``core`` (threads it starts later inherit it)."""
    for tid in os.listdir(f"/proc/{pid}/task"):
        with contextlib.suppress(ProcessLookupError, FileNotFoundError):
            os.sched_setaffinity(int(tid), {core})


def group_pids(pgid: int) -> list:
    """The processes of process group ``pgid`` (a launch and the nodes it started)."""
    pids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            with contextlib.suppress(ProcessLookupError, FileNotFoundError, PermissionError):
                if os.getpgid(int(entry)) == pgid:
                    pids.append(int(entry))
    return pids


@contextlib.contextmanager
def busy_core(core: int, loops: int):
    """``loops`` busy processes pinned to ``core`` while the block runs; always ended."""
    procs = [subprocess.Popen([sys.executable, "-c", BUSY_LOOP, str(core)], stdin=subprocess.DEVNULL)
             for _ in range(loops)]
    try:
        yield procs
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()
