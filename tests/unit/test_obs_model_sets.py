"""The model-set registry, the `none` set and the bearing an observer watches."""

import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_common.bearings import CATALOG, load_bearing
from bearing_common.states import FaultState
from bearing_observer.hw_model import ModelFileError
from bearing_observer.impulse_trains import TWO_PI, impulse_train
from bearing_observer.model_sets import (
    NONE,
    SHIPPED,
    available_model_sets,
    choose_model_set,
    load_model_set,
    model_set,
)
from bearing_observer.observer import BearingMismatchWarning, FaultObserver

B6205, B6203 = CATALOG["6205"], CATALOG["6203"]


def test_shipped_sets_match_their_registry_entries():
    assert set(SHIPPED) < set(available_model_sets()) and NONE in available_model_sets()
    for name, entry in SHIPPED.items():
        for ft, m in load_model_set(name, sample_rate=entry.sample_rate).items():
            assert m.fault_type == ft and m.sample_rate == entry.sample_rate
            assert m.bearing == entry.bearing  # recorded in the file's provenance
            assert m.provenance["command"].startswith("bearing-identify") and "date" in m.provenance
            assert 0.0 < m.fit.identification <= 100.0
    with pytest.raises(ModelFileError, match="12000 Hz"):
        load_model_set("sim_48k", sample_rate=12000.0)
    with pytest.raises(ModelFileError, match="unknown model set 'no_such_set'"):
        load_model_set("no_such_set")
    with pytest.raises(ModelFileError, match="give the sample rate"):
        load_model_set(NONE)


@pytest.mark.parametrize("source, rate, bearing, resample, expected", [
    ("simulator", 48000, CATALOG["6205"], False, "sim_48k"),
    ("simulator", 12000, CATALOG["6205"], False, "sim_12k"),
    ("cwru", 12000, None, False, "cwru_de_6205"),       # None: the default bearing, 6205
    ("CWRU", 12000, load_bearing("9,0.3126in,1.537in,0deg"), False, "cwru_de_6205"),  # same orders, other name
    ("cwru", 48000, CATALOG["6205"], False, NONE),               # no set at that rate: none ...
    ("cwru", 48000, CATALOG["6205"], True, "cwru_de_6205"),      # ... unless the caller resamples
    ("simulator", 24000, CATALOG["6205"], True, "sim_48k"),      # lowest rate at or above the input's
    ("simulator", 8000, CATALOG["6205"], True, "sim_12k"),
    ("simulator", 96000, CATALOG["6205"], True, "sim_48k"),      # else the highest
    ("cwru", 12000, CATALOG["6203"], True, NONE),                # another bearing
    ("mfpt", 48828, CATALOG["mfpt"], True, NONE),
    ("mat", 51200, CATALOG["6205"], True, NONE),                 # HIT-SM, any user's sensor
])
def test_which_set_for_source_rate_and_bearing(source, rate, bearing, resample, expected):
    assert choose_model_set(source, rate, bearing, resample=resample).name == expected


def test_set_by_directory_records_rate_and_bearing(tmp_path):
    target = tmp_path / "mine"
    target.mkdir()
    for ft, m in load_model_set("cwru_de_6205", 12000.0).items():
        m.save(target / f"{ft}.json")
    entry = model_set(str(target))
    assert (entry.sample_rate, entry.bearing, entry.source, entry.directory) == (12000.0, B6205, None, target)
    assert model_set("mine", root=tmp_path).directory == target
    assert available_model_sets(tmp_path) == ["mine", NONE]
    obs = FaultObserver.from_model_set(str(target), "outer_race", 1797.0, 12000.0)
    assert obs.fault_order == load_model_set("cwru_de_6205")["outer_race"].fault_order


# --- the bearing -----------------------------------------------------------------------------
def test_observer_of_the_sets_bearing_keeps_the_measured_order():
    m = load_model_set("cwru_de_6205", 12000.0)["outer_race"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for bearing in (None, B6205):
            obs = FaultObserver(m, rpm=1797.0, bearing=bearing)
            assert obs.fault_order == m.fault_order  # slip measured on record 130, not the kinematic 3.5848
    assert m.fault_order != pytest.approx(B6205.orders().bpfo, rel=1e-4)


@pytest.mark.parametrize("fault", ["outer_race", "inner_race"])
def test_observer_of_another_bearing_warns_and_uses_that_bearings_frequency(fault):
    with pytest.warns(BearingMismatchWarning, match=r"cwru_de_6205 .* identified for SKF 6205.*not SKF 6203"):
        obs = FaultObserver.from_model_set("cwru_de_6205", fault, 1800.0, 12000.0, bearing=CATALOG["6203"])
    assert obs.bearing == B6203
    assert obs.fault_frequency == pytest.approx(B6203.frequencies(1800.0).of(FaultState[fault.upper()]), rel=1e-12)
    out = obs.process(np.zeros(1200))  # and it runs
    assert out.residual.shape == (1200,)


# --- none: no model ----------------------------------------------------------------------------
def _bursts(fs, freq, phase, n, seed=0):
    """Decaying 3 kHz bursts at the impacts of a train of ``freq`` Hz and ``phase`` rad, plus noise."""
    u = impulse_train(n, fs, freq, phase)
    h = np.exp(-np.arange(int(2e-3 * fs)) / (2.5e-4 * fs)) * np.sin(TWO_PI * 3000.0 * np.arange(int(2e-3 * fs)) / fs)
    return np.convolve(u, h)[:n] * 50.0 + np.random.default_rng(seed).normal(0.0, 0.5, n)


@pytest.mark.parametrize("fault, bearing, fs", [("outer_race", "mfpt", 48828.0), ("inner_race", "6203", 25600.0)])
def test_none_passes_the_measurement_and_locks_the_train(fault, bearing, fs):
    rpm = 1500.0
    b = CATALOG[bearing]
    freq = b.frequencies(rpm).of(FaultState[fault.upper()])
    y = _bursts(fs, freq, 1.3, int(0.5 * fs))
    obs = FaultObserver.from_model_set(NONE, fault, rpm, fs, bearing=b)
    assert obs.drive_mode == "phase" and obs.fault_frequency == pytest.approx(freq, rel=1e-12)
    parts = [obs.process(c) for c in np.array_split(y, 37)]
    res = np.concatenate([p.residual for p in parts])
    assert np.array_equal(res, y)                                     # residual = y, bit for bit
    assert not any(p.estimate.any() or p.drive.any() for p in parts)  # estimate = 0
    # chunking does not matter
    train = np.concatenate([p.impulse_train for p in parts])
    whole = FaultObserver.from_model_set(NONE, fault, rpm, fs, bearing=b).process(y)
    assert_allclose(whole.impulse_train, train, rtol=0, atol=1e-9)
    # after the first update the train's pulses sit on the bursts' energy (within 0.2 ms)
    err = np.angle(np.exp(1j * (obs.phase - (1.3 + TWO_PI * freq * y.size / fs)))) / TWO_PI / freq
    assert -2e-4 < err < 0.0, err  # the train marks the energy peak, a little after the impact
    # the thesis' cross-correlation of |r| with the train stays computable
    late = slice(int(0.1 * fs), None)
    assert np.corrcoef(np.abs(res[late]), np.convolve(train, np.ones(int(5e-4 * fs)))[: y.size][late])[0, 1] > 0.3


def test_none_needs_a_speed():
    with pytest.raises(ValueError, match="give rpm"):
        FaultObserver.from_model_set(NONE, "outer_race", sample_rate=48000.0)
