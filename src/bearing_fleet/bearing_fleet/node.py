"""The ``fleet`` node: every motor's fault state in one ``fleet_state`` summary.

Looks for ``<motor>/fault_state`` topics (FaultState) every ``discovery_period`` seconds,
subscribes to each new one (transient local: the current state arrives at once), and
publishes ``fleet_state`` (FleetState: one MotorState per motor, reliable + transient local)
every ``period`` seconds and on every change of a motor's state. The table logic lives in
:class:`.fleet_table.FleetTable`.
"""

import sys

from rclpy.node import Node

from bearing_common import topics
from bearing_common.log_throttle import LogThrottle
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_seconds, to_stamp
from bearing_msgs.msg import FaultState, FleetState, MotorState

from .fleet_node_config import PARAMETERS
from .fleet_table import FleetTable, motor_of

QUEUE = 10  # per motor: decisions arrive a few per second


class FleetNode(Node):
    """Thin adapter: FaultState of every motor -> FleetTable -> FleetState."""

    def __init__(self):
        super().__init__("fleet")
        self.values = declare(self, PARAMETERS, on_change=self._on_change)
        self.table = FleetTable(self.values["stale_timeout"])
        self.pub = self.create_publisher(FleetState, topics.FLEET_STATE.name, topics.qos(topics.FLEET_STATE))
        self.subscribed: set[str] = set()
        self.rejected = 0
        self._log_repeatable = LogThrottle(self._log, 5.0)
        self.create_timer(float(self.values["discovery_period"]), self.discover)
        self.create_timer(float(self.values["period"]), self.publish)
        self.discover()

    def _on_change(self, changed: dict) -> None:
        if "stale_timeout" in changed:
            self.table.stale_timeout = float(changed["stale_timeout"])

    def _log(self, level: str, text: str) -> None:
        getattr(self.get_logger(), level)(text)

    def _now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def discover(self) -> None:
        for name, types in self.get_topic_names_and_types():
            motor = motor_of(name)
            if motor is None or name in self.subscribed or topics.FAULT_STATE.msgtype not in types:
                continue
            self.subscribed.add(name)
            self.table.add_motor(motor)
            self.create_subscription(FaultState, name, lambda msg, m=motor: self.on_state(m, msg),
                                     topics.qos(topics.FAULT_STATE, depth=QUEUE))
            self.get_logger().info(f"watching motor {motor or '/'} ({name})")

    def on_state(self, motor: str, msg: FaultState) -> None:
        try:
            changed = self.table.update(motor, msg.state, msg.confidence, to_seconds(msg.onset),
                                        to_seconds(msg.header.stamp), self._now())
        except ValueError as exc:
            self.rejected += 1
            self._log_repeatable("rejected", "warning", f"ignoring fault_state ({self.rejected} so far): {exc}")
            return
        if changed:
            self.publish()

    def publish(self) -> None:
        now = self._now()
        msg = FleetState()
        msg.header.stamp = self.get_clock().now().to_msg()
        for row in self.table.rows():
            received = row.received != float("-inf")
            msg.motors.append(MotorState(motor=row.motor, state=int(row.state), confidence=row.confidence,
                                         onset=to_stamp(row.onset), last_update=to_stamp(row.stamp),
                                         age=row.age(now) if received else -1.0,
                                         stale=self.table.is_stale(row, now)))
        self.pub.publish(msg)


def main(args=None) -> int:
    return run_node_main("fleet", FleetNode, None, args)


if __name__ == "__main__":
    sys.exit(main())
