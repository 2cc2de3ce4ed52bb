"""``bearing-bag play``: publish a rosbag2 recording back into the graph.

Messages go out serialized, exactly as recorded, in log-time order, paced so that
``rate`` seconds of recording pass per wall-clock second (``rate`` 2 = twice as fast).
With ``clock`` the player also publishes ``/clock`` (rosgraph_msgs/Clock) carrying the
recording's log time, every 25 ms of wall time and before each message, so nodes started
with ``use_sim_time:=true`` follow the recording (this is what ``ros2 bag play --clock``
does).  Publishers use the graph topics' QoS: reliable, keep last ≥ 50 for the streams,
transient local for ``fault_state`` and ``sim/truth``; other topics use the QoS stored
in the bag.  Before the first message the player waits ``delay`` seconds for discovery;
at the end it waits until reliable subscribers have acknowledged everything.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from bearing_common import topics
from bearing_common.stop_signals import StopSignals

from .bag_read import bag_namespace_hint, find_topic, iter_raw, open_bag
from .bag_record import message_class
from .bag_types import BagError

#: Wall-clock period (s) of /clock messages while waiting between recorded messages.
CLOCK_PERIOD = 0.025

#: Longest wait (s) for subscribers with ``wait_for_subscribers``.
SUBSCRIBER_TIMEOUT = 60.0

#: Extra wait (s) after the subscribers appeared in the graph, for DDS endpoint matching.
MATCH_SETTLE = 0.5

#: Keep-last depth of the player's stream publishers (≥ the graph's 50, to absorb bursts).
PLAY_DEPTH = 200

LOG = logging.getLogger(__name__)


def _relative(name: str, namespace: str) -> str:
    ns = namespace.strip("/")
    prefix = f"/{ns}/" if ns else "/"
    return name[len(prefix):] if name.startswith(prefix) else name


def _recorded_topic(conn, name: str) -> topics.Topic:
    """A topic outside the graph's table, with the QoS it was offered with (bag metadata)."""
    try:
        from rosbags.interfaces import QosDurability
        profiles = conn.ext.offered_qos_profiles
        latched = any(q.durability == QosDurability.TRANSIENT_LOCAL for q in profiles)
        depth = max([q.depth for q in profiles] + [10])
    except AttributeError:
        latched, depth = False, 10
    return topics.Topic(name, conn.msgtype, depth, latched)


def select_connections(reader, names=None, namespace=None) -> list:
    """The bag's connections to play: all, or those of ``names`` (relative or absolute)."""
    if not names:
        return list(reader.connections)
    recorded = {c.topic for c in reader.connections}
    chosen = set()
    for t in names:
        name = find_topic(recorded, t, namespace)
        if name is None:
            raise BagError(f"topic {t!r} is not in the bag (it has {', '.join(sorted(recorded))})")
        chosen.add(name)
    return [c for c in reader.connections if c.topic in chosen]


def play(bag_dir, rate: float = 1.0, clock: bool = False, names=None, loop: bool = False,
         delay: float = 1.0, namespace: str | None = None, wait_for_subscribers: int = 0,
         log: Callable[[str], None] = LOG.info) -> dict:
    """Publish the recording; return the number of messages published per topic.

    ``namespace`` republishes the graph's topics under another namespace (``""`` = root)
    instead of the one they were recorded in.  ``wait_for_subscribers`` = N > 0: before
    the ``delay``, wait (up to :data:`SUBSCRIBER_TIMEOUT` s) until every played topic has
    N matched subscribers, so that nothing is published before the receivers are ready
    (e.g. 2 for the two observers on ``vibration/drive_end``).
    """
    import rclpy
    from rclpy.duration import Duration
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    if not (rate > 0):
        raise BagError(f"rate must be positive, got {rate:g}")
    counts: dict = {}
    with open_bag(bag_dir) as reader, StopSignals() as stop:
        conns = select_connections(reader, names)
        if not conns:
            raise BagError(f"{bag_dir}: nothing to play (the bag has no messages)")
        recorded_ns = bag_namespace_hint(bag_dir) or ""
        context = rclpy.Context()
        rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
        try:
            node = rclpy.create_node("bearing_bag_player", context=context, start_parameter_services=False)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            pubs, out_names = {}, {}
            for conn in conns:
                rel = _relative(conn.topic, recorded_ns)
                spec = topics.GRAPH_TOPICS.get(rel)
                out = topics.qualified(namespace, rel) if namespace is not None else conn.topic
                if conn.topic in pubs:
                    continue
                spec = spec or _recorded_topic(conn, out)
                pubs[conn.topic] = node.create_publisher(message_class(conn.msgtype), out,
                                                         topics.qos(spec, depth=max(spec.depth, PLAY_DEPTH)))
                out_names[conn.topic] = out
                counts[out] = 0
            clock_pub = None
            if clock:
                from rosgraph_msgs.msg import Clock
                clock_pub = node.create_publisher(Clock, topics.CLOCK.name, topics.CLOCK.depth)

            def publish_clock(t_ns: int):
                if clock_pub is not None:
                    msg = Clock()
                    msg.clock.sec, msg.clock.nanosec = divmod(int(t_ns), 1_000_000_000)
                    clock_pub.publish(msg)

            log(f"bearing-bag: playing {bag_dir} at {rate:g}x: {', '.join(out_names.values())}"
                + (" + /clock" if clock else ""))
            if wait_for_subscribers:
                deadline = time.monotonic() + SUBSCRIBER_TIMEOUT
                while not stop and time.monotonic() < deadline and \
                        any(p.get_subscription_count() < wait_for_subscribers for p in pubs.values()):
                    executor.spin_once(timeout_sec=0.05)
                missing = [out_names[t] for t, p in pubs.items() if p.get_subscription_count() < wait_for_subscribers]
                if missing:
                    log(f"bearing-bag: fewer than {wait_for_subscribers} subscribers after "
                        f"{SUBSCRIBER_TIMEOUT:g} s on {', '.join(missing)}; playing anyway")
                delay = max(delay, MATCH_SETTLE)
            end = time.monotonic() + max(0.0, delay)
            while not stop and time.monotonic() < end:
                executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))
            passes = 0
            while not stop:
                t0 = None
                wall0 = time.monotonic()
                for conn, t, raw in iter_raw(reader, conns):
                    if t0 is None:
                        t0 = t
                    target = wall0 + (t - t0) * 1e-9 / rate
                    while not stop:
                        now = time.monotonic()
                        if now >= target:
                            break
                        publish_clock(t0 + int((now - wall0) * rate * 1e9))
                        time.sleep(min(CLOCK_PERIOD, target - now))
                    if stop:
                        break
                    publish_clock(t)
                    pubs[conn.topic].publish(bytes(raw))
                    counts[out_names[conn.topic]] += 1
                passes += 1
                if not loop:
                    break
            for pub in pubs.values():
                pub.wait_for_all_acked(Duration(seconds=5.0))
            # a last spin so that transient-local late joiners and acks get serviced
            end = time.monotonic() + 0.2
            while time.monotonic() < end:
                executor.spin_once(timeout_sec=0.05)
        finally:
            try:
                rclpy.shutdown(context=context)
            except Exception:
                pass
    log(f"bearing-bag: published {sum(counts.values())} messages"
        + (" (stopped by signal)" if stop else ""))
    return counts
