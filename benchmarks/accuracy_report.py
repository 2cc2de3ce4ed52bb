"""`make accuracy`: the accuracy report over every development recording, with what each block adds.

Runs :mod:`bearing_diagnoser.accuracy` on ``benchmarks/shared_data.yaml`` (the recordings in
../shared/data or $BEARING_DATA_DIR) with the decision and the textbook envelope baseline,
then the decision with one block changed at a time (prewhitening off, fundamental only, no
slip search, no dropping of ambiguous lines, no shaft-harmonic mask, the speed as told
without refinement, the kurtogram's band instead of the evidence-chosen one) and with the
speed not told (estimated from the vibration), and writes ``out/accuracy.md``.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # `benchmarks` as a package

from bearing_diagnoser.accuracy import evaluate, load_manifest, markdown, run, totals  # noqa: E402

MANIFEST = ROOT / "benchmarks" / "shared_data.yaml"


def _spectral(**changes):
    return lambda cfg: replace(cfg, front_end=replace(cfg.front_end, **changes))


#: One block changed at a time (the decision's own settings otherwise).
VARIANTS = {
    "no prewhitening": _spectral(prewhiten=False),
    "fundamental only (no harmonics, no sidebands)": _spectral(fundamental_only=True),
    "no slip search": _spectral(slip_search=False),
    "no ambiguity drop (a line two hypotheses could match counts for both)": _spectral(drop_ambiguous=False),
    "no shaft-harmonic mask": _spectral(mask_shaft=False),
    "speed as told (no refinement)": _spectral(refine_speed=False),
    "kurtogram band (most impulsive) instead of the evidence-chosen one": _spectral(band_criterion="kurtogram"),
}


def block_table(records) -> list[str]:
    """Per variant and data set: faults right, healthy records without alarm, alarm windows."""
    rows = ["| variant | " + " | ".join(f"{d}: faults / healthy clean (alarm windows)" for d in _datasets(records))
            + " |", "|---|" + "---|" * len(_datasets(records))]

    def line(name, results):
        t = totals(results)
        cells = [f"{t[d]['faults_right']}/{t[d]['faults']} / {t[d]['healthy_clean']}/{t[d]['healthy']} "
                 f"({t[d]['alarm_windows']})" if d in t else "-" for d in _datasets(records)]
        rows.append(f"| {name} | " + " | ".join(cells) + " |")

    line("decision (all blocks)", [evaluate(r) for r in records])
    line("textbook envelope baseline", [evaluate(r, "envelope") for r in records])
    for name, variant in VARIANTS.items():
        line(f"decision, {name}", [evaluate(r, variant=variant) for r in records])
    line("decision, speed not told (estimated from the vibration)", [evaluate(r, speed_told=False) for r in records])
    return rows


def _datasets(records) -> list[str]:
    return list(dict.fromkeys(r.dataset for r in records))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "out" / "accuracy.md")
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
    text = ["# Accuracy on the development recordings", "", markdown(results), "## What each block adds", ""]
    text += block_table(records)
    text += ["", f"({len(records)} recordings, {time.monotonic() - start:.0f} s)"]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(text) + "\n")
    print(f"accuracy: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
