"""A window not diagnosed is one outcome with one reason, from either front end to every output; a readable
recording always gets a verdict.

* :class:`~bearing_diagnoser.decision.not_diagnosed.NotDiagnosed`: kinds, its text and JSON, the reason that
  stands for a run;
* unusable sensor signals (constant, all-zero, clipped, 1-bit, few-level, NaN/inf-laden; random levels and
  gains, property-based) through the fold front end (the simulator's model sets) and the envelope-spectrum
  one: every window "not diagnosed: sensor", labelled UNKNOWN with confidence 0, never a state change, never
  an exception;
* the node's session: /diagnostics says "not diagnosed: <kind>: <reason>";
* ``bearing-diagnose`` on such a .npz (a real machine's and the simulator's) and .mat: exit 0 and one segment
  ``unknown``, confidence 0, with ``not_diagnosed``; a speed never confirmed likewise; exit 2 stays for what
  cannot be read or analysed (non-finite samples, a record shorter than a window);
* a .npz is a real machine's recording unless its ``source`` says ``simulator``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.io import savemat

from bearing_common.bearings import CATALOG, fault_frequency
from bearing_common.states import FaultState
from bearing_diagnoser.decision.not_diagnosed import KINDS, NotDiagnosed, prevailing
from bearing_diagnoser.diagnose_cli import main
from bearing_diagnoser.diagnoser import Diagnoser
from bearing_diagnoser.diagnoser_node_config import LEVEL_WARN, PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_recordings.load import load_recording
from bearing_recordings.recording import InputError

FS = 12000.0
RPM = 1797.0
O, I = FaultState.OUTER_RACE, FaultState.INNER_RACE
BEARING = CATALOG["6205"]


def test_one_kind_and_one_line_of_reason():
    nd = NotDiagnosed("speed", "shaft speed not confirmed")
    assert str(nd) == "speed: shaft speed not confirmed"
    assert nd.to_json() == {"kind": "speed", "reason": "shaft speed not confirmed"}
    assert KINDS == ("sensor", "speed", "resolution")
    with pytest.raises(ValueError, match="unknown kind 'sensors'"):
        NotDiagnosed("sensors", "flat")
    with pytest.raises(ValueError, match="one line"):
        NotDiagnosed("sensor", "flat\nsignal")


def test_the_prevailing_reason_is_the_most_frequent_kind_with_its_first_reason():
    a, b, c = NotDiagnosed("speed", "first"), NotDiagnosed("sensor", "flat"), NotDiagnosed("speed", "second")
    assert prevailing([None, a, b, None, c]) is a
    assert prevailing([b, a]) is b  # a tie: sensor before speed
    assert prevailing([None, None]) is None and prevailing([]) is None


# ---------------------------------------------------------------------------------------
# unusable sensor signals through both front ends

def _healthy(n: int, seed: int) -> np.ndarray:
    return white_noise(n / FS, FS, 4.5e-3, np.random.default_rng(seed))


def unusable(kind: str, n: int, level: float, gain: float, step: int, seed: int) -> np.ndarray:
    """A sensor signal no window of which may be diagnosed (``level``: an offset, ``gain`` a scale,
    ``step``: every how many samples a poisoned one sits)."""
    x = gain * _healthy(n, seed) / 4.5e-3 / np.sqrt(FS / 2)  # unit standard deviation, times gain
    if kind == "constant":
        return np.full(n, level)
    if kind == "zero":
        return np.zeros(n)
    if kind == "clipped":  # at ±(0.2 .. 2) standard deviations: ≥ 4.5 % of the samples at the rails
        c = gain * (0.2 + 1.8 * (step % 10) / 9)
        return level + np.clip(x, -c, c)
    if kind == "one_bit":
        return level + gain * np.sign(x)
    if kind == "few_levels":  # 3..15 levels of a coarse ADC
        levels = 3 + step % 13
        return level + gain * np.round(np.clip(x / gain, -2, 2) * (levels - 1) / 4)
    if kind in ("nan", "inf"):
        x[seed % step::step] = np.nan if kind == "nan" else np.inf * (-1) ** seed
        return x
    raise ValueError(kind)


KINDS_OF_SIGNAL = ("constant", "zero", "clipped", "one_bit", "few_levels", "nan", "inf")


def decide(model_set: str, y: np.ndarray) -> list:
    """Every window decision of ``model_set``'s front end on ``y`` fed as both observers' streams."""
    dg = Diagnoser(config_for(model_set), model_set, BEARING, FS)
    dg.tell_speed(RPM, 0.02)
    out = []
    for i in range(0, y.size, 600):
        for h in (O, I):
            out += dg.update(h, i, FS, y[i:i + 600], None, None, fault_frequency(BEARING, h, RPM))
    return out + dg.flush()


@pytest.mark.parametrize("model_set", ["sim_12k", "none"], ids=["fold", "spectral"])
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kind=st.sampled_from(KINDS_OF_SIGNAL), level=st.floats(-1e3, 1e3), gain=st.floats(1e-3, 1e3),
       step=st.integers(1, 200), seed=st.integers(0, 2**16))
def test_an_unusable_sensor_signal_is_never_diagnosed(model_set, kind, level, gain, step, seed):
    out = decide(model_set, unusable(kind, int(1.5 * FS), level, gain, step, seed))
    assert out, "no window decided"
    for d in out:
        assert d.not_diagnosed is not None and d.not_diagnosed.kind == "sensor", (kind, d.label, d.not_diagnosed)
        assert d.label == FaultState.UNKNOWN and not d.changed and not d.diagnosed


@pytest.mark.parametrize("model_set", ["sim_12k", "none"], ids=["fold", "spectral"])
def test_the_sensor_check_passes_healthy_and_faulty_vibration(model_set):
    y = _healthy(int(1.5 * FS), 0)
    assert all(d.diagnosed and d.label == FaultState.NORMAL for d in decide(model_set, y))
    y = y + burst_train(1.5, FS, fault_frequency(BEARING, O, RPM), amplitude=10.0, resonance_hz=3000.0)
    out = decide(model_set, y)
    assert all(d.diagnosed for d in out) and out[-1].state == FaultState.OUTER_RACE


@pytest.mark.parametrize("model_set", ["sim_12k", ""], ids=["fold", "spectral"])
def test_diagnostics_say_why_a_window_is_not_diagnosed(model_set):
    v = {p.name: p.default for p in PARAMETERS} | {"rpm": RPM, "rpm_tolerance": 0.02, "model_set": model_set}
    s = DiagnoserSession(v, lambda *a: None)
    y = np.zeros(int(1.0 * FS))
    for i in range(0, y.size, 600):
        for h in (O, I):
            assert s.on_residual(h, i / FS, i, FS, y[i:i + 600], None, None, fault_frequency(BEARING, h, RPM),
                                 model_set or "none", now=i / FS) == []  # nothing published
    health = s.health(1.0)
    assert health.level == LEVEL_WARN and health.message.startswith("not diagnosed: sensor: flat signal")
    assert health.values["not diagnosed"] == "sensor"


# ---------------------------------------------------------------------------------------
# bearing-diagnose: a verdict for every readable recording

def run(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, [json.loads(x) for x in out.splitlines() if x.strip()], err


def write(path, x: np.ndarray, form: str):
    """``x`` (m/s² at 12 kHz, 1797 rpm) as a real machine's .npz, a bearing-sim .npz or a one-signal .mat (g)."""
    if form == "mat":
        savemat(path.with_suffix(".mat"), {"signal": x[:, None] / 9.80665})
        return path.with_suffix(".mat")
    extra = {"source": "simulator", "truth": np.zeros(x.size, int)} if form == "simulator" else {}
    np.savez(path.with_suffix(".npz"), accel=x, sample_rate=FS, rpm=RPM, **extra)
    return path.with_suffix(".npz")


@pytest.mark.parametrize("form", ["npz", "simulator", "mat"])
@pytest.mark.parametrize("kind", ["constant", "zero", "clipped", "one_bit", "few_levels"])
def test_a_dead_sensors_recording_is_not_diagnosed_sensor_with_exit_0(tmp_path, capsys, form, kind):
    path = write(tmp_path / kind, unusable(kind, int(1.0 * FS), 0.37, 2.0, 5, 1), form)
    code, lines, err = run([path, "--sample-rate", FS, "--rpm", RPM], capsys)
    assert code == 0, err
    assert len(lines) == 1, lines
    (seg,) = lines
    assert seg["state"] == "unknown" and seg["confidence"] == 0.0 and seg["model_set"] == (
        "sim_12k" if form == "simulator" else "none")
    assert seg["start"] == 0.0 and seg["end"] == pytest.approx(1.0)
    assert seg["not_diagnosed"]["kind"] == "sensor" and seg["not_diagnosed"]["reason"]
    assert "windows not diagnosed" in err and "error" not in err


@pytest.mark.parametrize("form", ["npz", "simulator", "mat"])
@pytest.mark.parametrize("poison", [np.nan, np.inf])
def test_non_finite_samples_cannot_be_read(tmp_path, capsys, form, poison):
    x = _healthy(int(1.0 * FS), 0)
    x[::97] = poison
    code, lines, err = run([write(tmp_path / "poisoned", x, form), "--sample-rate", FS, "--rpm", RPM], capsys)
    assert code == 2 and lines == []
    errors = [e for e in err.splitlines() if "error:" in e]
    assert len(errors) == 1 and "non-finite samples" in errors[0], err


def test_a_speed_never_confirmed_is_tested_over_its_tolerance_not_refused(tmp_path, capsys):
    """Noise has no 1x line: a nameplate speed (±10 %) is never confirmed; the windows are diagnosed over
    that whole range, paid for (it ended with exit 2, then with every window "not diagnosed: speed")."""
    path = write(tmp_path / "noise", _healthy(int(2.0 * FS), 3), "mat")
    code, lines, err = run([path, "--sample-rate", FS, "--rpm", RPM], capsys)
    assert code == 0, err
    assert [x["state"] for x in lines] == ["normal"] and "not_diagnosed" not in lines[0]
    assert "shaft speed not confirmed: told 1797 rpm ± 10 %" in err


def test_a_diagnosed_recording_carries_no_not_diagnosed_field(tmp_path, capsys):
    y = _healthy(int(1.0 * FS), 0) + burst_train(1.0, FS, fault_frequency(BEARING, O, RPM), amplitude=10.0,
                                                  resonance_hz=3000.0)
    code, lines, err = run([write(tmp_path / "or", y, "npz")], capsys)
    assert code == 0, err
    assert [x["state"] for x in lines] == ["outer_race"] and "not_diagnosed" not in lines[0]


# ---------------------------------------------------------------------------------------
# a .npz is a real machine's recording unless it says it came from the simulator

def test_npz_source_decides_simulator_or_real_machine(tmp_path, caplog):
    x = _healthy(int(0.5 * FS), 0)
    sim = {"t": np.arange(x.size) / FS, "unbalance": np.zeros(x.size), "truth": np.zeros(x.size, int)}
    np.savez(tmp_path / "sim.npz", accel=x, sample_rate=FS, source="simulator", **sim)
    np.savez(tmp_path / "old_sim.npz", accel=x, sample_rate=FS, **sim)  # bearing-sim before it wrote source
    np.savez(tmp_path / "real.npz", accel=x, sample_rate=FS, truth=np.zeros(x.size, int))  # a labelled rig
    np.savez(tmp_path / "rig.npz", accel=x, sample_rate=FS, source=np.bytes_("cwru"))
    np.savez(tmp_path / "bad.npz", accel=x, sample_rate=FS, source=np.arange(3))
    assert load_recording(tmp_path / "sim.npz").source == "simulator"
    old = load_recording(tmp_path / "old_sim.npz")
    assert old.source == "npz" and "--model-set sim_48k" in old.notes[0]
    real = load_recording(tmp_path / "real.npz")
    assert real.source == "npz" and real.truth is not None and not real.notes
    assert load_recording(tmp_path / "rig.npz").source == "cwru"
    with pytest.raises(InputError, match="source must be one text"):
        load_recording(tmp_path / "bad.npz")


@pytest.mark.parametrize("source, model_set", [({"source": "simulator"}, "sim_12k"), ({}, "none")])
def test_the_model_set_follows_the_npz_source(tmp_path, capsys, source, model_set):
    np.savez(tmp_path / "x.npz", accel=_healthy(int(1.0 * FS), 0), sample_rate=FS, rpm=RPM, **source)
    code, lines, err = run([tmp_path / "x.npz"], capsys)
    assert code == 0, err
    assert {x["model_set"] for x in lines} == {model_set} and f"model set {model_set}" in err
