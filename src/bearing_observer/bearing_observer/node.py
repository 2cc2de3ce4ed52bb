"""The ``observer`` node: one fault observer (thesis Fig. 3.1) on the live vibration stream.

    ros2 run bearing_observer observer --ros-args -p fault_type:=outer_race

Subscribes ``vibration/drive_end`` and ``shaft_speed``; publishes
``residual/outer_race`` or ``residual/inner_race`` (Residual: residual, estimate
and the impulse train used, stamped with the input chunk's stamp). Bad chunks
are rejected with a counted, throttled warning and the observer resynchronises;
it never publishes a non-finite value.
"""

import math
import sys

import numpy as np
from rclpy.node import Node

from bearing_common import topics
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_seconds
from bearing_common.states import parse_fault
from bearing_msgs.msg import Residual, ShaftSpeed, VibrationChunk

from .chunk_stream import ChunkStream
from .hw_model import ModelFileError
from .model_sets import choose_model_set
from .kernels import warm_up
from .observer import FaultObserver
from .observer_node_config import PARAMETERS, default_node_name

WARN_PERIOD_S = 5.0


class ObserverNode(Node):
    """Thin adapter: VibrationChunk -> FaultObserver.process -> Residual."""

    def __init__(self, name: str):
        super().__init__(name)
        self.values = declare(self, PARAMETERS)
        self.fault = parse_fault(self.values["fault_type"])
        self.rpm = float(self.values["rpm"])
        self.observer = None
        self.model_set = None
        self.stream = ChunkStream(topics.VIBRATION.name)
        warm_up()  # compile or load the kernels now, not on the first chunks
        out = topics.residual_topic(self.fault)
        self.pub = self.create_publisher(Residual, out.name, topics.qos(out))
        self.create_subscription(VibrationChunk, topics.VIBRATION.name, self.on_chunk, topics.qos(topics.VIBRATION))
        self.create_subscription(ShaftSpeed, topics.SHAFT_SPEED.name, self.on_speed, topics.qos(topics.SHAFT_SPEED))
        self.get_logger().info(f"{self.fault.label} observer: {topics.VIBRATION.name} -> {self.pub.topic_name}")

    def on_speed(self, msg: ShaftSpeed) -> None:
        rpm = msg.angular_velocity * 60.0 / (2.0 * math.pi)
        if not math.isfinite(rpm) or rpm <= 0:
            self.stream.counts["bad shaft speed"] += 1
            self.get_logger().warn(f"ignoring shaft speed {msg.angular_velocity!r} rad/s",
                                   throttle_duration_sec=WARN_PERIOD_S)
            return
        if abs(rpm - self.rpm) > float(self.values["speed_tolerance"]) * self.rpm:
            self.rpm = rpm
            if self.observer is not None:
                self.observer.set_speed(rpm)

    def _ensure_observer(self, msg: VibrationChunk) -> bool:
        """Build (or rebuild for a new rate or source) the observer; False when no model fits."""
        try:
            wanted = self.values["model_set"] or choose_model_set(msg.source, msg.sample_rate, None).name
            if self.observer is not None and wanted == self.model_set and self.observer.sample_rate == msg.sample_rate:
                return True
            self.observer = FaultObserver.from_model_set(wanted, self.fault.label, self.rpm, msg.sample_rate)
        except (ModelFileError, ValueError) as exc:
            self.observer = None
            self.stream.counts["no model"] += 1
            self.get_logger().error(f"cannot observe {msg.sample_rate:g} Hz '{msg.source}' data: {exc}",
                                    throttle_duration_sec=WARN_PERIOD_S)
            return False
        self.model_set = wanted
        self.get_logger().info(f"model set {wanted} at {msg.sample_rate:g} Hz, {self.rpm:.1f} rpm, "
                               f"fault frequency {self.observer.fault_frequency:.3f} Hz")
        return True

    def on_chunk(self, msg: VibrationChunk) -> None:
        y = np.asarray(msg.samples, dtype=float)
        verdict = self.stream.check(to_seconds(msg.header.stamp), msg.first_sample_index, msg.sample_rate, y)
        if not verdict.accepted:
            self.get_logger().warn(f"rejected chunk ({dict(self.stream.counts)}): {verdict.reason}",
                                   throttle_duration_sec=WARN_PERIOD_S)
            return
        if not self._ensure_observer(msg):
            return
        if verdict.resync:
            self.observer.reset()
            if verdict.reason:
                self.get_logger().info(verdict.reason)
        out = self.observer.process(y)
        if not (np.all(np.isfinite(out.residual)) and np.all(np.isfinite(out.estimate))):
            self.stream.counts["non-finite output"] += 1
            self.observer.reset()
            self.stream.restart()
            self.get_logger().error("observer produced non-finite values; state reset, chunk dropped")
            return
        res = Residual(sample_rate=msg.sample_rate, first_sample_index=msg.first_sample_index,
                       fault_hypothesis=int(self.fault), model_set=self.model_set,
                       fault_frequency=float(self.observer.fault_frequency))
        res.header = msg.header
        res.residual = out.residual.tolist()
        res.estimate = out.estimate.tolist()
        res.impulse_train = out.impulse_train.tolist()
        self.pub.publish(res)


def main(args=None) -> int:
    argv = sys.argv if args is None else args
    return run_node_main("observer", lambda: ObserverNode(default_node_name(argv)), None, argv)

if __name__ == "__main__":
    sys.exit(main())
