"""A listener node in a process of its own, for tests whose listener cannot live in the test
process (the two-host test runs it inside a network namespace with ``ip netns exec``).

    python netns_probe.py [--name NODE] [--watch TOPIC]... [--discover TOPIC]... [--discover-node NODE]...

Prints one JSON object per line on stdout. Times ``t`` are CLOCK_MONOTONIC, which every
network namespace of a machine shares, so the lines of probes in different namespaces
compare directly:

* ``{"event": "up", "t": ...}`` once its node exists;
* ``{"event": "publisher", "topic": NAME, "t": ...}`` the first time a publisher of a
  ``--discover`` topic is in its graph (wherever DDS discovery found it);
* ``{"event": "node", "name": NAME, "t": ...}`` the first time a ``--discover-node`` node
  is in its graph (as ``ros2 node list`` would show it);
* ``{"event": "msg", "topic": NAME, "t": ..., "stamp": s, ...}`` for every message on a
  ``--watch`` topic (contract QoS, a 1000-deep queue): FaultState adds ``state``, ``onset``
  and ``confidence``; VibrationChunk adds ``n`` (samples) and ``end`` (stamp +
  duration).

TOPIC is a relative name of ``bearing_common.topics.GRAPH_TOPICS``. Stops with exit code 0
on SIGINT or SIGTERM (``bearing_common.node_main``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from rclpy.node import Node

from bearing_common import topics
from bearing_common.node_main import run_node_main

DISCOVERY_POLL_S = 0.005


def seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def emit(**fields) -> None:
    print(json.dumps(fields), flush=True)


def describe(msg) -> dict:
    out = {"stamp": seconds(msg.header.stamp)}
    if hasattr(msg, "onset"):
        out.update(state=int(msg.state), onset=seconds(msg.onset), confidence=float(msg.confidence))
    if hasattr(msg, "samples"):
        out.update(n=len(msg.samples), end=out["stamp"] + len(msg.samples) / msg.sample_rate)
    return out


class Probe(Node):
    def __init__(self, name: str, watch: list, discover: list, discover_nodes: list):
        super().__init__(name)
        emit(event="up", t=time.monotonic())
        for name in watch:
            topic = topics.GRAPH_TOPICS[name]
            self.create_subscription(topics.message_class(topic.msgtype), topic.name,
                                     lambda msg, name=name: emit(event="msg", topic=name, t=time.monotonic(),
                                                                 **describe(msg)),
                                     topics.qos(topic, depth=1000))
        self.pending = list(discover)
        self.pending_nodes = list(discover_nodes)
        self.create_timer(DISCOVERY_POLL_S, self.poll_discovery)

    def poll_discovery(self) -> None:
        for name in list(self.pending):
            if self.count_publishers(name) >= 1:
                emit(event="publisher", topic=name, t=time.monotonic())
                self.pending.remove(name)
        if self.pending_nodes:
            names = set(self.get_node_names())
            for name in [n for n in self.pending_nodes if n in names]:
                emit(event="node", name=name, t=time.monotonic())
                self.pending_nodes.remove(name)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--watch", action="append", default=[], choices=sorted(topics.GRAPH_TOPICS))
    parser.add_argument("--discover", action="append", default=[], choices=sorted(topics.GRAPH_TOPICS))
    parser.add_argument("--discover-node", action="append", default=[], metavar="NODE")
    parser.add_argument("--name", default="netns_probe", help="node name")
    args = parser.parse_args(argv)
    return run_node_main("netns_probe", lambda: Probe(args.name, args.watch, args.discover, args.discover_node))


if __name__ == "__main__":
    sys.exit(main())
