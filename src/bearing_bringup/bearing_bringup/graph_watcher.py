"""An rclpy listener for ``bearing-graph``: fault states, ground truth and the vibration, for the report."""

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


class GraphWatcher:
    """Collects ``fault_state``, ``sim/truth`` and ``vibration/drive_end`` in a background thread."""

    def __init__(self, namespace: str = ""):
        self.on_change: Callable[[str], None] | None = None
        self._lock = threading.Lock()
        self._decisions: list = []
        self._truth: list = []
        self._signal = collections.deque()
        self._fs = None
        self._end = None
        self.context = rclpy.Context()
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO)  # bearing-graph's own
        ns = f"/{namespace.strip('/')}" if namespace else ""
        self.node = rclpy.create_node("graph_watcher", namespace=ns or None, context=self.context)
        self.node.create_subscription(FaultStateMsg, topics.FAULT_STATE.name, self._on_state,
                                      topics.qos(topics.FAULT_STATE, depth=QUEUE))
        self.node.create_subscription(FaultStateMsg, topics.TRUTH.name, self._on_truth,
                                      topics.qos(topics.TRUTH, depth=QUEUE))
        self.node.create_subscription(VibrationChunk, topics.VIBRATION.name, self._on_chunk,
                                      topics.qos(topics.VIBRATION, depth=QUEUE))
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

    def _on_state(self, msg):
        change = StateChange(int(msg.state), to_seconds(msg.onset), to_seconds(msg.header.stamp), float(msg.confidence))
        with self._lock:
            previous = self._decisions[-1] if self._decisions else None
            self._decisions.append(change)
        if previous is None or previous.state != change.state:
            before = FaultState(previous.state).name if previous else "(start)"
            text = (f"t={change.detected_at:.3f} s  {before} -> {FaultState(change.state).name}  "
                    f"(confidence {change.confidence:.2f}, onset {change.onset:.3f} s)")
            if self.on_change:
                self.on_change(text)

    def _on_truth(self, msg):
        change = StateChange(int(msg.state), to_seconds(msg.onset), to_seconds(msg.header.stamp))
        with self._lock:
            if self._truth and change.onset <= self._truth[-1].onset:  # a restarted simulator: a new run
                self._truth.clear()
                self._decisions.clear()
                self._signal.clear()
            self._truth.append(change)

    def _on_chunk(self, msg):
        t0 = to_seconds(msg.header.stamp)
        samples = np.asarray(msg.samples)
        with self._lock:
            self._fs = msg.sample_rate
            self._end = t0 + len(samples) / msg.sample_rate
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

    def wait_decided_to_end(self, timeout: float, stop, slack: float = 0.06) -> bool:
        """Wait until a fault_state covers the end of the received signal (within ``slack`` s), or ``stop``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not stop:
            with self._lock:
                done = self._end is not None and self._decisions and \
                    self._decisions[-1].detected_at >= self._end - slack
            if done:
                return True
            time.sleep(0.05)
        return False

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

    def close(self) -> None:
        self._running = False
        self._thread.join(timeout=2.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)  # a signal may have shut it down (Jazzy: shutdown() raises then)
