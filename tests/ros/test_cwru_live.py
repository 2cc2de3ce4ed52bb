"""Real CWRU recordings streamed through the live observers and diagnoser (issue 7).

``bearing-bag from-mat`` turns a recording into the chunks a sensor driver would publish;
``bearing-bag play`` streams them in real time into fresh observer and diagnoser processes.
The live fault states must match ``bearing-diagnose`` on the same bag (the offline path).
"""

from __future__ import annotations

import json
import subprocess

import pytest
from graph_helpers import BAG_CLI, STATE_CODES, live_states, replay_into_pipeline, transitions, wait_quiet
from ros_harness import executable

from bearing_common import topics
from bearing_common.states import FaultState

pytestmark = [pytest.mark.ros, pytest.mark.slow]

SECONDS = 2.0  # of each recording: 10 decision windows of 0.2 s (hop 0.05 s) after the first
ONSET_TOL = 0.06  # s: a hop and a chunk
RECORDS = [  # file, channel, from-mat options, expected state
    ("105_IR007_0hp_DE12k.mat", "X105_DE_time", ["--sample-rate", "12000"], FaultState.INNER_RACE),
    ("130_OR007at6_0hp_DE12k.mat", "X130_DE_time", ["--sample-rate", "12000"], FaultState.OUTER_RACE),
    ("097_normal_0hp_DE48k.mat", "X097_DE_time", ["--sample-rate", "48000", "--resample", "12000"],
     FaultState.NORMAL),
]


@pytest.mark.parametrize("name, channel, options, expected", RECORDS, ids=["105-IR", "130-OR", "097-normal"])
def test_recording_through_the_live_graph_matches_offline(ros_graph, tmp_path, cwru_record, name, channel,
                                                          options, expected):
    bag = tmp_path / "bag"
    convert = subprocess.run(BAG_CLI + ["from-mat", str(cwru_record(name)), "--channel", channel, *options,
                                        "--duration", str(SECONDS), "--out", str(bag)],
                             capture_output=True, text=True, timeout=120, env=ros_graph.env)
    assert convert.returncode == 0, convert.stderr

    states = ros_graph.subscribe(topics.FAULT_STATE)
    replay_into_pipeline(ros_graph, bag)
    wait_quiet(ros_graph, states, "the live diagnosis to settle")
    live = live_states(states)
    assert live[-1][0] == expected, (live, ros_graph.output())

    run = subprocess.run([str(executable("bearing_diagnoser", "bearing-diagnose")), str(bag)],
                         capture_output=True, text=True, timeout=300, env=ros_graph.env)
    assert run.returncode == 0, run.stderr
    offline = transitions([(STATE_CODES[s["state"]], s["start"])
                           for s in map(json.loads, filter(None, run.stdout.splitlines()))])
    assert [s for s, _ in live] == [s for s, _ in offline], (live, offline, run.stderr)
    for (_, t_live), (_, t_off) in list(zip(live, offline))[1:]:
        assert abs(t_live - t_off) <= ONSET_TOL, (live, offline)
