"""Snapshot input: FEMTO acc_*.csv folders, folders of .mat/.npz recordings, rosbag2 chunks with gaps."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from synthetic_snapshots import FS, femto_rows, write_femto

from bearing_common.units import STANDARD_GRAVITY
from bearing_recordings.recording import InputError
from bearing_recordings.snapshots import cut_stretch, open_snapshots


def test_femto_folder_times_from_the_snapshot_clocks_and_channels(tmp_path):
    starts = [9 * 3600 + 39 * 60 + 39.065664 + 60 * k for k in range(4)]
    folder = write_femto(tmp_path / "B", starts)
    (folder / "temp_00001.csv").write_text("9,39,39,0,25.0\n")  # temperatures beside: ignored
    src = open_snapshots(folder)
    snaps = list(src)
    assert src.kind == "femto" and src.channel == "horizontal" and src.bearing == "femto"
    assert len(snaps) == 4 and not src.damaged
    assert_allclose([s.t - snaps[0].t for s in snaps], [0, 60, 120, 180], atol=1e-5)
    assert_allclose(snaps[0].sample_rate, FS, rtol=1e-4)  # from the sample clock
    ref = femto_rows(starts[0])
    assert_allclose(snaps[0].samples, np.round(ref[:, 4], 3) * STANDARD_GRAVITY)
    vertical = list(open_snapshots(folder, channel="vertical"))
    assert_allclose(vertical[0].samples, np.round(ref[:, 5], 3) * STANDARD_GRAVITY)
    assert list(open_snapshots(folder, sample_rate=25000.0))[0].sample_rate == 25000.0


def test_femto_semicolons_and_a_test_running_past_midnight(tmp_path):
    starts = [86400.0 - 90.0 + 60 * k for k in range(3)]  # 23:58:30, 23:59:30, 00:00:30
    snaps = list(open_snapshots(write_femto(tmp_path / "B", starts, delimiter=";")))
    assert_allclose([s.t - snaps[0].t for s in snaps], [0, 60, 120], atol=1e-5)


def test_damaged_snapshot_in_the_middle_is_counted_not_fatal(tmp_path):
    folder = write_femto(tmp_path / "B", [36000.0 + 60 * k for k in range(5)])
    files = sorted(folder.glob("acc_*.csv"))
    files[2].write_text("9,39,39,65664,0.5\nthis is not a number\n")
    files[3].write_text("")
    src = open_snapshots(folder)
    snaps = list(src)
    assert len(snaps) == 3
    assert [name for name, _ in src.damaged] == [files[2].name, files[3].name]
    assert "not a table of numbers" in src.damaged[0][1] or "columns" in src.damaged[0][1]


def test_snapshot_with_a_clock_going_back_is_damaged(tmp_path):
    folder = write_femto(tmp_path / "B", [36000.0, 36060.0, 36030.0, 36120.0])
    src = open_snapshots(folder)
    assert len(list(src)) == 3 and "not after the previous" in src.damaged[0][1]


@pytest.mark.parametrize("make,match", [
    (lambda p: p, "no such file"),
    (lambda p: (p.mkdir(), p)[1], "no snapshots here"),
    (lambda p: (p.write_text("x"), p)[1], "unknown kind"),
])
def test_unusable_paths_get_one_error(tmp_path, make, match):
    path = make(tmp_path / "x")
    with pytest.raises(InputError, match=match):
        open_snapshots(path)


def test_unknown_femto_channel_and_bad_window(tmp_path):
    folder = write_femto(tmp_path / "B", [36000.0])
    with pytest.raises(InputError, match="channels horizontal, vertical"):
        open_snapshots(folder, channel="axial")
    with pytest.raises(InputError, match="window"):
        open_snapshots(folder, window=0.0)


def test_cut_stretch_keeps_snapshots_whole_and_cuts_streams_into_windows():
    x = np.arange(2560.0)
    assert len(cut_stretch(5.0, x, FS, 1.0, "s")) == 1  # 0.1 s: one snapshot
    long = np.arange(int(2.5 * FS), dtype=float)
    windows = cut_stretch(5.0, long, FS, 1.0, "r")
    assert [w.t for w in windows] == [5.0, 6.0]  # the 0.5 s remainder is dropped
    assert all(w.samples.size == int(FS) for w in windows)


def test_folder_of_npz_recordings_laid_end_to_end(tmp_path):
    folder = tmp_path / "rec"
    folder.mkdir()
    fs = 12000.0
    for i in range(3):
        x = np.sin(2 * np.pi * 100 * np.arange(int(2.0 * fs)) / fs) * (i + 1)
        np.savez(folder / f"run_{i}.npz", accel=x, sample_rate=fs, rpm=1800.0)
    (folder / "run_9.npz").write_bytes(b"not a zip")
    src = open_snapshots(folder)
    snaps = list(src)
    assert src.kind == "recordings" and src.rpm == 1800.0
    assert [round(s.t, 6) for s in snaps] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    assert_allclose([np.sqrt(np.mean(s.samples ** 2)) for s in snaps[::2]], np.array([1, 2, 3]) / math.sqrt(2),
                    rtol=1e-3)
    assert [n for n, _ in src.damaged] == ["run_9.npz"]
    # one file alone: its errors are errors
    with pytest.raises(InputError, match="not a readable"):
        list(open_snapshots(folder / "run_9.npz"))


def test_bag_chunks_with_gaps_are_snapshots(tmp_path):
    from bearing_common import topics
    from bearing_recordings.bag_write import BagWriter, time_msg

    fs, n = 10000.0, 500  # two 0.05 s chunks make a 0.1 s snapshot, one snapshot every 10 s
    with BagWriter(tmp_path / "bag") as bag:
        ts = bag.typestore
        Header, Chunk = ts.types["std_msgs/msg/Header"], ts.types[topics.VIBRATION.msgtype]
        bag.add_graph_topic(topics.VIBRATION)
        index = 0
        for k in range(4):
            for half in range(2):
                stamp_s = 100.0 + 10.0 * k + half * n / fs
                stamp = time_msg(ts, stamp_s)
                x = np.full(n, float(k + 1)) + np.sin(np.arange(n))
                msg = Chunk(header=Header(stamp=stamp, frame_id="drive_end"), sample_rate=fs,
                            first_sample_index=index, source="sensor", samples=x)
                bag.write(topics.qualified("", topics.VIBRATION), int(stamp_s * 1e9),
                          bag.serialize(msg, topics.VIBRATION.msgtype))
                index += n  # the sensor counts only its own samples: indices continue, stamps jump
    src = open_snapshots(tmp_path / "bag")
    snaps = list(src)
    assert src.kind == "rosbag2" and src.source == "sensor"
    assert [s.t for s in snaps] == pytest.approx([100.0, 110.0, 120.0, 130.0])
    assert all(s.samples.size == 2 * n for s in snaps)
    assert_allclose([s.samples.mean() for s in snaps], [1, 2, 3, 4], atol=0.01)
