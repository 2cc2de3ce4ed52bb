"""Benchmarks of the bag tools: rows of (figure, value, unit) for ``make bench``.

* :func:`bench_bag_throughput` — writing (``bearing-bag`` writer, rosbags) and reading
  (``bearing_recordings.bag_read.read_bag``) 48 kHz vibration bags, MCAP and sqlite3:
  messages/s and MB/s of CDR payload.
* :func:`bench_bag_diagnose_speed` — ``bearing-diagnose BAG_DIR`` (load + offline
  pipeline, in process) on a simulator OR-IR bag and, when the CWRU recordings are
  present, on a ``from-mat`` bag of record 105: seconds of signal per second of wall
  time (multiple of real time).

``python -m bearing_bringup.bag_benchmarks`` prints the rows.
"""

from __future__ import annotations

import os
import pathlib
import tempfile
import time

import numpy as np

#: Signal (s) and rate (Hz) of the throughput bags: 1000 chunks of 480 samples.
THROUGHPUT_SECONDS = 10.0
THROUGHPUT_RATE = 48000.0


def _payload_bytes(bag_dir: pathlib.Path) -> int:
    return sum(f.stat().st_size for f in bag_dir.iterdir() if f.suffix in (".mcap", ".db3"))


def bench_bag_throughput(seconds: float = THROUGHPUT_SECONDS, rate: float = THROUGHPUT_RATE) -> list:
    """Write and read back a vibration bag; rows per storage."""
    from bearing_recordings.bag_read import read_bag
    from bearing_recordings.bag_write import write_signal_bag
    rng = np.random.default_rng(0)
    x = rng.standard_normal(int(seconds * rate))
    rows = []
    with tempfile.TemporaryDirectory(prefix="bag_bench_") as tmp:
        for storage in ("mcap", "sqlite3"):
            out = pathlib.Path(tmp) / storage
            t0 = time.perf_counter()
            chunks = write_signal_bag(out, x, rate, 1800.0, "simulator", storage=storage)
            t_write = time.perf_counter() - t0
            size_mb = _payload_bytes(out) / 1e6
            t0 = time.perf_counter()
            contents = read_bag(out)
            t_read = time.perf_counter() - t0
            assert len(contents.chunks) == chunks
            msgs = 2 * chunks  # chunks + shaft speeds
            rows += [(f"bag write ({storage}, {rate / 1000:g} kHz chunks of 10 ms)", round(msgs / t_write),
                      "messages/s"),
                     (f"bag write ({storage})", round(size_mb / t_write, 1), "MB/s"),
                     (f"bag write ({storage})", round(seconds / t_write, 1), "x real time"),
                     (f"bag read ({storage}, bag_files.read_bag)", round(msgs / t_read), "messages/s"),
                     (f"bag read ({storage})", round(size_mb / t_read, 1), "MB/s"),
                     (f"bag read ({storage})", round(seconds / t_read, 1), "x real time")]
    return rows


def _cwru_105() -> pathlib.Path | None:
    root = pathlib.Path(__file__).resolve().parents[3]
    d = pathlib.Path(os.environ.get("BEARING_CWRU_DIR", root.parent / "shared" / "data" / "cwru"))
    p = d / "105_IR007_0hp_DE12k.mat"
    return p if p.is_file() else None


def _diagnose_speed(bag: pathlib.Path, label: str) -> list:
    from bearing_diagnoser.recording_diagnosis import diagnose_recording
    from bearing_recordings.load import load_recording
    t0 = time.perf_counter()
    rec = load_recording(bag)
    t_load = time.perf_counter() - t0
    diagnose_recording(rec)
    t_all = time.perf_counter() - t0
    return [(f"bearing-diagnose BAG_DIR ({label}, {rec.duration:.1f} s signal)", round(rec.duration / t_all, 2),
             "x real time"),
            (f"bag loading share ({label})", round(t_load / t_all, 3), "fraction of the run")]


def bench_bag_diagnose_speed() -> list:
    """Replay speed of the offline pipeline on bags, as a multiple of real time."""
    from bearing_recordings.bag_write import recording_to_bag, write_signal_bag
    from bearing_recordings.mat_files import load_mat
    rows = []
    with tempfile.TemporaryDirectory(prefix="bag_bench_") as tmp:
        try:
            from .evaluation import simulate_case
            rec = simulate_case("or-ir", segment_s=1.0)
            sim_bag = pathlib.Path(tmp) / "sim"
            write_signal_bag(sim_bag, rec.accel, rec.sample_rate, rec.rpm, "simulator")
            rows += _diagnose_speed(sim_bag, f"simulator or-ir, {rec.sample_rate / 1000:g} kHz")
        except ImportError as exc:
            rows.append(("bearing-diagnose BAG_DIR (simulator)", float("nan"), f"not available: {exc}"))
        mat = _cwru_105()
        if mat is not None:
            cwru_bag = pathlib.Path(tmp) / "cwru"
            recording_to_bag(load_mat(mat, 12000.0), cwru_bag)
            rows += _diagnose_speed(cwru_bag, "CWRU 105 IR, 12 kHz")
    return rows


def main() -> int:
    for func in (bench_bag_throughput, bench_bag_diagnose_speed):
        for figure, value, unit in func():
            print(f"{figure}: {value} {unit}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
