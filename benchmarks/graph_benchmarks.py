"""`make bench` rows of the live graph: end-to-end latency over DDS.

Latency = wall time at which a fault_state arrives minus wall time at which the
vibration chunk holding the last sample of its window arrived, both seen by one
listener process, with the four nodes as separate processes paced in real time.
"""

from __future__ import annotations

import bisect
import os
import threading
import time

import numpy as np

from bearing_bringup.graph import GRAPH, config_path
from bearing_bringup.graph_cli import installed_executable
from bearing_bringup.process_group import ProcessGroup

SCENARIO = "or-ir"
SEGMENT_S = 1.0


def bench_end_to_end_latency():
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from bearing_common import topics
    from bearing_msgs.msg import FaultState, VibrationChunk

    domain = 200 + os.getpid() % 30
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    os.environ.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    node = rclpy.create_node("latency_probe", context=context)
    chunk_ends, chunk_wall, latencies = [], [], []
    lock = threading.Lock()

    def on_chunk(msg):
        end = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 + len(msg.samples) / msg.sample_rate
        with lock:
            chunk_ends.append(end)
            chunk_wall.append(time.monotonic())

    def on_state(msg):
        arrived = time.monotonic()
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        with lock:
            i = bisect.bisect_left(chunk_ends, t - 1e-9)
            if i < len(chunk_ends):
                latencies.append(arrived - chunk_wall[i])

    node.create_subscription(VibrationChunk, topics.VIBRATION.name, on_chunk, topics.qos(topics.VIBRATION, depth=100))
    node.create_subscription(FaultState, topics.FAULT_STATE.name, on_state, topics.qos(topics.FAULT_STATE, depth=100))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    group = ProcessGroup(env=env, echo=False)
    try:
        for spec in GRAPH:
            argv = [str(installed_executable(spec.package, spec.executable)), "--ros-args",
                    "-r", f"__node:={spec.name}", "--params-file", str(config_path())]
            if spec.executable == "simulator":
                argv += ["-p", f"scenario:={SCENARIO}", "-p", f"segment_duration:={SEGMENT_S}"]
            group.start(spec.name, argv)
        sim = group.members[0]
        deadline = time.monotonic() + 120.0
        while sim.returncode is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        settle = time.monotonic() + 2.0
        while time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.01)
    finally:
        group.stop()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)  # a Ctrl-C may have shut it down (Jazzy: shutdown() raises then)
    if not latencies:
        raise RuntimeError("no fault_state received: " + "\n".join(sum((m.lines[-5:] for m in group.members), [])))
    lat = np.array(latencies) * 1e3
    return [
        ("end-to-end latency vibration chunk -> fault_state, median (live graph, 48 kHz, 10 ms chunks)",
         float(np.median(lat)), "ms"),
        ("end-to-end latency vibration chunk -> fault_state, 95th percentile", float(np.percentile(lat, 95)), "ms"),
        ("fault_state messages measured", len(lat), "count"),
    ]
