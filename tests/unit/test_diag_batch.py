"""``bearing-diagnose`` over many files and folders: tagged lines in the files' order, the same lines
as each file's own run, --jobs, a bad file reported on its own line, the progress line."""

from __future__ import annotations

import numpy as np
import pytest
from test_diag_cli import BPFO, FS, KEYS, run, write_npz

from bearing_common.progress_bar import ProgressBar
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_recordings.recording_files import expand


@pytest.fixture
def archive(tmp_path):
    """(loose file, folder, the folder's recordings in walk order): an outer-race and a normal
    recording in a folder (one in a subfolder, beside a file that is not a recording), one outside."""
    folder = tmp_path / "archive"
    (folder / "b").mkdir(parents=True)
    rng = np.random.default_rng(7)
    inside = [write_npz(folder / "a_or.npz", burst_train(0.4, FS, BPFO, amplitude=10.0) + white_noise(0.4, FS, 4.5e-3)),
              write_npz(folder / "b" / "normal.npz", rng.normal(0.0, 0.3, int(0.4 * FS)))]
    (folder / "notes.txt").write_text("not a recording")
    (folder / ".hidden.npz").write_bytes(b"skipped: hidden")
    loose = write_npz(tmp_path / "loose.npz", burst_train(0.4, FS, BPFO, amplitude=8.0) + white_noise(0.4, FS, 4.5e-3))
    return loose, folder, inside


def test_files_and_a_folder_are_tagged_in_order_with_each_files_own_lines(archive, capsys):
    loose, folder, inside = archive
    assert expand([loose, folder, inside[0]]) == ([str(loose), *map(str, inside)], [])  # once each
    code, lines, err = run([loose, folder], capsys)
    assert code == 0, err
    files = [str(loose), *map(str, inside)]
    assert list(dict.fromkeys(x["file"] for x in lines)) == files
    assert all(set(x) == KEYS | {"file"} for x in lines)
    for path in files:
        code, alone, _ = run([path], capsys)
        assert code == 0 and "file" not in alone[0]
        assert [{k: v for k, v in x.items() if k != "file"} for x in lines if x["file"] == path] == alone
    states = {x["file"]: x["state"] for x in lines}
    assert states[str(inside[0])] == "outer_race" and states[str(inside[1])] == "normal"
    assert f"{inside[0]}: model set sim_48k" in err
    assert "3 files: 3 diagnosed, 0 failed" in err


def test_jobs_2_gives_the_lines_of_jobs_1(archive, capsys):
    loose, folder, _ = archive
    code1, lines1, _ = run([loose, folder, "--jobs", "1"], capsys)
    code2, lines2, err2 = run([loose, folder, "--jobs", "2"], capsys)
    assert code1 == code2 == 0, err2
    assert lines2 == lines1 and len(lines1) >= 3


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_a_bad_file_is_reported_on_its_line_and_the_batch_goes_on(archive, tmp_path, capsys, jobs):
    loose, folder, inside = archive
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    code, lines, err = run([bad, loose, folder, "--jobs", jobs], capsys)
    assert code == 2
    assert list(dict.fromkeys(x["file"] for x in lines)) == [str(loose), *map(str, inside)]
    errors = [x for x in err.splitlines() if "error:" in x]
    assert len(errors) == 1 and errors[0].startswith(f"bearing-diagnose: error: {bad}: not a readable .npz"), err
    assert "4 files: 3 diagnosed, 1 failed" in err


def test_an_empty_folder_is_an_error_but_not_the_end(archive, tmp_path, capsys):
    loose, _, _ = archive
    empty = tmp_path / "empty"
    empty.mkdir()
    code, lines, err = run([empty, loose], capsys)
    assert code == 2 and {x["file"] for x in lines} == {str(loose)}
    assert f"error: {empty}: not a rosbag2 recording" in err


def test_progress_only_when_asked_in_a_pipe(archive, capsys):
    loose, folder, _ = archive
    _, lines, err = run([loose, folder], capsys)  # stderr is not a terminal: no progress line
    assert "files, " not in err and "[" not in err
    _, lines_p, err_p = run([loose, folder, "--progress"], capsys)
    assert lines_p == lines  # stdout holds only the JSON lines
    progress = [x for x in err_p.splitlines() if x.startswith("bearing-diagnose [")]
    assert progress and progress[-1].startswith("bearing-diagnose [" + "#" * ProgressBar.WIDTH + "] 3/3 files")
    _, _, err_n = run([loose, folder, "--no-progress"], capsys)
    assert "[" not in err_n


def test_progress_line_counts_and_redraws_in_place():
    class Stream:
        text = ""

        def write(self, s):
            self.text += s

        def flush(self):
            pass

    log, tty = Stream(), Stream()
    plain, live = ProgressBar(20, log, "x", live=False), ProgressBar(20, tty, "x", live=True)
    for k in range(20):
        plain.advance(1.5, failed=k == 3)
        live.advance(1.5)
    assert len(log.text.splitlines()) == 10  # a line per tenth in a log
    assert log.text.splitlines()[-1].startswith("x [" + "#" * ProgressBar.WIDTH + "] 20/20 files (1 failed), 30 s")
    assert "\n" not in tty.text and tty.text.count("\r") == 20  # one line redrawn on a terminal
    live.clear()
    assert tty.text.endswith("\r\033[K")
