"""Many node stops under load, counted (``make stop-repeats``; skipped unless BEARING_STOP_REPEATS is set).

Each round starts OBSERVERS observer processes beside one simulator, pins them, once their output
flows, to one core beside two busy processes, and sends SIGINT to all of them at once. A stop is
clean when the process exits 0 within the stall watchdog (``node_main.STOP_STALL_S``); one that
reached the teardown's bound (``node_main.TEARDOWN_END_S``: rmw's deletion of the DDS participant
inside ``destroy_node`` still running) ends with exit 0 and its one line, and is counted apart. A
process still running ROUND_DUMP_S after the signal has its native stacks printed (py-spy). The
rounds, the stops, the bounded ones and the slowest stop are printed (``-s``).
"""

from __future__ import annotations

import os
import signal
import time

import pytest
from cpu_load import busy_core, native_stacks, one_core, pin
from graph_helpers import params_file
from ros_harness import executable, ros_args
from test_signals import assert_clean_exit

from bearing_common import topics
from bearing_common.node_main import STOP_STALL_S

pytestmark = pytest.mark.ros

ROUNDS = int(os.environ.get("BEARING_STOP_REPEATS", "0"))
OBSERVERS = 3  #: stopped together each round
BUSY_LOOPS = 2
CHUNKS = 20  #: residuals per observer before its stop
ROUND_DUMP_S = 2.0  #: s after the signal: native stacks of whatever still runs
BOUNDED = "s after the stop: ended without it"  # the teardown bound's line (node_main.tear_down)


@pytest.mark.skipif(ROUNDS <= 0, reason="make stop-repeats (BEARING_STOP_REPEATS rounds)")
def test_repeated_stops_under_load_all_end_cleanly(ros_graph):
    residuals = ros_graph.subscribe(topics.RESIDUAL_OUTER_RACE)
    simulator = ros_graph.start("bearing_sim", "simulator", name="simulator", params_file=params_file(),
                                params={"scenario": "", "wait_for_subscribers": ""})
    ros_graph.wait_until(lambda: any("simulator ready" in line for line in simulator.lines), 300.0, "the simulator")
    core, stops, bounded, slowest = one_core(), 0, 0, 0.0
    with busy_core(core, BUSY_LOOPS):
        for round_ in range(ROUNDS):
            seen = len(residuals)
            members = [ros_graph.start("", "", name=f"observer_{round_}_{k}", argv=[
                str(executable("bearing_observer", "observer"))]
                + ros_args(f"or_observer_{k}", {"fault_type": "outer_race", "model_set": ""}))
                for k in range(OBSERVERS)]
            ros_graph.wait_until(lambda seen=seen: len(residuals) >= seen + CHUNKS * OBSERVERS, 180.0,
                                 "the observers' residuals")
            for member in members:
                pin(member.process.pid, core)
            time.sleep(0.5)
            sent = time.monotonic()
            for member in members:
                os.kill(member.process.pid, signal.SIGINT)
            while any(m.returncode is None for m in members) and time.monotonic() - sent < ROUND_DUMP_S:
                time.sleep(0.01)
            late = [m.process.pid for m in members if m.returncode is None]
            if late:
                print(f"\nround {round_}: still running {ROUND_DUMP_S} s after SIGINT\n{native_stacks(late)}")
            for member in members:
                assert_clean_exit(member)  # exit 0, no traceback (the watchdog's dump exits 1)
                took = time.monotonic() - sent
                stops += 1
                bounded += any(BOUNDED in line for line in member.lines)
            slowest = max(slowest, took)
            print(f"round {round_ + 1}/{ROUNDS}: {OBSERVERS} stops clean, the last exit {took:.2f} s after SIGINT",
                  flush=True)
            assert slowest < STOP_STALL_S
    print(f"\n{ROUNDS} rounds, {stops} stops under load: all clean, {bounded} ended by the teardown's bound; "
          f"slowest round {slowest:.2f} s from SIGINT to the last exit")
