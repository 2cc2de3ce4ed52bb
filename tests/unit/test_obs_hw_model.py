"""HW model files and the model-set registry."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_common.bearings import CATALOG
from bearing_observer import hw_model
from bearing_observer.hw_model import HWModel, ModelFileError, load
from bearing_observer.piecewise_linear import MonotonePiecewiseLinear


def _model(fs=48000.0, fault="outer_race"):
    return HWModel(fault_type=fault, sample_rate=fs, rpm=1800.0, fault_frequency=107.5,
                   fault_order=107.5 / 30.0, b=[1.0, 0.5], f=[1.0, -1.6, 0.8], nk=1,
                   input_nonlinearity=MonotonePiecewiseLinear.gain(1.0),
                   output_nonlinearity=MonotonePiecewiseLinear([-1, 0, 2], [-2, 0, 1]),
                   provenance={"source": "test"})


def test_save_load_roundtrip(tmp_path):
    m = _model()
    path = m.save(tmp_path / "outer_race.json")
    d = json.loads(path.read_text())
    assert d["format_version"] == hw_model.FORMAT_VERSION
    assert d["train"]["equation"] == "2.55"
    m2 = load(path, sample_rate=48000.0, fault_type="outer_race")
    u = np.zeros(50)
    u[3] = 1.0
    assert_allclose(m2.simulate(u), m.simulate(u), rtol=0, atol=1e-15)
    assert m2.nk == 1 and m2.nb == 2 and m2.nf == 2


def test_bearing_recorded_in_provenance(tmp_path):
    m = _model()
    assert m.bearing is None
    m.provenance["bearing"] = CATALOG["6203"].to_dict()
    assert load(m.save(tmp_path / "m.json")).bearing == CATALOG["6203"]
    m.provenance["bearing"] = {"rolling_elements": 9}
    with pytest.raises(ModelFileError, match="corrupt.*element_diameter"):
        load(m.save(tmp_path / "m.json"))


def test_missing_file(tmp_path):
    with pytest.raises(ModelFileError, match="not found"):
        load(tmp_path / "nope.json")


def test_corrupt_file(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text("{not json")
    with pytest.raises(ModelFileError, match="corrupt"):
        load(p)
    d = _model().to_dict()
    del d["linear"]["b"]
    p.write_text(json.dumps(d))
    with pytest.raises(ModelFileError, match="corrupt"):
        load(p)
    d = _model().to_dict()
    d["output_nonlinearity"]["y"] = [0, 0, 1]  # not invertible
    p.write_text(json.dumps(d))
    with pytest.raises(ModelFileError, match="corrupt"):
        load(p)


def test_wrong_sample_rate_fault_type_and_version(tmp_path):
    p = _model().save(tmp_path / "m.json")
    with pytest.raises(ModelFileError, match="identified at 48000 Hz but 12000 Hz"):
        load(p, sample_rate=12000.0)
    with pytest.raises(ModelFileError, match="not inner_race"):
        load(p, fault_type="inner_race")
    d = json.loads(p.read_text())
    d["format_version"] = 99
    p.write_text(json.dumps(d))
    with pytest.raises(ModelFileError, match="format_version"):
        load(p)


def test_unstable_linear_block_rejected():
    with pytest.raises(ValueError, match="unstable"):
        HWModel(fault_type="outer_race", sample_rate=1.0, rpm=1.0, fault_frequency=1.0,
                fault_order=1.0, b=[1.0], f=[1.0, -1.5], nk=0,
                input_nonlinearity=MonotonePiecewiseLinear.gain(1.0),
                output_nonlinearity=MonotonePiecewiseLinear.identity())
