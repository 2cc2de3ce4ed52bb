"""`make accuracy`: the accuracy report over every development recording, with what each block adds.

Runs :mod:`bearing_diagnoser.accuracy` on ``benchmarks/shared_data.yaml`` (the recordings in
../shared/data or $BEARING_DATA_DIR) with the decision and the textbook envelope baseline
(which gets the same long horizon), then the decision with one block changed at a time (no
long horizon, prewhitening off, fundamental only, no slip search, no dropping of ambiguous
lines, no shaft-harmonic mask, the speed as told without measuring it, the kurtogram's band
instead of the evidence-chosen one) and with the speed not told (estimated from the
vibration); then the detection-against-amplitude curves (:mod:`benchmarks.detection_curves`).
Writes ``out/accuracy.md`` and the curves' figure ``out/detection_curves.png``.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # `benchmarks` as a package

from bearing_common.states import FaultState  # noqa: E402
from bearing_diagnoser.accuracy import evaluate, load_manifest, markdown, run, totals  # noqa: E402
from benchmarks import detection_curves  # noqa: E402
from benchmarks.doc_tables import add_docs_option, nested, write_block  # noqa: E402

MANIFEST = ROOT / "benchmarks" / "shared_data.yaml"


def _spectral(**changes):
    return lambda cfg: replace(cfg, front_end=replace(cfg.front_end, **changes))


#: One block changed at a time (the decision's own settings otherwise).
VARIANTS = {
    "no long horizon (each window alone)": _spectral(accumulate=False),
    "no prewhitening": _spectral(prewhiten=False),
    "fundamental only (no harmonics, no sidebands)": _spectral(fundamental_only=True),
    "no slip search": _spectral(slip_search=False),
    "no ambiguity drop (a line two hypotheses could match counts for both)": _spectral(drop_ambiguous=False),
    "no shaft-harmonic mask": _spectral(mask_shaft=False),
    "speed as told (not measured)": _spectral(refine_speed=False),
    "kurtogram band (most impulsive) instead of the evidence-chosen one": _spectral(band_criterion="kurtogram"),
}


def _evaluate(task):
    record, method, variant, told = task
    return evaluate(record, method, speed_told=told, variant=VARIANTS[variant] if variant else None)


def block_table(records, jobs: int = 1) -> list[str]:
    """Per variant and data set: race faults right, ball records called a race fault, healthy records
    without alarm (alarm windows)."""
    datasets = _datasets(records)
    rows = ["| variant | " + " | ".join(f"{d}: race faults, ball called race, healthy clean (alarm windows)"
                                        for d in datasets) + " |", "|---|" + "---|" * len(datasets)]

    def line(name, results):
        t = totals(results)
        cells = [f"{t[d]['faults_right'] - t[d]['ball_right']}/{t[d]['faults'] - t[d]['ball']}, "
                 f"{t[d]['ball_called_race']}/{t[d]['ball']}, {t[d]['healthy_clean']}/{t[d]['healthy']} "
                 f"({t[d]['alarm_windows']})" if d in t else "-" for d in datasets]
        rows.append(f"| {name} | " + " | ".join(cells) + " |")

    runs = [("decision (all blocks)", "model", None, True), ("textbook envelope baseline", "envelope", None, True)]
    runs += [(f"decision, {name}", "model", name, True) for name in VARIANTS]
    runs.append(("decision, speed not told (estimated from the vibration)", "model", None, False))
    tasks = [(r, method, variant, told) for _, method, variant, told in runs for r in records]
    with ProcessPoolExecutor(jobs) as pool:
        results = list(pool.map(_evaluate, tasks, chunksize=4))
    for i, (name, *_) in enumerate(runs):
        line(name, results[i * len(records):(i + 1) * len(records)])
    return rows


def decision_times(results) -> list[str]:
    """Per data set and method: the time to the first decision of the right state, over the records
    diagnosed right (median and longest), with the window length it is counted in."""
    rows = ["| data set | method | time to decision: median | longest | records |", "|---|---|---|---|---|"]
    for dataset in _datasets([r.record for r in results]):
        for method in dict.fromkeys(r.method for r in results):
            t = [r.decided_at for r in results if r.record.dataset == dataset and r.method == method and r.correct
                 and r.record.truth != FaultState.NORMAL and r.decided_at is not None]
            if t:
                rows.append(f"| {dataset} | {method} | {np.median(t):.2f} s | {max(t):.2f} s | {len(t)} |")
    return rows


def _datasets(records) -> list[str]:
    return list(dict.fromkeys(r.dataset for r in records))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "out" / "accuracy.md")
    p.add_argument("--figure", type=Path, default=ROOT / "out" / "detection_curves.png")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="processes for the ablations and curves")
    add_docs_option(p, "docs/results.md")
    args = p.parse_args(argv)
    root = os.environ.get("BEARING_DATA_DIR")
    records = load_manifest(MANIFEST, root=root)
    missing = [r.path for r in records if not r.path.is_file()]
    if missing:
        print(f"accuracy: {len(missing)} recordings missing (first {missing[0]}); set BEARING_DATA_DIR",
              file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.ERROR)  # the runs' notes (assumed speed, ...) are in the table
    start = time.monotonic()
    results = run(records)
    text = ["# Accuracy on the development recordings", "", markdown(results), "## Time to decision", ""]
    text += decision_times(results)
    text += ["", "## What each block adds", ""]
    text += block_table(records, args.jobs)
    limits = detection_curves.curves(records, jobs=args.jobs)
    text += ["", "## Detection against fault amplitude", "", detection_curves.__doc__.split("\n\n", 1)[1], ""]
    text += detection_curves.markdown(limits)
    detection_curves.figure(limits, args.figure)
    text += ["", f"({len(records)} recordings, {time.monotonic() - start:.0f} s)"]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(text) + "\n")
    if args.docs:
        write_block(args.docs, "accuracy", nested("\n".join(text), 2), "make accuracy")
    print(f"accuracy: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
