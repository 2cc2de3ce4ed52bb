"""`make false-alarms`: hours of healthy signal through the decision, as streams; alarms per hour.

The spectral decision states its false-alarm rate per hour of healthy operation
(``false_alarm_rate``, default 1e-3 per hour; :mod:`bearing_diagnoser.spectral.front_end`). This
runs healthy streams long enough to see it, through :class:`bearing_diagnoser.pipeline.MonitorPipeline`
(the node's own sessions) with the node's defaults:

* the simulator (a 6205 at 1800 rpm, 12 kHz, no defect) with the thesis' sensor noise,
  4.5e-3 (m/s²)/√Hz: one noise-free run of ``BASE_S`` seconds, each pass with fresh noise
  (the simulator's noise is the only random part of its output), the speed known to a
  tachometer's 2 %;
* every healthy development recording (CWRU 097 at 48 kHz and decimated to 12 kHz, HIT-SM
  ``Normal_600/900/1200`` at 51.2 kHz) looped, with its own statement of the speed (CWRU's
  measured one; HIT-SM's nominal label, a nameplate's 10 %).

Joins, as a real stream has them: the simulator's passes follow each other without a gap in
the sample index (one sensor, fresh noise throughout; the join is a step in the signal). A
recording's passes are separated by a gap of ``GAP_S`` (a sensor that reconnects: the stamps
jump), which restarts the decision's evidence, as any gap does. Played back to back without
it, the long horizon would average the same windows again and again: their noise is then
not independent, which the long horizon's null distribution assumes (looped that way, HIT-SM
``Normal_1200`` is called BALL after 14 s, when the horizon outgrows the 5.1 s record). Each
pass of a recording therefore repeats the recording's own decisions.

Reported per stream: hours, windows, windows not diagnosed (and why), windows whose
published state was not NORMAL, and alarms (changes of the published state from NORMAL to
anything else) per hour.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # `benchmarks` as a package

from bearing_common.bearings import load_bearing  # noqa: E402
from bearing_common.states import FaultState  # noqa: E402
from bearing_diagnoser.accuracy import load_manifest  # noqa: E402
from bearing_diagnoser.front_ends import config_for  # noqa: E402
from bearing_diagnoser.pipeline import MonitorPipeline  # noqa: E402
from bearing_recordings.recording import MEASURED_RPM_TOLERANCE  # noqa: E402
from benchmarks.doc_tables import add_docs_option, nested, write_block  # noqa: E402
from benchmarks.evaluation import STEADY_RATE, STEADY_RPM, steady_run  # noqa: E402

MANIFEST = ROOT / "benchmarks" / "shared_data.yaml"
#: The simulated stream (at evaluation.STEADY_RATE, STEADY_RPM): base run (s), noise density ((m/s²)/√Hz).
BASE_S, SIM_NOISE = 60.0, 4.5e-3
#: Chunk length fed to the sessions (s); the decision does not depend on it.
CHUNK_S = 1.0
#: Gap between two passes of a recording (s).
GAP_S = 1.0
#: Longest piece of the simulated stream run by one process (h).
PIECE_H = 1.0


@dataclass
class StreamResult:
    name: str
    hours: float
    windows: int
    not_diagnosed: Counter
    alarm_windows: int
    alarms: int
    cpu_s: float

    @property
    def per_hour(self) -> float:
        return self.alarms / self.hours if self.hours else float("nan")


def _passes(name: str, seed: int):
    """(sample rate, rpm, rpm tolerance, bearing, gap between passes (samples), generator of the stream's
    passes) of stream ``name``."""
    if name == "simulator":
        base = steady_run(FaultState.NORMAL, BASE_S)
        sigma = SIM_NOISE * np.sqrt(STEADY_RATE / 2)
        rng = np.random.default_rng(seed)
        return STEADY_RATE, STEADY_RPM, MEASURED_RPM_TOLERANCE, load_bearing("6205"), 0, (
            base + sigma * rng.standard_normal(base.size) for _ in iter(int, 1))
    entry = next(e for e in load_manifest(MANIFEST) if f"{e.dataset} {e.name}" == name)
    rec = entry.load()
    return rec.sample_rate, rec.rpm, rec.rpm_tolerance, load_bearing(entry.bearing), int(GAP_S * rec.sample_rate), (
        rec.accel for _ in iter(int, 1))


def run_stream(args) -> StreamResult:
    """Stream ``name`` for ``hours`` of signal (seed ``seed`` for the simulator's noise)."""
    name, hours, seed = args
    fs, rpm, tolerance, bearing, gap, passes = _passes(name, seed)
    pipeline = MonitorPipeline(bearing, "none", config_for("none"), rpm, observed=False,
                               streams=(FaultState.OUTER_RACE,), rpm_tolerance=tolerance)
    total = int(hours * 3600 * fs)
    chunk = int(CHUNK_S * fs)
    index, played, windows, alarm_windows, alarms, previous = 0, 0, 0, 0, 0, FaultState.NORMAL
    not_diagnosed: Counter = Counter()
    start = time.process_time()
    for x in passes:
        x = x[: total - played]
        for i in range(0, x.size, chunk):
            pipeline.feed(index + i, fs, x[i:i + chunk], "measurement")
        index += x.size + gap
        played += x.size
        for d in pipeline.decisions:
            windows += 1
            if not d.diagnosed:
                not_diagnosed[d.not_diagnosed.kind] += 1
                continue
            alarm_windows += d.state != FaultState.NORMAL
            alarms += d.state != FaultState.NORMAL and previous == FaultState.NORMAL
            previous = d.state
        pipeline.decisions.clear()  # hours of windows: count them, do not keep them
        if played >= total:
            break
    return StreamResult(name, played / fs / 3600, windows, not_diagnosed, alarm_windows, alarms,
                        time.process_time() - start)


def streams(hours: float, real_hours: float) -> list[tuple[str, float, int]]:
    """The streams and their lengths: the simulator's ``hours`` in pieces of at most ``PIECE_H``
    (each its own noise seed: independent sensors, spread over the cores), each healthy
    recording ``real_hours``."""
    healthy = [f"{e.dataset} {e.name}" for e in load_manifest(MANIFEST) if e.truth == FaultState.NORMAL]
    pieces = max(1, math.ceil(hours / PIECE_H))
    return [("simulator", hours / pieces, seed) for seed in range(1, pieces + 1)] + \
        [(h, real_hours, 0) for h in healthy]


def markdown(results: list[StreamResult]) -> list[str]:
    merged: dict = {}
    for r in results:
        m = merged.setdefault(r.name, StreamResult(r.name, 0.0, 0, Counter(), 0, 0, 0.0))
        m.hours += r.hours
        m.windows += r.windows
        m.not_diagnosed += r.not_diagnosed
        m.alarm_windows += r.alarm_windows
        m.alarms += r.alarms
        m.cpu_s += r.cpu_s
    lines = ["| healthy stream | hours | windows | not diagnosed | windows not NORMAL | alarms | alarms per hour |",
             "|---|---|---|---|---|---|---|"]
    for m in list(merged.values()) + [_total(list(merged.values()))]:
        why = ", ".join(f"{n} ({k})" for k, n in m.not_diagnosed.items()) or "0"
        lines.append(f"| {m.name} | {m.hours:.2f} | {m.windows} | {why} | {m.alarm_windows} | {m.alarms} | "
                     f"{m.per_hour:.3g} |")
    return lines


def _total(rows: list[StreamResult]) -> StreamResult:
    return StreamResult("**all**", sum(r.hours for r in rows), sum(r.windows for r in rows),
                        sum((r.not_diagnosed for r in rows), Counter()), sum(r.alarm_windows for r in rows),
                        sum(r.alarms for r in rows), sum(r.cpu_s for r in rows))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--hours", type=float, default=10.0, help="hours of the simulated stream (default 10)")
    p.add_argument("--real-hours", type=float, default=0.2, help="hours of each healthy recording, looped")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--out", type=Path, default=ROOT / "out" / "false_alarms.md")
    add_docs_option(p, "docs/results.md")
    args = p.parse_args(argv)
    missing = [e.path for e in load_manifest(MANIFEST) if e.truth == FaultState.NORMAL and not e.path.is_file()]
    if missing:
        print(f"false-alarms: {len(missing)} recordings missing (first {missing[0]}); set BEARING_DATA_DIR",
              file=sys.stderr)
        return 2
    wall = time.monotonic()
    results = []
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        for r in as_completed([pool.submit(run_stream, s) for s in streams(args.hours, args.real_hours)]):
            results.append(r.result())
            print(markdown([results[-1]])[2], flush=True)  # progress: the stream's own row
    text = ["# False alarms on healthy streams", "",
            "The node's defaults (false_alarm_rate 1e-3 per hour); see benchmarks/false_alarms.py.", ""]
    text += markdown(results)
    text += ["", f"({sum(r.cpu_s for r in results):.0f} s of CPU, {time.monotonic() - wall:.0f} s wall)"]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(text) + "\n")
    if args.docs:
        write_block(args.docs, "false-alarms", nested("\n".join(text), 2), "make false-alarms")
    print("\n".join(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
