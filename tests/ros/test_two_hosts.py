"""The monitoring graph split over two hosts, emulated by two network namespaces.

Host A runs the simulator (the sensor) and both observers, host B the diagnoser (or, as
an edge sensor, A only the simulator and B the observers too); their only connection is one
veth pair (10.213.0.1/30 - 10.213.0.2/30, no other interface, no default route, each host
with its own /dev/shm, see ``netns_hosts.py``), so DDS discovery and every sample from A to B
cross that link. The fault states published on B for the thesis' OR-IR case must be those
of the same scenario run on one host (all of it in namespace A, localhost discovery as in
the other ROS tests): the same decision for every window, hence the same states, and onsets
within one 10 ms chunk (decisions are timed by stamps, not arrival).

Two ways of discovering across the link are tested:

* ``multicast``: ``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET`` (Fast DDS's multicast discovery);
* ``static-peers``: ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and ``ROS_STATIC_PEERS`` =
  the other host's address (unicast only: no multicast at all).

The processes, probes and discovery modes are ``split_graph.py``'s. The test's listeners are
probe processes (``netns_probe.py``) run inside the namespaces:
one on A records the vibration chunks, one on B the fault states; both print JSON lines
with CLOCK_MONOTONIC times, which the namespaces share, so the end-to-end latency
(vibration chunk on A -> fault_state on B) and the discovery time across the link are
measured too and printed. Skipped where namespaces cannot be created (not root, no ``ip``,
``ip netns add`` refused). Namespaces and processes are removed after the module, pass
or fail.
"""

from __future__ import annotations

import pytest
from netns_hosts import VETH, TwoHosts, Unavailable
from split_graph import ONSET_TOL_S, Outcome, run_scenario

from bearing_common.states import FaultState

pytestmark = pytest.mark.ros

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
