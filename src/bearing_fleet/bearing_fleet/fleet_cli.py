"""``bearing-fleet``: the fleet's bearing states, live in the terminal (like ``top``).

    bearing-fleet [--once] [--timeout S]

Subscribes to ``fleet_state`` (published by the ``fleet`` node) and redraws the table on
every summary; ``--once`` prints the first summary and exits (exit 1 when none arrives
within ``--timeout`` seconds). Ctrl-C ends it.
"""

from __future__ import annotations

import argparse
import sys
import time

from .fleet_table import FleetTable

CLEAR = "\033[H\033[2J"  # cursor home, clear screen


def table_of(msg, now: float) -> str:
    """The text table of a FleetState message."""
    from bearing_common.stamps import to_seconds
    stale_ages = [m.age for m in msg.motors if m.stale and m.age >= 0]
    table = FleetTable(min(stale_ages) - 1e-9 if stale_ages else float("inf"))  # the sender's stale verdicts
    for m in msg.motors:
        if m.age >= 0:
            table.update(m.motor, m.state, m.confidence, to_seconds(m.onset), to_seconds(m.last_update), now - m.age)
        else:
            table.add_motor(m.motor)
    return table.render(now)


def main(argv=None) -> int:
    """Run the CLI; returns the exit status."""
    p = argparse.ArgumentParser(prog="bearing-fleet", description="Bearing states of every monitored motor, live.")
    p.add_argument("--once", action="store_true", help="print the first summary and exit")
    p.add_argument("--timeout", type=float, default=10.0, help="seconds to wait for a summary with --once")
    args = p.parse_args(argv)
    import rclpy
    from rclpy.executors import ExternalShutdownException

    from bearing_common import topics
    from bearing_msgs.msg import FleetState

    rclpy.init()
    node = rclpy.create_node("bearing_fleet_viewer")
    latest: list = []
    node.create_subscription(FleetState, topics.FLEET_STATE.name, latest.append, topics.qos(topics.FLEET_STATE))
    start = time.monotonic()
    try:
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.2)
            if latest:
                text = table_of(latest[-1], time.time())
                print(text if args.once else CLEAR + text, flush=True)
                latest.clear()
                if args.once:
                    return 0
            elif args.once and time.monotonic() - start > args.timeout:
                print(f"bearing-fleet: no {topics.FLEET_STATE.name} within {args.timeout:g} s (is the fleet node "
                      "running?)", file=sys.stderr)
                return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
