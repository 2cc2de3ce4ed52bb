"""The monitoring graph over four hosts of one LAN that discover through Fast DDS discovery
servers (docs/fleet.md "Across machines": the choice for plants), emulated by network namespaces.

Hosts H1-H4 hang on one switch (``netns_hosts.LanHosts``: a bridge, 10.213.1.1-4/24, no
other interface, no route out, each host with its own /dev/shm). H1 runs discovery server 0
and the sensor (the simulator and the probe recording its chunks), H2 the OR observer, H3
the IR observer, H4 discovery server 1 (the redundant one), the diagnoser and the probe
taking its fault states. Every process has ``ROS_DISCOVERY_SERVER`` = both servers; the
nodes are plain clients, the simulator and the probes super clients (they look at topics
they do not use themselves: the simulator's start gate counts the residuals' subscribers).
The fault states published on H4 for the thesis' OR-IR case must be, window for window,
those of the same scenario with the whole graph on H1 (localhost discovery): with both
servers up, and with server 0 never started (every client finds the graph through server 1).
Processes (``split_graph.py``) and namespaces are removed after the module, pass or fail;
skipped where namespaces cannot be created (not root, no ``ip``).
"""

from __future__ import annotations

import pytest
from netns_hosts import LanHosts, Unavailable
from split_graph import ONSET_TOL_S, SERVER_PREFIX, Outcome, run_scenario

from bearing_common.states import FaultState

pytestmark = pytest.mark.ros

ONE_HOST = dict.fromkeys(("simulator", "or_observer", "ir_observer", "diagnoser", "probe_a", "probe_b"), "H1")
SPLIT = {f"{SERVER_PREFIX}0": "H1", "simulator": "H1", "probe_a": "H1", "or_observer": "H2", "ir_observer": "H3",
         f"{SERVER_PREFIX}1": "H4", "diagnoser": "H4", "probe_b": "H4"}
#: bytes per sample and hypothesis an observer's host sends at least: its float32 residuals
RESIDUAL_BYTES = 4


@pytest.fixture(scope="module")
def lan():
    hosts = LanHosts(4)
    try:
        try:
            hosts.create()
        except Unavailable as exc:
            pytest.skip(f"the discovery-server test needs network namespaces: {exc}")
        hosts.wait_link_running()
        yield hosts
    finally:
        errors = hosts.close()
    assert not errors, errors


@pytest.fixture(scope="module")
def one_host(lan) -> Outcome:
    outcome = run_scenario(lan, ONE_HOST, "localhost")
    print(f"\none host (localhost discovery): {outcome.summary()}")
    assert [s for s, _ in outcome.transitions] == [FaultState.OUTER_RACE, FaultState.INNER_RACE], outcome.summary()
    return outcome


@pytest.mark.parametrize("servers", ["both", "only-server-1"])
def test_graph_over_four_hosts_decides_as_on_one_host(lan, one_host, servers):
    placement = dict(SPLIT)
    if servers == "only-server-1":  # listed in ROS_DISCOVERY_SERVER, never started
        placement = {k: v for k, v in placement.items() if k != f"{SERVER_PREFIX}0"}
    outcome = run_scenario(lan, placement, "discovery-server", listed_servers=SPLIT)
    print(f"\nfour hosts, discovery servers ({servers}): {outcome.summary()}")
    got, expected = outcome.transitions, one_host.transitions
    assert [s for s, _ in got] == [s for s, _ in expected], (got, expected)
    for (_, onset), (_, ref) in zip(got, expected):
        assert abs(onset - ref) <= ONSET_TOL_S, (got, expected)
    assert [(t, s) for t, s, _ in outcome.decisions] == [(t, s) for t, s, _ in one_host.decisions], \
        (outcome.decisions, one_host.decisions)
    # the signal and the residuals really crossed the LAN: each observer's host sent its residuals
    for host in ("H2", "H3"):
        assert outcome.link_bytes[host] >= RESIDUAL_BYTES * outcome.samples, outcome.summary()
    assert outcome.link_bytes["H1"] >= 2 * 8 * outcome.samples, outcome.summary()  # the chunks, to H2 and H3
