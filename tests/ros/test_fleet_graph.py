"""Three motors with different faults in one graph: ``bearing-graph --fleet`` over real DDS.

motor_1 has an outer-race fault, motor_2 an inner-race fault, motor_3 none; each has its own
simulator, and the role layout with two motors per process runs their observers in two
processes and their diagnosers in two more, beside the fleet node. Checked: each motor's
namespaced fault_state, its /diagnostics status (name and hardware id for
diagnostic_aggregator), the fleet_state summary and ``bearing-fleet --once``; then the
observers process of motor_1 and motor_2 is killed: bearing-graph restarts that process
alone, their states come back right while motor_3 never stops, and the scenario ends with
exit code 0 and a correct summary per motor.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass

import pytest
import yaml
from ros_harness import RosGraph, session_domain_id

from bearing_common import topics
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_session import status_name

pytestmark = pytest.mark.ros

GRAPH_CLI = [sys.executable, "-m", "bearing_bringup.graph_cli"]
FLEET_CLI = [sys.executable, "-m", "bearing_fleet.fleet_cli"]
EXPECTED = {"motor_1": FaultState.OUTER_RACE, "motor_2": FaultState.INNER_RACE, "motor_3": FaultState.NORMAL}
SCENARIO = {"motor_1": "or", "motor_2": "ir", "motor_3": "normal"}
# s of signal: room for the restart of a process (start-up up to 10 s) before the end, and no longer
SEGMENT_S = 24.0
LEVEL = {FaultState.NORMAL: 0, FaultState.OUTER_RACE: 2, FaultState.INNER_RACE: 2}  # OK, ERROR
VICTIM = "observers_1"  # motor_1's and motor_2's observers
STARTED = re.compile(r"\] (started|restarted) (\S+) \(pid (\d+)\)")


class Arrivals:
    """Messages with their arrival time (monotonic s), thread-safe."""

    def __init__(self):
        self.items: list = []
        self.lock = threading.Lock()

    def add(self, msg):
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def since(self, t: float = 0.0) -> list:
        with self.lock:
            return [m for at, m in self.items if at >= t]


@dataclass
class FleetRun:
    states: dict  # motor -> Arrivals of its fault_state
    statuses: list  # DiagnosticStatus of the three diagnosers, in arrival order
    fleet_state: object  # the last FleetState before the kill
    fleet_cli: subprocess.CompletedProcess
    killed_at: float
    restarted_at: float
    pids: dict  # process name -> pid of its last start
    starter_lines: list
    starter_code: int


def pids(lines) -> dict:
    return {m.group(2): int(m.group(3)) for m in map(STARTED.search, list(lines)) if m}


@pytest.fixture(scope="module")
def fleet_run(tmp_path_factory) -> FleetRun:
    tmp = tmp_path_factory.mktemp("fleet")
    (tmp / "fleet.yaml").write_text(yaml.safe_dump({
        "layout": "role", "motors_per_process": 2, "defaults": {"segment_duration": SEGMENT_S},
        "motors": {m: {"scenario": s} for m, s in SCENARIO.items()}}))
    graph = RosGraph(session_domain_id())
    try:
        states = {m: Arrivals() for m in EXPECTED}
        for m, arrivals in states.items():
            graph.node.create_subscription(topics.message_class(topics.FAULT_STATE.msgtype),
                                           topics.qualified(m, topics.FAULT_STATE), arrivals.add,
                                           topics.qos(topics.FAULT_STATE, depth=1000))
        diagnostics = graph.subscribe(topics.DIAGNOSTICS)
        fleet_states = graph.subscribe(topics.FLEET_STATE)
        starter = graph.start("", "", name="bearing_graph", argv=GRAPH_CLI + [
            "--fleet", str(tmp / "fleet.yaml"), "--out", str(tmp / "out"), "--restart-delay", "1"])

        def current(m, since=0.0):
            got = states[m].since(since)
            return FaultState(got[-1].state) if got else None

        graph.wait_until(lambda: all(current(m) == s for m, s in EXPECTED.items()), 240.0,
                         "every motor's expected fault_state")
        graph.wait_until(lambda: {s.name for d in diagnostics for s in d.status} >= {status_name(m) for m in EXPECTED}
                         and any(s.level == b"\x02" for d in diagnostics for s in d.status), 30.0,
                         "/diagnostics of every motor")
        fleet_cli = subprocess.run(FLEET_CLI + ["--once", "--timeout", "30"], env=graph.env, capture_output=True,
                                   text=True, timeout=90)
        fleet_state = fleet_states[-1]

        victim = pids(starter.lines)[VICTIM]
        killed_at = time.monotonic()
        os.kill(victim, signal.SIGKILL)
        graph.wait_until(lambda: pids(starter.lines)[VICTIM] != victim, 30.0, f"{VICTIM} restarted")
        restarted_at = time.monotonic()
        graph.wait_until(lambda: all(len(states[m].since(restarted_at)) >= 20 for m in ("motor_1", "motor_2")),
                         120.0, "fault_states computed by the restarted observers")
        graph.wait_until(lambda: starter.returncode is not None, 240.0, "the scenarios to end")
        statuses = [s for d in diagnostics for s in d.status if s.name in {status_name(m) for m in EXPECTED}]
        yield FleetRun(states, statuses, fleet_state, fleet_cli, killed_at, restarted_at, pids(starter.lines),
                       list(starter.lines), starter.returncode)
    finally:
        graph.close()


def test_each_motor_publishes_its_own_fault_state(fleet_run):
    for motor, expected in EXPECTED.items():
        got = [FaultState(m.state) for m in fleet_run.states[motor].since()]
        assert got and set(got) == {expected}, f"{motor}: {sorted(set(got))}"


def test_diagnostics_name_each_motor_for_the_aggregator(fleet_run):
    for motor, expected in EXPECTED.items():
        mine = [s for s in fleet_run.statuses if s.name == status_name(motor)]
        assert mine and {s.hardware_id for s in mine} == {motor}
        assert bytes([LEVEL[expected]]) in {s.level for s in mine}, [(s.level, s.message) for s in mine]


def test_fleet_state_and_bearing_fleet_list_the_three_motors(fleet_run):
    summary = {m.motor: (FaultState(m.state), m.stale) for m in fleet_run.fleet_state.motors}
    assert summary == {m: (s, False) for m, s in EXPECTED.items()}
    out = fleet_run.fleet_cli.stdout.splitlines()
    assert fleet_run.fleet_cli.returncode == 0, fleet_run.fleet_cli.stderr
    rows = {line.split()[0]: line.split()[1] for line in out[1:-1]}
    assert rows == {m: s.name for m, s in EXPECTED.items()}, out
    assert out[-1] == "3 motors, 2 not normal, 0 stale"


def test_a_killed_multi_node_process_is_restarted_alone(fleet_run):
    lines = fleet_run.starter_lines
    assert [m.group(2) for m in map(STARTED.search, lines) if m and m.group(1) == "restarted"] == [VICTIM]
    assert 1.0 <= fleet_run.restarted_at - fleet_run.killed_at < 5.0
    for motor in ("motor_1", "motor_2"):  # its observers are back and right
        after = fleet_run.states[motor].since(fleet_run.restarted_at)
        assert after and {FaultState(m.state) for m in after} == {EXPECTED[motor]}
    during = fleet_run.states["motor_3"].since(fleet_run.killed_at)  # the other process never stopped
    assert len(during) > 100


def test_the_fleet_ends_with_its_scenarios_and_a_correct_summary_per_motor(fleet_run):
    assert fleet_run.starter_code == 0, "\n".join(fleet_run.starter_lines[-40:])
    exit_line = next(line for line in fleet_run.starter_lines if "exit codes:" in line)
    assert all(code == "0" for code in re.findall(r" (-?\d+)(?:,|$)", exit_line)), exit_line
    for motor, expected in EXPECTED.items():
        header = next(i for i, line in enumerate(fleet_run.starter_lines) if line.startswith(f"{motor}: summary"))
        row = fleet_run.starter_lines[header + 3]
        assert f"| {expected.name} | {expected.name} |" in row and row.endswith("| yes |"), row
