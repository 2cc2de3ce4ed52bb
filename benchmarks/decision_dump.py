"""Every window decision on the thesis cases and the development recordings, to check that a change keeps them.

``python -m benchmarks.decision_dump dump OUT.pkl [SIM_DIR]`` writes, per run, each window's
(window end, label, published state, confidence, onset, changed, why it was not diagnosed
("kind: reason") or else its detail, scores) and the
JSON lines ``bearing-diagnose`` prints: the
thesis' eight cases from the simulator (48 kHz noise-free, with sensor noise, at 1500 rpm,
and 12 kHz with noise) and every recording of ``shared_data.yaml``, each with the model
and the envelope method. ``python -m benchmarks.decision_dump compare BEFORE.pkl AFTER.pkl``
exits 1 when any label, state, change flag, detail or JSON line differs, and reports how many scores
are bit-identical and the largest relative difference of the others. The simulator's output
is the same in every process of one build, but differs by up to its tolerance (1e-4) between
builds, and once between the first run after a build and later ones: to compare the decision
across builds (before and after a change), give both dumps the same SIM_DIR, which keeps the
simulated cases as .npz files (written by the first dump that needs them, read by the others).
"""

from __future__ import annotations

import math
import pathlib
import pickle
import sys

import numpy as np

from bearing_common.bearings import load_bearing
from bearing_diagnoser.accuracy import load_manifest
from bearing_diagnoser.recording_diagnosis import diagnose_recording
from bearing_recordings.recording import Recording

from .evaluation import THESIS_CASES, simulate_case

MANIFEST = pathlib.Path(__file__).resolve().parent / "shared_data.yaml"
SIMULATED = ((1800.0, 0.0, 48000.0), (1800.0, 4.5e-3, 48000.0), (1500.0, 4.5e-3, 48000.0), (1800.0, 4.5e-3, 12000.0))
METHODS = ("model", "envelope")


def _windows(result) -> list[tuple]:
    return [(round(d.window_end, 9), d.label.name, d.state.name, d.confidence, d.onset, d.changed,
             str(d.not_diagnosed) if d.not_diagnosed else d.detail, d.scores.as_dict())
            for d in result.decisions]


def _run(result) -> dict:
    """A run's windows and the JSON lines ``bearing-diagnose`` prints for it."""
    return {"windows": _windows(result), "segments": [s.to_json() for s in result.segments]}


def _simulated(name: str, rpm: float, noise: float, fs: float, sim_dir: pathlib.Path | None) -> Recording:
    """Thesis case ``name`` simulated, or read from ``sim_dir`` where an earlier dump kept it."""
    if sim_dir is None:
        return simulate_case(name, rpm, noise, sample_rate=fs)
    path = sim_dir / f"{name}_{rpm:g}rpm_{noise:g}_{fs:g}Hz.npz"
    if not path.is_file():
        rec = simulate_case(name, rpm, noise, sample_rate=fs)
        sim_dir.mkdir(parents=True, exist_ok=True)
        np.savez(path, accel=rec.accel, sample_rate=rec.sample_rate, rpm=rec.rpm, truth=rec.truth)
    with np.load(path) as f:
        return Recording(f["accel"], float(f["sample_rate"]), float(f["rpm"]), "simulator", f["truth"], "accel",
                         f"sim:{name}")


def dump(sim_dir: pathlib.Path | None = None) -> dict:
    """{run: windows, or the error message}, for every run named in the module docstring."""
    out: dict = {}
    for name in THESIS_CASES:
        for rpm, noise, fs in SIMULATED:
            rec = _simulated(name, rpm, noise, fs, sim_dir)
            for method in METHODS:
                out[("sim", name, rpm, noise, fs, method)] = _run(diagnose_recording(rec, method=method))
    for entry in load_manifest(MANIFEST):
        rec = entry.load()
        for method in METHODS:
            try:
                out[("rec", entry.dataset, entry.name, method)] = _run(
                    diagnose_recording(rec, method=method, rpm=rec.rpm, bearing=load_bearing(entry.bearing)))
            except Exception as exc:  # an input refused before is refused after, with the same reason
                out[("rec", entry.dataset, entry.name, method)] = repr(exc)
    return out


def compare(before: dict, after: dict) -> int:
    """Print the differences; return the number of windows whose decision differs."""
    if before.keys() != after.keys():
        print("runs differ:", set(before) ^ set(after))
        return 1
    differing, windows, same, scores, worst = 0, 0, 0, 0, (0.0, None)
    for run, a in before.items():
        b = after[run]
        if isinstance(a, str) or isinstance(b, str) or len(a["windows"]) != len(b["windows"]):
            differing += int(a != b)
            continue
        if a["segments"] != b["segments"]:
            differing += 1
            print("segments differ:", run)
        a, b = a["windows"], b["windows"]
        for x, y in zip(a, b):
            windows += 1
            if x[:3] != y[:3] or x[5:7] != y[5:7] or x[7].keys() != y[7].keys():
                differing += 1
                print("differs:", run, x[:3], y[:3])
            for key, u, v in [("confidence", x[3], y[3]), ("onset", x[4], y[4])] + \
                    [(k, x[7][k], y[7].get(k)) for k in x[7]]:
                scores += 1
                if u == v or (isinstance(u, float) and math.isnan(u) and v is not None and math.isnan(v)):
                    same += 1
                elif v is not None:
                    rel = abs(u - v) / max(abs(u), abs(v))
                    worst = max(worst, (rel, (run, x[0], key)), key=lambda w: w[0])
    print(f"{len(before)} runs, {windows} windows, {differing} with a different decision; {same} of {scores} "
          f"scores bit-identical, largest relative difference of the others {worst[0]:.2g} ({worst[1]})")
    return differing


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["dump"] and len(argv) in (2, 3):
        pathlib.Path(argv[1]).write_bytes(pickle.dumps(dump(pathlib.Path(argv[2]) if len(argv) == 3 else None)))
        return 0
    if argv[:1] == ["compare"] and len(argv) == 3:
        return 1 if compare(*(pickle.loads(pathlib.Path(p).read_bytes()) for p in argv[1:])) else 0
    print(__doc__)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
