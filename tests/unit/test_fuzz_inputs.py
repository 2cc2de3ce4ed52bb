"""Bad input tried systematically (property-based, hypothesis): message callbacks and file loaders.

* the diagnoser's residual callback (:class:`bearing_diagnoser.diagnoser_session.DiagnoserSession`, what the
  node calls for every message) with chunks of random size (empty to huge), NaN/inf samples,
  zero/negative/absurd sample rates, stamps backwards and far in the future, unknown model sets
  and arrays of unequal length: nothing raises, nothing non-finite is published, every
  rejection is counted and logged, and good input is served afterwards;
* the observer's vibration callback (:class:`bearing_observer.observer_session.ObserverSession`)
  with the same kinds of chunks and unknown sources: nothing raises, nothing non-finite is
  returned, every refusal is counted and logged, good input is observed afterwards;
* the shaft-speed callbacks of both with any float;
* the fleet node's fault_state callback (:class:`bearing_fleet.fleet_table.FleetTable`) with
  any state byte, confidence and times: unknown states and non-finite values are refused;
* every file loader with random bytes and with valid files cut short: .mat, .npz, rosbag2
  (MCAP), model files (JSON) and bearing files (YAML) — a one-line InputError (or the
  loader's own error type), never another exception.

The number of cases each property ran is in its ``max_examples`` (summed in docs/robustness.md).
"""

from __future__ import annotations

import io
import json
import math
import os

import numpy as np
import pytest
from bearing_fleet.fleet_table import FleetTable
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bearing_common.bearings import CATALOG, BearingError, load_bearing
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_node_config import PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_observer.observer_session import ObserverSession
from bearing_recordings.load import load_recording
from bearing_recordings.recording import InputError

FS = 12000.0
O, I = FaultState.OUTER_RACE, FaultState.INNER_RACE
#: Cases per property (``BEARING_FUZZ_CASES`` raises it for a long search: ``make fuzz``).
CASES = int(os.environ.get("BEARING_FUZZ_CASES", "300"))

floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
rates = st.one_of(st.sampled_from([0.0, -12000.0, math.nan, math.inf, 1e-9, 1e12, 12000.0, 48000.0]), floats)


def new_session():
    logged = []
    values = {p.name: p.default for p in PARAMETERS} | {"rpm": 1797.0, "rpm_tolerance": 0.02}
    return DiagnoserSession(values, lambda level, text: logged.append((level, text))), logged


#: Good input after the fuzzing: an outer-race fault the session must still diagnose.
GOOD = burst_train(1.5, FS, 106.5, amplitude=3.0, jitter=0.01) + white_noise(1.5, FS, 4.5e-3)

stamps = st.one_of(st.floats(-1e3, 1e12), st.sampled_from([0.0, 1e15, -5.0]))
indices = st.one_of(st.integers(0, 10**7), st.sampled_from([0, 2**62]))
sizes = st.one_of(st.integers(0, 2000), st.sampled_from([0, 1, 2_000_001]))
poisons = st.sampled_from([None, math.nan, math.inf, -math.inf])

chunk = st.fixed_dictionaries({
    "hypothesis": st.sampled_from([O, I]),
    "stamp": stamps,
    "first_index": indices,
    "rate": rates,
    "n": sizes,
    "poison": poisons,
    "ragged": st.booleans(),
    "model_set": st.sampled_from(["", "none", "sim_48k", "cwru_de_6205", "no-such-set", "x" * 300]),
    "fault_hz": floats,
})


def _arrays(c, rng):
    n = c["n"]
    r = rng.standard_normal(n) if n < 100_000 else np.zeros(n)
    if c["poison"] is not None and n:
        r[rng.integers(n)] = c["poison"]
    e = np.zeros(n + (1 if c["ragged"] else 0))
    return r, e, np.zeros(n)


@settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(chunk, min_size=1, max_size=8))
def test_residual_callback_survives_anything_and_keeps_serving(chunks):
    session, logged = new_session()
    rng = np.random.default_rng(0)
    for c in chunks:
        r, e, u = _arrays(c, rng)
        reports = session.on_residual(c["hypothesis"], c["stamp"], c["first_index"], c["rate"], r, e, u,
                                      c["fault_hz"], c["model_set"], now=0.0)
        for rep in reports:
            assert math.isfinite(rep.confidence) and math.isfinite(rep.stamp) and math.isfinite(rep.onset)
    rejected = sum(s.counts["rejected"] + s.counts["rejected by decision"] for s in session.streams.values())
    assert (rejected > 0) == any(level == "warning" for level, _ in logged)  # each kind said (once per period)
    health = session.health(now=0.0)
    assert 0 <= health.level <= 3 and health.message
    # good input afterwards: a fresh stream (index 0, later stamp) is decided on
    stamp0 = 2e12
    out = []
    for i in range(0, GOOD.size, 1200):
        for h in (O, I):
            y = GOOD[i:i + 1200]
            out += session.on_residual(h, stamp0 + i / FS, i, FS, y, np.zeros(y.size), np.zeros(y.size), 107.0,
                                       "none", now=1.0)
    assert out and out[-1].state == FaultState.OUTER_RACE, (session.health(1.0).message, out[-1:] if out else None)


@settings(max_examples=CASES, deadline=None)
@given(floats)
def test_shaft_speed_callback_takes_any_float(rad_s):
    session, _ = new_session()
    session.on_speed(rad_s)
    assert session.shaft_rpm is None or (math.isfinite(session.shaft_rpm) and session.shaft_rpm > 0)
    observer = ObserverSession(O, CATALOG["6205"], rpm=1797.0)
    observer.on_speed(rad_s)
    assert math.isfinite(observer.rpm) and observer.rpm > 0


vibration_chunk = st.fixed_dictionaries({
    "stamp": stamps,
    "first_index": indices,
    "rate": rates,
    "n": sizes,
    "poison": poisons,
    "source": st.sampled_from(["simulator", "cwru", "mfpt", "", "accelerometer_3", "x" * 300, "bad\nsource"]),
})


@settings(max_examples=CASES // 2, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(vibration_chunk, min_size=1, max_size=6), st.sampled_from([O, I]))
def test_vibration_callback_survives_anything_and_keeps_serving(chunks, fault):
    logged = []
    session = ObserverSession(fault, CATALOG["6205"], rpm=1797.0, log=lambda level, text: logged.append((level, text)))
    rng = np.random.default_rng(0)
    for c in chunks:
        x, _, _ = _arrays(dict(c, ragged=False), rng)
        out = session.on_chunk(c["stamp"], c["first_index"], c["rate"], c["source"], x)
        if out is not None:
            assert all(np.all(np.isfinite(a)) and a.size == x.size
                       for a in (out.residual, out.estimate, out.impulse_train) if a is not None)
    refused = session.counts["rejected"] + session.counts["no model"]
    assert (refused > 0) == any(level in ("warning", "error") and "bearing" not in text for level, text in logged)
    # good input afterwards: a fresh stream (index 0, later stamp) is observed
    y = GOOD[:6000]
    out = [session.on_chunk(2e12 + i / FS, i, FS, "cwru", y[i:i + 1200]) for i in range(0, y.size, 1200)]
    assert all(o is not None and np.all(np.isfinite(o.residual)) for o in out)
    assert out[-1].model_set == "cwru_de_6205"


@settings(max_examples=CASES, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["motor_1", "", "a/b"]), st.integers(0, 255), floats, floats, floats),
                min_size=1, max_size=6))
def test_fleet_table_refuses_malformed_states_and_keeps_serving(updates):
    table = FleetTable(stale_timeout=5.0)
    for motor, state, confidence, onset, stamp in updates:
        try:
            table.update(motor, state, confidence, onset, stamp, now=1.0)
        except ValueError as exc:
            assert "\n" not in str(exc)
    assert all(math.isfinite(r.confidence) and math.isfinite(r.onset) for r in table.rows())
    table.render(now=2.0)
    assert table.update("motor_9", 1, 0.9, 0.5, 1.0, now=2.0)
    assert table.rows()[-1].state == FaultState.OUTER_RACE


# ---------------------------------------------------------------------------------------
# file loaders


def _valid_mat(compressed: bool = False) -> bytes:
    """A CWRU-style file, or (compressed) an MFPT-style struct as MATLAB's save writes it."""
    from scipy.io import savemat
    buf = io.BytesIO()
    y = white_noise(0.5, FS, 4.5e-3)
    if compressed:
        savemat(buf, {"bearing": {"gs": y[:, None], "sr": FS, "rate": 25.0, "load": 0.0}}, do_compression=True)
    else:
        savemat(buf, {"X200_DE_time": y[:, None], "X200RPM": np.array([[1797]], dtype=np.uint16)})
    return buf.getvalue()


def _valid_npz() -> bytes:
    buf = io.BytesIO()
    np.savez(buf, accel=white_noise(0.5, 48000.0, 4.5e-3), sample_rate=48000.0, rpm=1800.0)
    return buf.getvalue()


def _valid_csv() -> bytes:
    y = white_noise(0.05, FS, 4.5e-3)
    return ("time,accel (g)\n" + "".join(f"{i / FS!r},{v!r}\n" for i, v in enumerate(y))).encode()


def _valid_wav() -> bytes:
    from scipy.io import wavfile
    buf = io.BytesIO()
    wavfile.write(buf, int(FS), (white_noise(0.05, FS, 4.5e-3) * 1000).astype(np.int16))
    return buf.getvalue()


VALID = {".mat": _valid_mat(), "compressed.mat": _valid_mat(compressed=True), ".npz": _valid_npz(),
         ".csv": _valid_csv(), ".wav": _valid_wav()}


@settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(suffix=st.sampled_from(sorted(VALID)), data=st.data())
def test_recording_loaders_refuse_garbage_and_cut_files_with_one_line(tmp_path, suffix, data):
    valid = VALID[suffix]
    cut = data.draw(st.integers(0, len(valid) - 1))
    content = data.draw(st.one_of(st.binary(max_size=4096), st.just(valid[:cut]),
                                  st.just(valid[:cut] + b"\x00" * 64)))
    path = tmp_path / f"f{suffix}"
    path.write_bytes(content)
    try:
        rec = load_recording(path, sample_rate=FS, units="g")
    except InputError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc)
    else:
        assert rec.accel.size > 0 and np.all(np.isfinite(rec.accel))


@settings(max_examples=CASES // 2, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_bag_reader_refuses_cut_and_corrupted_storage(tmp_path_factory, data):
    from bearing_recordings.bag_write import write_signal_bag
    base = tmp_path_factory.mktemp("bag")
    bag = base / "b"
    write_signal_bag(bag, white_noise(0.2, FS, 4.5e-3), FS, 1797.0, source="fuzz")
    storage = next(bag.glob("*.mcap"))
    raw = storage.read_bytes()
    cut = data.draw(st.integers(0, len(raw) - 1))
    flip = data.draw(st.integers(0, len(raw) - 1))
    mode = data.draw(st.sampled_from(["cut", "flip", "garbage-metadata"]))
    if mode == "cut":
        storage.write_bytes(raw[:cut])
    elif mode == "flip":
        storage.write_bytes(raw[:flip] + bytes([raw[flip] ^ 0xFF]) + raw[flip + 1:])
    else:
        (bag / "metadata.yaml").write_bytes(data.draw(st.binary(max_size=512)))
    try:
        rec = load_recording(bag)
    except InputError as exc:
        assert "\n" not in str(exc)
    else:
        assert np.all(np.isfinite(rec.accel))


yaml_scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), floats, st.text(max_size=20))
yaml_values = st.recursive(yaml_scalars,
                           lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                   st.dictionaries(st.text(max_size=20), inner, max_size=5)),
                           max_leaves=10)
bearing_keys = st.sampled_from(["name", "rolling_elements", "element_diameter", "element_diameter_in", "pitch_diameter",
                                "pitch_diameter_in", "contact_angle", "contact_angle_deg", "bearing", "other"])


@settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(doc=st.one_of(st.dictionaries(bearing_keys, yaml_values, max_size=8), yaml_values), raw=st.binary(max_size=300))
def test_bearing_files_refuse_anything_but_a_bearing(tmp_path, doc, raw):
    import yaml
    for i, text in enumerate((yaml.safe_dump(doc), raw)):
        path = tmp_path / f"b{i}.yaml"
        path.write_bytes(text.encode() if isinstance(text, str) else text)
        try:
            b = load_bearing(str(path))
        except BearingError as exc:
            assert "\n" not in str(exc)
        else:
            f = b.frequencies(1800.0)
            assert 0 < f.ftf < f.shaft < f.bpfi and 0 < f.bpfo and f.bsf > 0


@settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(doc=yaml_values, raw=st.binary(max_size=300))
def test_model_files_refuse_anything_but_a_model(tmp_path, doc, raw):
    from bearing_observer.hw_model import ModelFileError, load
    path = tmp_path / "outer_race.json"
    shipped = json.loads((_models_dir() / "sim_48k" / "outer_race.json").read_text())
    for content in (json.dumps(doc, allow_nan=True), raw,
                    json.dumps(_perturb(shipped, doc), allow_nan=True)):
        path.write_bytes(content.encode() if isinstance(content, str) else content)
        try:
            model = load(path)
        except (ModelFileError, ValueError) as exc:
            assert str(exc)
        else:
            out = model.simulate(np.r_[1.0, np.zeros(63)])
            assert np.all(np.isfinite(out))


def _models_dir():
    from bearing_observer.hw_model import MODELS_DIR
    return MODELS_DIR


def _perturb(model: dict, value) -> dict:
    """The shipped model with one field replaced by ``value`` (the field chosen by its hash)."""
    keys = sorted(model)
    out = dict(model)
    out[keys[hash(json.dumps(value, default=str)) % len(keys)]] = value
    return out


@pytest.mark.parametrize("name", ["6205", "mfpt", "za2115", "6203"])
def test_catalog_bearings_load(name):
    assert load_bearing(name).frequencies(1800.0).bpfo > 0
