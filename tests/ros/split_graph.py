"""The monitoring graph run on emulated hosts (``netns_hosts``), with one way of discovering:
what ``test_two_hosts.py`` and ``test_discovery_server.py`` run.

A placement maps each process to a host: the graph's nodes, two probe processes
(``netns_probe.py``: ``probe_a`` records the vibration chunks next to the simulator,
``probe_b`` the fault states next to the diagnoser; both print JSON lines with
CLOCK_MONOTONIC times, which the namespaces share) and, for discovery-server runs, the
servers ``discovery_server_<id>`` (the Fast DDS binary of the ``ros-fastrtps`` wheel).

Discovery modes (:func:`discovery_env`):

* ``localhost``: ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (one host, as the other ROS tests);
* ``multicast``: ``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET`` (Fast DDS's multicast discovery);
* ``static-peers``: ``LOCALHOST`` and ``ROS_STATIC_PEERS`` = the other host (two hosts only);
* ``discovery-server``: ``ROS_DISCOVERY_SERVER`` = every server of the run, in id order; the
  processes that look at the graph beyond their own topics (the simulator's start gate
  counts the residual topics' subscribers, the probes look for topics and nodes) are super
  clients (``ROS_SUPER_CLIENT=TRUE``), the others plain clients.
"""

from __future__ import annotations

import bisect
import json
import os
import pathlib
import signal
import statistics
import subprocess
import sys
import time
from collections import defaultdict
from dataclasses import dataclass

from graph_helpers import transitions, wait_spec
from ros_harness import REPO_ROOT, executable, ros_args

from bearing_bringup.graph import GRAPH, config_path
from bearing_bringup.process_group import ProcessGroup
from bearing_common import topics

SCENARIO = "or-ir"
DOMAIN_ID = 87  # unique to these tests (sessions use 100-199); <= 101 keeps its ports below Linux's ephemeral range
CHUNK_S = 0.01  # s per published chunk (config/monitor.yaml)
ONSET_TOL_S = CHUNK_S + 0.001
PROBE = REPO_ROOT / "tests" / "ros" / "netns_probe.py"
NODES = {spec.name: spec for spec in GRAPH}
STARTUP_S = 90.0  # node start-up (imports, compiled-code caches) on a loaded 2-core machine
DISCOVERY_S = 30.0
RUN_S = 60.0
SERVER_PORT = 11811  #: UDP port of every discovery server (Fast DDS's default)
SERVER_PREFIX = "discovery_server_"
SUPER_CLIENTS = ("simulator", "probe_a", "probe_b")

#: Inherited settings that would change how DDS discovers: every run sets its own.
DDS_VARIABLES = ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY",
                 "ROS_DISCOVERY_SERVER", "ROS_SUPER_CLIENT", "FASTDDS_BUILTIN_TRANSPORTS",
                 "FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE", "RMW_FASTRTPS_USE_QOS_FROM_XML")


def discovery_server_argv(server_id: int, address: str, port: int = SERVER_PORT) -> list:
    """The ``ros-fastrtps`` wheel's ``fast-discovery-server`` as server ``server_id`` on ``address``:
    the wheel installs it in the venv's ``bin/`` while its RPATH points into site-packages, so
    its libraries are given by LD_LIBRARY_PATH (``env`` prefix)."""
    venv = pathlib.Path(sys.executable).parent.parent
    libs = [str(p) for p in sorted(venv.glob("lib/python3*/site-packages/ros_fastrtps.libs"))] + [str(venv / "lib")]
    return ["env", f"LD_LIBRARY_PATH={':'.join(libs)}", str(venv / "bin" / "fast-discovery-server"),
            "-i", str(server_id), "-l", address, "-p", str(port)]


def servers_variable(hosts, placement: dict) -> str:
    """``ROS_DISCOVERY_SERVER`` for the servers of ``placement``: ``address:port`` by id, ``;``-separated."""
    ids = sorted(int(name[len(SERVER_PREFIX):]) for name in placement if name.startswith(SERVER_PREFIX))
    return ";".join(f"{hosts.address(placement[SERVER_PREFIX + str(i)])}:{SERVER_PORT}" for i in ids)


def discovery_env(mode: str, hosts, host: str, name: str = "", servers: str = "") -> dict:
    """The DDS discovery variables of ``mode`` for process ``name`` on ``host``."""
    if mode == "localhost":
        return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    if mode == "multicast":
        return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}
    if mode == "static-peers":
        return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_STATIC_PEERS": hosts.address(hosts.other(host))}
    if mode == "discovery-server":
        return {"ROS_DISCOVERY_SERVER": servers} | ({"ROS_SUPER_CLIENT": "TRUE"} if name in SUPER_CLIENTS else {})
    raise ValueError(mode)


@dataclass
class Outcome:
    """What one run of the scenario published and what it took."""

    decisions: list  # [(stamp s, state, onset s)] in publication order, as received on the diagnoser's host
    discovery_s: float  # a node started on the diagnoser's host: created -> a node on host A in its graph
    latencies_ms: list  # vibration chunk on A -> fault_state on the diagnoser's host, per decision
    samples: int  # vibration samples published
    link_bytes: dict  # bytes sent over each host's link during the run

    @property
    def transitions(self) -> list:
        return transitions([(state, onset) for _, state, onset in self.decisions])

    def summary(self) -> str:
        lat = sorted(self.latencies_ms)
        p95 = lat[min(len(lat) - 1, int(round(0.95 * (len(lat) - 1))))]
        sent = ", ".join(f"{host} {n}" for host, n in self.link_bytes.items())
        return (f"discovery {self.discovery_s * 1e3:.0f} ms; latency median {statistics.median(lat):.1f} ms, "
                f"95th percentile {p95:.1f} ms over {len(lat)} decisions; link bytes sent: {sent}; "
                f"transitions {self.transitions}")


class Run:
    """The graph's processes, placed on hosts, with one discovery mode; stopped by ``stop()``."""

    def __init__(self, hosts, placement: dict, mode: str, listed_servers: dict | None = None):
        """``listed_servers``: the placement whose servers clients are told of (default ``placement``'s;
        a server listed but not placed is never started)."""
        self.hosts, self.placement, self.mode = hosts, placement, mode
        self.servers = servers_variable(hosts, listed_servers or placement)
        env = {k: v for k, v in os.environ.items() if k not in DDS_VARIABLES}
        env.update(ROS_DOMAIN_ID=str(DOMAIN_ID), OPENBLAS_NUM_THREADS="1")
        self.group = ProcessGroup(env=env, echo=False)

    def start(self, name: str, argv: list):
        host = self.placement[name]
        return self.group.start(name, self.hosts.exec_argv(host, argv),
                                extra_env=discovery_env(self.mode, self.hosts, host, name, self.servers))

    def start_servers(self) -> None:
        """The discovery servers of the placement (none in other modes)."""
        for name, host in self.placement.items():
            if name.startswith(SERVER_PREFIX):
                self.start(name, discovery_server_argv(int(name[len(SERVER_PREFIX):]), self.hosts.address(host)))

    def start_node(self, name: str, params: dict | None = None):
        spec = NODES[name]
        return self.start(name, [executable(spec.package, spec.executable)] + ros_args(name, params, config_path()))

    def start_probe(self, name: str, watch=(), discover=(), discover_nodes=()):
        argv = [sys.executable, PROBE, "--name", name]
        argv += [a for t in watch for a in ("--watch", t.name)] + [a for t in discover for a in ("--discover", t.name)]
        argv += [a for n in discover_nodes for a in ("--discover-node", n)]
        return self.start(name, argv)

    @staticmethod
    def events(member, event: str, topic=None) -> list:
        out = []
        for line in list(member.lines):
            if line.startswith("{"):
                item = json.loads(line)
                if item["event"] == event and (topic is None or item.get("topic") == topic.name):
                    out.append(item)
        return out

    def wait_until(self, condition, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            failed = [m.name for m in self.group.members if m.returncode not in (None, 0)]
            if failed:
                raise AssertionError(f"{', '.join(failed)} exited with an error while waiting for {what}\n"
                                     f"{self.output()}")
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out after {timeout} s waiting for {what}\n{self.output()}")
            time.sleep(0.05)

    def output(self) -> str:
        """Each process's last lines; of a probe's messages, per topic only how many and the last stamp."""
        return "\n".join(f"--- {m.name} on host {self.placement[m.name]} (exit {m.returncode}) ---\n"
                         + "\n".join(line for line in m.lines[-30:] if not line.startswith('{"event": "msg"'))
                         + self.received(m) for m in self.group.members)

    def received(self, member) -> str:
        per_topic = defaultdict(list)
        for item in self.events(member, "msg"):
            per_topic[item["topic"]].append(item["stamp"])
        return "".join(f"\n({len(stamps)} messages on {name}, the last stamped {stamps[-1]:.3f} s)"
                       for name, stamps in per_topic.items())

    def stop_one(self, member, timeout: float = 10.0) -> int:
        """Stop one process (SIGINT to its group, SIGKILL after ``timeout``) and forget it."""
        try:
            os.killpg(member.process.pid, signal.SIGINT)
            code = member.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(member.process.pid, signal.SIGKILL)
            code = member.process.wait()
        except ProcessLookupError:
            code = member.process.wait()
        member.reader.join(timeout=2.0)
        self.group.members.remove(member)
        return code

    def stop(self) -> dict:
        return self.group.stop()


def run_scenario(hosts, placement: dict, mode: str, listed_servers: dict | None = None) -> Outcome:
    """Start the servers and the consumers, wait (on what the probes see) until the graph is
    connected, run the scenario, wait for the decision on its last window; always stop every process."""
    run = Run(hosts, placement, mode, listed_servers)
    try:
        run.start_servers()
        for name in ("or_observer", "ir_observer", "diagnoser"):
            run.start_node(name)
        residuals = (topics.RESIDUAL_OUTER_RACE, topics.RESIDUAL_INNER_RACE)
        probe_a = run.start_probe("probe_a", watch=[topics.VIBRATION], discover=residuals + (topics.FAULT_STATE,))
        run.wait_until(lambda: len(run.events(probe_a, "publisher")) == 3, STARTUP_S,
                       f"the sensor's host to find the observers and the diagnoser ({mode} discovery)")
        # the graph is up and idle: how long a node started now on the diagnoser's host takes to see one on A
        probe_b = run.start_probe("probe_b", watch=[topics.FAULT_STATE], discover_nodes=["probe_a"])
        run.wait_until(lambda: run.events(probe_b, "node"), STARTUP_S + DISCOVERY_S,
                       f"host {placement['probe_b']} to discover the sensor host's nodes ({mode} discovery)")
        discovery_s = run.events(probe_b, "node")[0]["t"] - run.events(probe_b, "up")[0]["t"]

        sent_before = {host: hosts.tx_bytes(host) for host in hosts.names}
        wait = wait_spec({topics.VIBRATION: 3, topics.SHAFT_SPEED: 3, topics.RESIDUAL_OUTER_RACE: 1,
                          topics.RESIDUAL_INNER_RACE: 1, topics.FAULT_STATE: 1})
        sim = run.start_node("simulator", {"scenario": SCENARIO, "realtime": True, "wait_for_subscribers": wait,
                                           "subscriber_timeout": 2 * RUN_S})
        run.wait_until(lambda: sim.returncode is not None, RUN_S, "the scenario to end")
        assert sim.returncode == 0, run.output()
        assert not [line for line in sim.lines if "starting with" in line], \
            f"the simulator started before the graph was connected\n{run.output()}"
        chunks = run.events(probe_a, "msg", topics.VIBRATION)
        assert chunks, run.output()
        end = max(c["end"] for c in chunks)
        run.wait_until(lambda: any(s["stamp"] >= end - ONSET_TOL_S for s in run.events(probe_b, "msg")), RUN_S,
                       f"the diagnoser's decision on the last window (ending at {end:.3f} s)")
        states = run.events(probe_b, "msg", topics.FAULT_STATE)
        sent = {host: hosts.tx_bytes(host) - sent_before[host] for host in hosts.names}
        members = {m.name: m for m in run.group.members}
        for name in members:
            if name != "simulator":
                assert members[name].returncode is None, f"{name} died\n{run.output()}"
    finally:
        run.stop()

    chunks.sort(key=lambda c: c["end"])
    ends = [c["end"] for c in chunks]
    latencies = []
    for s in states:
        i = bisect.bisect_left(ends, s["stamp"] - 1e-9)  # the chunk holding the window's last sample
        if i < len(chunks):
            latencies.append((s["t"] - chunks[i]["t"]) * 1e3)
    return Outcome([(s["stamp"], s["state"], s["onset"]) for s in states], discovery_s, latencies,
                   sum(c["n"] for c in chunks), sent)
