"""``bearing-bag record``: subscribe to the graph's topics and write a rosbag2 directory.

Messages are taken serialized (``raw=True`` subscriptions: the CDR bytes exactly as they
travelled, header stamps untouched) and written with the recorder's receive time as log
time, like ``ros2 bag record``.  Subscriptions use the topics' QoS (reliable; transient
local for ``fault_state`` and ``sim/truth`` so their current value is recorded even when
it was published before the recorder started).  SIGINT (Ctrl-C) and SIGTERM stop the
recording and close the bag, which is then complete and readable.
"""

from __future__ import annotations

import logging
import signal
import time
from collections.abc import Callable

from bearing_common import topics
from bearing_common.stop_signals import StopSignals

from .bag_types import BagError
from .bag_write import BagWriter

#: Recorded by default: the whole graph but ``/diagnostics`` (for humans; add it with ``--topics``).
DEFAULT_RECORD_TOPICS = tuple(n for n in topics.GRAPH_TOPICS if n != topics.DIAGNOSTICS.name)

#: Queue depth of the recorder's subscriptions (contract QoS policies, deeper queue).
RECORD_DEPTH = 100

LOG = logging.getLogger(__name__)


def message_class(msgtype: str):
    """The rclpy message class of a rosbag2 type name such as ``bearing_msgs/msg/FaultState``."""
    try:
        return topics.message_class(msgtype)
    except (ValueError, ImportError, AttributeError):
        raise BagError(f"message type {msgtype} is not importable here (is its package installed?)") from None


def record(out, names=None, namespace: str = "", storage: str = "mcap", duration: float | None = None,
           log: Callable[[str], None] = LOG.info) -> dict:
    """Record until SIGINT/SIGTERM or ``duration`` (s, wall time); return counts per topic.

    ``topics`` are graph topic names (relative to ``namespace``, or absolute); their
    types and QoS come from :data:`bearing_common.topics.GRAPH_TOPICS`, or for other
    topics from the graph once a publisher appears.
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    wanted = list(names or DEFAULT_RECORD_TOPICS)
    with StopSignals() as stop:
        context = rclpy.Context()
        rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
        bag = None
        try:
            node = rclpy.create_node("bearing_bag_recorder", context=context,
                                     start_parameter_services=False)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            bag = BagWriter(out, storage, namespace)
            clock = node.get_clock()
            pending = {}  # qualified name -> relative/absolute name as given
            for name in wanted:
                pending[topics.qualified(namespace, name)] = name

            def subscribe(qualified: str, msgtype: str, spec: topics.Topic | None):
                if spec is not None:
                    bag.add_topic(qualified, msgtype, spec.latched, spec.depth)
                else:
                    bag.add_topic(qualified, msgtype, False, RECORD_DEPTH)

                def on_raw(raw, _name=qualified):
                    bag.write(_name, clock.now().nanoseconds, raw)
                    if bag.counts[_name] == 1:
                        log(f"bearing-bag: first message on {_name}")

                spec = spec or topics.Topic(qualified, msgtype, RECORD_DEPTH)
                node.create_subscription(message_class(msgtype), qualified, on_raw,
                                         topics.qos(spec, depth=max(spec.depth, RECORD_DEPTH)), raw=True)

            def resolve_pending():
                known = dict(node.get_topic_names_and_types()) if pending else {}
                for qualified, given in list(pending.items()):
                    spec = topics.GRAPH_TOPICS.get(given) or topics.GRAPH_TOPICS.get(given.lstrip("/"))
                    if spec is not None:
                        subscribe(qualified, spec.msgtype, spec)
                    elif qualified in known:
                        subscribe(qualified, known[qualified][0], None)
                    else:
                        continue
                    del pending[qualified]

            resolve_pending()
            log(f"bearing-bag: recording {', '.join(bag.connections)} to {out} ({storage})"
                + (f"; waiting for {', '.join(pending)}" if pending else ""))
            start = time.monotonic()
            last_discovery = start
            while not stop and context.ok():
                executor.spin_once(timeout_sec=0.05)
                now = time.monotonic()
                if duration is not None and now - start >= duration:
                    break
                if pending and now - last_discovery > 0.5:
                    last_discovery = now
                    resolve_pending()
        finally:
            if bag is not None:
                bag.close()
            try:
                rclpy.shutdown(context=context)
            except Exception:
                pass
    why = {signal.SIGINT: "SIGINT", signal.SIGTERM: "SIGTERM"}.get(stop.signal, "duration reached")
    counts = dict(bag.counts) if bag is not None else {}
    log(f"bearing-bag: stopped ({why}); wrote {sum(counts.values())} messages to {out}: "
        + ", ".join(f"{k} {v}" for k, v in counts.items()))
    return counts
