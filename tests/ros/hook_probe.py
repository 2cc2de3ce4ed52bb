"""A node run by ``bearing_common.node_main`` with an ``on_shutdown`` hook (signal tests).

Publishes a /diagnostics status "running" every 0.1 s, and "stopped" from its hook,
as the diagnoser does when it is stopped. With ``--slow-start`` its construction takes
``SLOW_START_S`` after the node is in the graph (as the diagnoser's JIT warm-up does under load).
With ``--stuck-teardown`` its ``destroy_node`` first holds the main thread in one C call that keeps
the GIL for ``STUCK_TEARDOWN_S`` (as rmw's deletion of the DDS participant, inside rclpy's
``destroy_node``, waited past the stall watchdog under load).
"""

import ctypes
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.duration import Duration
from rclpy.node import Node

from bearing_common import topics
from bearing_common.node_main import run_node_main

RUNNING, STOPPED = "running", "stopped"
SLOW_START_S = 60.0
STUCK_TEARDOWN_S = 10


class HookProbe(Node):
    def __init__(self):
        super().__init__("hook_probe")
        if "--slow-start" in sys.argv:
            self.get_logger().info("starting slowly")
            time.sleep(SLOW_START_S)
        self.pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS.name, topics.qos(topics.DIAGNOSTICS))
        self.create_timer(0.1, lambda: self.publish(RUNNING))

    def publish(self, message: str) -> None:
        self.pub.publish(DiagnosticArray(status=[DiagnosticStatus(name=self.get_name(), message=message)]))

    def on_shutdown(self) -> None:
        self.publish(STOPPED)
        self.pub.wait_for_all_acked(Duration(seconds=2.0))

    def destroy_node(self) -> None:
        if "--stuck-teardown" in sys.argv:
            ctypes.PyDLL(None).sleep(STUCK_TEARDOWN_S)  # PyDLL: the GIL stays held, as in pybind11's calls
        super().destroy_node()


if __name__ == "__main__":
    sys.exit(run_node_main("hook_probe", HookProbe))
