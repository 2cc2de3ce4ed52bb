"""The graph's topics: name, message type and QoS, in one table (``CONTRACT.md``, "Topics").

Every node, bag tool, watcher and test takes its topic names and QoS from here. Names
are relative (a namespace per machine works), except the ROS-wide ``/diagnostics`` and
``/clock``.

QoS, chosen on purpose:

* measured sample streams (vibration, unbalance): reliable, volatile, keep last 50 — a
  consumer that is briefly busy loses nothing (a 0.01 s chunk every 10 ms: 0.5 s of
  slack), and a late joiner does not get stale signal;
* residuals: reliable, transient local, keep last 50 — the same slack, and a diagnoser
  whose reader matches an observer late (at a cold start the observers may publish before
  their writers have discovered the diagnoser's reader, whatever the graph already shows)
  or that starts after the observers still gets their last 0.5 s: it decides from the
  stream's start instead of losing it (each chunk carries its sample index and stamp, so
  history is never mistaken for new signal);
* ``shaft_speed``: reliable, keep last 10 (slow, only the latest matters);
* ``shaft_pulses`` (tachometer pulses): reliable, volatile, keep last 50 — a stream like the vibration (each
  message carries the pulses of one interval; a lost one would cost the shaft angle
  revolutions), so the same slack;
* ``fault_state``: reliable, transient local, keep last 10 — a late ``ros2 topic echo``
  gets the current state (the last of at most 10 recent decisions), and a burst of
  decisions (the diagnoser catching up) does not overwrite samples a reliable reader has
  not acknowledged yet, as keep-last-1 would; ``sim/truth`` keeps the last 10 changes;
* ``fleet_state``: reliable, transient local, keep last 1 (the current summary);
* ``health``: reliable, transient local, keep last 60 — a late dashboard or ``ros2 topic
  echo`` gets the current condition at once, with the recent trend to draw: the last minute
  of a stream (about 1 Hz) or the last hour of one-a-minute snapshots; reliable because the
  messages are few and small and each carries a state change's time;
* ``envelope_spectrum``: reliable, transient local, keep last 1 — a plot that joins late (Foxglove's
  live view, PlotJuggler) gets the current spectrum at once; only the latest is worth drawing;
* ``/diagnostics``: the ROS default (reliable, volatile, keep last 10), as
  ``diagnostic_aggregator`` expects.

Subscribers that must not miss a state change (recorders, watchers) use the same policies
with a deeper queue: ``qos(FAULT_STATE, depth=100)``.
"""

from __future__ import annotations

from dataclasses import dataclass

from .states import FaultState


@dataclass(frozen=True)
class Topic:
    """One topic of the graph.

    Attributes
    ----------
    name : str
        Relative name (``/diagnostics`` and ``/clock`` are absolute).
    msgtype : str
        ROS type name, e.g. ``bearing_msgs/msg/VibrationChunk``.
    depth : int
        Keep-last depth of publishers (and by default of subscribers).
    latched : bool
        Transient local durability: a late subscriber receives the last ``depth`` samples.
    """

    name: str
    msgtype: str
    depth: int
    latched: bool = False


VIBRATION = Topic("vibration/drive_end", "bearing_msgs/msg/VibrationChunk", 50)
UNBALANCE = Topic("unbalance", "bearing_msgs/msg/VibrationChunk", 50)
SHAFT_SPEED = Topic("shaft_speed", "bearing_msgs/msg/ShaftSpeed", 10)
TACHOMETER = Topic("shaft_pulses", "bearing_msgs/msg/Tachometer", 50)
TRUTH = Topic("sim/truth", "bearing_msgs/msg/FaultState", 10, latched=True)
RESIDUAL_OUTER_RACE = Topic("residual/outer_race", "bearing_msgs/msg/Residual", 50, latched=True)
RESIDUAL_INNER_RACE = Topic("residual/inner_race", "bearing_msgs/msg/Residual", 50, latched=True)
FAULT_STATE = Topic("fault_state", "bearing_msgs/msg/FaultState", 10, latched=True)
FLEET_STATE = Topic("fleet_state", "bearing_msgs/msg/FleetState", 1, latched=True)
HEALTH = Topic("health", "bearing_msgs/msg/HealthIndicators", 60, latched=True)
ENVELOPE_SPECTRUM = Topic("envelope_spectrum", "bearing_msgs/msg/EnvelopeSpectrum", 1, latched=True)
DIAGNOSTICS = Topic("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", 10)
CLOCK = Topic("/clock", "rosgraph_msgs/msg/Clock", 10)

#: Residual topic per fault hypothesis.
RESIDUALS = {FaultState.OUTER_RACE: RESIDUAL_OUTER_RACE, FaultState.INNER_RACE: RESIDUAL_INNER_RACE}

#: Every topic of one machine's graph, in the order recorders list them.
GRAPH_TOPICS: dict[str, Topic] = {t.name: t for t in (
    VIBRATION, UNBALANCE, SHAFT_SPEED, TACHOMETER, TRUTH, RESIDUAL_OUTER_RACE, RESIDUAL_INNER_RACE, FAULT_STATE, HEALTH,
    ENVELOPE_SPECTRUM, DIAGNOSTICS)}


def residual_topic(fault) -> Topic:
    """The residual topic of a fault hypothesis (FaultState or its integer)."""
    return RESIDUALS[FaultState(fault)]


def qos(topic: Topic, depth: int | None = None):
    """The rclpy QoSProfile of ``topic`` (``depth`` overrides the queue depth only)."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth or topic.depth,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if topic.latched else DurabilityPolicy.VOLATILE)


def message_class(msgtype: str):
    """The generated Python class of ``pkg/msg/Name`` (imported on demand)."""
    import importlib

    package, kind, name = msgtype.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


def qualified(namespace: str, topic: Topic | str) -> str:
    """The fully qualified name of ``topic`` under ``namespace`` (``""`` = root)."""
    name = topic.name if isinstance(topic, Topic) else topic
    if name.startswith("/"):
        return name
    ns = namespace.strip("/")
    return f"/{ns}/{name}" if ns else f"/{name}"
