"""``bearing-bag record``: subscribe to the graph's topics and write a rosbag2 directory.

Messages are taken serialized (``raw=True`` subscriptions: the CDR bytes exactly as they
travelled, header stamps untouched) and written with the recorder's receive time as log
time, like ``ros2 bag record``.  Subscriptions use the topics' QoS (reliable; transient
local for ``fault_state`` and ``sim/truth`` so their current value is recorded even when
it was published before the recorder started).  SIGINT (Ctrl-C) and SIGTERM stop the
recording and close the bag, which is then complete and readable.
"""

from __future__ import annotations

import importlib
import signal
import sys
import time
from typing import Callable, Optional

from bearing_diagnoser.bag_files import DEFAULT_RECORD_TOPICS, GRAPH_TOPICS, BagError

from .bag_write import BagWriter, qualify


def message_class(msgtype: str):
    """The rclpy message class of a rosbag2 type name such as ``bearing_msgs/msg/FaultState``."""
    try:
        pkg, kind, name = msgtype.split("/")
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ValueError, ImportError, AttributeError):
        raise BagError(f"message type {msgtype} is not importable here (is its package installed?)") from None


def rclpy_qos(latched: bool, depth: int):
    """rclpy QoS profile: reliable, keep last ``depth``, transient local if ``latched``."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)


class _StopFlag:
    """Set by SIGINT / SIGTERM (installed for the duration of a recording)."""

    def __init__(self):
        self.signal: Optional[int] = None
        self._old = {}

    def __enter__(self):
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._old[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, _frame):
        self.signal = signum

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)

    def __bool__(self):
        return self.signal is not None


def record(out, topics=None, namespace: str = "", storage: str = "mcap", duration: Optional[float] = None,
           log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True)) -> dict:
    """Record until SIGINT/SIGTERM or ``duration`` (s, wall time); return counts per topic.

    ``topics`` are graph topic names (relative to ``namespace``, or absolute); their
    types come from :data:`~bearing_diagnoser.bag_files.GRAPH_TOPICS`, or for other
    topics from the graph once a publisher appears.
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    wanted = list(topics or DEFAULT_RECORD_TOPICS)
    with _StopFlag() as stop:
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
                pending[qualify(namespace, name)] = name

            def subscribe(qualified: str, msgtype: str, latched: bool, depth: int):
                bag.add_topic(qualified, msgtype, latched, depth)

                def on_raw(raw, _name=qualified):
                    bag.write(_name, clock.now().nanoseconds, raw)
                    if bag.counts[_name] == 1:
                        log(f"bearing-bag: first message on {_name}")

                node.create_subscription(message_class(msgtype), qualified, on_raw,
                                         rclpy_qos(latched, max(depth, 100)), raw=True)

            def resolve_pending():
                known = dict(node.get_topic_names_and_types()) if pending else {}
                for qualified, given in list(pending.items()):
                    spec = GRAPH_TOPICS.get(given) or GRAPH_TOPICS.get(given.lstrip("/"))
                    if spec is not None:
                        subscribe(qualified, spec.msgtype, spec.latched, spec.depth)
                    elif qualified in known:
                        subscribe(qualified, known[qualified][0], False, 100)
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
