"""Harness for tests that start real node executables talking over DDS.

Each test session gets its own ROS_DOMAIN_ID with localhost-only discovery, so
runs do not hear each other. Nodes run as separate processes (the executables
colcon installed, exactly what ``ros2 run`` starts) in a ProcessGroup that is
always torn down, and die with the test process if it is killed.
"""

from __future__ import annotations

import os
import pathlib
import threading
import time
from collections.abc import Callable

import rclpy
from rclpy.executors import SingleThreadedExecutor

from bearing_bringup.process_group import ProcessGroup
from bearing_common import topics
from bearing_common.topics import Topic

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
INSTALL = REPO_ROOT / "ros_ws" / "install"


def session_domain_id() -> int:
    """A DDS domain for this test session: 100-199, from the process id."""
    return 100 + os.getpid() % 100


def isolated_env(domain_id: int) -> dict:
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.pop("ROS_STATIC_PEERS", None)
    return env


def executable(package: str, name: str) -> pathlib.Path:
    """Path of an installed node executable, as ``ros2 run`` finds it."""
    path = INSTALL / package / "lib" / package / name
    if not path.exists():
        raise FileNotFoundError(f"{path} not built: run `make test` (it builds ros_ws/)")
    return path


def ros_args(name: str | None = None, params: dict | None = None,
             params_file: pathlib.Path | None = None) -> list:
    """``--ros-args`` for a node name, parameters and a parameters file."""
    args = ["--ros-args"]
    if name:
        args += ["-r", f"__node:={name}"]
    if params_file:
        args += ["--params-file", str(params_file)]
    for key, value in (params or {}).items():
        if isinstance(value, bool):
            value = "true" if value else "false"
        elif value == "":
            value = "''"
        args += ["-p", f"{key}:={value}"]
    return args


class RosGraph:
    """Node processes plus an in-process listener node, in one isolated domain."""

    def __init__(self, domain_id: int):
        self.domain_id = domain_id
        self.env = isolated_env(domain_id)
        os.environ.update(ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        self.processes = ProcessGroup(env=self.env, echo=False)
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node("test_listener", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._lock = threading.Lock()
        self._spinning = True
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while self._spinning and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # Jazzy: RCLError when a signal shuts the context down mid-spin
                if self.context.ok():
                    raise

    def start(self, package: str, exe: str, name: str | None = None, params: dict | None = None,
              params_file: pathlib.Path | None = None, argv: list | None = None, join=None):
        """Start a node executable (or ``argv``) as a separate process; return its Member
        (in the process group of member ``join`` when given, else in one of its own)."""
        command = argv if argv is not None else [str(executable(package, exe))] + ros_args(name, params, params_file)
        return self.processes.start(name or exe, command, join=join)

    def subscribe(self, topic: Topic, namespace: str = "", depth: int = 1000) -> list:
        """Collect every message on ``topic`` (contract QoS, a ``depth``-deep queue) into the returned list."""
        received: list = []

        def on_msg(msg):
            with self._lock:
                received.append(msg)

        self.node.create_subscription(topics.message_class(topic.msgtype), topics.qualified(namespace, topic),
                                      on_msg, topics.qos(topic, depth=depth))
        return received

    def publisher(self, topic: Topic, namespace: str = "", depth: int = 100):
        """A publisher of ``topic`` with the contract's QoS (keep last ``depth``)."""
        return self.node.create_publisher(topics.message_class(topic.msgtype), topics.qualified(namespace, topic),
                                          topics.qos(topic, depth=depth))

    def wait_until(self, condition: Callable[[], bool], timeout: float, what: str) -> None:
        """Wait for ``condition``; on timeout fail with ``what`` and the processes' output."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return
            crashed = [m.name for m in self.processes.members if m.returncode not in (None, 0)]
            if crashed:
                raise AssertionError(f"{', '.join(crashed)} exited with an error while waiting for {what}\n"
                                     f"{self.output()}")
            time.sleep(0.05)
        raise AssertionError(f"timed out after {timeout} s waiting for {what}\n{self.output()}")

    def output(self) -> str:
        """Everything the node processes printed, for failure messages."""
        parts = []
        for member in self.processes.members:
            tail = "\n".join(member.lines[-40:])
            parts.append(f"--- {member.name} (exit {member.returncode}) ---\n{tail}")
        return "\n".join(parts)

    def close(self) -> dict:
        codes = self.processes.stop()
        self._spinning = False
        self._thread.join(timeout=2.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)  # a signal may have shut it down (Jazzy: shutdown() raises then)
        return codes
