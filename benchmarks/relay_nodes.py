"""The per-message floor of the monitoring graph: bare rclpy relays in its place (``make bench``).

    python benchmarks/relay_nodes.py --hop SAMPLES --scores NAME,NAME,... /motor_1/or_observer \\
        /motor_1/ir_observer ... --ros-args --params-file fleet_params.yaml

Each named node stands in for the graph's node of that name (same fully qualified name,
topics, message types and QoS from :mod:`bearing_common.topics`, the same EventsExecutor
and process, :func:`bearing_common.node_main.run_nodes_main`) and does nothing else:

* ``or_observer`` / ``ir_observer``: every VibrationChunk becomes a Residual of the same
  length, built as the observer node builds its own (float32 arrays from bytes; estimate
  and train too unless the chunk's source and rate get model set ``none``);
* ``diagnoser``: takes both residual streams and publishes a FaultState with the real
  decision's scores (``--scores``: their names) every ``--hop`` samples of signal (its
  window hop), and a /diagnostics status with as many key-values as the real one's once a
  second.

``benchmarks/fleet_benchmarks.py`` runs them in the monitoring graph's process layout with
the same player and listener; the monitoring CPU over theirs is what our per-message work
costs above rclpy's own.
"""

from __future__ import annotations

import array
import sys

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node

from bearing_common import topics
from bearing_common.bearings import CATALOG, DEFAULT_BEARING
from bearing_common.node_main import run_nodes_main
from bearing_common.states import FaultState
from bearing_msgs.msg import FaultState as FaultStateMsg
from bearing_msgs.msg import Residual, ShaftSpeed, VibrationChunk
from bearing_observer.model_sets import NONE, choose_model_set

#: A diagnoser status's key-values besides one per score (DiagnoserSession.health).
STATUS_KEYS = ("state", "confidence", "onset (s)", "decided at (s)", "model set", "bearing", "shaft speed (rpm)",
               "residual/outer_race chunks", "residual/inner_race chunks")


def ignore(msg) -> None:
    """Shaft speeds are taken (as the real nodes take them) and dropped."""


def float32_array(x) -> array.array:
    return array.array("f", np.asarray(x, dtype=np.float32).tobytes())


class RelayObserver(Node):
    """VibrationChunk -> Residual of the same length (see the module docstring)."""

    def __init__(self, name: str, namespace: str):
        super().__init__(name, namespace=namespace)
        self.fault = FaultState.OUTER_RACE if name.startswith("or_") else FaultState.INNER_RACE
        self.full: dict = {}  # (source, rate) -> whether the observer would send estimate and train
        out = topics.residual_topic(self.fault)
        self.pub = self.create_publisher(Residual, out.name, topics.qos(out))
        self.create_subscription(VibrationChunk, topics.VIBRATION.name, self.on_chunk, topics.qos(topics.VIBRATION))
        self.create_subscription(ShaftSpeed, topics.SHAFT_SPEED.name, ignore, topics.qos(topics.SHAFT_SPEED))

    def on_chunk(self, msg: VibrationChunk) -> None:
        key = (msg.source, msg.sample_rate)
        if key not in self.full:
            self.full[key] = choose_model_set(msg.source, msg.sample_rate, CATALOG[DEFAULT_BEARING]).name != NONE
        res = Residual(sample_rate=msg.sample_rate, first_sample_index=msg.first_sample_index,
                       fault_hypothesis=int(self.fault), model_set="relay", fault_frequency=100.0)
        res.header = msg.header
        res.residual = float32_array(msg.samples)
        if self.full[key]:
            res.estimate = float32_array(msg.samples)
            res.impulse_train = float32_array(msg.samples)
        self.pub.publish(res)


class RelayDiagnoser(Node):
    """Both residual streams in; a FaultState every ``hop`` samples, /diagnostics every second."""

    def __init__(self, name: str, namespace: str, hop: int, scores: list):
        super().__init__(name, namespace=namespace)
        self.hop, self.scores = hop, scores
        self.next_end: dict = {}  # stream -> sample index of its next decision
        self.pub_state = self.create_publisher(FaultStateMsg, topics.FAULT_STATE.name, topics.qos(topics.FAULT_STATE))
        self.pub_diag = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS.name, topics.qos(topics.DIAGNOSTICS))
        for h, topic in topics.RESIDUALS.items():
            self.create_subscription(Residual, topic.name, lambda msg, h=h: self.on_residual(h, msg), topics.qos(topic))
        self.create_subscription(ShaftSpeed, topics.SHAFT_SPEED.name, ignore, topics.qos(topics.SHAFT_SPEED))
        self.create_timer(1.0, self.publish_diagnostics)

    def on_residual(self, hypothesis, msg: Residual) -> None:
        end = msg.first_sample_index + len(msg.residual)
        due = self.next_end.setdefault(hypothesis, self.hop)
        if hypothesis != FaultState.OUTER_RACE:  # one stream times the decisions, as windows close once
            return
        while due <= end:
            state = FaultStateMsg(state=0, confidence=1.0, model_set="relay", detail="")
            t_ns = (msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
                    + round((due - msg.first_sample_index) * 1e9 / msg.sample_rate))
            state.header.stamp.sec, state.header.stamp.nanosec = divmod(t_ns, 10**9)
            state.hypotheses = list(self.scores)
            state.scores = [0.0] * len(self.scores)
            self.pub_state.publish(state)
            due += self.hop
        self.next_end[hypothesis] = due

    def publish_diagnostics(self) -> None:
        status = DiagnosticStatus(level=b"\x00", name=f"relay{self.get_namespace()}", message="NORMAL",
                                  hardware_id=self.get_namespace())
        status.values = [KeyValue(key=k, value="0.000") for k in (*STATUS_KEYS, *self.scores)]
        array_msg = DiagnosticArray(status=[status])
        array_msg.header.stamp = self.get_clock().now().to_msg()
        self.pub_diag.publish(array_msg)


def make_nodes(names: list, hop: int, scores: list) -> list:
    nodes = []
    for fqn in names:
        namespace, _, name = fqn.rpartition("/")
        if name in ("or_observer", "ir_observer"):
            nodes.append(RelayObserver(name, namespace or "/"))
        elif name == "diagnoser":
            nodes.append(RelayDiagnoser(name, namespace or "/", hop, scores))
        else:
            raise ValueError(f"{fqn!r}: no relay for this node")
    return nodes


def main(argv=None) -> int:
    from rclpy.utilities import remove_ros_args

    argv = sys.argv if argv is None else argv
    args = remove_ros_args(argv)[1:]
    if len(args) < 4 or args[0] != "--hop" or args[2] != "--scores":
        print("relay_nodes: usage: relay_nodes.py --hop SAMPLES --scores NAME,... NODE... --ros-args ...",
              file=sys.stderr)
        return 2
    hop, scores, names = int(args[1]), args[3].split(","), args[4:]
    return run_nodes_main("relay_nodes", lambda: make_nodes(names, hop, scores), None, argv)


if __name__ == "__main__":
    sys.exit(main())
