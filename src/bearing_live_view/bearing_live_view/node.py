"""The ``live_view`` node: the running graph served to Foxglove over its WebSocket protocol.

A bridge beside the graph, not code inside the monitoring nodes: it only subscribes to their
topics, so they run unchanged (and a machine's monitoring does not depend on anyone watching), and
one live view serves every motor it discovers, one per host or per fleet. Every
``discovery_period`` s it looks for topics of the types it serves (:data:`.channels.KINDS`) and
advertises each as a channel of the same name; it subscribes to a ROS topic only while a Foxglove
client subscribes to its channel (a latched topic then delivers its current value and recent
history at once: the fault state, the last minute of health, the current spectrum), so a vibration
stream costs nothing while nobody watches it. Messages go out as :mod:`.channels` says, timed by
the node's clock at arrival (the data's own stamps are in each message's ``header.stamp``). The
logic of what is served and how lives in :mod:`.channels`, :mod:`.vibration_blocks` and
:mod:`.server`; this module only wires ROS to them.
"""

from __future__ import annotations

import sys
from functools import cache

from rclpy.node import Node

from bearing_common import topics
from bearing_common.log_throttle import LogThrottle
from bearing_common.node_main import run_node_main
from bearing_common.parameters import declare
from bearing_common.stamps import to_seconds

from .channels import DIAGNOSTICS, KINDS, VIBRATION, VIEWS, block_view, encode, qos_topic
from .live_view_node_config import PARAMETERS
from .server import LiveServer
from .vibration_blocks import BlockReducer

#: Seconds between checks of which channels clients watch (a new subscriber waits at most this long).
WATCH_PERIOD = 0.2


@cache
def ros2msg(msgtype: str) -> str:
    """The ``ros2msg`` schema text of ``msgtype`` with its dependencies (as MCAP and Foxglove read it)."""
    from bearing_recordings.bag_types import project_typestore
    return project_typestore().generate_msgdef(msgtype, ros_version=2)[0]


class LiveViewNode(Node):
    """Thin adapter: the graph's topics -> :class:`.server.LiveServer` channels."""

    def __init__(self, name: str = "live_view", namespace: str | None = None):
        super().__init__(name, namespace=namespace)
        self.values = declare(self, PARAMETERS)
        host, port = self.values["host"], int(self.values["port"])
        try:
            self.server = LiveServer(host, port, "bearing-monitor live view", ros2msg)
        except RuntimeError as exc:
            raise ValueError(f"cannot serve on {host}:{port} ({exc}); choose another port "
                             "(parameter port, launch argument foxglove_port)") from None
        self.kinds: dict = {}  # served topic -> Kind
        self.taken: dict = {}  # topic -> ROS subscription, while a client watches its channel
        self.reducers: dict = {}  # sample-stream topic -> BlockReducer
        self.rejected = 0
        self._log_repeatable = LogThrottle(lambda level, text: getattr(self.get_logger(), level)(text), 5.0)
        self.create_timer(float(self.values["discovery_period"]), self.discover)
        self.create_timer(WATCH_PERIOD, self.follow_clients)
        self.discover()
        self.get_logger().info(f"serving the graph to Foxglove on ws://{host}:{self.server.port}")

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def discover(self) -> None:
        for name, types in self.get_topic_names_and_types():
            kind = next((KINDS[t] for t in types if t in KINDS), None)
            if kind is not None and name not in self.kinds:
                self.kinds[name] = kind
                self.server.advertise(name, kind)

    def follow_clients(self) -> None:
        """Take the ROS topics whose channels a client watches; drop the others."""
        for topic, kind in self.kinds.items():
            watched = self.server.watched(topic)
            if watched and topic not in self.taken:
                self.taken[topic] = self._subscribe(topic, kind)
            elif not watched and topic in self.taken:
                self.destroy_subscription(self.taken.pop(topic))
                self.reducers.pop(topic, None)

    def _subscribe(self, topic: str, kind):
        qos = topics.qos(qos_topic(kind.msgtype))
        message_type = topics.message_class(kind.msgtype)
        if kind is DIAGNOSTICS:  # passed on as it is: CDR bytes
            return self.create_subscription(message_type, topic, lambda data: self.server.send(
                topic, data, self._now_ns()), qos, raw=True)
        if kind is VIBRATION:
            self.reducers[topic] = BlockReducer(topic, float(self.values["vibration_block"]))
            return self.create_subscription(message_type, topic, lambda msg: self.on_samples(topic, msg), qos)
        view = VIEWS[kind]
        return self.create_subscription(message_type, topic, lambda msg: self.on_message(topic, view, msg), qos)

    def on_message(self, topic: str, view, msg) -> None:
        try:
            payload = encode(view(msg))
        except ValueError as exc:
            self._reject(topic, exc)
            return
        self.server.send(topic, payload, self._now_ns())

    def on_samples(self, topic: str, msg) -> None:
        """A chunk of a sample stream: its completed blocks, each timed back from now by how much earlier
        than the chunk's end it began (so a plot over arrival time keeps the blocks' spacing)."""
        stamp, now = to_seconds(msg.header.stamp), self._now_ns()
        try:
            blocks = self.reducers[topic].push(stamp, msg.first_sample_index, msg.sample_rate, msg.samples)
        except ValueError as exc:
            self._reject(topic, exc)
            return
        end = stamp + len(msg.samples) / msg.sample_rate
        for block in blocks:
            self.server.send(topic, encode(block_view(block, msg.header.frame_id)),
                             now - round((end - block.stamp) * 1e9))

    def _reject(self, topic: str, exc: Exception) -> None:
        self.rejected += 1
        self._log_repeatable(f"rejected {topic}", "warning", f"not served ({self.rejected} so far): {topic}: {exc}")

    def on_shutdown(self) -> None:
        """Called by the node main while the context is still valid: the clients are told the server stops."""
        self.server.close()


def main(args=None) -> int:
    return run_node_main("live_view", LiveViewNode, None, args)


if __name__ == "__main__":
    sys.exit(main())
