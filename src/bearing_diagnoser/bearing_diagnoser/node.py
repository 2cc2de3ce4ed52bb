"""The ``diagnoser`` node: fault states from the two observers' residuals.

Subscribes ``residual/outer_race`` and ``residual/inner_race`` (and
``shaft_speed`` for the health report); publishes ``fault_state`` (FaultState,
reliable + transient local: a late subscriber sees the current state) on every
decision, and ``/diagnostics`` (OK for NORMAL, ERROR for a fault, WARN for
UNKNOWN or a silent observer, STALE when no residual arrives). Signal timing
comes from the residuals' stamps and sample indices only, so replays at any
rate (with ``use_sim_time``) give the same decisions.
"""

import sys

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node

from bearing_common import topics
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_seconds, to_stamp
from bearing_common.states import FaultState
from bearing_msgs.msg import FaultState as FaultStateMsg
from bearing_msgs.msg import Residual, ShaftSpeed
from bearing_observer.chunk_stream import ChunkStream
from bearing_observer.model_sets import SHIPPED

from .decision import Diagnoser, config_for
from .diagnoser_node_config import PARAMETERS, health

WARN_PERIOD_S = 5.0


class DiagnoserNode(Node):
    """Thin adapter: Residual chunks -> Diagnoser.update -> FaultState and /diagnostics."""

    def __init__(self):
        super().__init__("diagnoser")
        self.values = declare(self, PARAMETERS)
        self.core = None
        self.core_streams = set()  # hypotheses that have fed the current core (a restart of either starts a new one)
        self.time_offset = None  # stamp of sample index 0 (s)
        self.streams = {h: ChunkStream(topic.name) for h, topic in topics.RESIDUALS.items()}
        self.last_heard = {h: None for h in topics.RESIDUALS}
        self.last_decision = None
        self.shaft_speed = None
        self.warm_thresholds()  # before subscribing: being subscribed means being ready
        self.pub_state = self.create_publisher(FaultStateMsg, topics.FAULT_STATE.name, topics.qos(topics.FAULT_STATE))
        self.pub_diag = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS.name, topics.qos(topics.DIAGNOSTICS))
        for h, topic in topics.RESIDUALS.items():
            self.create_subscription(Residual, topic.name, lambda msg, h=h: self.on_residual(h, msg), topics.qos(topic))
        self.create_subscription(ShaftSpeed, topics.SHAFT_SPEED.name, self.on_speed, topics.qos(topics.SHAFT_SPEED))
        self.create_timer(float(self.values["diagnostics_period"]), self.publish_diagnostics)

    def warm_thresholds(self) -> None:
        """Derive the thresholds of every model set this node may meet (about 1 s each)."""
        for name, entry in SHIPPED.items():
            if self.values["model_set"] in ("", name):
                Diagnoser(self._config(name), model_set=name, sample_rate=entry.sample_rate).thresholds()

    def _config(self, name: str):
        overrides = {}
        if self.values["false_alarm_probability"] > 0:
            overrides["pfa"] = float(self.values["false_alarm_probability"])
        if self.values["window"] > 0:
            overrides["window_s"] = float(self.values["window"])
        if self.values["hop"] > 0:
            overrides["hop_s"] = float(self.values["hop"])
        return config_for(name, **overrides)

    def _make_core(self, model_set: str, sample_rate: float) -> Diagnoser:
        name = self.values["model_set"] or model_set
        core = Diagnoser(self._config(name), model_set=name, sample_rate=sample_rate)
        core.keep_history = False
        cfg = core.config
        threshold, kurtosis_threshold = core.thresholds()  # cached by warm_thresholds for the default sets
        self.get_logger().info(f"deciding with {name} defaults: window {cfg.window_s:g} s, hop {cfg.hop_s:g} s, "
                               f"false-alarm probability {cfg.pfa:g} per window -> periodicity threshold "
                               f"{threshold:.3g}, kurtosis threshold {kurtosis_threshold:.3g}")
        return core

    def on_speed(self, msg: ShaftSpeed) -> None:
        self.shaft_speed = msg.angular_velocity

    def on_residual(self, hypothesis: FaultState, msg: Residual) -> None:
        self.last_heard[hypothesis] = self.get_clock().now()
        r = np.asarray(msg.residual, dtype=float)
        stamp = to_seconds(msg.header.stamp)
        verdict = self.streams[hypothesis].check(stamp, msg.first_sample_index, msg.sample_rate, r)
        if verdict.accepted and not (len(msg.estimate) == len(msg.impulse_train) == len(r)):
            verdict = None
        if not verdict or not verdict.accepted:
            self.get_logger().warn(f"rejected residual chunk: {verdict.reason if verdict else 'array lengths differ'}",
                                   throttle_duration_sec=WARN_PERIOD_S)
            return
        if self.core is None or (verdict.restart and hypothesis in self.core_streams):
            if self.core is not None:
                self.get_logger().info(f"{verdict.reason}; restarting the decision")
            self.core = self._make_core(msg.model_set, msg.sample_rate)
            self.core_streams = set()
            self.time_offset = stamp - msg.first_sample_index / msg.sample_rate
        self.core_streams.add(hypothesis)
        try:
            decisions = self.core.update(hypothesis, msg.first_sample_index, msg.sample_rate, r,
                                         np.asarray(msg.estimate), np.asarray(msg.impulse_train), msg.fault_frequency)
        except ValueError as exc:
            self.streams[hypothesis].counts["rejected by decision"] += 1
            self.get_logger().warn(f"rejected residual chunk: {exc}", throttle_duration_sec=WARN_PERIOD_S)
            return
        for decision in decisions:
            self.publish_state(decision)

    def publish_state(self, decision) -> None:
        msg = FaultStateMsg(state=int(decision.state), confidence=float(decision.confidence),
                            model_set=self.core.model_set, detail=decision.detail)
        msg.header.stamp = to_stamp(self.time_offset + decision.time)
        msg.onset = to_stamp(self.time_offset + decision.onset)
        msg.hypotheses = list(decision.scores)
        msg.scores = [float(v) for v in decision.scores.values()]
        self.pub_state.publish(msg)
        if decision.changed:
            self.get_logger().info(f"t={self.time_offset + decision.time:.3f} s  state {decision.state.name} "
                                   f"(confidence {decision.confidence:.2f}, onset "
                                   f"{self.time_offset + decision.onset:.3f} s)")
        self.last_decision = decision

    def publish_diagnostics(self) -> None:
        now = self.get_clock().now()
        timeout = float(self.values["stale_timeout"])
        silent = [topics.RESIDUALS[h].name for h, t in self.last_heard.items()
                  if t is None or (now - t).nanoseconds * 1e-9 > timeout]
        state = self.last_decision.state if self.last_decision else FaultState.NORMAL
        level, message = health(state, silent, len(silent) == len(topics.RESIDUALS))
        status = DiagnosticStatus(level=bytes([level]), name=f"{self.get_name()}: bearing drive_end",
                                  message=message, hardware_id="drive_end")
        values = {"state": FaultState(state).name}
        if self.last_decision is not None:
            values["confidence"] = f"{self.last_decision.confidence:.3f}"
            values["onset (s)"] = f"{self.time_offset + self.last_decision.onset:.4f}"
            values.update({k: f"{v:.4g}" for k, v in self.last_decision.scores.items()})
        if self.shaft_speed is not None:
            values["shaft speed (rad/s)"] = f"{self.shaft_speed:.3f}"
        for h, stream in self.streams.items():
            values[f"{topics.RESIDUALS[h].name} chunks"] = ", ".join(f"{k} {v}" for k, v in sorted(stream.counts.items()))
        status.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
        array = DiagnosticArray(status=[status])
        array.header.stamp = now.to_msg()
        self.pub_diag.publish(array)


def main(args=None) -> int:
    return run_node_main("diagnoser", DiagnoserNode, None, args)

if __name__ == "__main__":
    sys.exit(main())
