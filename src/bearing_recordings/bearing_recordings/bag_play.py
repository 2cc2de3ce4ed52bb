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

Two things are not played byte for byte:

* ``chunk_duration``: the ``VibrationChunk`` topics are re-cut into chunks of that many
  seconds, as a sensor sending such chunks would have published them (indices and
  stamps exact, :mod:`.rechunk`); the other topics are played as recorded;
* a ``bearing_msgs`` message recorded with another definition than the installed one (a
  bag from before a message changed, told by its type hash) is decoded with the bag's
  own definition and re-encoded with the installed one, field by field
  (:func:`.bag_types.convert_message`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from bearing_common import topics
from bearing_common.delivery import wait_acknowledged
from bearing_common.stop_signals import StopSignals

from .bag_read import bag_namespace_hint, find_topic, iter_raw, open_bag
from .bag_record import message_class
from .bag_types import MSG_PACKAGE, BagError, convert_message, project_typestore
from .rechunk import NS_PER_S, Rechunker, SampleChunk

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


class Translator:
    """What one recorded topic's messages become on the wire: ``__call__(raw)`` gives the CDR
    messages to publish for one recorded message (re-cut chunks, re-encoded messages, or
    the message itself), :meth:`flush` what a re-cut stream holds at the end of a pass."""

    def __init__(self, reader, conn, store, chunk_duration: float | None):
        self.reader, self.msgtype, self.store = reader, conn.msgtype, store
        self.rechunker = (Rechunker(chunk_duration) if chunk_duration and conn.msgtype == topics.VIBRATION.msgtype
                          else None)
        self.reencode = (conn.msgtype.startswith(f"{MSG_PACKAGE}/")
                         and getattr(conn, "digest", None) != store.hash_rihs01(conn.msgtype))

    @property
    def verbatim(self) -> bool:
        return self.rechunker is None and not self.reencode

    def __call__(self, raw) -> list:
        if self.verbatim:
            return [bytes(raw)]
        msg = self.reader.deserialize(raw, self.msgtype)
        if self.rechunker is None:
            return [self._encode(convert_message(msg, self.msgtype, self.store))]
        stamp = msg.header.stamp
        chunk = SampleChunk(stamp.sec * NS_PER_S + stamp.nanosec, int(msg.first_sample_index), float(msg.sample_rate),
                            str(msg.source), str(msg.header.frame_id), np.asarray(msg.samples, dtype=np.float64))
        return [self._chunk(c) for c in self.rechunker.push(chunk)]

    def flush(self) -> list:
        return [self._chunk(c) for c in self.rechunker.flush()] if self.rechunker is not None else []

    def _chunk(self, c: SampleChunk) -> bytes:
        t = self.store.types
        sec, nanosec = divmod(c.stamp_ns, NS_PER_S)
        header = t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec),
                                          frame_id=c.frame_id)
        return self._encode(t[self.msgtype](header=header, sample_rate=c.sample_rate, first_sample_index=c.first_index,
                                            source=c.source, samples=c.samples))

    def _encode(self, msg) -> bytes:
        return bytes(self.store.serialize_cdr(msg, self.msgtype))


class Player:
    """The player's ROS side: its node, one publisher per played topic, /clock, pacing."""

    def __init__(self, context, reader, conns, namespace: str | None, recorded_ns: str, clock: bool,
                 chunk_duration: float | None):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node("bearing_bag_player", context=context, start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        store = project_typestore()
        self.pubs, self.out_names, self.translators = {}, {}, {}
        for conn in conns:
            if conn.topic in self.pubs:
                continue
            rel = _relative(conn.topic, recorded_ns)
            out = topics.qualified(namespace, rel) if namespace is not None else conn.topic
            spec = topics.GRAPH_TOPICS.get(rel) or _recorded_topic(conn, out)
            self.pubs[conn.topic] = self.node.create_publisher(message_class(conn.msgtype), out,
                                                               topics.qos(spec, depth=max(spec.depth, PLAY_DEPTH)))
            self.out_names[conn.topic] = out
            self.translators[conn.topic] = Translator(reader, conn, store, chunk_duration)
        self.counts = dict.fromkeys(self.out_names.values(), 0)
        self.clock_pub = None
        if clock:
            from rosgraph_msgs.msg import Clock
            self.clock_pub = self.node.create_publisher(Clock, topics.CLOCK.name, topics.CLOCK.depth)

    def publish_clock(self, t_ns: int) -> None:
        if self.clock_pub is not None:
            from rosgraph_msgs.msg import Clock
            msg = Clock()
            msg.clock.sec, msg.clock.nanosec = divmod(int(t_ns), NS_PER_S)
            self.clock_pub.publish(msg)

    def spin_for(self, seconds: float, stop) -> None:
        """Serve DDS for ``seconds`` of wall time (or until ``stop``)."""
        end = time.monotonic() + max(0.0, seconds)
        while not stop and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))

    def wait_for_subscribers(self, n: int, stop, log) -> None:
        """Until every played topic has ``n`` matched subscribers (at most :data:`SUBSCRIBER_TIMEOUT` s)."""
        deadline = time.monotonic() + SUBSCRIBER_TIMEOUT
        while not stop and time.monotonic() < deadline and self._missing(n):
            self.executor.spin_once(timeout_sec=0.05)
        missing = self._missing(n)
        if missing:
            log(f"bearing-bag: fewer than {n} subscribers after {SUBSCRIBER_TIMEOUT:g} s on "
                f"{', '.join(missing)}; playing anyway")

    def _missing(self, n: int) -> list:
        return [self.out_names[t] for t, p in self.pubs.items() if p.get_subscription_count() < n]

    def wait_until(self, target: float, wall0: float, t0: int, rate: float, stop) -> None:
        """Sleep until wall time ``target``, publishing /clock meanwhile (recording time from ``t0``)."""
        while not stop:
            now = time.monotonic()
            if now >= target:
                return
            self.publish_clock(t0 + int((now - wall0) * rate * 1e9))
            time.sleep(min(CLOCK_PERIOD, target - now))

    def publish(self, topic: str, messages: list) -> None:
        for raw in messages:
            self.pubs[topic].publish(raw)
        self.counts[self.out_names[topic]] += len(messages)

    def play_pass(self, reader, conns, rate: float, stop) -> None:
        """The recording once, in log-time order, paced at ``rate``; re-cut streams flushed at the end."""
        t0 = None
        wall0 = time.monotonic()
        for conn, t, raw in iter_raw(reader, conns):
            if t0 is None:
                t0 = t
            self.wait_until(wall0 + (t - t0) * 1e-9 / rate, wall0, t0, rate, stop)
            if stop:
                return
            self.publish_clock(t)
            self.publish(conn.topic, self.translators[conn.topic](raw))
        for topic, translator in self.translators.items():
            self.publish(topic, translator.flush())

    def finish(self, stop) -> list[str]:
        """Wait for reliable subscribers' acknowledgements (:func:`.delivery.wait_acknowledged`), then
        serve late joiners a little; return the topics not acknowledged in time."""
        unacknowledged = wait_acknowledged(self.pubs.values(), stop=stop)
        self.spin_for(0.2, stop)
        return unacknowledged


def play(bag_dir, rate: float = 1.0, clock: bool = False, names=None, loop: bool = False,
         delay: float = 1.0, namespace: str | None = None, wait_for_subscribers: int = 0,
         chunk_duration: float | None = None, log: Callable[[str], None] = LOG.info) -> dict:
    """Publish the recording; return the number of messages published per topic.

    ``namespace`` republishes the graph's topics under another namespace (``""`` = root)
    instead of the one they were recorded in.  ``wait_for_subscribers`` = N > 0: before
    the ``delay``, wait (up to :data:`SUBSCRIBER_TIMEOUT` s) until every played topic has
    N matched subscribers, so that nothing is published before the receivers are ready
    (e.g. 2 for the two observers on ``vibration/drive_end``).  ``chunk_duration`` (s):
    re-cut the vibration streams into chunks of that length (module docstring).
    """
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    if not (rate > 0):
        raise BagError(f"rate must be positive, got {rate:g}")
    if chunk_duration is not None and not (np.isfinite(chunk_duration) and chunk_duration > 0):
        raise BagError(f"chunk duration must be positive, got {chunk_duration:g} s")
    with open_bag(bag_dir) as reader, StopSignals() as stop:
        conns = select_connections(reader, names)
        if not conns:
            raise BagError(f"{bag_dir}: nothing to play (the bag has no messages)")
        context = rclpy.Context()
        rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
        try:
            player = Player(context, reader, conns, namespace, bag_namespace_hint(bag_dir) or "", clock,
                            chunk_duration)
            log(f"bearing-bag: playing {bag_dir} at {rate:g}x: {', '.join(player.out_names.values())}"
                + (" + /clock" if clock else "")
                + (f", vibration in chunks of {chunk_duration:g} s" if chunk_duration else ""))
            if wait_for_subscribers:
                player.wait_for_subscribers(wait_for_subscribers, stop, log)
                delay = max(delay, MATCH_SETTLE)
            player.spin_for(delay, stop)
            while not stop:
                player.play_pass(reader, conns, rate, stop)
                if not loop:
                    break
            if unacknowledged := player.finish(stop):
                log(f"bearing-bag: not every subscriber acknowledged the end of {', '.join(unacknowledged)}")
        finally:
            try:
                rclpy.shutdown(context=context)
            except Exception:
                pass
    counts = player.counts
    log(f"bearing-bag: published {sum(counts.values())} messages" + (" (stopped by signal)" if stop else ""))
    return counts
