"""The graph decides the same whatever the sensor's chunk: observer and diagnoser sessions fed
chunks of 0.01 to 1 s (and of a length that divides nothing) publish the same fault states
(stamps, states, onsets, confidences and every score, bit for bit), because the decision's
schedule follows sample indices, not chunks; float32 residuals (Residual.msg) keep every state;
an offline run's 10 s chunks decide as the simulator's 0.01 s ones.
"""

import numpy as np
import pytest

from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState, parse_fault
from bearing_diagnoser.diagnoser_node_config import PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.pipeline import MonitorPipeline
from bearing_diagnoser.recording_diagnosis import OFFLINE_CHUNK_S, run_pipeline
from bearing_observer.observer_session import ObserverSession
from bearing_sim.simulator import SimulationConfig, simulate

CHUNKS = (0.01, 0.1, 1.0, 0.0123)  #: s; 0.0123 s divides neither the windows nor the hops
STREAMS = (FaultState.OUTER_RACE, FaultState.INNER_RACE)


def measurement(rate: float, schedule) -> np.ndarray:
    config = SimulationConfig(rpm=1800.0, sample_rate=rate, noise_density=4.5e-3, seed=1)
    return simulate(config, [(parse_fault(f), s) for f, s in schedule])["accel"]


def decisions(y, rate, chunk, source, wire=lambda a: a) -> list:
    """What the diagnoser session publishes for ``y`` cut into ``chunk``-s chunks, each observer's
    residual chunk passed as the message carries it (``wire``: the arrays' element type)."""
    observers = {h: ObserverSession(h, CATALOG["6205"], "", 1800.0) for h in STREAMS}
    diagnoser = DiagnoserSession({p.name: p.default for p in PARAMETERS} | {"rpm": 1800.0}, lambda *a: None)
    n = int(round(chunk * rate))
    out = []
    for i in range(0, y.size, n):
        for h, observer in observers.items():
            r = observer.on_chunk(i / rate, i, rate, source, y[i:i + n])
            arrays = [None if a is None else wire(a) for a in (r.residual, r.estimate, r.impulse_train)]
            out += diagnoser.on_residual(h, i / rate, i, rate, *arrays, r.fault_frequency, r.model_set, 0.0)
    return out


def summary(reports) -> list:
    return [(r.stamp, r.state, r.onset, r.confidence, r.scores, r.model_set) for r in reports]


@pytest.fixture(scope="module")
def fold_case():
    """The simulator's model set at 48 kHz (folding decision, a state every 0.01 s): OR then IR."""
    return measurement(48000.0, [("outer_race", 0.4), ("inner_race", 0.4)]), 48000.0, "simulator"


@pytest.fixture(scope="module")
def spectral_case():
    """A real machine's sensor at 12 kHz (model set none, spectral decision): normal, then OR,
    with the shaft's 1x line and harmonics (30 Hz; the decision measures the speed from them:
    the nameplate's 1800 rpm ± 10 % alone is not diagnosed on)."""
    rate = 12000.0
    y = measurement(rate, [("normal", 2.0), ("outer_race", 2.0)])
    t = np.arange(y.size) / rate
    return y + sum(0.1 / k * np.sin(2 * np.pi * 30.0 * k * t + k) for k in range(1, 6)), rate, "accelerometer"


@pytest.mark.parametrize("case", ["fold_case", "spectral_case"])
def test_every_chunk_size_gives_the_same_decisions(case, request):
    y, rate, source = request.getfixturevalue(case)
    reference = decisions(y, rate, CHUNKS[0], source)
    states = [r.state for r in reference if r.changed]
    assert FaultState.OUTER_RACE in states and len(states) >= 2, states
    for chunk in CHUNKS[1:]:
        assert summary(decisions(y, rate, chunk, source)) == summary(reference), f"{chunk} s chunks"


@pytest.mark.parametrize("case", ["fold_case", "spectral_case"])
def test_float32_residuals_keep_every_state_onset_and_window(case, request):
    """Residual.msg's float32 arrays against float64: the same windows, states and onsets;
    confidences and scores differ by float32's rounding only (measured: confidences by at most
    1e-8, scores by at most 2e-4 relative, and by 1.3e-3 relative on posteriors near 1e-173)."""
    y, rate, source = request.getfixturevalue(case)
    f64 = decisions(y, rate, 0.1, source)
    f32 = decisions(y, rate, 0.1, source, wire=lambda a: a.astype(np.float32))
    assert [(r.stamp, r.state, r.onset) for r in f32] == [(r.stamp, r.state, r.onset) for r in f64]
    for a, b in zip(f32, f64):
        assert a.confidence == pytest.approx(b.confidence, abs=1e-5)
        scores_a, scores_b = a.scores.as_dict(), b.scores.as_dict()
        assert scores_a.keys() == scores_b.keys()
        for k in scores_b:
            assert scores_a[k] == pytest.approx(scores_b[k], rel=1e-3, abs=1e-4), k


def test_the_offline_chunk_decides_every_stream_together_as_live():
    """bearing-diagnose's offline chunk (10 s) against the simulator's 0.01 s, on 2.5 s of an inner-race
    fault (folding decision, 48 kHz): the same decisions, every one INNER_RACE once published. Before,
    the pipeline handed a chunk to the decision stream after stream: the outer-race stream ran 2.5 s
    ahead, beyond the folding decision's 1 s lag, so it decided without the inner-race stream and
    published OUTER_RACE until 1.5 s."""
    rate = 48000.0
    y = measurement(rate, [("inner_race", 2.5)])

    def run(chunk_s):
        pipeline = MonitorPipeline(CATALOG["6205"], "sim_48k", config_for("sim_48k"), 1800.0)
        return [(d.window_start, d.window_end, d.label, d.state, d.confidence, d.detail)
                for d in run_pipeline(pipeline, y, rate, "simulator", chunk_s)]

    live = run(0.01)
    assert {state for *_, state, _, _ in live} == {FaultState.INNER_RACE}, live[:5]
    assert run(OFFLINE_CHUNK_S) == live
