"""The bearing-identify command line (identify_cli.main): one command per rig, a set the observer runs."""

import json

import numpy as np
import pytest

from bearing_common.bearings import CATALOG
from bearing_observer.identify_cli import main
from bearing_observer.impulse_trains import TWO_PI
from bearing_observer.model_sets import load_model_set
from bearing_observer.observer import FaultObserver
from bearing_recordings.load import load_recording


def test_bad_arguments(tmp_path, capsys):
    assert main(["--source", "x.mat", "--sample-rate", "12000", "--model-set", "t",
                 "--out", str(tmp_path)]) == 2
    assert "needs --fault" in capsys.readouterr().err
    assert main(["--source", "x.mat", "--fault", "outer_race", "--sample-rate", "12000",
                 "--model-set", "t", "--out", str(tmp_path)]) == 1
    assert "no such file" in capsys.readouterr().err
    assert main(["--source", "sim", "--model-set", "t", "--out", str(tmp_path)]) == 1
    assert "--source sim needs --sample-rate" in capsys.readouterr().err
    assert main(["--source", "sim", "--sample-rate", "12000", "--model-set", "none"]) == 2
    assert "invalid model set name 'none'" in capsys.readouterr().err
    assert main(["--source", "sim", "--sample-rate", "12000", "--model-set", "t", "--bearing", "nope"]) == 2
    assert "unknown bearing 'nope'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--sample-rate", "12000", "--model-set", "t"])  # --source missing


def test_one_sample_rate_per_set(tmp_path, capsys):
    """Recordings that store different rates (npz here) cannot make one set."""
    rng = np.random.default_rng(0)
    for name, fs in (("a.npz", 48000.0), ("b.npz", 24000.0)):
        n = int(0.3 * fs)
        u = (np.arange(n) % int(fs / 107.5) == 0).astype(float)
        ring = np.exp(-np.arange(200) / 20.0) * np.sin(np.arange(200) * 0.8)
        np.savez(tmp_path / name, accel=np.convolve(u, ring)[:n] + 0.01 * rng.standard_normal(n),
                 sample_rate=fs, rpm=1800.0)
    rc = main(["--source", f"outer_race={tmp_path / 'a.npz'}", "--source", f"inner_race={tmp_path / 'b.npz'}",
               "--orders", "4", "4", "0", "--model-set", "mixed", "--out", str(tmp_path)])
    assert rc == 1
    assert "a model set runs at one sample rate: " in capsys.readouterr().err


def test_identifies_cwru_set_with_provenance(tmp_path, capsys, cwru_record):
    outer, inner = cwru_record("130_OR007at6_0hp_DE12k.mat"), cwru_record("105_IR007_0hp_DE12k.mat")
    rc = main(["--source", f"outer_race={outer}",
               "--source", f"inner_race={inner}",
               "--sample-rate", "12000", "--orders", "6", "6", "0", "--max-seconds", "1.0",
               "--model-set", "tiny", "--out", str(tmp_path)])
    assert rc == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    assert [x["fault"] for x in lines] == ["outer_race", "inner_race"]
    models = load_model_set("tiny", sample_rate=12000.0, root=tmp_path)
    prov = models["outer_race"].provenance
    assert prov["file"] == "130_OR007at6_0hp_DE12k.mat" and len(prov["sha256"]) == 64
    assert prov["command"].startswith("bearing-identify --source outer_race=")
    assert models["outer_race"].nb == 6


# What bearing-identify measured on the first 0.5 s (orders 6 6 0) of one OR and one IR record of
# each rig: identification fit (%), time-series fit (%), fault frequency (Hz, slip included).
RIGS = {
    "mfpt": ("mfpt", [], "OuterRaceFault_vload_1.mat", "InnerRaceFault_vload_1.mat",
             {"outer_race": (15.0, 1.0, 80.066), "inner_race": (24.5, -4.7, 117.789)}),
    "hit-sm": ("6205", ["--sample-rate", "51200", "--rpm", "900"], "spectraquest/OR5_900.mat",
               "spectraquest/IR5_900.mat", {"outer_race": (32.5, -16.8, 53.865), "inner_race": (37.6, 4.2, 81.295)}),
}


@pytest.mark.parametrize("rig", RIGS)
def test_identifies_a_set_on_each_rig_that_the_observer_runs(tmp_path, capsys, shared_recording, rig):
    """One command per rig (MFPT: everything from the file; HIT-SM: rate and speed given, units g).
    Fits within 5 points of the measured ones (real impacts wander, so time-series fits stay
    near 0: see the models README); the measured fault frequency carries the slip (MFPT 1.3 %
    below the kinematic one), so the new set's observer locks its phase on its own fault."""
    bearing, extra, outer, inner, expected = RIGS[rig]
    outer, inner = shared_recording(rig, outer), shared_recording(rig, inner)
    rc = main(["--source", f"outer_race={outer}", "--source", f"inner_race={inner}", "--bearing", bearing, *extra,
               "--orders", "6", "6", "0", "--max-seconds", "0.5", "--model-set", "mine", "--out", str(tmp_path)])
    out = capsys.readouterr()
    assert rc == 0, out.err
    assert ("assuming g" in out.err) == (rig == "hit-sm")
    models = load_model_set(str(tmp_path / "mine"))
    for fault, (fit_id, fit_series, frequency) in expected.items():
        m = models[fault]
        assert m.bearing == CATALOG[bearing] and len(m.provenance["sha256"]) == 64
        assert m.fit.identification == pytest.approx(fit_id, abs=5.0), m.fit
        assert m.fit.time_series == pytest.approx(fit_series, abs=5.0), m.fit
        assert m.fault_frequency == pytest.approx(frequency, rel=2e-4)
    # the fresh set in the observer: phase estimates every 0.05 s over 1.5 s of the OR record,
    # referred to the record start, stay put (resultant length 1 = locked)
    rec = load_recording(outer, **({"sample_rate": 51200.0, "rpm": 900.0} if rig == "hit-sm" else {}))
    obs = FaultObserver.from_model_set(str(tmp_path / "mine"), "outer_race", rec.rpm, rec.sample_rate,
                                       bearing=CATALOG[bearing])
    step = int(0.05 * rec.sample_rate)
    phases = []
    for i in range(0, int(1.5 * rec.sample_rate), step):
        res = obs.process(rec.accel[i:i + step])
        assert np.all(np.isfinite(res.residual)) and res.residual.size == step
        phases.append(obs.phase - TWO_PI * obs.fault_frequency * (i + step) / rec.sample_rate)
    assert abs(np.mean(np.exp(1j * np.array(phases[4:])))) > 0.8
