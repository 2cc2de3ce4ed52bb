"""The live graph fed 0.1 s chunks (a sensor's choice, the fleet default for external sensors):
simulator, two observers and the diagnoser as separate processes over DDS publish, window for
window, the fault states the observer and diagnoser sessions give in this process on the same
signal cut into the simulator's usual 0.01 s chunks (their residuals rounded to float32 as on
the wire): same stamps, states and onsets, confidences to float32's rounding."""

import numpy as np
import pytest
import yaml
from graph_helpers import wait_spec

from bearing_bringup.graph import GRAPH, config_path
from bearing_common import topics
from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_node_config import PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_observer.observer_session import ObserverSession

pytestmark = pytest.mark.ros

CHUNK_S = 0.1
OFFLINE_CHUNK_S = 0.01
SEGMENT_S = 0.5


def seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def offline(y: np.ndarray, rate: float, source: str, diagnoser_values: dict) -> list:
    """(stamp, state, onset, confidence) the sessions publish for ``y`` in 0.01 s chunks."""
    streams = (FaultState.OUTER_RACE, FaultState.INNER_RACE)
    observers = {h: ObserverSession(h, CATALOG["6205"], "", 1800.0) for h in streams}
    diagnoser = DiagnoserSession({p.name: p.default for p in PARAMETERS} | diagnoser_values, lambda *a: None)
    n, out = int(round(OFFLINE_CHUNK_S * rate)), []
    for i in range(0, y.size, n):
        for h, observer in observers.items():
            r = observer.on_chunk(i / rate, i, rate, source, y[i:i + n])
            arrays = [None if a is None else a.astype(np.float32) for a in (r.residual, r.estimate, r.impulse_train)]
            out += diagnoser.on_residual(h, i / rate, i, rate, *arrays, r.fault_frequency, r.model_set, 0.0)
    return [(r.stamp, int(r.state), r.onset, r.confidence) for r in out]


def test_the_graph_on_0_1_s_chunks_decides_as_on_0_01_s_chunks(ros_graph):
    states = ros_graph.subscribe(topics.FAULT_STATE)
    vib = ros_graph.subscribe(topics.VIBRATION)
    for spec in GRAPH:
        if spec.executable != "simulator":
            ros_graph.start(spec.package, spec.executable, name=spec.name, params_file=config_path())
    wait = wait_spec({topics.VIBRATION: 3, topics.RESIDUAL_OUTER_RACE: 1, topics.RESIDUAL_INNER_RACE: 1,
                      topics.FAULT_STATE: 1})
    sim = ros_graph.start("bearing_sim", "simulator", name="simulator", params_file=config_path(),
                          params={"scenario": "or-ir", "segment_duration": SEGMENT_S, "chunk_duration": CHUNK_S,
                                  "noise_density": 4.5e-3, "wait_for_subscribers": wait})
    ros_graph.wait_until(lambda: sim.returncode is not None, timeout=180.0, what="the scenario to end")
    assert sim.returncode == 0, ros_graph.output()
    assert {len(m.samples) for m in vib} == {int(CHUNK_S * 48000)}, ros_graph.output()
    end = max(seconds(m.header.stamp) + len(m.samples) / m.sample_rate for m in vib)
    ros_graph.wait_until(lambda: states and seconds(states[-1].header.stamp) >= end - 0.011, timeout=30.0,
                         what="the diagnoser to decide the last window")
    chunks = sorted(vib, key=lambda m: m.first_sample_index)
    y = np.concatenate([np.asarray(m.samples) for m in chunks])
    assert chunks[0].first_sample_index == 0 and y.size == chunks[-1].first_sample_index + len(chunks[-1].samples)
    base = yaml.safe_load(config_path().read_text())["diagnoser"]["ros__parameters"]
    expected = offline(y, chunks[0].sample_rate, chunks[0].source, base)
    live = [(seconds(m.header.stamp), int(m.state), seconds(m.onset), m.confidence) for m in states]
    assert {FaultState.OUTER_RACE, FaultState.INNER_RACE} <= {s for _, s, _, _ in expected}
    assert len(live) == len(expected), (len(live), len(expected), ros_graph.output())
    for (t, s, onset, conf), (t_ref, s_ref, onset_ref, conf_ref) in zip(live, expected):
        assert (s, onset) == (s_ref, pytest.approx(onset_ref, abs=1e-9)) and t == pytest.approx(t_ref, abs=1e-9)
        assert conf == pytest.approx(conf_ref, abs=1e-5)
