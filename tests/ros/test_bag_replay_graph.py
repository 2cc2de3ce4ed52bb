"""Record a live OR-IR run of the whole graph, replay it into fresh observers + diagnoser,
and diagnose the bag offline: all three must tell the same story.

1. simulator (scenario or-ir) → OR/IR observers → diagnoser, recorded by ``bearing-bag record``;
2. the bag's ``vibration/drive_end`` + ``shaft_speed`` played by ``bearing-bag play`` into
   fresh observer and diagnoser processes: same fault_state sequence and onsets;
3. ``bearing-diagnose BAG_DIR``: same states in the same order, onsets close to the live ones.

Timing in the graph comes from header stamps and sample indices only, so the replay must
reproduce the live decisions exactly (up to a chunk); the offline run uses the same cores.
"""

from __future__ import annotations

import json
import subprocess

import pytest
from graph_helpers import (
    BAG_CLI,
    STATE_CODES,
    live_states,
    params_file,
    replay_into_pipeline,
    start_pipeline,
    stop,
    transitions,
    wait_quiet,
    wait_spec,
)
from ros_harness import executable

from bearing_common import topics
from bearing_common.states import FaultState

pytestmark = [pytest.mark.ros, pytest.mark.slow]

SEGMENT = 0.5  # s per scenario segment: long enough for the decision windows
ONSET_TOL_REPLAY = 0.011  # s: one 10 ms chunk
ONSET_TOL_OFFLINE = 0.05  # s


def test_live_run_replay_and_offline_agree(ros_graph, tmp_path):
    bag = tmp_path / "or_ir"
    # 1. live run, recorded
    recorder = ros_graph.start("", "", name="bag_record", argv=BAG_CLI + ["record", "--out", str(bag)])
    ros_graph.wait_until(lambda: any("recording" in line for line in recorder.lines), 30.0, "the recorder to start")
    start_pipeline(ros_graph)
    live = ros_graph.subscribe(topics.FAULT_STATE)
    sim = ros_graph.start("bearing_sim", "simulator", name="simulator", params_file=params_file(),
                          params={"scenario": "or-ir", "segment_duration": SEGMENT, "wait_for_subscribers": wait_spec(
                              {topics.VIBRATION: 3, topics.RESIDUAL_OUTER_RACE: 2, topics.RESIDUAL_INNER_RACE: 2}),
                                  "linger": 2.0})
    ros_graph.wait_until(lambda: sim.returncode is not None, 120.0, "the simulator to finish the scenario")
    assert sim.returncode == 0, ros_graph.output()
    wait_quiet(ros_graph, live, "the diagnoser to publish its last decision")
    assert stop(recorder) == 0, ros_graph.output()
    for member in ros_graph.processes.members:
        stop(member)

    from bearing_recordings.bag_read import read_bag
    contents = read_bag(bag)
    assert contents.chunks and contents.truth, "bag lacks vibration or sim/truth"
    recorded = transitions([(s.state, s.onset) for s in contents.fault_states])
    truth = transitions([(s.state, s.onset) for s in contents.truth])
    assert [s for s, _ in recorded][-1] == FaultState.INNER_RACE, (recorded, ros_graph.output())
    assert FaultState.OUTER_RACE in [s for s, _ in recorded], recorded
    assert [s for s, _ in truth][-2:] == [FaultState.OUTER_RACE, FaultState.INNER_RACE], truth

    # 2. replay into fresh observers + diagnoser
    replayed = ros_graph.subscribe(topics.FAULT_STATE)
    replay_into_pipeline(ros_graph, bag, "--rate", "1")
    wait_quiet(ros_graph, replayed, "the replayed diagnosis to settle")
    again = live_states(replayed)
    assert [s for s, _ in again] == [s for s, _ in recorded], (again, recorded, truth, ros_graph.output())
    for (_, t_live), (_, t_replay) in zip(recorded, again):
        assert abs(t_live - t_replay) <= ONSET_TOL_REPLAY, (recorded, again, truth, ros_graph.output())

    # 3. offline: bearing-diagnose BAG_DIR
    exe = executable("bearing_diagnoser", "bearing-diagnose")  # FileNotFoundError when not built
    run = subprocess.run([str(exe), str(bag)], capture_output=True, text=True, timeout=300, env=ros_graph.env)
    assert run.returncode == 0, run.stderr
    segments = [json.loads(line) for line in run.stdout.splitlines() if line.strip()]
    t0 = contents.chunks[0].stamp  # segment times are relative to the first sample
    offline = transitions([(STATE_CODES[s["state"]], s["start"] + t0) for s in segments])
    assert [s for s, _ in offline] == [s for s, _ in recorded], (offline, recorded, run.stderr)
    for (_, t_live), (_, t_off) in list(zip(recorded, offline))[1:]:
        assert abs(t_live - t_off) <= ONSET_TOL_OFFLINE, (
            f"onsets differ between the live graph and bearing-diagnose on its recording: live {recorded}, "
            f"offline {offline}, truth {truth}\n{run.stderr}")
