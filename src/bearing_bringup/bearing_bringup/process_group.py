"""Run several node processes side by side, with prefixed output and a clean stop.

Used by ``bearing-graph`` (the ``make demo`` starter, for machines without
``ros2 launch``) and by the test harness. Each child runs in its own process
group so that stopping it also stops anything it started; ``stop()``
sends SIGINT, then SIGTERM, then SIGKILL, and always reaps. No rclpy here.
"""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TextIO


@dataclass
class Member:
    """One child process of a group (the latest one, after restarts)."""

    name: str
    argv: list
    env: dict
    process: subprocess.Popen
    lines: list = field(default_factory=list)  # everything it printed, for tests and post-mortems
    reader: threading.Thread | None = None
    restarts: int = 0

    @property
    def returncode(self) -> int | None:
        return self.process.poll()


class ProcessGroup:
    """Start, watch and stop a set of child processes.

    Parameters
    ----------
    env : dict, optional
        Environment for every child (default: this process's).
    echo : bool
        Echo children's output, each line prefixed ``[name]``, to ``out``
        (default: the current ``sys.stdout``); it is always kept in ``Member.lines``.
    on_line : callable(name, line), optional
        Called for every output line (from reader threads).
    """

    def __init__(self, env: dict | None = None, echo: bool = True, out: TextIO | None = None,
                 on_line: Callable[[str, str], None] | None = None):
        self.env = dict(os.environ if env is None else env)
        self.echo_output = echo
        self.out = out
        self.on_line = on_line
        self.members: list[Member] = []
        self._lock = threading.Lock()
        self._width = 10

    def start(self, name: str, argv: list, extra_env: dict | None = None, join: Member | None = None) -> Member:
        """Start ``argv`` as member ``name``; output is captured line by line.

        The child gets a process group of its own, or with ``join`` it enters that
        member's (a signal to the group then reaches both, as a terminal's Ctrl-C
        reaches every process started by ``ros2 launch``).
        """
        env = dict(self.env)
        env.update(extra_env or {})
        env.setdefault("PYTHONUNBUFFERED", "1")
        env.setdefault("RCUTILS_COLORIZED_OUTPUT", "0")
        group = 0 if join is None else os.getpgid(join.process.pid)
        member = Member(name, list(argv), env, self._spawn(argv, env, group))
        self._width = max(self._width, len(name))
        self._read(member)
        self.members.append(member)
        return member

    def restart(self, member: Member) -> None:
        """Start an exited member's command again, in a process group of its own; its
        output continues in ``member.lines`` under the same name."""
        member.process.wait()
        member.reader.join(timeout=2.0)
        member.process = self._spawn(member.argv, member.env, 0)
        member.restarts += 1
        self._read(member)

    @staticmethod
    def _spawn(argv: list, env: dict, process_group: int) -> subprocess.Popen:
        return subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, text=True, bufsize=1,
                                process_group=process_group, preexec_fn=_die_with_parent)

    def _read(self, member: Member) -> None:
        member.reader = threading.Thread(target=self._pump, args=(member, member.process), daemon=True)
        member.reader.start()

    def _pump(self, member: Member, process: subprocess.Popen) -> None:
        for line in process.stdout:
            line = line.rstrip("\n")
            member.lines.append(line)
            if self.on_line is not None:
                self.on_line(member.name, line)
            if self.echo_output:
                self._print(member.name, line)

    def echo(self, text: str, name: str = "graph") -> None:
        """Print a line of our own, interleaved with the children's."""
        if self.echo_output:
            self._print(name, text)

    def _print(self, name: str, text: str) -> None:
        with self._lock:
            print(f"[{name:<{self._width}}] {text}", file=self.out or sys.stdout, flush=True)

    def wait_any_exit(self, timeout: float, names: list | None = None) -> Member | None:
        """Wait until one of ``names`` (default: any member) exits; return it, or None on timeout."""
        watched = [m for m in self.members if names is None or m.name in names]
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for member in watched:
                if member.returncode is not None:
                    return member
            time.sleep(0.05)
        return None

    def stop(self, grace: float = 5.0) -> dict:
        """Stop every member (SIGINT, then SIGTERM, then SIGKILL) and reap; return exit codes."""
        for sig, wait in ((signal.SIGINT, grace), (signal.SIGTERM, 2.0), (signal.SIGKILL, 2.0)):
            alive = [m for m in self.members if m.returncode is None]
            if not alive:
                break
            for member in alive:
                try:
                    os.killpg(member.process.pid, sig)
                except ProcessLookupError:
                    pass
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline and any(m.returncode is None for m in alive):
                time.sleep(0.05)
        for member in self.members:
            _kill_leftovers(member.process.pid)
            member.process.wait()
            if member.reader is not None:
                member.reader.join(timeout=2.0)
        return {m.name: m.returncode for m in self.members}

    def __enter__(self) -> ProcessGroup:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """In the child before exec: get SIGTERM if the starting process dies (Linux), so
    that a killed test run or starter leaves no orphan nodes behind."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):
        pass


def _kill_leftovers(pgid: int) -> None:
    """SIGKILL whatever is left in a member's process group (grandchildren)."""
    try:
        os.killpg(pgid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
