"""A plain WebSocket client of Foxglove's protocol, written from its specification, for the live view's tests.

It offers both names of the protocol: ``foxglove.sdk.v1`` (foxglove-sdk 0.30's name) and
``foxglove.websocket.v1`` (the same protocol's older name, which older servers answer), as Foxglove's
app does. Text frames are JSON operations (``serverInfo``, ``advertise``, ``unadvertise``, ...);
a binary frame with opcode 1 is a message: subscription id (uint32 LE), log time (uint64 LE, ns),
payload.
"""

from __future__ import annotations

import json
import struct
import time

from websockets.sync.client import connect

PROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")
MESSAGE_DATA = 0x01
_HEADER = struct.Struct("<BIQ")


class FoxgloveClient:
    """Connects to ``ws://host:port``; :attr:`channels` by topic as advertised, :attr:`messages` by
    topic as ``(log time ns, payload bytes)`` in arrival order; ``on_timeout()`` adds to a wait's failure."""

    def __init__(self, port: int, host: str = "127.0.0.1", timeout: float = 10.0, on_timeout=lambda: ""):
        self._on_timeout = on_timeout  # what else to say when a wait times out (the servers' output)
        self.ws = connect(f"ws://{host}:{port}", subprotocols=list(PROTOCOLS), open_timeout=timeout, legacy=True)
        self.protocol = self.ws.subprotocol
        self.server_info: dict | None = None
        self.channels: dict[str, dict] = {}
        self.messages: dict[str, list] = {}
        self._subscriptions: dict[int, str] = {}  # subscription id -> topic

    def poll(self, seconds: float) -> None:
        """Read whatever arrives for ``seconds``."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            try:
                frame = self.ws.recv(timeout=left)
            except TimeoutError:
                return
            if isinstance(frame, bytes):
                op, sub, log_time = _HEADER.unpack_from(frame)
                assert op == MESSAGE_DATA, f"unexpected binary opcode {op}"
                self.messages.setdefault(self._subscriptions[sub], []).append((log_time, frame[_HEADER.size:]))
                continue
            msg = json.loads(frame)
            if msg["op"] == "serverInfo":
                self.server_info = msg
            elif msg["op"] == "advertise":
                self.channels.update({c["topic"]: c for c in msg["channels"]})
            elif msg["op"] == "unadvertise":
                gone = set(msg["channelIds"])
                self.channels = {t: c for t, c in self.channels.items() if c["id"] not in gone}

    def wait_for(self, condition, timeout: float, what: str) -> None:
        """Poll until ``condition()``; AssertionError naming ``what`` after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                counts = {t: len(m) for t, m in self.messages.items()}
                raise AssertionError(f"timed out after {timeout} s waiting for {what}; channels: "
                                     f"{sorted(self.channels)}, messages: {counts}\n{self._on_timeout()}")
            self.poll(0.1)

    def subscribe(self, topics) -> None:
        subs = []
        for topic in topics:
            sub = len(self._subscriptions) + 1
            self._subscriptions[sub] = topic
            subs.append({"id": sub, "channelId": self.channels[topic]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def json_messages(self, topic: str) -> list:
        """The JSON messages of ``topic``, parsed strictly (NaN or Infinity is an error: not JSON)."""
        def refuse(constant):
            raise ValueError(f"{topic}: {constant} is not JSON")
        return [json.loads(payload, parse_constant=refuse) for _, payload in self.messages.get(topic, [])]

    def close(self) -> None:
        self.ws.close()
