"""Stopping real node processes by signal: exit 0, no traceback, the shutdown hook's last message.

Modes: SIGINT (Ctrl-C), SIGTERM (a supervisor), SIGINT twice 10 ms apart (a terminal
Ctrl-C under ``ros2 launch``: the terminal and launch both send it). Sent to one node of
a running graph at a time, and to the whole graph started as one process group.
"""

import os
import signal
import subprocess
import sys
import time

import pytest
from graph_helpers import BAG_CLI, params_file
from ros_harness import REPO_ROOT, executable

from bearing_bringup.graph import GRAPH
from bearing_common import topics
from bearing_common.node_main import STOP_STALL_S, TEARDOWN_END_S
from bearing_recordings.bag_read import read_bag

pytestmark = pytest.mark.ros

MODES = {"SIGINT": (signal.SIGINT,), "SIGTERM": (signal.SIGTERM,), "SIGINT-twice": (signal.SIGINT, signal.SIGINT)}
DOUBLE_GAP_S = 0.01
BAD_OUTPUT = ("Traceback", "RCLError", "context is not valid", "Failed to publish")
STOP_TIMEOUT_S = 10.0  # the harness escalates to SIGTERM after 5 s and SIGKILL after 7 s: must not be needed


def send(pgid: int, mode: str) -> None:
    for i, sig in enumerate(MODES[mode]):
        if i:
            time.sleep(DOUBLE_GAP_S)
        os.killpg(pgid, sig)


def assert_clean_exit(member) -> None:
    try:
        code = member.process.wait(timeout=STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:  # not even node_main's stall watchdog (stacks, exit 1 at 4 s) ended it
        code = None
    member.reader.join(timeout=2.0)
    text = "\n".join(member.lines)
    assert code is not None, f"{member.name} still running {STOP_TIMEOUT_S} s after the signal\n{text}"
    assert code == 0, f"{member.name} exited with {code}\n{text}"
    bad = [b for b in BAD_OUTPUT if b in text]
    assert not bad, f"{member.name} printed {bad}\n{text}"


def start_graph(ros_graph, one_group: bool) -> dict:
    """The whole graph (simulator in endless normal operation), running once a fault_state is out."""
    states = ros_graph.subscribe(topics.FAULT_STATE)
    members, leader = {}, None
    for spec in GRAPH:
        params = {"scenario": ""} if spec.executable == "simulator" else None
        members[spec.name] = ros_graph.start(spec.package, spec.executable, name=spec.name,
                                             params_file=params_file(), params=params, join=leader)
        if one_group and leader is None:
            leader = members[spec.name]
    ros_graph.wait_until(lambda: len(states) > 0, 120.0, "the graph's first fault_state")
    return members


@pytest.mark.parametrize("mode", MODES)
def test_each_node_stops_cleanly_alone(ros_graph, mode):
    members = start_graph(ros_graph, one_group=False)
    for name in ("or_observer", "diagnoser", "simulator", "ir_observer"):  # the rest keeps running meanwhile
        send(members[name].process.pid, mode)
        assert_clean_exit(members[name])


@pytest.mark.parametrize("mode", MODES)
def test_the_whole_graph_stops_cleanly_as_one_process_group(ros_graph, mode, tmp_path):
    """... with a bearing-bag recorder in the group, whose bag is then complete."""
    members = start_graph(ros_graph, one_group=True)
    recorder = ros_graph.start("", "", name="bag_record", join=members["simulator"],
                               argv=BAG_CLI + ["record", "--out", str(tmp_path / "bag")])
    for topic in (topics.VIBRATION, topics.FAULT_STATE):
        seen = f"first message on {topics.qualified('', topic)}"
        ros_graph.wait_until(lambda seen=seen: any(seen in line for line in recorder.lines), 60.0, seen)
    send(os.getpgid(members["simulator"].process.pid), mode)
    for member in [*members.values(), recorder]:
        assert_clean_exit(member)
    bag = read_bag(tmp_path / "bag")
    assert bag.chunks and bag.fault_states


@pytest.mark.parametrize("mode", MODES)
def test_a_node_stopped_while_starting_ends_at_once(ros_graph, mode):
    """A signal during a node's construction (the diagnoser's warm-up: seconds under load) ends the
    start-up: exit 0 and one line, not the stall watchdog's dump after 4 s."""
    probe = ros_graph.start("", "", name="hook_probe",
                            argv=[sys.executable, str(REPO_ROOT / "tests" / "ros" / "hook_probe.py"), "--slow-start"])
    ros_graph.wait_until(lambda: any("starting slowly" in line for line in probe.lines), 60.0, "the slow start")
    sent = time.monotonic()
    send(probe.process.pid, mode)
    assert_clean_exit(probe)
    assert time.monotonic() - sent < 3.0
    assert any(f"hook_probe: {MODES[mode][0].name} while starting: stopped" in line for line in probe.lines)


@pytest.mark.parametrize("mode", MODES)
def test_shutdown_hook_publishes_a_last_message(ros_graph, mode):
    from hook_probe import RUNNING, STOPPED

    diagnostics = ros_graph.subscribe(topics.DIAGNOSTICS)
    probe = ros_graph.start("", "", name="hook_probe",
                            argv=[sys.executable, str(REPO_ROOT / "tests" / "ros" / "hook_probe.py")])
    ros_graph.wait_until(lambda: any(m.status[0].message == RUNNING for m in diagnostics), 60.0, "the probe running")
    send(probe.process.pid, mode)
    assert_clean_exit(probe)
    assert [m.status[0].message for m in diagnostics][-1] == STOPPED


def test_a_stuck_teardown_ends_cleanly_within_its_bound(ros_graph):
    """rclpy's teardown (destroy_node, where rmw deletes the DDS participant) held in C with the GIL
    past TEARDOWN_END_S after the signal: the process still ends with exit 0 and one line, after the
    hook's last message, before the stall watchdog (without the bound: its dump and exit 1 at 4 s)."""
    from hook_probe import RUNNING, STOPPED

    diagnostics = ros_graph.subscribe(topics.DIAGNOSTICS)
    probe = ros_graph.start("", "", name="hook_probe", argv=[
        sys.executable, str(REPO_ROOT / "tests" / "ros" / "hook_probe.py"), "--stuck-teardown"])
    ros_graph.wait_until(lambda: any(m.status[0].message == RUNNING for m in diagnostics), 60.0, "the probe running")
    sent = time.monotonic()
    send(probe.process.pid, "SIGINT")
    assert_clean_exit(probe)
    took = time.monotonic() - sent
    assert TEARDOWN_END_S < took < STOP_STALL_S, f"stopped after {took:.1f} s"
    assert any(f"hook_probe: rclpy's teardown (the node's and DDS participant's deletion) still ran "
               f"{TEARDOWN_END_S:g} s after the stop: ended without it" in line for line in probe.lines), \
        "\n".join(probe.lines)
    assert [m.status[0].message for m in diagnostics][-1] == STOPPED


def catches(pid: int, sig: signal.Signals) -> bool:
    """Process ``pid`` has a handler for ``sig`` (``SigCgt`` in /proc: Python catches SIGINT from
    its start, SIGTERM only once node_main's stop signals are in place)."""
    with open(f"/proc/{pid}/status") as status:
        caught = next(int(line.split()[1], 16) for line in status if line.startswith("SigCgt:"))
    return bool(caught >> (sig - 1) & 1)


def assert_stopped_while_starting(member, program: str, mode: str, sent: float) -> None:
    """Exit 0, no traceback, the one line of a stop during the start-up, well within the watchdog."""
    assert_clean_exit(member)
    took = time.monotonic() - sent
    assert any(f"{program}: {MODES[mode][0].name} while starting: stopped" in line for line in member.lines), \
        "\n".join(member.lines)
    assert took < STOP_STALL_S, f"{program} took {took:.1f} s to stop"


@pytest.mark.parametrize("mode", MODES)
def test_a_node_stopped_during_its_imports_ends_at_once(ros_graph, mode):
    """A signal once the executable handles it (its first lines), while the node module imports
    numpy, numba and rclpy (seconds under load): a stop, not a KeyboardInterrupt traceback or
    death by SIGTERM."""
    member = ros_graph.start("bearing_diagnoser", "diagnoser")
    deadline = time.monotonic() + 30.0
    while not catches(member.process.pid, signal.SIGTERM):
        assert member.returncode is None and time.monotonic() < deadline, "\n".join(member.lines)
        time.sleep(0.002)
    with open(f"/proc/{member.process.pid}/maps") as maps:
        assert "_multiarray_umath" not in maps.read(), "numpy already imported: too late to test the imports"
    sent = time.monotonic()
    send(member.process.pid, mode)
    assert_stopped_while_starting(member, "diagnoser", mode, sent)
    assert not any("[diagnoser]" in line for line in member.lines), "the node was built: not during its imports"


#: each node's node name, and its log line once its compiles are done
FIRST_COMPILE = {("bearing_sim", "simulator"): ("simulator", "simulator ready after"),  # warm-up after the build
                 ("bearing_observer", "observer"): ("or_observer", "observer: vibration")}  # warm-up in the build


@pytest.mark.parametrize("package, program", FIRST_COMPILE)
def test_a_node_stopped_during_its_first_numba_compile_ends_cleanly(ros_graph, tmp_path, package, program):
    """As after an install: numba's cache is empty and the node, once in the graph, compiles its
    kernels for seconds, much of it inside LLVM (C calls the signal handler waits for); Ctrl-C
    meanwhile is a stop."""
    node, compiled = FIRST_COMPILE[(package, program)]
    member = ros_graph.processes.start(program, [str(executable(package, program))],
                                       extra_env={"NUMBA_CACHE_DIR": str(tmp_path / "numba")})
    ros_graph.wait_until(lambda: node in ros_graph.node.get_node_names() or member.returncode is not None,
                         60.0, f"{node} in the graph")
    time.sleep(0.3)  # into the compile (seconds from scratch)
    assert not any(compiled in line for line in member.lines), "the compile ended before the signal"
    sent = time.monotonic()
    send(member.process.pid, "SIGINT")
    assert_stopped_while_starting(member, program, "SIGINT", sent)
    assert not any(compiled in line for line in member.lines)
