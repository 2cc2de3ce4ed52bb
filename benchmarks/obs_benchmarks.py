"""Benchmarks of the observer core for ``make bench``: rows of (figure, value, unit).

* Steady-state observer throughput (samples/s on one core, and as a multiple of real
  time) at 48 kHz with the shipped ``sim_48k`` models, and at 1 MHz (the thesis' rate)
  with the same model structure re-labelled to 1 MHz (the cost per sample depends on the
  model order and the chunking, not on the coefficient values). Input: the model's
  response to its own fault train plus white noise, in 0.1 s chunks, adaptive
  phase/amplitude estimation on. Start-up (build + first chunk) is its own row.
* Identification time of one model (``sim_48k`` preprocessing, orders 8/8/0) on a
  synthetic record, excluding simulation.

Run: ``python -m bearing_observer.obs_benchmarks`` prints the rows as JSON lines.
"""

from __future__ import annotations

import copy
import json
import time

import numpy as np

from bearing_observer.impulse_trains import impulse_train
from bearing_observer.model_sets import load_model_set
from bearing_observer.observer import FaultObserver


def _signal(model, seconds: float, seed: int = 0) -> np.ndarray:
    fs = model.sample_rate
    n = int(seconds * fs)
    u = impulse_train(n, fs, model.fault_frequency, phase=0.5)
    y = model.simulate(u)
    rng = np.random.default_rng(seed)
    return y + 0.05 * np.std(y) * rng.standard_normal(n)


def observer_throughput(model, seconds: float = 2.0, chunk_seconds: float = 0.1,
                        poles="model", repeats: int = 15) -> float:
    """Steady-state observer throughput (samples per CPU-second), best of ``repeats``.

    Each repeat builds a fresh observer and feeds it one second of signal first (start-up:
    construction, the first estimate updates and the template cache; measured separately by
    :func:`observer_startup_time`), then times ``seconds`` more in ``chunk_seconds`` chunks.
    Run with ``OPENBLAS_NUM_THREADS=1`` for a single-core figure.
    """
    fs = model.sample_rate
    warm = int(fs)
    y = _signal(model, seconds + 1.0)
    step = max(1, int(chunk_seconds * fs))
    best = np.inf
    for _ in range(repeats):
        obs = FaultObserver(model, poles=poles)
        for i in range(0, warm, step):
            obs.process(y[i:min(i + step, warm)])
        t0 = time.process_time()  # CPU time of this process: per-core cost on a shared host
        for i in range(warm, y.size, step):
            obs.process(y[i:i + step])
        best = min(best, time.process_time() - t0)
    return (y.size - warm) / best


def observer_startup_time(model, poles="model", repeats: int = 5) -> float:
    """CPU time (s) to build an observer and process its first 0.1 s chunk (best of
    ``repeats``; the first estimate update and template are part of the first chunk)."""
    y = _signal(model, 0.1)
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        FaultObserver(model, poles=poles).process(y)
        best = min(best, time.process_time() - t0)
    return best


def _relabel(model, sample_rate: float):
    m = copy.deepcopy(model)
    m.sample_rate = float(sample_rate)
    m.pulse_width = 1.0 / sample_rate
    return m


def identification_time(seconds: float = 0.5) -> float:
    """Wall time (s) of :func:`identify_fault_model` on a synthetic 48 kHz OR record."""
    from bearing_observer.fault_identification import identify_fault_model

    model = load_model_set("sim_48k", 48000.0)["outer_race"]
    y = _signal(model, seconds, seed=1)
    t0 = time.perf_counter()
    identify_fault_model(y, 48000.0, model.rpm, "outer_race", model.bearing, refine_frequency=False)
    return time.perf_counter() - t0


def benchmark_rows() -> list[tuple[str, float, str]]:
    """All rows (the ``bench_*`` functions below, in order)."""
    return bench_observer_throughput() + bench_identification_time() + bench_observer_noise_gain()


def main() -> int:
    for fig, value, unit in benchmark_rows():
        print(json.dumps({"figure": fig, "value": value, "unit": unit}))
    return 0


# --- entry points collected by tools/bench.py (functions named bench_*) -----------------
def bench_observer_throughput() -> list[tuple[str, float, str]]:
    """Observer throughput at 48 kHz (both fault models, both pole choices) and 1 MHz."""
    models = load_model_set("sim_48k", 48000.0)
    rows = []
    for ft in ("outer_race", "inner_race"):
        for poles in ("model", "contracted"):
            sps = observer_throughput(models[ft], seconds=2.0, poles=poles)
            rows.append((f"observer {ft} 48 kHz (poles={poles}) throughput", sps,
                         "samples/s per core"))
            rows.append((f"observer {ft} 48 kHz (poles={poles}) speed", sps / 48000.0,
                         "x real time"))
        sps = observer_throughput(_relabel(models[ft], 1e6), seconds=0.5, chunk_seconds=0.01)
        rows.append((f"observer {ft} 1 MHz throughput", sps, "samples/s per core"))
        rows.append((f"observer {ft} 1 MHz speed", sps / 1e6, "x real time"))
        rows.append((f"observer {ft} 48 kHz start-up (build + first 0.1 s chunk)",
                     observer_startup_time(models[ft]), "s"))
    return rows


def bench_identification_time() -> list[tuple[str, float, str]]:
    """Wall time of one HW identification (0.5 s of 48 kHz OR data)."""
    return [("identification time, one model (0.5 s of 48 kHz data)", identification_time(), "s")]


def bench_observer_noise_gain() -> list[tuple[str, float, str]]:
    """Measured white-noise gain of the residual filter per pole choice."""
    m = load_model_set("sim_48k", 48000.0)["outer_race"]
    return [("observer noise gain, poles=model (L=0, default)", FaultObserver(m).noise_gain, "ratio"),
            ("observer noise gain, poles=contracted (0.95)",
             FaultObserver(m, poles="contracted").noise_gain, "ratio")]


if __name__ == "__main__":
    raise SystemExit(main())
