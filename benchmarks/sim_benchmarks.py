"""Simulator figures for ``make bench``: rows of (figure, value, unit).

    python -m bearing_sim.sim_benchmarks [--quick]

* first-call time: importing the compiled functions (numba, ``cache=True``: a
  compile on the very first run, a cache load after) plus the static
  equilibrium; excluded from the real-time factors;
* real-time factor = simulated seconds per wall-clock second (median of several
  short runs, one process, one core) per case at 48 kHz and 1 MHz output, and
  the same per CPU second (robust when other processes share the machine);
* cost of one right-hand-side evaluation (us), integrator steps per simulated second;
* peak memory: process peak RSS, and the peak of Python-level allocations
  while streaming (bounded: independent of the simulated duration).
"""

import argparse
import resource
import statistics
import sys
import time
import tracemalloc

import numpy as np

from bearing_common.states import FaultState
from bearing_sim.simulator import SimulationConfig, Simulator

CASES = (("normal", FaultState.NORMAL), ("or", FaultState.OUTER_RACE), ("ir", FaultState.INNER_RACE))


def _run(state, sample_rate, seconds, chunk=0.05):
    sim = Simulator(SimulationConfig(sample_rate=sample_rate), [(state, seconds)])
    n = max(1, int(round(chunk * sample_rate)))
    w0, c0 = time.perf_counter(), time.process_time()
    while not sim.finished:
        sim.advance(n)
    return time.perf_counter() - w0, time.process_time() - c0, sim.stats


def first_call_time():
    """Seconds for the first tiny run in this process (compile or cache load)."""
    t0 = time.perf_counter()
    _run(FaultState.OUTER_RACE, 48000.0, 0.002)
    return time.perf_counter() - t0


def rhs_cost_us(n=200000):
    """Mean cost of one compiled right-hand-side evaluation (us) near equilibrium."""
    from numba import njit

    from bearing_sim.model_parameters import ModelParameters
    from bearing_sim.rotor_rhs import NSTATE, WORK_LEN, make_rhs_args, rhs, static_equilibrium

    params = ModelParameters.create()
    p, ct0, st0 = make_rhs_args(params)
    y = np.zeros(NSTATE)
    y[:29] = static_equilibrium(params)
    z = np.zeros(9)

    @njit
    def loop(n, y, p, ct0, st0, z, dy, w):
        acc = 0.0
        for k in range(n):
            y[40] = 1e-9 * (k % 100)
            rhs(k * 1e-6, y, p, ct0, st0, z, z, dy, w)
            acc += dy[32]
        return acc

    dy, w = np.zeros(NSTATE), np.zeros(WORK_LEN)
    loop(10, y, p, ct0, st0, z, dy, w)
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        loop(n, y, p, ct0, st0, z, dy, w)
        best = min(best, time.perf_counter() - t0)
    return best / n * 1e6


def bench_simulator(seconds=0.2, repeats=5, rates=(48000.0, 1.0e6)):
    """All rows as a list of (figure, value, unit)."""
    rows = [("first-call (compile or cache load) time", first_call_time(), "s")]
    rows.append(("rhs evaluation cost (best of 3)", rhs_cost_us(), "us"))
    for fs in rates:
        for name, state in CASES:
            walls, cpus, stats = [], [], None
            for _ in range(repeats):
                w, c, stats = _run(state, fs, seconds)
                walls.append(w)
                cpus.append(c)
            label = f"{name} @ {fs / 1000:g} kHz"
            rows.append((f"real-time factor {label} (wall, median of {repeats})",
                         seconds / statistics.median(walls), "x"))
            rows.append((f"real-time factor {label} (cpu, median of {repeats})",
                         seconds / statistics.median(cpus), "x"))
            if fs == rates[0]:
                rows.append((f"integrator steps per simulated second, {name}", stats["steps"] / seconds, "1/s"))
                rows.append((f"rhs evaluations per simulated second, {name}", stats["rhs_evals"] / seconds, "1/s"))
    tracemalloc.start()
    _run(FaultState.OUTER_RACE, 48000.0, 2 * seconds)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rows.append((f"peak Python allocations while streaming {2 * seconds:g} s OR @ 48 kHz", peak / 2**20, "MiB"))
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    rows.append(("peak resident memory of the benchmark process", rss, "MiB"))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(prog="sim-benchmarks", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.1 s runs, 1 repeat, 48 kHz only")
    args = ap.parse_args(argv)
    if args.quick:
        rows = bench_simulator(0.1, 1, (48000.0,))
    else:
        rows = bench_simulator()
    width = max(len(r[0]) for r in rows)
    for fig, val, unit in rows:
        print(f"{fig:<{width}}  {val:12.4g} {unit}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
