"""The observer node's session logic without ROS: set choice, rebuilds, speed, resync, rejections, parameters."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_observer.impulse_trains import impulse_train
from bearing_observer.model_sets import load_model_set
from bearing_observer.observer import FaultObserver, ObserverOutput
from bearing_observer.observer_node_config import PARAMETERS
from bearing_observer.observer_session import ObserverSession

FS = 48000.0
N = 480
OR = FaultState.OUTER_RACE


def signal(n_chunks, fs=FS):
    m = load_model_set("sim_48k", FS)["outer_race"]
    u = impulse_train(n_chunks * N, fs, m.fault_frequency, phase=0.5)
    return m.simulate(u) + np.random.default_rng(2).normal(0.0, 0.3, u.size)


class Session(ObserverSession):
    """A session that keeps its log lines and feeds numbered chunks."""

    def __init__(self, **kwargs):
        self.lines = []
        kwargs.setdefault("bearing", CATALOG["6205"])
        kwargs.setdefault("log_period", 0.0)
        super().__init__(OR, log=lambda level, text: self.lines.append((level, text)), **kwargs)

    def feed(self, i, samples, fs=FS, source="simulator", first=None):
        first = i * N if first is None else first
        return self.on_chunk(first / fs, first, fs, source, samples)


def test_outputs_equal_the_offline_observer_and_the_set_follows_source_and_rate():
    y = signal(12)
    s = Session()
    outs = [s.feed(i, y[i * N:(i + 1) * N]) for i in range(10)]
    ref = FaultObserver.from_model_set("sim_48k", "outer_race", 1800.0, FS).process(y[:10 * N])
    assert_allclose(np.concatenate([o.residual for o in outs]), ref.residual, rtol=0, atol=0)
    assert {o.model_set for o in outs} == {"sim_48k"}
    assert outs[0].fault_frequency == pytest.approx(load_model_set("sim_48k")["outer_race"].fault_order * 30.0)
    # a source and rate without a shipped set: none, the measurement passed through, no estimate, no train
    out = s.feed(0, y[:N], fs=25600.0, source="my_sensor")
    assert out.model_set == "none" and np.array_equal(out.residual, y[:N])
    assert out.estimate is None and out.impulse_train is None
    assert out.fault_frequency == pytest.approx(CATALOG["6205"].frequencies(1800.0).bpfo)
    assert s.feed(0, y[:N], source="cwru", fs=12000.0).model_set == "cwru_de_6205"
    assert [t for lv, t in s.lines if t.startswith("model set")] == [
        "model set sim_48k at 48000 Hz for SKF 6205-2RS JEM (CWRU drive end), 1800.0 rpm: fault frequency 107.543 Hz",
        "model set none at 25600 Hz for SKF 6205-2RS JEM (CWRU drive end), 1800.0 rpm: fault frequency 107.543 Hz",
        "model set cwru_de_6205 at 12000 Hz for SKF 6205-2RS JEM (CWRU drive end), 1800.0 rpm: "
        "fault frequency 107.881 Hz",  # measured at 1796 rpm on record 130, slip included
    ]


def test_bad_chunks_are_rejected_and_counted_and_a_gap_resyncs():
    y = signal(12)
    s = Session()
    for i in range(3):
        s.feed(i, y[i * N:(i + 1) * N])
    bad = y[3 * N:4 * N].copy()
    bad[7] = np.nan
    assert s.feed(3, bad) is None
    assert s.feed(2, y[2 * N:3 * N]) is None  # stamp goes back
    assert s.counts["rejected"] == 2 and s.counts["accepted"] == 3
    # after the rejected chunk the stream restarts: state reset, the same as a fresh observer
    after = np.concatenate([s.feed(i, y[i * N:(i + 1) * N]).residual for i in range(5, 9)])
    fresh = FaultObserver.from_model_set("sim_48k", "outer_race", 1800.0, FS).process(y[5 * N:9 * N]).residual
    assert_allclose(after, fresh, rtol=0, atol=0)
    assert any("non-finite samples: 1 NaN/inf of 480" in t for _, t in s.lines)
    assert any("out-of-order stamp" in t for _, t in s.lines)
    # repeatable messages at most once per log_period
    quiet = Session(log_period=60.0)
    for _ in range(3):
        quiet.feed(0, np.zeros(0))
        quiet.on_speed(-1.0)
    assert [lv for lv, t in quiet.lines if "rejected" in t or "ignoring" in t] == ["warning", "warning"]
    assert quiet.counts["rejected"] == 3 and quiet.counts["bad shaft speed"] == 3


def test_non_finite_output_is_dropped_and_resets(monkeypatch):
    s = Session()
    s.feed(0, np.zeros(N))
    nan = np.full(N, np.nan)
    monkeypatch.setattr(s.observer, "process", lambda y: ObserverOutput(nan, nan, nan, nan))
    assert s.feed(1, np.zeros(N)) is None
    assert s.counts["non-finite output"] == 1 and ("error", "observer produced non-finite values; state reset, "
                                                   "chunk dropped") in s.lines


def test_speed_messages_beyond_the_tolerance_retune_the_train():
    s = Session(speed_tolerance=0.01)
    s.feed(0, np.zeros(N))
    f0 = s.observer.fault_frequency
    s.on_speed(2 * math.pi * 1810.0 / 60.0)  # 0.56 %: ignored
    assert s.rpm == 1800.0 and s.observer.fault_frequency == f0
    s.on_speed(2 * math.pi * 1900.0 / 60.0)
    assert s.rpm == pytest.approx(1900.0) and s.observer.fault_frequency == pytest.approx(f0 * 1900.0 / 1800.0)
    s.on_speed(float("nan"))
    s.on_speed(-1.0)
    assert s.counts["bad shaft speed"] == 2 and s.rpm == pytest.approx(1900.0)
    s.configure({"rpm": 900.0})  # the rpm parameter sets the speed at once
    assert s.observer.fault_frequency == pytest.approx(f0 / 2)


def test_a_speed_beyond_the_identified_one_is_said_once_the_train_follows_it():
    s = Session(speed_tolerance=0.001)
    s.feed(0, np.zeros(N))
    identified = s.observer.model.rpm
    s.on_speed(2 * math.pi * identified * 1.015 / 60.0)  # within 2 %: the model holds
    assert s.model_speed_note() == "" and not [t for level, t in s.lines if level == "warning"]
    s.on_speed(2 * math.pi * identified * 1.2 / 60.0)
    warned = [t for level, t in s.lines if level == "warning"]
    assert len(warned) == 1 and f"identified at {identified:.0f} rpm" in warned[0] and s.model_speed_note() == warned[0]
    assert s.observer.fault_frequency == pytest.approx(s.observer.model.fault_frequency * 1.2, rel=1e-6)


def test_bearing_and_model_set_changes_rebuild_at_the_next_chunk():
    y = signal(4)
    s = Session()
    s.feed(0, y[:N])
    s.configure({"bearing": "6203"})
    assert s.observer.fault_frequency == pytest.approx(107.543, abs=1e-3)  # not before the next chunk
    out = s.feed(1, y[N:2 * N])
    bpfo_6203 = CATALOG["6203"].frequencies(1800.0).bpfo
    assert out.model_set == "none" and out.fault_frequency == pytest.approx(bpfo_6203)  # no sim set for a 6203
    s.configure({"model_set": "sim_48k"})  # asked for explicitly: runs, and says it is another bearing's
    out = s.feed(2, y[2 * N:3 * N])
    assert out.model_set == "sim_48k" and out.fault_frequency == pytest.approx(bpfo_6203)
    assert any(lv == "warning" and "identified for SKF 6205" in t and "not SKF 6203" in t for lv, t in s.lines)
    s.configure({"model_set": "sim_12k"})  # a set for another rate: nothing published, said why
    assert s.feed(3, y[3 * N:]) is None and s.counts["no model"] == 1
    assert any("cannot observe 48000 Hz 'simulator' data" in t and "12000 Hz" in t for _, t in s.lines)


def test_parameters_live_or_read_only_and_checked(tmp_path):
    specs = {p.name: p for p in PARAMETERS}
    assert not specs["fault_type"].dynamic
    assert all(specs[n].dynamic for n in ("bearing", "model_set", "rpm", "speed_tolerance"))
    assert specs["bearing"].default == "6205" and specs["bearing"].validate("mfpt") is None
    assert "unknown bearing 'nope'" in specs["bearing"].validate("nope")
    for ok in ("", "none", "sim_48k", "cwru_de_6205"):
        assert specs["model_set"].validate(ok) is None
    assert "unknown model set 'nope'" in specs["model_set"].validate("nope")
    assert "no directory" in specs["model_set"].validate(str(tmp_path / "missing"))
