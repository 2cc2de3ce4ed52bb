"""Which dead nodes ``bearing-graph`` restarts, and when it gives up (no rclpy).

A node that dies (non-zero exit: a crash, ``kill -9``) is restarted after ``delay``
seconds, under the same name and parameters. More than ``max_restarts`` restarts of
one node within ``window`` seconds is a crash loop: the graph stops with that message.
Not restarted: exit 0 (the node was stopped on request, or the simulator finished its
scenario: the caller handles that first) and exit 2 (invalid parameters, see
:mod:`bearing_common.node_main`: a restart would fail the same way).
"""

from __future__ import annotations

import collections
import signal
from dataclasses import dataclass

EXIT_INVALID_PARAMETERS = 2
RESTART_DELAY_S = 1.0  #: s before a dead node is restarted (also the launch file's respawn_delay)
MAX_RESTARTS = 5  #: restarts of one node per window (the launch file: in total, launch has no window)
WINDOW_S = 60.0  #: s


def describe_exit(returncode: int) -> str:
    """``exit code 1`` or ``killed by SIGKILL`` (Popen's negative codes)."""
    if returncode < 0:
        try:
            return f"killed by {signal.Signals(-returncode).name}"
        except ValueError:
            return f"killed by signal {-returncode}"
    return f"exit code {returncode}"


@dataclass(frozen=True)
class Verdict:
    restart: bool
    message: str


class RestartPolicy:
    """Restart decisions for the nodes of one graph; times in monotonic seconds."""

    def __init__(self, delay: float = RESTART_DELAY_S, max_restarts: int = MAX_RESTARTS, window: float = WINDOW_S):
        self.delay = delay
        self.max_restarts = max_restarts
        self.window = window
        self._restarts = collections.defaultdict(collections.deque)  # name -> times of recent restarts

    def after_exit(self, name: str, returncode: int, now: float) -> Verdict:
        """What to do now that node ``name`` exited with ``returncode``."""
        if returncode == 0:
            return Verdict(False, f"{name} stopped (exit code 0); stopping the graph")
        if returncode == EXIT_INVALID_PARAMETERS:
            return Verdict(False, f"{name} refused its parameters (exit code 2); stopping the graph")
        recent = self._restarts[name]
        while recent and now - recent[0] > self.window:
            recent.popleft()
        if len(recent) >= self.max_restarts:
            return Verdict(False, f"{name} died ({describe_exit(returncode)}) after {len(recent)} restarts within "
                                  f"{self.window:g} s: crash loop, stopping the graph")
        recent.append(now)
        return Verdict(True, f"{name} died ({describe_exit(returncode)}); restarting it in {self.delay:g} s "
                             f"(restart {len(recent)} of at most {self.max_restarts} per {self.window:g} s)")
