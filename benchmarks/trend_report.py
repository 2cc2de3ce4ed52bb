"""`make trend`: the early warning measured on the six FEMTO lives and on healthy recordings.

* The six FEMTO/PRONOSTIA run-to-failure bearings through ``bearing-trend`` itself (the command
  acceptance runs on held-out bearings: ``bearing-trend DIR --bearing femto``): first warning
  and first alarm as minutes before the failure (the last snapshot) and as a fraction of the
  life, against the textbook rule (horizontal RMS above the mean + 3 sd of the first 20 % of
  the life, three snapshots in a row; it needs the life's length, which no online rule has).
* Healthy recordings of the other rigs (CWRU 097 drive and fan end, HIT-SM Normal_600/900/1200)
  played as snapshots: 0.1 s cut from the recording one after the other, one a minute (the
  FEMTO cadence), through :class:`~bearing_diagnoser.health.monitor.HealthMonitor` (the code
  behind ``bearing-trend``); and the FEMTO lives' first quarters: warnings and alarms per day.
* The detector's false alarms on synthetic healthy indicators against its design (iid and
  AR(1), baselines estimated), as in ``tests/unit/test_health_trend.py`` but with more machines.

Writes ``out/trend.md``; with ``--docs docs/health.md`` (``make trend``) also its three tables into
that file's generated blocks (:mod:`benchmarks.doc_tables`); with ``--figure`` also regenerates
``docs/figures/health/trend_Bearing1_1.png``.

    .venv/bin/python benchmarks/trend_report.py [--out out/trend.md] [--docs docs/health.md] [--figure]
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # `benchmarks` as a package
from benchmarks.doc_tables import add_docs_option, write_block  # noqa: E402
from benchmarks.healthy_data import CONTINUOUS, DATA, FEMTO_LIVES  # noqa: E402

BEARINGS = tuple(FEMTO_LIVES)
FIGURE = ROOT / "docs/figures/health/trend_Bearing1_1.png"

#: Healthy recordings of the other rigs: (name, file, sample rate, channel).
HEALTHY = tuple((h.label, h.file, h.sample_rate, h.channel) for h in CONTINUOUS)

SNAPSHOT = 0.1  # s
INTERVAL = 60.0  # s


def trend_command() -> list[str]:
    exe = ROOT / ".venv" / "bin" / "bearing-trend"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "bearing_diagnoser.health.trend_cli"]


def run_trend(folder: Path, plot: Path | None = None) -> list[dict]:
    cmd = trend_command() + [str(folder), "--bearing", "femto"] + (["--plot", str(plot)] if plot else [])
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return [json.loads(line) for line in out.stdout.splitlines()]


def textbook_alarm(t: np.ndarray, rms: np.ndarray) -> float | None:
    """Time of the third of three consecutive snapshots above mean + 3 sd of the first 20 % of life
    (when the rule can fire; ../shared/data/femto/README.md dates the first of the three, 2 min earlier)."""
    ref = rms[: max(2, int(0.2 * rms.size))]
    above = rms > ref.mean() + 3 * ref.std(ddof=1)
    run = 0
    for k, a in enumerate(above):
        run = run + 1 if a else 0
        if run == 3:
            return float(t[k])
    return None


def before(t: float | None, end: float) -> str:
    if t is None:
        return "none"
    return f"{(end - t) / 60:.0f} min ({100 * t / end:.0f} %)"


def femto_table(figure: bool) -> tuple[list[str], dict]:
    rows = ["| bearing | life | ours: first warning | ours: first alarm | textbook alarm | "
            "ours: warnings / alarms in the first quarter |", "|---|---|---|---|---|---|"]
    quarters = {"minutes": 0.0, "warnings": 0, "alarms": 0}
    aims = {"alarm >= 10 min before": 0, "alarm in first quarter": 0, "textbook >= 10 min before": 0}
    for name in BEARINGS:
        folder = DATA / "femto" / name
        with tempfile.TemporaryDirectory() as tmp:
            lines = run_trend(folder, Path(tmp) if figure and name == "Bearing1_1" else None)
            if figure and name == "Bearing1_1":
                FIGURE.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy(Path(tmp) / "trend_Bearing1_1.png", FIGURE)
        records, summary = lines[:-1], lines[-1]["summary"]
        end = summary["end"]
        t = np.array([r["t"] for r in records])
        rms = np.array([r["indicators"]["rms_m_s2"] for r in records])
        tb = textbook_alarm(t, rms)
        fa = summary["first_alarm"]
        aims["alarm >= 10 min before"] += fa is not None and end - fa >= 600
        aims["alarm in first quarter"] += fa is not None and fa < 0.25 * end
        aims["textbook >= 10 min before"] += tb is not None and end - tb >= 600
        onsets = _onsets(records, 0.25 * end)
        monitored = sum(1 for r in records if not r["trend"]["learning"] and r["t"] < 0.25 * end)
        quarters["minutes"] += monitored * INTERVAL / 60
        quarters["warnings"] += onsets["warning"]
        quarters["alarms"] += onsets["alarm"]
        rows.append(f"| {name} | {end / 60:.0f} min | {before(summary['first_warning'], end)} | {before(fa, end)} | "
                    f"{before(tb, end)} | {onsets['warning']} / {onsets['alarm']} "
                    f"(over {monitored} monitored snapshots) |")
    return rows, {"quarters": quarters, "aims": aims}


def _onsets(records, until: float) -> dict:
    """Onsets of each level (entering it or a higher one) among records before ``until`` s."""
    out = {"warning": 0, "alarm": 0}
    rank = {"healthy": 0, "warning": 1, "alarm": 2}
    prev = 0
    for r in records:
        if r["t"] >= until:
            break
        now = rank[r["state"]]
        out["warning"] += now >= 1 > prev
        out["alarm"] += now >= 2 > prev
        prev = now
    return out


def healthy_table(quarters: dict) -> list[str]:
    from bearing_diagnoser.health.monitor import HealthMonitor
    from bearing_recordings.load import load_recording

    rows = ["| recording | snapshots (0.1 s, one a minute) | monitored after the baseline | warnings | alarms |",
            "|---|---|---|---|---|"]
    total_min, total_w, total_a = 0.0, 0, 0
    for name, rel, fs, channel in HEALTHY:
        path = DATA / rel
        if not path.is_file():
            rows.append(f"| {name} | missing ({path}) | | | |")
            continue
        rec = load_recording(path, sample_rate=fs, channel=channel)
        n = int(round(SNAPSHOT * rec.sample_rate))
        monitor = HealthMonitor()
        records = [monitor.update(INTERVAL * k, rec.accel[k * n:(k + 1) * n], rec.sample_rate)
                   for k in range(rec.accel.size // n)]
        records = [r.to_json() for r in records if r is not None]
        onsets = _onsets(records, math.inf)
        monitored = sum(1 for r in records if not r["trend"]["learning"])
        total_min += monitored * INTERVAL / 60
        total_w += onsets["warning"]
        total_a += onsets["alarm"]
        rows.append(f"| {name} | {len(records)} | {monitored} | {onsets['warning']} | {onsets['alarm']} |")
    rows.append(f"| FEMTO, the six lives' first quarters | | {quarters['minutes']:.0f} | {quarters['warnings']} | "
                f"{quarters['alarms']} |")
    minutes = total_min + quarters["minutes"]
    w, a = total_w + quarters["warnings"], total_a + quarters["alarms"]
    days = minutes / 1440.0
    rows.append(f"| **all** | | {minutes:.0f} min = {days:.3f} days | {w} ({w / days:.1f} per day) | "
                f"{a} ({a / days:.1f} per day) |")
    rows.append("")
    rows.append(f"{minutes:.0f} monitored minutes: no alarm bounds the alarm rate at {3 / days:.0f} per day (95 %, "
                "Poisson), far above the design rates (0.1 warnings, 0.01 alarms per day), which the healthy data "
                "at hand is much too short to check; the synthetic check below does.")
    return rows


def synthetic_table() -> list[str]:
    sys.path.insert(0, str(ROOT / "tests"))
    from synthetic_health import false_onsets_per_day

    rows = ["| healthy indicator (log) | machines x snapshots | design (per day) | measured (per day) "
            "| measured / design |", "|---|---|---|---|---|"]
    rate = 10.0
    for phi in (0.0, 0.5, 0.8):
        mean, se = false_onsets_per_day(phi, machines=300, steps=240, rate=rate, seed=1000 + int(100 * phi))
        label = "iid" if phi == 0 else f"AR(1), φ = {phi}"
        rows.append(f"| {label} | 300 x 270 | {rate:g} | {mean:.2f} ± {se:.2f} | {mean / rate:.2f} |")
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(ROOT / "out" / "trend.md"))
    p.add_argument("--figure", action="store_true", help=f"regenerate {FIGURE.relative_to(ROOT)}")
    add_docs_option(p, "docs/health.md")
    args = p.parse_args(argv)
    if not (DATA / "femto").is_dir():
        print(f"trend_report: no FEMTO data in {DATA / 'femto'} (set BEARING_DATA_DIR)", file=sys.stderr)
        return 2
    t0 = time.time()
    femto, extra = femto_table(args.figure)
    femto += ["", "Aims: " + ", ".join(f"{k}: {v}/6" for k, v in extra["aims"].items())]
    healthy, synthetic = healthy_table(extra["quarters"]), synthetic_table()
    lines = ["# Early warning over a machine's life (`make trend`)", "",
             "## The six FEMTO lives (`bearing-trend DIR --bearing femto`, defaults)", "", *femto, "",
             "## Healthy recordings played as snapshots", "", *healthy, "",
             "## False onsets on synthetic healthy indicators (no relevance band; baselines of 30 estimated)", "",
             *synthetic, "", f"({time.time() - t0:.0f} s)"]
    if args.docs:
        for name, rows in (("trend-femto", femto), ("trend-healthy", healthy), ("trend-synthetic", synthetic)):
            write_block(args.docs, name, "\n".join(rows), "make trend")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
