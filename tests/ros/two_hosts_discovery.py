"""Discovery time across the emulated link (docs/fleet.md, "Across machines"): with both observers
running on host A, start a node on host B ``--starts`` times and time until it sees a node of
host A, for each discovery mode of ``test_two_hosts.py`` (and, for comparison, on one host).

    .venv/bin/python tests/ros/two_hosts_discovery.py [--starts 15]     # as root

Prints one line per mode: median, range and every time (ms).
"""

from __future__ import annotations

import argparse
import statistics
import sys

from netns_hosts import TwoHosts, Unavailable
from split_graph import STARTUP_S, Run
from test_two_hosts import ONE_HOST, SPLITS

from bearing_common import topics

MODES = (("localhost", ONE_HOST), ("multicast", SPLITS["observers-on-A"][0]),
         ("static-peers", SPLITS["observers-on-A"][0]))


def measure(hosts: TwoHosts, mode: str, placement: dict, starts: int) -> list:
    run = Run(hosts, placement, mode)
    try:
        for name in ("or_observer", "ir_observer"):
            run.start_node(name)
        probe_a = run.start_probe("probe_a", discover=(topics.RESIDUAL_OUTER_RACE, topics.RESIDUAL_INNER_RACE))
        run.wait_until(lambda: len(run.events(probe_a, "publisher")) == 2, STARTUP_S, "the observers")
        times = []
        for _ in range(starts):
            probe_b = run.start_probe("probe_b", discover_nodes=["probe_a"])
            run.wait_until(lambda probe=probe_b: run.events(probe, "node"), STARTUP_S, "host A's node")
            times.append(run.events(probe_b, "node")[0]["t"] - run.events(probe_b, "up")[0]["t"])
            run.stop_one(probe_b)
        return times
    finally:
        run.stop()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=15)
    args = parser.parse_args(argv)
    hosts = TwoHosts()
    try:
        hosts.create()
        hosts.wait_link_running()
        for mode, placement in MODES:
            ms = sorted(t * 1e3 for t in measure(hosts, mode, placement, args.starts))
            print(f"{mode:>12}: median {statistics.median(ms):.0f} ms, {ms[0]:.0f}-{ms[-1]:.0f} ms  "
                  f"{[round(x) for x in ms]}", flush=True)
    except Unavailable as exc:
        print(f"two_hosts_discovery: {exc}", file=sys.stderr)
        return 2
    finally:
        hosts.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
