"""The monitoring graph split over two hosts, emulated by two network namespaces.

Host A runs the simulator (the sensor) and both observers, host B the diagnoser (or, as
an edge sensor, A only the simulator and B the observers too); their only connection is one
veth pair (10.213.0.1/30 - 10.213.0.2/30, no other interface, no default route, each host
with its own /dev/shm, see ``two_hosts.py``), so DDS discovery and every sample from A to B
cross that link. The fault states published on B for the thesis' OR-IR case must be those
of the same scenario run on one host (all of it in namespace A, localhost discovery as in
the other ROS tests): the same decision for every window, hence the same states, and onsets
within one 10 ms chunk (decisions are timed by stamps, not arrival).

Two ways of discovering across the link are tested:

* ``multicast``: ``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET`` (Fast DDS's multicast discovery);
* ``static-peers``: ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and ``ROS_STATIC_PEERS`` =
  the other host's address (unicast only: no multicast at all).

The test's listeners are probe processes (``netns_probe.py``) run inside the namespaces:
one on A records the vibration chunks, one on B the fault states; both print JSON lines
with CLOCK_MONOTONIC times, which the namespaces share, so the end-to-end latency
(vibration chunk on A -> fault_state on B) and the discovery time across the link are
measured too and printed. Skipped where namespaces cannot be created (not root, no ``ip``,
``ip netns add`` refused). Namespaces and processes are removed after the module, pass
or fail.
"""

from __future__ import annotations

import bisect
import json
import os
import signal
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass

import pytest
from graph_helpers import transitions, wait_spec
from ros_harness import REPO_ROOT, executable, ros_args
from two_hosts import VETH, TwoHosts, Unavailable

from bearing_bringup.graph import GRAPH, config_path
from bearing_bringup.process_group import ProcessGroup
from bearing_common import topics
from bearing_common.states import FaultState

pytestmark = pytest.mark.ros

SCENARIO = "or-ir"
DOMAIN_ID = 87  # unique to this test (sessions use 100-199); <= 101 keeps its ports below Linux's ephemeral range
CHUNK_S = 0.01  # s per published chunk (config/monitor.yaml)
ONSET_TOL_S = CHUNK_S + 0.001
PROBE = REPO_ROOT / "tests" / "ros" / "netns_probe.py"
NODES = {spec.name: spec for spec in GRAPH}
STARTUP_S = 90.0  # node start-up (imports, compiled-code caches) on a loaded 2-core machine
DISCOVERY_S = 30.0
RUN_S = 60.0

#: Inherited settings that would change how DDS discovers: every run sets its own.
DDS_VARIABLES = ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY",
                 "ROS_DISCOVERY_SERVER", "ROS_SUPER_CLIENT", "FASTDDS_BUILTIN_TRANSPORTS",
                 "FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE", "RMW_FASTRTPS_USE_QOS_FROM_XML")

#: Where each process runs. probe_a records the vibration chunks next to the simulator,
#: probe_b the fault states next to the diagnoser.
ONE_HOST = {"simulator": "A", "or_observer": "A", "ir_observer": "A", "diagnoser": "A", "probe_a": "A", "probe_b": "A"}
SPLITS = {
    # the residuals cross the link (float32 residual, estimate and train per sample and hypothesis with the
    # simulator's model set; at least the residuals themselves)
    "observers-on-A": ({"simulator": "A", "or_observer": "A", "ir_observer": "A", "diagnoser": "B",
                        "probe_a": "A", "probe_b": "B"}, 2 * 4),
    # an edge sensor: only the vibration (one float64 per sample) and the shaft speed cross the link
    "sensor-on-A": ({"simulator": "A", "or_observer": "B", "ir_observer": "B", "diagnoser": "B",
                     "probe_a": "A", "probe_b": "B"}, 8),
}


def discovery_env(mode: str, hosts: TwoHosts, host: str) -> dict:
    """The DDS discovery variables of ``mode`` for a process on ``host``."""
    if mode == "localhost":
        return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    if mode == "multicast":
        return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}
    if mode == "static-peers":
        return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_STATIC_PEERS": hosts.address(hosts.other(host))}
    raise ValueError(mode)


@dataclass
class Outcome:
    """What one run of the scenario published and what it took."""

    decisions: list  # [(stamp s, state, onset s)] in publication order, as received on the diagnoser's host
    discovery_s: float  # a node started on the diagnoser's host: created -> a node on host A in its graph
    latencies_ms: list  # vibration chunk on A -> fault_state on the diagnoser's host, per decision
    samples: int  # vibration samples published
    link_bytes: dict  # bytes sent over the veth pair during the run, per host

    @property
    def transitions(self) -> list:
        return transitions([(state, onset) for _, state, onset in self.decisions])

    def summary(self) -> str:
        lat = sorted(self.latencies_ms)
        p95 = lat[min(len(lat) - 1, int(round(0.95 * (len(lat) - 1))))]
        return (f"discovery {self.discovery_s * 1e3:.0f} ms; latency median {statistics.median(lat):.1f} ms, "
                f"95th percentile {p95:.1f} ms over {len(lat)} decisions; link bytes A->B {self.link_bytes['A']}, "
                f"B->A {self.link_bytes['B']}; transitions {self.transitions}")


class Run:
    """The graph's processes, placed on hosts, with one discovery mode; stopped by ``stop()``."""

    def __init__(self, hosts: TwoHosts, placement: dict, mode: str):
        self.hosts, self.placement, self.mode = hosts, placement, mode
        env = {k: v for k, v in os.environ.items() if k not in DDS_VARIABLES}
        env.update(ROS_DOMAIN_ID=str(DOMAIN_ID), OPENBLAS_NUM_THREADS="1")
        self.group = ProcessGroup(env=env, echo=False)

    def start(self, name: str, argv: list):
        host = self.placement[name]
        return self.group.start(name, self.hosts.exec_argv(host, argv),
                                extra_env=discovery_env(self.mode, self.hosts, host))

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
        return "\n".join(f"--- {m.name} on host {self.placement[m.name]} (exit {m.returncode}) ---\n"
                         + "\n".join(line for line in m.lines[-30:] if not line.startswith('{"event": "msg"'))
                         for m in self.group.members)

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


def run_scenario(hosts: TwoHosts, placement: dict, mode: str) -> Outcome:
    """Start the consumers, wait (on what the probes see) until the graph is connected, run
    the scenario, wait for the decision on its last window; always stop every process."""
    run = Run(hosts, placement, mode)
    try:
        for name in ("or_observer", "ir_observer", "diagnoser"):
            run.start_node(name)
        residuals = (topics.RESIDUAL_OUTER_RACE, topics.RESIDUAL_INNER_RACE)
        probe_a = run.start_probe("probe_a", watch=[topics.VIBRATION], discover=residuals + (topics.FAULT_STATE,))
        run.wait_until(lambda: len(run.events(probe_a, "publisher")) == 3, STARTUP_S,
                       f"host A to find the observers and the diagnoser ({mode} discovery)")
        # the graph is up and idle: how long a node started now on the diagnoser's host takes to see one on A
        probe_b = run.start_probe("probe_b", watch=[topics.FAULT_STATE], discover_nodes=["probe_a"])
        run.wait_until(lambda: run.events(probe_b, "node"), STARTUP_S + DISCOVERY_S,
                       f"host {placement['probe_b']} to discover host A's nodes ({mode} discovery)")
        discovery_s = run.events(probe_b, "node")[0]["t"] - run.events(probe_b, "up")[0]["t"]

        sent_before = {host: hosts.tx_bytes(host) for host in ("A", "B")}
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
                       "the diagnoser's decision on the last window")
        states = run.events(probe_b, "msg", topics.FAULT_STATE)
        sent = {host: hosts.tx_bytes(host) - sent_before[host] for host in ("A", "B")}
        members = {m.name: m for m in run.group.members}
        for name in ("or_observer", "ir_observer", "diagnoser"):
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


@pytest.fixture(scope="module")
def hosts():
    """Namespaces A and B joined by a veth pair; deleted after the module, pass or fail."""
    pair = TwoHosts()
    try:
        try:
            pair.create()
        except Unavailable as exc:
            pytest.skip(f"two-host test needs network namespaces: {exc}")
        pair.wait_link_running()  # before any DDS participant exists (see TwoHosts.wait_link_running)
        yield pair
    finally:
        errors = pair.close()
    assert not errors, errors


@pytest.fixture(scope="module")
def one_host(hosts) -> Outcome:
    """The reference: the whole graph and both probes on host A, localhost discovery."""
    outcome = run_scenario(hosts, ONE_HOST, "localhost")
    print(f"\none host (localhost discovery): {outcome.summary()}")
    assert outcome.link_bytes["A"] < 0.05 * 8 * outcome.samples, f"the one-host run used the link: {outcome.summary()}"
    return outcome


def test_hosts_reach_only_each_other(hosts):
    for host in ("A", "B"):
        assert hosts.interfaces(host) == {"lo", VETH[host]}
        routes = hosts.routes(host)
        assert not [r for r in routes if r.get("dst") == "default"], routes
        assert {r.get("dev") for r in routes} <= {"lo", VETH[host]}, routes


@pytest.mark.parametrize("split, mode", [("observers-on-A", "multicast"), ("observers-on-A", "static-peers"),
                                         ("sensor-on-A", "multicast")])
def test_split_graph_decides_as_on_one_host(hosts, one_host, split, mode):
    placement, link_bytes_per_sample = SPLITS[split]
    outcome = run_scenario(hosts, placement, mode)
    print(f"\ntwo hosts, {split} ({mode} discovery): {outcome.summary()}")
    expected = one_host.transitions
    assert [s for s, _ in expected] == [FaultState.OUTER_RACE, FaultState.INNER_RACE], one_host.summary()
    got = outcome.transitions
    assert [s for s, _ in got] == [s for s, _ in expected], (got, expected)
    for (_, onset), (_, ref) in zip(got, expected):
        assert abs(onset - ref) <= ONSET_TOL_S, (got, expected)
    # every window's decision, timed by stamps: the same windows, the same states
    assert [(t, s) for t, s, _ in outcome.decisions] == [(t, s) for t, s, _ in one_host.decisions], \
        (outcome.decisions, one_host.decisions)
    # the signal really crossed the link
    assert outcome.link_bytes["A"] >= link_bytes_per_sample * outcome.samples, (outcome.link_bytes, outcome.samples)
