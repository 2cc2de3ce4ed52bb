"""The Foxglove WebSocket server of the live view (foxglove-sdk; no rclpy).

One server per live view, on its own :class:`foxglove.Context` (so that several in one process never
mix their channels). A channel is advertised when the graph shows its topic, and a client subscribes
to it; :meth:`LiveServer.watched` tells whether any client does, so the node takes a ROS topic only
while someone watches it.

The protocol is Foxglove's WebSocket protocol, which foxglove-sdk 0.30 names ``foxglove.sdk.v1`` (the
``foxglove.websocket.v1`` protocol renamed; Foxglove's app and recent Lichtblick offer both names).
"""

from __future__ import annotations

import foxglove

from .channels import Kind, encode


class LiveServer:
    """Channels by topic name on one WebSocket server.

    Parameters
    ----------
    host, port : str, int
        Where to listen (port 0: any free port, :attr:`port` tells which).
    name : str
        The server's name, shown by the app.
    ros2msg : callable(type name) -> str
        The ``ros2msg`` schema text of a ROS type, for the kinds served as CDR.
    """

    def __init__(self, host: str, port: int, name: str, ros2msg):
        self._ros2msg = ros2msg
        self.context = foxglove.Context()
        self.server = foxglove.start_server(name=name, host=host, port=port, context=self.context)
        self.channels: dict[str, foxglove.Channel] = {}

    @property
    def port(self) -> int:
        return self.server.port

    def advertise(self, topic: str, kind: Kind) -> None:
        """Offer ``topic`` (a fully qualified name) to clients, as ``kind`` says."""
        if topic in self.channels:
            return
        if kind.json_schema is None:
            schema = foxglove.Schema(name=kind.schema_name, encoding="ros2msg",
                                     data=self._ros2msg(kind.msgtype).encode())
            encoding = "cdr"
        else:
            schema = foxglove.Schema(name=kind.schema_name, encoding="jsonschema", data=encode(kind.json_schema))
            encoding = "json"
        self.channels[topic] = foxglove.Channel(topic, schema=schema, message_encoding=encoding, context=self.context)

    def watched(self, topic: str) -> bool:
        """Whether a client subscribes to ``topic`` now."""
        channel = self.channels.get(topic)
        return channel is not None and channel.has_sinks()

    def send(self, topic: str, payload: bytes, log_time_ns: int) -> None:
        """One message on ``topic``: JSON (:func:`.channels.encode`) or CDR bytes; ``log_time_ns`` its time."""
        self.channels[topic].log(payload, log_time=int(log_time_ns))

    def close(self) -> None:
        for channel in self.channels.values():
            channel.close()
        self.server.stop()
