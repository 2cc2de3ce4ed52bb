"""CPU starvation for stop tests: busy processes and the graph's processes pinned to one core;
the native stacks of processes that are slow to stop.

A process whose threads all run on one core beside ``n`` busy loops gets at most
1 / (n + its neighbours) of that core, whatever the machine's core count, so a stop that
needs a given amount of CPU takes a predictable multiple of it in wall time. Whether the
graph then falls behind real time depends on what it needs (a faster build, a lighter
scenario): :func:`starved` adds busy loops until it does, so the starving always takes hold.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import shutil
import subprocess
import sys
import time
from collections.abc import Callable

BUSY_LOOPS = 2  #: beside the graph on its core, to start with
MAX_BUSY_LOOPS = 6  #: the graph's simulator then gets at most a seventh of the core
STARVE_STEP_S = 8.0  #: s without the graph behind real time before one more busy loop

#: A busy process on core argv[1]; it ends with its parent, pid argv[2] (PR_SET_PDEATHSIG), so that a test
#: process killed by pytest-timeout leaves no loop behind.
BUSY_LOOP = ("import ctypes, os, signal, sys\nctypes.CDLL(None).prctl(1, signal.SIGKILL)\n"
             "if os.getppid() != int(sys.argv[2]):\n    sys.exit()\n"
             "os.sched_setaffinity(0, {int(sys.argv[1])})\nwhile True:\n    pass\n")


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


def busy_loop(core: int) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", BUSY_LOOP, str(core), str(os.getpid())], stdin=subprocess.DEVNULL)


@contextlib.contextmanager
def busy_core(core: int, loops: int):
    """``loops`` busy processes pinned to ``core`` while the block runs; always ended."""
    procs = [busy_loop(core) for _ in range(loops)]
    try:
        yield procs
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


@contextlib.contextmanager
def starved(core: int, pids: Callable[[], list], behind: Callable[[], bool]):
    """The processes ``pids()`` pinned to ``core`` beside :data:`BUSY_LOOPS` busy processes, one more
    every :data:`STARVE_STEP_S` until ``behind()`` (at most :data:`MAX_BUSY_LOOPS`); yields the busy
    processes while the block runs. AssertionError if even the most never made ``behind()`` true."""
    with busy_core(core, BUSY_LOOPS) as procs:
        added = time.monotonic()
        while True:
            for pid in pids():
                pin(pid, core)
            if behind():
                break
            if time.monotonic() - added > STARVE_STEP_S:
                assert len(procs) < MAX_BUSY_LOOPS, f"not behind real time beside {len(procs)} busy loops"
                procs.append(busy_loop(core))
                added = time.monotonic()
            time.sleep(0.1)
        yield procs


def native_stacks(pids: list) -> str:
    """Every thread's stack, Python and native, of each process in ``pids`` that still runs
    (``py-spy dump --native``; a note where py-spy is missing)."""
    spy = shutil.which("py-spy") or str(pathlib.Path(sys.executable).with_name("py-spy"))
    if not os.path.exists(spy):
        return "(py-spy is not installed: no native stacks)"
    dumps = []
    for pid in pids:
        run = subprocess.run([spy, "dump", "--native", "--pid", str(pid)], capture_output=True, text=True,
                             timeout=60)
        if run.returncode == 0:
            dumps.append(f"--- pid {pid}\n{run.stdout}")
        else:  # gone, or exiting (a zombie: no executable any more)
            dumps.append(f"--- pid {pid}: {(run.stderr.strip().splitlines() or ['?'])[0]}")
    return "\n".join(dumps)
