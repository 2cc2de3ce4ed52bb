"""DDS participants for the discovery benchmark: ``count`` of them in this process (one rclpy
context each), numbered from ``first`` of ``total`` on the whole LAN.

    python benchmarks/discovery_participants.py --first I --count K --total P [--seconds S]

Participant i publishes ``chain_i`` and subscribes ``chain_{i-1}`` (modulo P), as a graph of
point-to-point streams: each must discover exactly one remote writer and one remote reader
among P participants. Prints one JSON line per participant when both are matched
(``{"participant": i, "created": t, "matched": t}``, CLOCK_MONOTONIC, which every network
namespace of a machine shares), then stays up ``seconds`` (the steady state's traffic) and
exits 0. Nothing is published: every byte on the wire is discovery and its upkeep.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

POLL_S = 0.005


def main(argv=None) -> int:
    import rclpy
    from std_msgs.msg import Empty

    from bearing_common import topics

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--first", type=int, required=True)
    parser.add_argument("--count", type=int, required=True)
    parser.add_argument("--total", type=int, required=True)
    parser.add_argument("--seconds", type=float, default=10.0, help="stay up this long after every match")
    args = parser.parse_args(argv)
    parts = []
    for i in range(args.first, args.first + args.count):
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node(f"participant_{i}", context=context, start_parameter_services=False)
        mine, previous = (topics.Topic(f"chain_{k}", "std_msgs/msg/Empty", 1) for k in (i, (i - 1) % args.total))
        pub = node.create_publisher(Empty, mine.name, topics.qos(mine))
        sub = node.create_subscription(Empty, previous.name, lambda msg: None, topics.qos(previous))
        parts.append({"i": i, "context": context, "node": node, "pub": pub, "sub": sub, "created": time.monotonic()})
    pending = list(parts)
    while pending:
        for p in list(pending):
            if p["pub"].get_subscription_count() >= 1 and p["node"].count_publishers(p["sub"].topic_name) >= 1:
                print(json.dumps({"participant": p["i"], "created": p["created"], "matched": time.monotonic()}),
                      flush=True)
                pending.remove(p)
        time.sleep(POLL_S)
    time.sleep(args.seconds)
    for p in parts:
        p["node"].destroy_node()
        rclpy.try_shutdown(context=p["context"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
