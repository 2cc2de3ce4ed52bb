"""The ``simulator`` node: publishes the 29-DOF model's output in chunks, in simulation time.

Topics (relative names, so a namespace per machine works):
``vibration/drive_end`` and ``unbalance`` (VibrationChunk), ``shaft_speed``
(ShaftSpeed, rad/s), ``sim/truth`` (FaultState, transient local; evaluation only),
optionally ``/clock``. Stamps are simulation time (0 at the start of the run,
continuing across repeats). Paced to wall-clock time unless ``realtime`` is false.
"""

import math
import sys
import time

import rclpy
from rclpy.node import Node
from rosgraph_msgs.msg import Clock

from bearing_common import topics
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_stamp
from bearing_common.states import FaultState
from bearing_msgs.msg import FaultState as FaultStateMsg
from bearing_msgs.msg import ShaftSpeed, VibrationChunk

from .sim_node_config import PARAMETERS, SOURCE, build_run, parse_wait_spec
from .simulator import Simulator

ENDLESS_SEGMENT_S = 3600.0  # normal operation without a schedule: hour-long segments, repeated
RTF_LOG_PERIOD_S = 5.0  # wall seconds between real-time-factor log lines



class SimulatorNode(Node):
    """Thin adapter: parameters -> Simulator; chunks -> messages."""

    def __init__(self):
        super().__init__("simulator")
        self.values = declare(self, PARAMETERS)
        self.run = build_run(self.values)
        self.repeat = bool(self.values["repeat"]) or self.run.schedule is None
        self.schedule = self.run.schedule or [(FaultState.NORMAL, ENDLESS_SEGMENT_S)]
        self.pub_vib = self.create_publisher(VibrationChunk, topics.VIBRATION.name, topics.qos(topics.VIBRATION))
        self.pub_unb = self.create_publisher(VibrationChunk, topics.UNBALANCE.name, topics.qos(topics.UNBALANCE))
        self.pub_speed = self.create_publisher(ShaftSpeed, topics.SHAFT_SPEED.name, topics.qos(topics.SHAFT_SPEED))
        self.pub_truth = self.create_publisher(FaultStateMsg, topics.TRUTH.name, topics.qos(topics.TRUTH))
        self.pub_clock = self.create_publisher(Clock, topics.CLOCK.name, topics.qos(topics.CLOCK)) \
            if self.values["publish_clock"] else None
        self.omega = self.run.config.rpm * 2.0 * math.pi / 60.0
        self.fs = self.run.config.sample_rate
        self.sim = Simulator(self.run.config, self.schedule)
        self.time_offset = 0.0  # s of earlier repeats
        self.index_offset = 0
        self.last_truth = None
        self.get_logger().info(
            f"simulating {self._describe()} at {self.run.config.rpm:g} rpm, {self.fs:g} Hz, "
            f"chunks of {self.run.chunk_samples} samples, {'real time' if self.values['realtime'] else 'as fast as possible'}")

    def _describe(self) -> str:
        if self.run.schedule is None:
            return "normal operation (no end)"
        return ", ".join(f"{state.label} {seconds:g} s" for state, seconds in self.schedule)

    def step(self) -> bool:
        """Simulate and publish one chunk; False when the run has ended."""
        if self.sim.finished:
            if not self.repeat:
                return False
            self.time_offset += self.sim.samples_done / self.fs
            self.index_offset += self.sim.samples_done
            self.sim = Simulator(self.run.config, self.schedule)
        chunk = self.sim.advance(self.run.chunk_samples)
        t0 = self.time_offset + chunk.t0
        index = self.index_offset + chunk.start_index
        stamp = to_stamp(t0)
        if self.pub_clock is not None:
            self.pub_clock.publish(Clock(clock=stamp))
        self._publish_truth(chunk.truth, t0)
        self.pub_vib.publish(self._chunk_msg(stamp, index, chunk.accel, self.values["frame_id"]))
        self.pub_unb.publish(self._chunk_msg(stamp, index, chunk.unbalance, "disk"))
        speed = ShaftSpeed(angular_velocity=self.omega, source=SOURCE)
        speed.header.stamp = stamp
        self.pub_speed.publish(speed)
        return True

    def _chunk_msg(self, stamp, index, samples, frame_id) -> VibrationChunk:
        msg = VibrationChunk(sample_rate=self.fs, first_sample_index=index, source=SOURCE)
        msg.header.stamp = stamp
        msg.header.frame_id = frame_id
        msg.samples = samples.tolist()
        return msg

    def _publish_truth(self, truth, t0) -> None:
        """Publish sim/truth at every change of the true state, with its exact onset."""
        changes = [0] if self.last_truth is None or truth[0] != self.last_truth else []
        changes += [int(i) + 1 for i in (truth[1:] != truth[:-1]).nonzero()[0]]
        for i in changes:
            onset = to_stamp(t0 + i / self.fs)
            msg = FaultStateMsg(state=int(truth[i]), confidence=1.0, detail="ground truth")
            msg.header.stamp = onset
            msg.onset = onset
            self.pub_truth.publish(msg)
            self.get_logger().info(f"t={t0 + i / self.fs:.4f} s  true state {FaultState(int(truth[i])).name}")
        self.last_truth = int(truth[-1])


WARM_UP_SCHEDULE = [(FaultState.OUTER_RACE, 0.002), (FaultState.INNER_RACE, 0.002), (FaultState.NORMAL, 0.002)]


def warm_up(node: SimulatorNode) -> None:
    """Load (or compile) the simulator's compiled code before the real-time clock starts."""
    start = time.monotonic()
    scratch = Simulator(node.run.config, WARM_UP_SCHEDULE)
    while not scratch.finished:
        scratch.advance(node.run.chunk_samples)
    node.get_logger().info(f"simulator ready after {time.monotonic() - start:.2f} s of loading/compilation")


def wait_for_subscribers(node: SimulatorNode, stop) -> None:
    """Hold the start until the graph's consumers are matched (published chunks are not latched)."""
    wanted = parse_wait_spec(node.values["wait_for_subscribers"])
    deadline = time.monotonic() + float(node.values["subscriber_timeout"])

    def missing():
        return [(t, n, node.count_subscribers(t)) for t, n in wanted if node.count_subscribers(t) < n]

    while not stop and missing() and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    for topic, n, have in missing():
        node.get_logger().warn(f"starting with {have} of {n} subscribers to {topic}")


def run_node(node: SimulatorNode, stop) -> None:
    """Publish until the run ends, pacing to wall-clock time when asked; log the real-time
    factor of the compute (simulated seconds per CPU second of this thread spent
    simulating and publishing: not lowered by other processes sharing the cores)."""
    warm_up(node)
    wait_for_subscribers(node, stop)
    realtime = bool(node.values["realtime"])
    wall_start = time.monotonic()
    sim_seconds = 0.0
    busy = 0.0
    last_log = wall_start
    while not stop:
        t_busy = time.thread_time()
        if not node.step():
            break
        busy += time.thread_time() - t_busy
        sim_seconds += node.run.chunk_samples / node.fs
        rclpy.spin_once(node, timeout_sec=0.0)
        now = time.monotonic()
        if realtime:
            ahead = wall_start + sim_seconds - now
            if ahead > 0:
                time.sleep(ahead)
            elif ahead < -0.5:
                node.get_logger().warn(f"falling behind real time by {-ahead:.2f} s",
                                       throttle_duration_sec=RTF_LOG_PERIOD_S)
        if now - last_log >= RTF_LOG_PERIOD_S:
            node.get_logger().info(f"simulated {sim_seconds:.2f} s; compute real-time factor "
                                   f"{sim_seconds / max(busy, 1e-9):.2f}")
            last_log = now
    node.get_logger().info(f"run ended after {sim_seconds:.3f} s simulated; compute real-time factor "
                           f"{sim_seconds / max(busy, 1e-9):.2f}")
    linger_end = time.monotonic() + float(node.values["linger"])
    while not stop and time.monotonic() < linger_end:
        rclpy.spin_once(node, timeout_sec=0.05)


def main(args=None) -> int:
    return run_node_main("simulator", SimulatorNode, run_node, args)

if __name__ == "__main__":
    sys.exit(main())
