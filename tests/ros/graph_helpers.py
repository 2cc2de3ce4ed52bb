"""Helpers for tests that run the observers and diagnoser as processes and compare fault states."""

from __future__ import annotations

import os
import signal
import sys
import time

from bearing_common import topics

BAG_CLI = [sys.executable, "-m", "bearing_recordings.bag_cli"]
QUIET_S = 2.0  # s without a new fault_state: the diagnoser has caught up
STATE_CODES = {"normal": 0, "outer_race": 1, "inner_race": 2, "ball": 3, "unknown": 4}


def params_file():
    from bearing_bringup.graph import config_path
    return config_path()


def wait_spec(counts: dict) -> str:
    """The simulator's ``wait_for_subscribers`` value: {Topic: subscriber count} -> 'name:n,...'."""
    return ",".join(f"{topic.name}:{n}" for topic, n in counts.items())


def transitions(states) -> list:
    """[(state, onset s)] at each change of state (consecutive repeats dropped)."""
    out = []
    for s in states:
        if not out or out[-1][0] != s[0]:
            out.append(s)
    return out


def live_states(msgs) -> list:
    return transitions([(int(m.state), m.onset.sec + m.onset.nanosec * 1e-9) for m in msgs])


def wait_quiet(ros_graph, received: list, what: str, quiet: float = QUIET_S, timeout: float = 60.0):
    """Wait until ``received`` has messages and no new one arrived for ``quiet`` seconds
    (the nodes may lag behind real time on a loaded machine)."""
    state = {"n": -1, "since": time.monotonic()}

    def settled():
        if len(received) != state["n"]:
            state["n"], state["since"] = len(received), time.monotonic()
        return state["n"] > 0 and time.monotonic() - state["since"] >= quiet

    ros_graph.wait_until(settled, timeout, what)


def start_pipeline(ros_graph, suffix=""):
    """OR and IR observers plus the diagnoser, with the graph's parameters."""
    pf = params_file()
    for name in ("or_observer", "ir_observer"):
        ros_graph.start("bearing_observer", "observer", name=name, params_file=pf)
    ros_graph.start("bearing_diagnoser", "diagnoser", name="diagnoser", params_file=pf)


def stop(member, timeout=15.0):
    if member.returncode is None:
        os.killpg(member.process.pid, signal.SIGINT)
    return member.process.wait(timeout=timeout)


def replay_into_pipeline(ros_graph, bag, *play_options):
    """Start fresh observers + diagnoser, wait until the diagnoser listens, play ``bag``'s
    vibration and shaft speed into them (both observers matched first); return the player."""
    start_pipeline(ros_graph)
    ros_graph.wait_until(lambda: all(ros_graph.node.count_subscribers(t.name) >= 1
                                     for t in topics.RESIDUALS.values()),
                         60.0, "the diagnoser to be ready")
    player = ros_graph.start("", "", name="bag_play", argv=BAG_CLI + [
        "play", str(bag), "--topics", topics.VIBRATION.name, topics.SHAFT_SPEED.name, "--wait-for-subscribers", "2",
        *play_options])
    ros_graph.wait_until(lambda: player.returncode is not None, 120.0, "the replay to finish")
    assert player.returncode == 0, ros_graph.output()
    return player
