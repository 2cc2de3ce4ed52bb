"""`make bench`: run every package's benchmarks and write a Markdown table.

Each benchmark module exposes ``bench_*()`` functions returning rows
``(figure, value, unit)``. Rows go to ``--out`` (default out/bench.md) as
| figure | value | unit | machine |. A failing benchmark is reported in the
table and makes the exit code non-zero; the others still run.
"""

import argparse
import importlib
import inspect
import os
import pathlib
import platform
import sys
import time
import traceback

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))  # `benchmarks` as a package
from benchmarks.doc_tables import add_docs_option, write_block  # noqa: E402

# Per-core figures: one BLAS thread (numpy would otherwise spread small solves over both
# cores, and process CPU time would count them twice). Set before the benchmark modules
# import numpy (they are imported in main()).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

MODULES = (
    "benchmarks.sim_benchmarks",
    "benchmarks.obs_benchmarks",
    "benchmarks.diag_benchmarks",
    "benchmarks.decision_cost",
    "benchmarks.batch_benchmarks",
    "benchmarks.bag_benchmarks",
    "benchmarks.graph_benchmarks",
    "benchmarks.fleet_benchmarks",
    "benchmarks.message_benchmarks",
    "benchmarks.discovery_benchmarks",
)


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def fmt(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/bench.md"))
    parser.add_argument("--only", help="substring of the benchmark functions to run")
    add_docs_option(parser, "docs/benchmarks.md")
    args = parser.parse_args(argv)
    host = machine()
    lines = ["| figure | value | unit | machine |", "|---|---|---|---|"]
    failed = 0
    for name in MODULES:
        try:
            module = importlib.import_module(name)
        except Exception:  # reported like a failing benchmark; the other modules still run
            failed += 1
            traceback.print_exc()
            lines.append(f"| {name} | FAILED (import) | - | {host} |")
            continue
        for fname, func in inspect.getmembers(module, inspect.isfunction):
            if not fname.startswith("bench_") or func.__module__ != name:
                continue
            if args.only and args.only not in fname:
                continue
            print(f"[bench] {name}.{fname} ...", flush=True)
            start = time.monotonic()
            try:
                rows = func()
            except Exception:  # a broken benchmark is reported, not fatal to the others
                failed += 1
                traceback.print_exc()
                lines.append(f"| {name}.{fname} | FAILED | - | {host} |")
                continue
            for figure, value, unit in rows:
                lines.append(f"| {figure} | {fmt(value)} | {unit} | {host} |")
                print(f"[bench]   {figure}: {fmt(value)} {unit}", flush=True)
            print(f"[bench]   ({time.monotonic() - start:.1f} s)", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("# Benchmarks\n\n" + "\n".join(lines) + "\n")
    if args.docs and not args.only:  # a partial run is not the table
        write_block(args.docs, "bench", "\n".join(lines), "make bench")
    print(f"[bench] wrote {args.out}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
