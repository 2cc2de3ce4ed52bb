"""Offline at archive scale (issue 20 item 4): rows of (figure, value, unit), as ratios measured in one run.

* :func:`bench_offline_batch` — ``bearing-diagnose`` over the 12 kHz CWRU records (each twice,
  as copies: six files) in one process with ``--jobs 1`` and ``--jobs 2``, default decision:
  seconds of signal per second of wall time times jobs, and per CPU second of the process and
  its workers (start-up included; the CPU figure is the one other users' load disturbs least), and whether
  every file's lines equal those of its own single-file run.
* :func:`bench_cli_startup` — wall time of each CLI's ``--help`` (interpreter, parser, exit)
  and of importing everything a diagnosis run uses, as ratios to ``python -c "import numpy,
  scipy.signal"`` timed alternately with them (median of several runs each).

``python -m benchmarks.batch_benchmarks`` prints the rows. The recordings are found in
../shared/data or ``$BEARING_DATA_DIR``; without them the batch rows say so.
"""

from __future__ import annotations

import json
import os
import pathlib
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parent.parent
CWRU_12K = ("105_IR007_0hp_DE12k.mat", "118_B007_0hp_DE12k.mat", "130_OR007at6_0hp_DE12k.mat")
COPIES = 2
CLIS = {  # executable: module whose main() it runs
    "bearing-diagnose": "bearing_diagnoser.diagnose_cli",
    "bearing-accuracy": "bearing_diagnoser.accuracy_cli",
    "bearing-sim": "bearing_sim.sim_cli",
    "bearing-identify": "bearing_observer.identify_cli",
    "bearing-bag": "bearing_recordings.bag_cli",
    "bearing-graph": "bearing_bringup.graph_cli",
    "bearing-fleet": "bearing_fleet.fleet_cli",
}
REFERENCE = [sys.executable, "-c", "import numpy, scipy.signal"]
REPEATS = 5


def _env() -> dict:
    """This checkout's packages first on the path (whatever is installed), one BLAS thread."""
    src = os.pathsep.join(str(p) for p in sorted((REPO / "src").iterdir()) if p.is_dir())
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")])))
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env.setdefault(var, "1")
    return env


def _wall(cmd: list[str], env: dict) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def _diagnose(paths, env: dict, *options: str) -> tuple[float, float, list[dict]]:
    """(wall s, CPU s of the process and its workers, JSON lines) of one ``bearing-diagnose`` run."""
    cmd = [sys.executable, "-m", CLIS["bearing-diagnose"], *map(str, paths), "--sample-rate", "12000", *options]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return wall, cpu, [json.loads(line) for line in out.splitlines()]


def _data_dir() -> pathlib.Path:
    return pathlib.Path(os.environ.get("BEARING_DATA_DIR", REPO.parent / "shared" / "data"))


def bench_offline_batch() -> list[tuple[str, object, str]]:
    """Rows of the batch runs (module docstring)."""
    sources = [_data_dir() / "cwru" / name for name in CWRU_12K]
    if not all(p.is_file() for p in sources):
        return [("offline batch (CWRU 12 kHz records)", "skipped", f"recordings not in {sources[0].parent}")]
    from bearing_recordings.load import load_recording

    env = _env()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        files = []
        for k in range(COPIES):
            for p in sources:
                files.append(pathlib.Path(tmp) / f"{p.stem}-{k}{p.suffix}")
                shutil.copyfile(p, files[-1])
        signal_s = sum(load_recording(f, sample_rate=12000.0).duration for f in files)
        alone = {}
        for p in sources:  # each record's own single-file run
            alone[p.stem] = _diagnose([p], env)[2]
        lines = {}
        for jobs in (1, 2):
            wall, cpu, lines[jobs] = _diagnose(files, env, "--jobs", str(jobs))
            label = f"offline batch, {len(files)} CWRU 12 kHz files ({signal_s:.0f} s), --jobs {jobs}"
            rows.append((label, round(signal_s / wall / jobs, 1), "x real time per core (wall x jobs, with start-up)"))
            rows.append((label, round(signal_s / cpu, 1), "x real time per CPU second (all processes, with start-up)"))
        by_file = {}  # (record, copy) -> its lines in the --jobs 1 batch, without "file"
        for line in lines[1]:
            stem, copy = pathlib.Path(line["file"]).stem.rsplit("-", 1)
            by_file.setdefault((stem, copy), []).append({k: v for k, v in line.items() if k != "file"})
        same = len(by_file) == len(files) and all(v == alone[stem] for (stem, _), v in by_file.items())
        jobs_same = lines[2] == lines[1]
        rows.append(("offline batch: every file's lines equal its single-file run", str(same).lower(), "yes/no"))
        rows.append(("offline batch: --jobs 2 lines equal --jobs 1", str(jobs_same).lower(), "yes/no"))
    return rows


def bench_cli_startup() -> list[tuple[str, object, str]]:
    """Rows of the start-up ratios (module docstring)."""
    env = _env()
    commands = {name: [sys.executable, "-m", module, "--help"] for name, module in CLIS.items()}
    commands["bearing-diagnose run's imports (the diagnosis, numba kernels included)"] = [
        sys.executable, "-c", "import bearing_diagnoser.recording_diagnosis, bearing_recordings.load"]
    ref, times = [], {name: [] for name in commands}
    _wall(REFERENCE, env)  # caches warm for everyone
    for _ in range(REPEATS):
        ref.append(_wall(REFERENCE, env))
        for name, cmd in commands.items():
            times[name].append(_wall(cmd, env))
    base = statistics.median(ref)
    rows = [("start-up reference: python -c 'import numpy, scipy.signal'", round(base, 3), "s")]
    for name, t in times.items():
        label = f"start-up {name} --help" if name in CLIS else f"start-up {name}"
        rows.append((label, round(statistics.median(t) / base, 2), "x the reference (same run)"))
    return rows


if __name__ == "__main__":
    for row in bench_cli_startup() + bench_offline_batch():
        print(*row, sep=" | ")
