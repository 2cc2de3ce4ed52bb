"""The ``simulator`` node: publishes the 29-DOF model's output in chunks, in simulation time.

Topics (relative names, so a namespace per machine works):
``vibration/drive_end`` and ``unbalance`` (VibrationChunk), ``shaft_speed``
(ShaftSpeed, rad/s, ``speed_rate`` messages per second of signal time), optionally
``shaft_pulses`` (Tachometer: the pulses of each chunk, with ``tachometer``), ``sim/truth`` (FaultState,
transient local; evaluation only), optionally ``/clock``. Stamps are simulation time
(0 at the start of the run, continuing across repeats and speed changes). Paced to
wall-clock time unless ``realtime`` is false. ``rpm``, ``noise_density`` and
``realtime`` can be set while it runs (``ros2 param set``); a changing speed is the
``rpm_profile`` / ``speed_wobble`` schedule. The logic lives in :mod:`.sim_stream`
and :mod:`.pacer`.
"""

import array
import sys
import time

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rosgraph_msgs.msg import Clock

from bearing_common import topics
from bearing_common.delivery import ACK_TIMEOUT_S, wait_acknowledged
from bearing_common.node_main import POLL_S, run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_stamp
from bearing_common.states import FaultState
from bearing_msgs.msg import FaultState as FaultStateMsg
from bearing_msgs.msg import ShaftSpeed, Tachometer, VibrationChunk

from .pacer import Pacer, SubscriberGate
from .sim_node_config import PARAMETERS, SOURCE, build_run, parse_wait_spec
from .sim_stream import SimulationStream
from .simulator import SimChunk, Simulator

BEHIND_WARN_S = 0.5  # s behind real time before warning
WARN_PERIOD_S = 5.0


class SimulatorNode(Node):
    """Thin adapter: parameters -> SimulationStream and Pacer; chunks -> messages."""

    def __init__(self):
        super().__init__("simulator")
        self.values = declare(self, PARAMETERS, self.on_change)
        self.run = build_run(self.values)
        self.stream = SimulationStream(self.run, bool(self.values["repeat"]))
        self.pacer = Pacer(bool(self.values["realtime"]))
        self.pub_vib = self.create_publisher(VibrationChunk, topics.VIBRATION.name, topics.qos(topics.VIBRATION))
        self.pub_unb = self.create_publisher(VibrationChunk, topics.UNBALANCE.name, topics.qos(topics.UNBALANCE))
        self.pub_speed = self.create_publisher(ShaftSpeed, topics.SHAFT_SPEED.name, topics.qos(topics.SHAFT_SPEED))
        self.pub_truth = self.create_publisher(FaultStateMsg, topics.TRUTH.name, topics.qos(topics.TRUTH))
        self.pub_tacho = self.create_publisher(Tachometer, topics.TACHOMETER.name, topics.qos(topics.TACHOMETER)) \
            if self.run.tacho_pulses else None
        self.pub_clock = self.create_publisher(Clock, topics.CLOCK.name, topics.qos(topics.CLOCK)) \
            if self.values["publish_clock"] else None
        pacing = "real time" if self.values["realtime"] else "as fast as possible"
        speed = (f"{self.stream.rpm:g} rpm" if self.run.config.speed_profile is None
                 else f"speed profile {self.run.config.speed_profile!r}")
        self.get_logger().info(
            f"simulating {self._describe()} at {speed}, {self.stream.sample_rate:g} Hz, "
            f"chunks of {self.run.chunk_samples} samples, {pacing}")

    def _describe(self) -> str:
        if self.run.schedule is None:
            return "normal operation (no end)"
        return ", ".join(f"{state.label} {seconds:g} s" for state, seconds in self.run.schedule)

    @property
    def streams(self) -> dict:
        """The run's publishers by topic name (not /clock's)."""
        own = {topics.VIBRATION.name: self.pub_vib, topics.UNBALANCE.name: self.pub_unb,
               topics.SHAFT_SPEED.name: self.pub_speed, topics.TRUTH.name: self.pub_truth}
        if self.pub_tacho is not None:
            own[topics.TACHOMETER.name] = self.pub_tacho
        return own

    def subscribers(self, topic: str) -> int:
        """Subscriptions matched by our publisher of ``topic`` (samples published from now on reach
        them: what a volatile stream needs), else the graph's count for topics of other nodes."""
        own = self.streams
        return own[topic].get_subscription_count() if topic in own else self.count_subscribers(topic)

    def on_change(self, changed: dict) -> None:
        """Apply live parameter changes (from the next chunk on)."""
        if "rpm" in changed:
            self.stream.set_rpm(changed["rpm"])
        if "noise_density" in changed:
            self.stream.set_noise_density(changed["noise_density"])
        if "realtime" in changed:
            self.pacer.set_realtime(changed["realtime"], time.monotonic())
        self.get_logger().info("set " + ", ".join(f"{k} = {v}" for k, v in changed.items()) + " (next chunk on)")

    def publish_next(self) -> SimChunk | None:
        """Simulate and publish one chunk; None when the run has ended."""
        chunk = self.stream.next_chunk()
        if chunk is None:
            return None
        stamp = to_stamp(chunk.t0)
        if self.pub_clock is not None:
            self.pub_clock.publish(Clock(clock=stamp))
        for state, onset in self.stream.truth_changes(chunk):
            msg = FaultStateMsg(state=int(state), confidence=1.0, detail="ground truth")
            msg.header.stamp = msg.onset = to_stamp(onset)
            self.pub_truth.publish(msg)
            self.get_logger().info(f"t={onset:.4f} s  true state {state.name}")
        self.pub_vib.publish(self._chunk_msg(stamp, chunk.start_index, chunk.accel, self.values["frame_id"]))
        self.pub_unb.publish(self._chunk_msg(stamp, chunk.start_index, chunk.unbalance, "disk"))
        for t, omega in self.stream.speed_samples(chunk):
            speed = ShaftSpeed(angular_velocity=omega, source=SOURCE)
            speed.header.stamp = to_stamp(t)
            self.pub_speed.publish(speed)
        if self.pub_tacho is not None:
            times, first = self.stream.tacho_pulses(chunk)
            tacho = Tachometer(duration=len(chunk) / self.stream.sample_rate, first_pulse_index=first,
                               pulses_per_revolution=self.run.tacho_pulses, timing_jitter=self.run.tacho_jitter,
                               source=SOURCE)
            tacho.header.stamp = stamp
            tacho.header.frame_id = "shaft"
            tacho.pulse_offsets = array.array("d", (times - chunk.t0).tobytes())
            self.pub_tacho.publish(tacho)
        return chunk

    def _chunk_msg(self, stamp, index, samples, frame_id) -> VibrationChunk:
        msg = VibrationChunk(sample_rate=self.stream.sample_rate, first_sample_index=index, source=SOURCE)
        msg.header.stamp = stamp
        msg.header.frame_id = frame_id
        msg.samples = array.array("d", np.ascontiguousarray(samples, dtype=np.float64).tobytes())  # one copy,
        # where a list would be converted and checked element by element
        return msg


WARM_UP_SCHEDULE = [(FaultState.OUTER_RACE, 0.002), (FaultState.INNER_RACE, 0.002), (FaultState.NORMAL, 0.002)]


def warm_up(node: SimulatorNode) -> None:
    """Load (or compile) the simulator's compiled code before the real-time clock starts (a stop
    signal meanwhile ends it: ``stop.aborting()``)."""
    start = time.monotonic()
    scratch = Simulator(node.run.config, WARM_UP_SCHEDULE)
    while not scratch.finished:
        scratch.advance(node.run.chunk_samples)
    node.get_logger().info(f"simulator ready after {time.monotonic() - start:.2f} s of loading/compilation")


def run_node(node: SimulatorNode, stop) -> None:
    """Hold the start until the consumers listen, then publish until the run ends or a stop
    is requested, serving parameter changes and DDS while waiting for real time; at the run's end,
    wait until every reliable subscriber has acknowledged the last chunk (:mod:`bearing_common.delivery`),
    then linger."""
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        with stop.aborting():  # a first compile after an install: seconds, mostly in LLVM (C)
            warm_up(node)
        gate = SubscriberGate(parse_wait_spec(node.values["wait_for_subscribers"]),
                              float(node.values["subscriber_timeout"]), time.monotonic())
        while not stop and not gate.is_open(node.subscribers, time.monotonic()):
            executor.spin_once(timeout_sec=0.05)
        for topic, n, have in gate.missing(node.subscribers):
            node.get_logger().warn(f"starting with {have} of {n} subscribers to {topic}")
        publish(node, executor, stop)
        if unacknowledged := wait_acknowledged(node.streams.values(), stop=stop):
            node.get_logger().warn(f"not every subscriber acknowledged the end of {', '.join(unacknowledged)} "
                                   f"within {ACK_TIMEOUT_S:g} s")
        linger_end = time.monotonic() + float(node.values["linger"])
        while not stop and time.monotonic() < linger_end:
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()


def publish(node: SimulatorNode, executor, stop) -> None:
    pacer = node.pacer
    pacer.start(time.monotonic())
    while not stop:
        t_busy = time.thread_time()
        chunk = node.publish_next()
        if chunk is None:
            break
        pacer.chunk_done(len(chunk) / node.stream.sample_rate, time.thread_time() - t_busy)
        while True:  # at least one spin per chunk; while ahead of real time, wait by spinning
            ahead = pacer.ahead(time.monotonic())
            executor.spin_once(timeout_sec=min(max(ahead, 0.0), POLL_S))
            if ahead <= 0.0 or stop:
                break
        if ahead < -BEHIND_WARN_S:
            node.get_logger().warn(f"falling behind real time by {-ahead:.2f} s", throttle_duration_sec=WARN_PERIOD_S)
        if (line := pacer.report(time.monotonic())) is not None:
            node.get_logger().info(line)
    node.get_logger().info(f"run ended after {pacer.simulated:.3f} s simulated; compute real-time factor "
                           f"{pacer.realtime_factor:.2f}")


def main(args=None) -> int:
    return run_node_main("simulator", SimulatorNode, run_node, args)


if __name__ == "__main__":
    sys.exit(main())
