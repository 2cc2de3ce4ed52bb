"""bearing-graph's restart policy: delay, cap per window, what is not restarted; supervise() with real children."""

import signal
import sys

from bearing_bringup.graph_cli import supervise
from bearing_bringup.process_group import ProcessGroup
from bearing_bringup.restart_policy import RestartPolicy, describe_exit
from bearing_common.stop_signals import StopSignals


def test_crashes_are_restarted_until_the_cap_within_the_window():
    policy = RestartPolicy(delay=1.0, max_restarts=2, window=60.0)
    first = policy.after_exit("or_observer", -signal.SIGKILL, now=0.0)
    assert first.restart and first.message == ("or_observer died (killed by SIGKILL); restarting it in 1 s "
                                               "(restart 1 of at most 2 per 60 s)")
    assert policy.after_exit("or_observer", 1, now=10.0).restart
    assert policy.after_exit("diagnoser", 1, now=10.0).restart  # counted per node
    loop = policy.after_exit("or_observer", 1, now=20.0)
    assert not loop.restart and "crash loop" in loop.message and "after 2 restarts within 60 s" in loop.message
    assert policy.after_exit("or_observer", 1, now=70.5).restart  # the first restart has left the window


def test_clean_exits_and_invalid_parameters_are_not_restarted():
    policy = RestartPolicy()
    assert not policy.after_exit("ir_observer", 0, now=0.0).restart
    refused = policy.after_exit("ir_observer", 2, now=0.0)
    assert not refused.restart and "refused its parameters" in refused.message


def test_describe_exit():
    assert describe_exit(-9) == "killed by SIGKILL"
    assert describe_exit(1) == "exit code 1"


def test_supervise_restarts_a_crashing_node_until_the_crash_loop_ends_the_graph():
    group = ProcessGroup(echo=False)
    crasher = group.start("or_observer", [sys.executable, "-c", "import sys; print('up'); sys.exit(1)"])
    with StopSignals() as stop:
        reason = supervise(group, RestartPolicy(delay=0.05, max_restarts=2), deadline=float("inf"), stop=stop)
    group.stop()
    assert "or_observer died (exit code 1) after 2 restarts" in reason
    assert crasher.restarts == 2 and crasher.lines == ["up", "up", "up"]  # one name, every run's output


def test_supervise_returns_when_the_simulator_ends_its_scenario():
    group = ProcessGroup(echo=False)
    group.start("simulator", [sys.executable, "-c", "pass"])
    other = group.start("diagnoser", [sys.executable, "-c", "import time; time.sleep(30)"])
    with StopSignals() as stop:
        assert supervise(group, RestartPolicy(), deadline=float("inf"), stop=stop) is None
    assert other.returncode is None
    group.stop()
