"""The ``observer`` node: one fault observer (thesis Fig. 3.1) on the live vibration stream.

    ros2 run bearing_observer observer --ros-args -p fault_type:=outer_race -p bearing:=6205

Subscribes ``vibration/drive_end`` and ``shaft_speed``; publishes ``residual/outer_race``
or ``residual/inner_race`` (Residual: residual, estimate and the impulse train used, in
float32, the last two empty without a model; stamped with the input chunk's stamp).
Parameters (``observer_node_config``): ``bearing``, ``model_set``, ``rpm`` and
``speed_tolerance`` apply when set; ``fault_type`` is read-only. What happens to each
message is :class:`.observer_session.ObserverSession`'s.
"""

import array
import sys

import numpy as np
from rclpy.node import Node

from bearing_common import topics
from bearing_common.bearings import load_bearing
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_seconds
from bearing_common.states import parse_fault
from bearing_msgs.msg import Residual, ShaftSpeed, VibrationChunk

from .observer import warm_up
from .observer_node_config import PARAMETERS, default_node_name
from .observer_session import ObserverSession


class ObserverNode(Node):
    """Thin adapter: VibrationChunk -> ObserverSession.on_chunk -> Residual."""

    def __init__(self, name: str, namespace: str | None = None):
        super().__init__(name, namespace=namespace)
        values = declare(self, PARAMETERS, lambda changed: self.session.configure(changed))
        fault = parse_fault(values["fault_type"])
        self.session = ObserverSession(fault, load_bearing(values["bearing"]), values["model_set"], values["rpm"],
                                       values["speed_tolerance"], log=self.log)
        warm_up()  # compile or load the kernels now, not on the first chunks
        out = topics.residual_topic(fault)
        self.pub = self.create_publisher(Residual, out.name, topics.qos(out))
        self.create_subscription(VibrationChunk, topics.VIBRATION.name, self.on_chunk, topics.qos(topics.VIBRATION))
        self.create_subscription(ShaftSpeed, topics.SHAFT_SPEED.name, self.on_speed, topics.qos(topics.SHAFT_SPEED))
        self.get_logger().info(f"{fault.label} observer: {topics.VIBRATION.name} -> {self.pub.topic_name}")

    def log(self, level: str, text: str) -> None:
        logger = self.get_logger()  # one call site per severity (rclpy requires it)
        if level == "error":
            logger.error(text)
        elif level == "warning":
            logger.warning(text)
        else:
            logger.info(text)

    def on_speed(self, msg: ShaftSpeed) -> None:
        self.session.on_speed(msg.angular_velocity)

    def on_chunk(self, msg: VibrationChunk) -> None:
        out = self.session.on_chunk(to_seconds(msg.header.stamp), msg.first_sample_index, msg.sample_rate,
                                    msg.source, np.asarray(msg.samples, dtype=float))
        if out is None:
            return
        res = Residual(sample_rate=msg.sample_rate, first_sample_index=msg.first_sample_index,
                       fault_hypothesis=int(self.session.fault), model_set=out.model_set,
                       fault_frequency=out.fault_frequency)
        res.header = msg.header
        res.residual = float32_array(out.residual)
        if out.estimate is not None:  # else empty: no model (Residual.msg)
            res.estimate = float32_array(out.estimate)
            res.impulse_train = float32_array(out.impulse_train)
        self.pub.publish(res)


def float32_array(x: np.ndarray) -> array.array:
    """``x`` as the array.array('f') a float32[] message field takes as it is (one copy, no
    per-element checks; a list would be converted and checked element by element)."""
    return array.array("f", np.asarray(x, dtype=np.float32).tobytes())


def main(args=None) -> int:
    argv = sys.argv if args is None else args
    return run_node_main("observer", lambda: ObserverNode(default_node_name(argv)), None, argv)


if __name__ == "__main__":
    sys.exit(main())
