"""A minimal separate process publishing one known VibrationChunk per 50 ms (DDS round-trip test)."""

import sys

import rclpy
from rclpy.executors import ExternalShutdownException

from bearing_common import topics
from bearing_msgs.msg import VibrationChunk

SAMPLES = [0.0, -1.5, 2.25, 1e-9, 3.0e4]


def known_chunk() -> VibrationChunk:
    msg = VibrationChunk()
    msg.header.stamp.sec = 12
    msg.header.stamp.nanosec = 345_000_000
    msg.header.frame_id = "drive_end"
    msg.sample_rate = 48000.0
    msg.first_sample_index = 480
    msg.source = "probe"
    msg.samples = SAMPLES
    return msg


def main() -> int:
    rclpy.init()
    node = rclpy.create_node("publish_probe")
    pub = node.create_publisher(VibrationChunk, topics.VIBRATION.name, topics.qos(topics.VIBRATION))
    node.create_timer(0.05, lambda: pub.publish(known_chunk()))
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
