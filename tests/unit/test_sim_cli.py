"""``bearing-sim`` command line and fault schedules (bearing_sim)."""

import os

import numpy as np
import pytest

from bearing_common.states import FaultState as F
from bearing_sim.schedule import SCENARIOS, parse_schedule, scenario
from bearing_sim.sim_cli import main


def test_scenarios_cover_the_thesis_cases():
    assert set(SCENARIOS) == {"normal", "or", "ir", "or-ir", "ir-or", "or-normal", "normal-or",
                              "ir-normal", "normal-ir"}
    assert scenario("or-ir") == [(F.OUTER_RACE, 0.2), (F.INNER_RACE, 0.2)]
    assert scenario("NORMAL-IR", 0.5) == [(F.NORMAL, 0.5), (F.INNER_RACE, 0.5)]
    with pytest.raises(ValueError, match="unknown scenario"):
        scenario("ball")
    with pytest.raises(ValueError, match="positive"):
        scenario("or", 0.0)


def test_parse_schedule():
    assert parse_schedule("normal:0.1,outer_race:0.2,inner_race:0.2") == [
        (F.NORMAL, 0.1), (F.OUTER_RACE, 0.2), (F.INNER_RACE, 0.2)]
    assert parse_schedule(" or:1 , ir:2.5") == [(F.OUTER_RACE, 1.0), (F.INNER_RACE, 2.5)]
    for bad, msg in [("", "empty"), ("or", "fault:seconds"), ("or:x", "not a number"),
                     ("or:-1", "positive"), ("xx:1", "unknown fault"), ("ball:1", "no model"),
                     ("or:inf", "positive")]:
        with pytest.raises(ValueError, match=msg):
            parse_schedule(bad)


def test_cli_writes_contract_npz(tmp_path):
    out = tmp_path / "run.npz"
    rc = main(["--schedule", "normal:0.01,or:0.02", "--sample-rate", "12000", "--out", str(out)])
    assert rc == 0
    d = np.load(out)
    assert set(d.files) == {"t", "accel", "unbalance", "sample_rate", "rpm", "truth", "source"}
    assert d["source"].item() == "simulator"  # else a .npz is read as a real machine's
    assert float(d["sample_rate"]) == 12000.0 and float(d["rpm"]) == 1800.0
    assert len(d["t"]) == len(d["accel"]) == len(d["unbalance"]) == len(d["truth"]) == 360
    np.testing.assert_allclose(d["t"][:3], [0.0, 1 / 12000, 2 / 12000])
    assert list(d["truth"][:120]) == [0] * 120 and list(d["truth"][120:]) == [1] * 240
    assert np.max(np.abs(d["accel"][130:])) > 10.0  # OR impacts, m/s^2


def test_cli_scenario_with_duration(tmp_path):
    out = tmp_path / "s.npz"
    assert main(["--scenario", "ir-or", "--duration", "0.01", "--rpm", "1500", "--out", str(out)]) == 0
    d = np.load(out)
    assert len(d["accel"]) == 960 and float(d["rpm"]) == 1500.0
    assert d["truth"][0] == 2 and d["truth"][-1] == 1


@pytest.mark.parametrize("argv, msg", [
    (["--scenario", "bogus"], "unknown scenario"),
    (["--scenario", "or", "--duration", "0"], "positive"),
    (["--scenario", "or", "--duration", "-1"], "positive"),
    (["--scenario", "or", "--sample-rate", "0"], "sample_rate"),
    (["--scenario", "or", "--sample-rate", "1000"], "too low"),
    (["--scenario", "or", "--rpm", "-5"], "rpm"),
    (["--schedule", "or:abc"], "not a number"),
    (["--scenario", "or", "--variant", "nope"], "variant"),
])
def test_cli_bad_arguments(tmp_path, capsys, argv, msg):
    rc = main(argv + ["--out", str(tmp_path / "x.npz")])
    assert rc != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bearing-sim: error:") and msg in err[0]
    assert not (tmp_path / "x.npz").exists()


def test_cli_unwritable_output_and_missing_source(tmp_path, capsys):
    rc = main(["--scenario", "or", "--out", str(tmp_path / "no" / "such" / "dir" / "x.npz")])
    assert rc != 0
    assert "does not exist" in capsys.readouterr().err
    ro = tmp_path / "ro"
    ro.mkdir()
    os.chmod(ro, 0o500)
    try:
        if not os.access(ro, os.W_OK):  # (root can write anyway)
            assert main(["--scenario", "or", "--out", str(ro / "x.npz")]) != 0
            assert "not writable" in capsys.readouterr().err
    finally:
        os.chmod(ro, 0o700)
    with pytest.raises(SystemExit) as exc:
        main(["--out", str(tmp_path / "x.npz")])
    assert exc.value.code != 0
    with pytest.raises(SystemExit):
        main(["--scenario", "or", "--schedule", "or:1", "--out", str(tmp_path / "x.npz")])


def test_cli_rpm_profile_writes_the_shaft_speed(tmp_path):
    from bearing_common.shaft_angle import RPM_TO_RAD_S
    out = tmp_path / "ramp.npz"
    rc = main(["--schedule", "or:0.05", "--sample-rate", "12000", "--rpm-profile", "0:1500,0.05:1800",
               "--quiet", "--out", str(out)])
    assert rc == 0
    d = np.load(out)
    assert set(d.files) == {"t", "accel", "unbalance", "sample_rate", "rpm", "truth", "source", "shaft_speed"}
    assert d["shaft_speed"].shape == d["accel"].shape == (600,)
    np.testing.assert_allclose(d["shaft_speed"], np.interp(d["t"], [0, 0.05], [1500, 1800]) * RPM_TO_RAD_S,
                               rtol=1e-12)
    assert float(d["rpm"]) == pytest.approx(1650.0, rel=1e-12)  # the mean over the run


def test_cli_speed_wobble(tmp_path):
    out = tmp_path / "wobble.npz"
    assert main(["--schedule", "normal:0.02", "--sample-rate", "12000", "--speed-wobble", "0.05:0.02",
                 "--quiet", "--out", str(out)]) == 0
    w = np.load(out)["shaft_speed"] * 30 / np.pi
    assert w.max() == pytest.approx(1800 * 1.05, rel=2e-3) and w.min() == pytest.approx(1800 * 0.95, rel=2e-3)


@pytest.mark.parametrize("argv, msg", [
    (["--rpm-profile", "0:900,x"], "seconds:rpm"),
    (["--rpm-profile", "1:900,1:1800"], "increase strictly"),
    (["--rpm-profile", "0:900,1:9000"], "6000"),
    (["--speed-wobble", "0.1"], "FRACTION:PERIOD"),
    (["--speed-wobble", "1.5:2"], "amplitude"),
])
def test_cli_bad_speed_profiles(tmp_path, capsys, argv, msg):
    rc = main(["--schedule", "or:0.01", *argv, "--out", str(tmp_path / "x.npz")])
    assert rc == 2
    err = capsys.readouterr().err
    assert msg in err and err.count("\n") == 1, err
    assert not (tmp_path / "x.npz").exists()


def test_cli_rpm_and_rpm_profile_exclude_each_other(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--schedule", "or:0.01", "--rpm", "1500", "--rpm-profile", "0:900,1:1800",
              "--out", str(tmp_path / "x.npz")])
    assert exc.value.code == 2 and "not allowed with" in capsys.readouterr().err
