"""`make bench` rows of discovery beyond one host: Fast DDS's simple discovery (multicast)
against a discovery server, as the number of participants grows (docs/fleet.md "Across machines").

Four emulated hosts on one switch (``tests/ros/netns_hosts.LanHosts``: network namespaces,
10.213.1.1-4/24); P participants (4 to 40, one rclpy context each, ``discovery_participants.py``)
spread evenly over them, each publishing one topic and subscribing its neighbour's (a graph
of point-to-point streams). Per mode and P:

* discovery time: each participant's time from its creation until it has matched its writer
  and its reader: the median and the slowest participant;
* discovery traffic: bytes all hosts sent (LAN link and loopback: every UDP datagram of DDS)
  from the start until every match, and per second in the steady state afterwards (10 s of
  participant announcements, heartbeats and, with the server, the clients' pings).

Modes: ``simple`` (``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET``, multicast) and ``server`` (one
``fast-discovery-server`` on host 1, ``ROS_DISCOVERY_SERVER`` on every participant, all plain
clients). Absolute times depend on this machine; the rows give each figure of the server as a
ratio to simple discovery's in the same run. Needs root and iproute2 (network namespaces);
without them the rows say why they are missing.

Standalone: ``python benchmarks/discovery_benchmarks.py [--participants 4 8 16 40]``.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import statistics
import sys
import time
from dataclasses import dataclass

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "ros"))  # the namespaces and the server's command line are the tests'

PARTICIPANTS = (4, 8, 16, 40)
HOSTS = 4
STEADY_S = 10.0
TIMEOUT_S = 120.0
DOMAIN_ID = 88
MODES = ("simple", "server")
PROGRAM = ROOT / "benchmarks" / "discovery_participants.py"


@dataclass
class Discovery:
    """One mode and size: seconds and bytes."""

    mode: str
    participants: int
    slowest_s: float  # a participant's creation -> its matches, the slowest
    median_s: float  # the same, median
    bytes_to_match: int  # sent by every host until all matched
    steady_bytes_s: float  # sent per second afterwards


def measure(hosts, mode: str, participants: int) -> Discovery:
    from split_graph import DDS_VARIABLES, SERVER_PORT, discovery_server_argv

    from bearing_bringup.process_group import ProcessGroup

    env = {k: v for k, v in os.environ.items() if k not in DDS_VARIABLES} | {"ROS_DOMAIN_ID": str(DOMAIN_ID)}
    group = ProcessGroup(env=env, echo=False)
    server = f"{hosts.address(hosts.names[0])}:{SERVER_PORT}"
    extra = ({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"} if mode == "simple" else {"ROS_DISCOVERY_SERVER": server})
    try:
        if mode == "server":
            group.start("server", hosts.exec_argv(hosts.names[0], discovery_server_argv(0, hosts.address(
                hosts.names[0]))))
            time.sleep(1.0)  # listening before any client starts
        per_host = [participants // HOSTS + (k < participants % HOSTS) for k in range(HOSTS)]
        sent0, first = hosts.traffic(), 0
        for host, count in zip(hosts.names, per_host):
            argv = [sys.executable, PROGRAM, "--first", first, "--count", count, "--total", participants,
                    "--seconds", STEADY_S + 5.0]
            group.start(f"participants_{host}", hosts.exec_argv(host, argv), extra_env=extra)
            first += count
        matches = wait_for_matches(group, participants)
        sent1, t1 = hosts.traffic(), time.monotonic()
        time.sleep(STEADY_S)
        steady = (hosts.traffic() - sent1) / (time.monotonic() - t1)
    finally:
        group.stop()
    times = [m["matched"] - m["created"] for m in matches]
    return Discovery(mode, participants, max(times), statistics.median(times), sent1 - sent0, steady)


def wait_for_matches(group, participants: int) -> list:
    deadline = time.monotonic() + TIMEOUT_S
    while True:
        lines = [json.loads(line) for m in group.members for line in list(m.lines) if line.startswith("{")]
        if len(lines) >= participants:
            return lines
        failed = [m.name for m in group.members if m.returncode not in (None, 0)]
        if failed or time.monotonic() > deadline:
            tails = "\n".join(f"[{m.name}] {line}" for m in group.members for line in m.lines[-5:])
            raise RuntimeError(f"{participants} participants: {len(lines)} matched"
                               + (f"; {', '.join(failed)} died" if failed else " before the timeout") + f"\n{tails}")
        time.sleep(0.05)


def run(sizes=PARTICIPANTS, report=print) -> list:
    from netns_hosts import LanHosts
    hosts = LanHosts(HOSTS)
    results = []
    try:
        hosts.create()
        hosts.wait_link_running()
        for p in sizes:
            for mode in MODES:
                results.append(measure(hosts, mode, p))
                r = results[-1]
                report(f"{mode:>6}, {p:2d} participants: matched after {r.median_s:.2f} s (median), "
                       f"{r.slowest_s:.2f} s (slowest), {r.bytes_to_match / 1e3:.0f} kB sent until all were, "
                       f"{r.steady_bytes_s / 1e3:.1f} kB/s afterwards")
    finally:
        hosts.close()
    return results


def rows(results: list) -> list:
    by = {(r.mode, r.participants): r for r in results}
    out = []
    for p in sorted({r.participants for r in results}):
        s, d = by[("simple", p)], by[("server", p)]
        what = f"discovery, {p} participants on {HOSTS} hosts"
        out += [
            (f"{what}: a participant matched after, median, simple / server (server / simple, same run)",
             f"{s.median_s:.2f} / {d.median_s:.2f} ({d.median_s / s.median_s:.2f})", "s (ratio)"),
            (f"{what}: the slowest participant matched after, simple / server (server / simple)",
             f"{s.slowest_s:.2f} / {d.slowest_s:.2f} ({d.slowest_s / s.slowest_s:.2f})", "s (ratio)"),
            (f"{what}: bytes sent until every participant matched, simple / server (server / simple)",
             f"{s.bytes_to_match / 1e3:.0f} / {d.bytes_to_match / 1e3:.0f} ({d.bytes_to_match / s.bytes_to_match:.2f})",
             "kB (ratio)"),
            (f"{what}: steady traffic, simple / server (server / simple)",
             f"{s.steady_bytes_s / 1e3:.1f} / {d.steady_bytes_s / 1e3:.1f} "
             f"({d.steady_bytes_s / s.steady_bytes_s:.2f})", "kB/s (ratio)"),
        ]
    return out


def bench_discovery_server() -> list:
    """Discovery time and traffic, simple discovery against a discovery server, 4 to 40 participants."""
    from netns_hosts import Unavailable
    try:
        return rows(run(report=lambda line: print(f"[bench]   {line}", flush=True)))
    except Unavailable as exc:
        return [("discovery benchmark: not run", str(exc), "")]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--participants", type=int, nargs="+", default=list(PARTICIPANTS))
    args = parser.parse_args(argv)
    for figure, value, unit in rows(run(args.participants)):
        print(f"{figure}: {value} {unit}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
