"""An rclpy listener for ``bearing-graph``: each motor's fault states, ground truth and vibration, for the report.

One node in its own context watches the graphs of every namespace given (one motor per
namespace, ``""`` = the root); :class:`MotorLog` keeps what one motor's graph published.
A motor's vibration is subscribed only once its ground truth arrives (the simulator
publishes it with the first chunk): until then the watcher is not counted among the
subscribers the simulator's start waits for (``wait_for_subscribers``: the observers).
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable

import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions

from bearing_common import topics
from bearing_common.stamps import to_seconds
from bearing_common.states import FaultState
from bearing_msgs.msg import FaultState as FaultStateMsg
from bearing_msgs.msg import VibrationChunk

from .state_report import StateChange

QUEUE = 100  # subscription depth: every state change is kept, even when this thread lags
KEEP_SIGNAL_S = 60.0  # seconds of vibration kept for the plot


class MotorLog:
    """What one motor's graph published: decisions, ground truth, the recent vibration (thread-safe)."""

    def __init__(self, motor: str):
        self.motor = motor
        self._lock = threading.Lock()
        self._decisions: list = []
        self._truth: list = []
        self._signal = collections.deque()
        self._fs = None
        self._end = None

    def add_state(self, change: StateChange) -> str | None:
        """A published decision; returns the text of a state change, None when the state stayed."""
        with self._lock:
            previous = self._decisions[-1] if self._decisions else None
            self._decisions.append(change)
        if previous is not None and previous.state == change.state:
            return None
        before = FaultState(previous.state).name if previous else "(start)"
        return (f"t={change.detected_at:.3f} s  {before} -> {FaultState(change.state).name}  "
                f"(confidence {change.confidence:.2f}, onset {change.onset:.3f} s)")

    def add_truth(self, change: StateChange) -> None:
        with self._lock:
            if self._truth and change.onset <= self._truth[-1].onset:  # a restarted simulator: a new run
                self._truth.clear()
                self._decisions.clear()
                self._signal.clear()
            self._truth.append(change)

    def add_chunk(self, t0: float, samples: np.ndarray, sample_rate: float) -> None:
        """A vibration chunk whose first sample is at ``t0`` (s)."""
        with self._lock:
            self._fs = sample_rate
            self._end = t0 + len(samples) / sample_rate
            self._signal.append((t0, samples))
            while self._signal and self._end - self._signal[0][0] > KEEP_SIGNAL_S:
                self._signal.popleft()

    def truth_changes(self) -> list:
        with self._lock:
            return list(self._truth)

    def state_changes(self, all_decisions: bool = False) -> list:
        """Published states; only the changes unless ``all_decisions``."""
        with self._lock:
            decisions = list(self._decisions)
        if all_decisions:
            return decisions
        return [d for i, d in enumerate(decisions) if i == 0 or decisions[i - 1].state != d.state]

    def decided_to_end(self, slack: float = 0.06) -> bool:
        """A fault_state covers the end of the received signal (within ``slack`` s)."""
        with self._lock:
            return self._end is not None and bool(self._decisions) and \
                self._decisions[-1].detected_at >= self._end - slack

    def signal_end(self) -> float | None:
        with self._lock:
            return self._end

    def plot(self, path, truth, decided, end) -> None:
        """Acceleration with the true and the published states (PNG)."""
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        with self._lock:
            parts = list(self._signal)
            fs = self._fs
        fig, (ax_sig, ax_state) = plt.subplots(2, 1, sharex=True, figsize=(10, 5.5),
                                               gridspec_kw={"height_ratios": [2, 1]})
        if parts and fs:
            t = np.concatenate([t0 + np.arange(len(s)) / fs for t0, s in parts])
            ax_sig.plot(t, np.concatenate([s for _, s in parts]), lw=0.4)
        ax_sig.set_ylabel("drive-end accel (m/s²)")
        for changes, label, style in ((truth, "true", "k-"), (decided, "published", "r--")):
            if changes:
                times = [c.onset if label == "true" else c.detected_at for c in changes] + [end]
                states = [c.state for c in changes] + [changes[-1].state]
                ax_state.step(times, states, style, where="post", label=label)
        ax_state.set_yticks([int(s) for s in FaultState], [s.name for s in FaultState], fontsize=7)
        ax_state.set_xlabel("time (s)")
        ax_state.legend(loc="upper left", fontsize=8)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)


class GraphWatcher:
    """Collects ``fault_state``, ``sim/truth`` and ``vibration/drive_end`` of each namespace in
    ``namespaces`` in a background thread; ``motors[namespace]`` holds them."""

    def __init__(self, namespaces=("",)):
        self.on_change: Callable[[str, str], None] | None = None  # (motor, text) of each state change
        self.motors = {ns.strip("/"): MotorLog(ns.strip("/")) for ns in namespaces}
        self.context = rclpy.Context()
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO)  # bearing-graph's own
        self.node = rclpy.create_node("graph_watcher", context=self.context)
        self._state_subscriptions = {}
        for ns, log in self.motors.items():
            self._state_subscriptions[log.motor] = self.node.create_subscription(
                FaultStateMsg, topics.qualified(ns, topics.FAULT_STATE), lambda msg, log=log: self._on_state(log, msg),
                topics.qos(topics.FAULT_STATE, depth=QUEUE))
            self.node.create_subscription(FaultStateMsg, topics.qualified(ns, topics.TRUTH),
                                          lambda msg, log=log: self._on_truth(log, msg),
                                          topics.qos(topics.TRUTH, depth=QUEUE))
        self._vibration: set = set()  # motors whose vibration is subscribed
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._running = True
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while self._running and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # Jazzy: RCLError when a signal shuts the context down mid-spin
                if self.context.ok():
                    raise

    def _on_state(self, log: MotorLog, msg):
        text = log.add_state(StateChange(int(msg.state), to_seconds(msg.onset), to_seconds(msg.header.stamp),
                                         float(msg.confidence)))
        if text is not None and self.on_change:
            self.on_change(log.motor, text)

    def _on_truth(self, log: MotorLog, msg):
        log.add_truth(StateChange(int(msg.state), to_seconds(msg.onset), to_seconds(msg.header.stamp)))
        if log.motor not in self._vibration:
            self._vibration.add(log.motor)
            self.node.create_subscription(VibrationChunk, topics.qualified(log.motor, topics.VIBRATION),
                                          lambda chunk: self._on_chunk(log, chunk),
                                          topics.qos(topics.VIBRATION, depth=QUEUE))

    @staticmethod
    def _on_chunk(log: MotorLog, msg):
        log.add_chunk(to_seconds(msg.header.stamp), np.asarray(msg.samples), msg.sample_rate)

    def wait_for_diagnosers(self, timeout: float, stop, motors=None) -> list:
        """Wait until the fault_state of each of ``motors`` (default: all) has a matched publisher,
        its diagnoser, or ``stop``; return the motors still without one. Started before the
        sensors, this makes sure the first decisions are received (a late match delivers only
        the last few)."""
        subscriptions = {m: self._state_subscriptions[m] for m in (self.motors if motors is None else motors)}
        deadline = time.monotonic() + timeout
        while True:
            pending = [m for m, sub in subscriptions.items() if sub.get_publisher_count() == 0]
            if not pending or time.monotonic() >= deadline or stop:
                return pending
            time.sleep(0.05)

    def wait_decided_to_end(self, timeout: float, stop, motors=None) -> list:
        """Wait until a fault_state covers the end of the received signal of each of ``motors``
        (default: all), or ``stop``; return the motors that did not get there."""
        logs = [self.motors[m] for m in (self.motors if motors is None else motors)]
        deadline = time.monotonic() + timeout
        while True:
            pending = [log.motor for log in logs if not log.decided_to_end()]
            if not pending or time.monotonic() >= deadline or stop:
                return pending
            time.sleep(0.05)

    def close(self) -> None:
        self._running = False
        self._thread.join(timeout=2.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)  # a signal may have shut it down (Jazzy: shutdown() raises then)
