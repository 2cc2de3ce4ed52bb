"""``bearing-diagnose`` command line: output format, stderr notes, and every bad-input case."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.io import savemat

from bearing_diagnoser.diagnose_cli import main
from bearing_diagnoser.synthetic import burst_train, white_noise

FS = 48000.0
BPFO = 107.54326610279765
KEYS = {"start", "end", "state", "confidence", "detected_at", "scores", "model_set"}


def write_npz(path, accel, fs=FS, rpm=1800.0, **extra):
    """A bearing-sim npz (``source`` = simulator unless ``extra`` says otherwise); a bad ``fs``
    (e.g. 0) is written as given, ``t`` then counts samples."""
    t = np.arange(np.size(accel)) / (fs if fs > 0 else 1.0)
    np.savez(path, **({"t": t, "accel": accel, "unbalance": np.zeros(np.size(accel)),
                       "truth": np.zeros(np.size(accel), int), "sample_rate": fs, "rpm": rpm,
                       "source": "simulator"} | extra))
    return path


def run(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, [json.loads(x) for x in out.splitlines() if x.strip()], err


@pytest.fixture
def or_npz(tmp_path):
    y = burst_train(0.4, FS, BPFO, amplitude=10.0) + white_noise(0.4, FS, 4.5e-3)
    return write_npz(tmp_path / "or.npz", y)


def test_model_method_prints_one_json_object_per_segment(or_npz, capsys):
    code, lines, err = run([or_npz], capsys)
    assert code == 0, err
    assert [x["state"] for x in lines] == ["outer_race"]
    assert set(lines[0]) == KEYS and lines[0]["model_set"] == "sim_48k"
    assert lines[0]["start"] == 0.0 and lines[0]["end"] == pytest.approx(0.4)
    assert lines[0]["detected_at"] <= 0.05 + 1e-9
    assert 0.0 <= lines[0]["confidence"] <= 1.0
    assert {"outer_race", "inner_race", "outer_race_explained"} <= set(lines[0]["scores"])
    assert "model set sim_48k" in err


def test_resampling_and_model_set_are_announced(tmp_path, capsys):
    y = burst_train(0.4, 96000.0, BPFO, amplitude=10.0) + white_noise(0.4, 96000.0, 4.5e-3)
    path = write_npz(tmp_path / "fast.npz", y, fs=96000.0)
    code, lines, err = run([path, "--method", "envelope"], capsys)
    assert code == 0 and lines and set(lines[0]) == KEYS
    assert "resampling 96000 Hz -> 48000 Hz" in err and "model set sim_48k" in err


def test_mat_file_with_channel_rpm_and_required_rate(tmp_path, capsys):
    fs = 12000.0
    y = (burst_train(1.0, fs, BPFO * 1797 / 1800, amplitude=5.0, resonance_hz=3000.0)
         + white_noise(1.0, fs, 4.5e-3)) / 9.80665
    path = tmp_path / "rec.mat"
    savemat(path, {"X200_DE_time": y[:, None], "X200_FE_time": y[:, None] * 0.1,
                   "X200RPM": np.array([[1797]], dtype=np.uint16)})
    code, lines, err = run([path, "--sample-rate", 12000, "--method", "envelope"], capsys)
    assert code == 0, err
    assert [x["state"] for x in lines] == ["outer_race"]
    assert lines[-1]["model_set"] == "cwru_de_6205" and "model set cwru_de_6205" in err
    code, _, err = run([path, "--method", "envelope"], capsys)
    assert code != 0 and "--sample-rate" in err
    code, _, err = run([path, "--sample-rate", 12000, "--channel", "X999_DE_time"], capsys)
    assert code != 0 and "no channel 'X999_DE_time'" in err and "X200_DE_time" in err


def _write(path, data):
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data)
    return path


def _mkdir(path):
    path.mkdir()
    return path


@pytest.mark.parametrize("make, message", [
    (lambda p: p / "missing.npz", "no such file"),
    (lambda p: _write(p / "bad.mat", b"garbage"), "not a MATLAB 5/7 MAT-file"),
    (lambda p: _write(p / "bad.npz", b"not a zip"), "not a readable .npz"),
    (lambda p: _write(p / "x.xls", "1,2"), "unknown file type"),
    (lambda p: write_npz(p / "nan.npz", np.r_[np.zeros(100), np.nan, np.zeros(50000)]), "non-finite"),
    (lambda p: write_npz(p / "inf.npz", np.r_[np.zeros(100), np.inf, np.zeros(50000)]), "non-finite"),
    (lambda p: write_npz(p / "empty.npz", np.zeros(0)), "no samples"),
    (lambda p: write_npz(p / "zero_rate.npz", np.zeros(50000), fs=0.0), "not plausible"),
    (lambda p: write_npz(p / "neg_rate.npz", np.zeros(50000), fs=-48000.0), "not plausible"),
    (lambda p: write_npz(p / "short.npz", np.zeros(100)), "too short"),
    (lambda p: _mkdir(p / "dir"), "not a rosbag2"),
])
def test_bad_input_gives_one_error_line_and_nonzero_exit(tmp_path, capsys, make, message):
    path = make(tmp_path)
    code, lines, err = run([path, "--method", "envelope"], capsys)
    assert code != 0
    assert lines == []
    errors = [x for x in err.splitlines() if "error:" in x]
    assert len(errors) == 1 and message in errors[0], err


def test_bad_options_are_rejected(or_npz, capsys):
    for argv, message in (([or_npz, "--sample-rate", "0"], "not plausible"),
                          ([or_npz, "--sample-rate", "-5"], "not plausible"),
                          ([or_npz, "--rpm", "-1"], "shaft speed must be a positive"),
                          ([or_npz, "--model-set", "nope"], "unknown model set")):
        code, lines, err = run(argv, capsys)
        assert code != 0 and lines == [] and message in err, err


def test_unknown_channel_in_npz(or_npz, capsys):
    code, _, err = run([or_npz, "--channel", "velocity"], capsys)
    assert code != 0 and "no channel 'velocity'" in err and "accel" in err


@pytest.mark.parametrize(("model_set", "seconds"), [([], 0.3), (["--model-set", "none"], 1.0)],
                         ids=["sim_48k", "none"])
def test_plot_writes_figures(model_set, seconds, tmp_path, capsys):
    """Also without a model, whose observers send no estimate and no train."""
    y = burst_train(seconds, FS, BPFO, amplitude=10.0) + white_noise(seconds, FS, 4.5e-3)
    path = write_npz(tmp_path / "or.npz", y)
    code, lines, err = run([path, "--plot", tmp_path / "fig", *model_set], capsys)
    assert code == 0, err
    names = sorted(p.name for p in (tmp_path / "fig").iterdir())
    assert names == ["acceleration_states.png", "residual_inner_race.png", "residual_outer_race.png",
                     "timeline.png", "xcorr_inner_race.png", "xcorr_outer_race.png"]


# ---------------------------------------------------------------------------------------
# real recordings of the three rigs, read directly

def test_mfpt_recording_needs_nothing_else(mfpt_record, capsys):
    code, lines, err = run([mfpt_record("OuterRaceFault_vload_2.mat")], capsys)
    assert code == 0, err
    assert [x["state"] for x in lines] == ["outer_race"] and lines[0]["model_set"] == "none"
    assert "NICE (MFPT rig)" in err
    assert lines[0]["scores"]["speed_hz"] == pytest.approx(25.0, rel=0.02)  # refined from the vibration


def test_hit_sm_recording_with_rate_and_speed(hit_record, capsys):
    code, lines, err = run([hit_record("IR5_900.mat"), "--sample-rate", 51200, "--rpm", 900], capsys)
    assert code == 0, err
    assert [x["state"] for x in lines] == ["inner_race"]
    assert "assuming g" in err  # the file does not state its unit
    band = (lines[0]["scores"]["band_low_hz"], lines[0]["scores"]["band_high_hz"])
    assert 0 < band[0] < band[1] <= 0.45 * 51200


def test_cwru_fan_end_channel_monitors_the_fan_end_bearing(cwru_record, capsys):
    code, _, err = run([cwru_record("105_IR007_0hp_DE12k.mat"), "--sample-rate", 12000,
                        "--channel", "X105_FE_time"], capsys)
    assert code == 0, err
    assert "bearing SKF 6203" in err


@pytest.mark.parametrize("argv, message", [
    (["--sample-rate", 100], "sample rate 100 Hz too low for bearing"),
    (["--sample-rate", 12000, "--rpm", 60000], "too low for bearing"),  # lines beyond Nyquist
    (["--sample-rate", 12000, "--rpm", 30], "too short"),  # 4 cage periods at 0.5 Hz: 20 s
    (["--sample-rate", 12000, "--bearing", "nosuch"], "unknown bearing 'nosuch'"),
    (["--sample-rate", 12000, "--bearing", "9,7mm,5mm"], "need 0 < element diameter < pitch diameter"),
])
def test_undecidable_cwru_inputs_fail_fast_with_one_line(cwru_record, capsys, argv, message):
    import time
    start = time.monotonic()
    code, lines, err = run([cwru_record("105_IR007_0hp_DE12k.mat"), *argv], capsys)
    assert code == 2 and lines == []
    errors = [x for x in err.splitlines() if "error:" in x]
    assert len(errors) == 1 and message in errors[0], err
    assert time.monotonic() - start < 10.0
