"""``bearing-trend`` on tiny synthetic snapshot folders written here: output, bad input, exit codes, imports."""

import json
import subprocess
import sys

import numpy as np
import pytest
from synthetic_snapshots import write_femto_file

from bearing_diagnoser.health.trend_cli import main

N_ROWS = 1024  # 0.04 s snapshots keep the test fast


def degrading_folder(path, snapshots=60, onset=40):
    """One snapshot a minute; Gaussian 0.3 g, growing 12 % a snapshot from ``onset`` on."""
    rng = np.random.default_rng(0)
    path.mkdir(parents=True)
    for k in range(snapshots):
        h = rng.standard_normal(N_ROWS) * 0.3 * 1.12 ** max(0, k - onset)
        write_femto_file(path / f"acc_{k + 1:05d}.csv", 36000.0 + 60.0 * k, n=N_ROWS, h=h, v=0.5 * h)
    return path


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, [json.loads(line) for line in out.splitlines()], err


def test_one_line_per_snapshot_then_a_summary(tmp_path, capsys):
    folder = degrading_folder(tmp_path / "B")
    code, lines, err = run(capsys, folder, "--bearing", "femto", "--rpm", "1800")
    assert code == 0
    *records, last = lines
    assert len(records) == 60
    assert records[0]["t"] == pytest.approx(0.0) and records[-1]["t"] == pytest.approx(59 * 60.0, abs=1e-3)
    assert {r["state"] for r in records} <= {"healthy", "warning", "alarm"}
    assert set(records[0]["indicators"]) >= {"rms_m_s2", "peak_m_s2", "crest_factor", "kurtosis", "velocity_rms_mm_s",
                                             "envelope_rms_m_s2"}
    assert records[0]["indicators"]["rms_m_s2"] == pytest.approx(0.3 * 9.80665, rel=0.1)
    summary = last["summary"]
    assert 40 * 60 < summary["first_warning"] <= summary["first_alarm"] < 59 * 60
    assert records[-1]["state"] == "alarm"
    assert summary["damaged"] == 0 and summary["baseline"]["snapshots"] == 30
    assert "baseline of 30 snapshots" in err


def test_damaged_snapshot_is_reported_and_skipped(tmp_path, capsys):
    folder = degrading_folder(tmp_path / "B", snapshots=40)
    (folder / "acc_00020.csv").write_text("1,2,3\n")
    code, lines, err = run(capsys, folder)
    assert code == 0
    assert len(lines) == 40  # 39 snapshots + summary
    assert lines[-1]["summary"]["damaged"] == 1
    assert "1 damaged snapshot(s) skipped; first acc_00020.csv" in err


@pytest.mark.parametrize("argv,match", [
    (["{missing}"], "no such file"),
    (["{empty}"], "no snapshots here"),
    (["{good}", "--baseline", "soon"], "--baseline"),
    (["{good}", "--machine-class", "group9"], "machine class"),
    (["{good}", "--bearing", "nosuch"], "unknown bearing"),
    (["{good}", "--channel", "axial"], "channels horizontal, vertical"),
    (["{good}", "--sample-rate", "5"], "not plausible"),
])
def test_bad_input_one_error_line_and_exit_2(tmp_path, capsys, argv, match):
    good = degrading_folder(tmp_path / "good", snapshots=8)
    (tmp_path / "empty").mkdir()
    paths = {"missing": tmp_path / "missing", "empty": tmp_path / "empty", "good": good}
    code, lines, err = run(capsys, *[a.format(**paths) for a in argv])
    assert code == 2
    assert lines == []
    assert err.count("error:") == 1 and match in err


def test_all_snapshots_damaged_is_an_error(tmp_path, capsys):
    folder = tmp_path / "B"
    folder.mkdir()
    for k in range(3):
        (folder / f"acc_{k + 1:05d}.csv").write_text("garbage\n")
    code, lines, err = run(capsys, folder)
    assert code == 2 and lines == [] and "no usable snapshot (3 damaged)" in err


def test_several_paths_carry_their_path_and_a_bad_one_does_not_stop_the_others(tmp_path, capsys):
    a = degrading_folder(tmp_path / "A", snapshots=35)
    code, lines, err = run(capsys, a, tmp_path / "nothing")
    assert code == 2
    assert {line["path"] for line in lines} == {str(a)}
    assert "summary" in lines[-1] and "no such file" in err


def test_baseline_as_a_duration(tmp_path, capsys):
    folder = degrading_folder(tmp_path / "B", snapshots=35)
    code, lines, _ = run(capsys, folder, "--baseline", "10min")
    assert code == 0 and lines[-1]["summary"]["baseline"]["snapshots"] == 11
    assert lines[5]["trend"]["learning"] and not lines[12]["trend"]["learning"]


def test_plot_writes_the_trend_figure(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    folder = degrading_folder(tmp_path / "B", snapshots=45)
    code, _, err = run(capsys, folder, "--plot", tmp_path / "fig")
    assert code == 0
    png = tmp_path / "fig" / "trend_B.png"
    assert png.read_bytes()[:4] == b"\x89PNG" and "wrote" in err


def test_start_up_imports_neither_rclpy_nor_matplotlib(tmp_path):
    folder = degrading_folder(tmp_path / "B", snapshots=8)
    code = ("import sys\nfrom bearing_diagnoser.health.trend_cli import main\n"
            f"assert main([{str(folder)!r}]) == 0\n"
            "print(sorted(m for m in ('rclpy', 'matplotlib', 'rosbags') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"
