"""``bearing-trend``: condition trend and early warning over a machine's life, offline.

    bearing-trend PATH... [--bearing NAME|FILE.yaml] [--rpm RPM] [--sample-rate HZ] [--channel NAME]
                  [--plot DIR] [--report DIR] [--json] [--window S] [--baseline N|DURATION]
                  [--machine-class CLASS] [--units g|m/s2 | --sensitivity S]

PATH is a folder of FEMTO ``acc_*.csv`` snapshots, a folder of ``.mat``/``.npz``/CSV/WAV
recordings (or one such file) or a rosbag2 directory (``bearing_recordings.snapshots``); each PATH is
one machine's life, fed as a snapshot sensor's chunks through the diagnoser session
(:func:`monitor_pipeline`: the code the live node runs) — condition indicators and trend
(:class:`.health_session.HealthSession`) with the fault-comb evidence each snapshot could
give (``"evidence"``: a 0.1 s snapshot tests no hypothesis at 1800 rpm, and says why).
Stdout, when it is not a terminal or with ``--json``: one JSON object per snapshot or window,
``{"t", "state", "indicators", ..., "speed_changing"}`` (t in s after the PATH's first snapshot, on
the data's own clock; ``speed_changing``: the data's measured shaft speed — a ``.npz``'s
``shaft_speed``, a bag's ``shaft_speed`` or tachometer pulses — spread by more than 2 % over
it, and its indicators were held out of the trend), then ``{"summary": {...}}``; with several PATHs
every line carries ``"path"``. On a terminal: each state change as it comes, then the summary in words
(:func:`.reports.terminal_text.trend_text`). ``--report DIR`` writes one HTML page per PATH
(:mod:`.reports.trend_page`). Stderr: what was read and assumed, damaged
snapshots (skipped and counted), the baseline and its limits; on bad input one ``error:``
line per PATH and exit status 2 (the other PATHs are still scored).
"""

from __future__ import annotations

import argparse
import json
import math
import sys

EXIT_BAD_INPUT = 2

PROG = "bearing-trend"


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``bearing-trend``."""
    p = argparse.ArgumentParser(prog=PROG, description="Condition trend and early warning over a machine's life.")
    p.add_argument("paths", nargs="+", metavar="PATH",
                   help="folder of FEMTO acc_*.csv snapshots, folder of .mat/.npz/.csv/.tsv/.wav recordings (or one), "
                        "or rosbag2 directory")
    p.add_argument("--bearing", metavar="NAME|FILE.yaml",
                   help="monitored bearing (catalog name such as femto, 6205; YAML file; 'N,d,D,angle'); "
                        "with --rpm it keeps the default demodulation band above 3x the fault rates")
    p.add_argument("--rpm", type=float, help="shaft speed (rev/min); default from the data, if any")
    p.add_argument("--sample-rate", type=float,
                   help="sample rate (Hz); default the data's (FEMTO: from the sample clock)")
    p.add_argument("--channel", help="FEMTO: horizontal (default) or vertical; .mat: the variable; CSV: column name "
                                     "or number; WAV: channel number; bag: the vibration topic (default "
                                     "vibration/drive_end)")
    p.add_argument("--plot", metavar="DIR", help="write the trend figure(s) to DIR")
    p.add_argument("--report", metavar="DIR", help="write one self-contained HTML page per PATH to DIR/<name>.html")
    p.add_argument("--json", action="store_true",
                   help="JSON lines on stdout also on a terminal (they are the default when stdout is not one)")
    p.add_argument("--window", type=float, default=1.0,
                   help="continuous signal is cut into windows of this many s (default 1; "
                        "a snapshot shorter than two windows is scored whole)")
    p.add_argument("--baseline", default="30",
                   help="the healthy baseline: the first N snapshots (default 30) or a duration "
                        "after the first snapshot such as 2h, 45min, 600s")
    p.add_argument("--machine-class", default=None,
                   help="ISO 20816-3 machine class: group1-rigid, group1-flexible, group2-rigid (default), "
                        "group2-flexible")
    p.add_argument("--units", choices=("g", "m/s2"),
                   help="what the numbers of files that do not say it measure: one-signal .mat, CSV (default g), WAV")
    p.add_argument("--sensitivity", metavar="S",
                   help="instead of --units, the numbers are a sensor's output: e.g. 100mV/g (volts), 0.05/g")
    return p


def _say(text: str) -> None:
    print(f"{PROG}: {text}", file=sys.stderr)


#: Relative difference within which a snapshot's sample rate (from its own clock: FEMTO) is the
#: first snapshot's: the clock's microseconds over 0.1 s put 1e-5 of jitter on it.
SAME_RATE = 1e-3


def monitor_pipeline(source, args):
    """The graph's sessions for one PATH, as the node runs them on a snapshot sensor: the diagnoser
    session of model set ``none`` on the measurement (the spectral decision's comb evidence, the
    condition trend), input mode ``snapshot``, the trend's parameters from the command line."""
    from bearing_common.bearings import CATALOG, DEFAULT_BEARING, load_bearing
    from bearing_recordings.recording import MEASURED_RPM_TOLERANCE

    from ..diagnoser import STREAMS
    from ..front_ends import config_for
    from ..pipeline import MonitorPipeline
    from .iso20816 import machine_class

    spec = args.bearing or source.bearing
    bearing = load_bearing(spec) if spec else CATALOG[DEFAULT_BEARING]
    parameters = {"input_mode": "snapshot", "baseline": args.baseline, "baseline_min_duration": 0.0,
                  "machine_class": machine_class(args.machine_class), "health_period": args.window}
    return MonitorPipeline(bearing, "none", config_for("none"), source.rpm, observed=False, streams=STREAMS[:1],
                           rpm_tolerance=MEASURED_RPM_TOLERANCE, parameters=parameters, strict=False)


def run_path(path: str, args, tag: dict, readable: bool = False):
    """Score one PATH through :func:`monitor_pipeline`; returns the HealthMonitor, the records and the
    summary (the records are printed as they come: JSON lines, or when ``readable`` the state changes)."""
    from collections import Counter

    from bearing_recordings.recording import InputError
    from bearing_recordings.snapshots import open_snapshots

    from ..reports.terminal_text import trend_change_line, trend_text

    source = open_snapshots(path, channel=args.channel, sample_rate=args.sample_rate, rpm=args.rpm,
                            window=args.window, units=args.units, sensitivity=args.sensitivity)
    for note in source.notes:
        _say(f"{path}: {note}")
    pipeline, records, first, rate = None, [], None, None
    no_evidence = Counter()
    for snap in source:
        if pipeline is None:
            pipeline, first, rate = monitor_pipeline(source, args), snap.t, snap.sample_rate
        fs = rate if abs(snap.sample_rate / rate - 1.0) <= SAME_RATE else snap.sample_rate
        if snap.shaft_speed is not None:  # a window whose speed changes is held out of the trend
            pipeline.diagnoser.speed_samples(snap.t, fs, snap.shaft_speed)
        pipeline.feed(int(round((snap.t - first) * fs)), fs, snap.samples, source.source or "snapshots", stamp=snap.t)
        for rec in pipeline.diagnoser.take_health():
            records.append(rec)
            no_evidence[rec.evidence.problem if rec.evidence is not None else ""] += 1
            if not readable:
                print(json.dumps({**tag, **rec.to_json()}), flush=True)
            elif len(records) > 1 and rec.trend.state != records[-2].trend.state:
                print(trend_change_line(path, rec.to_json()), flush=True)
    if source.damaged:
        name, why = source.damaged[0]
        _say(f"{path}: warning: {len(source.damaged)} damaged snapshot(s) skipped; first {name}: {why}")
    monitor = pipeline.diagnoser.condition.monitor if pipeline is not None else None
    if monitor is not None and monitor.sensor_problems:
        t, why = monitor.sensor_problems[0]
        _say(f"{path}: warning: {len(monitor.sensor_problems)} snapshot(s) not scored (sensor problem), "
             f"first at {t - (first or 0.0):.3f} s: {why}")
    if not records:
        raise InputError(f"{path}: no usable snapshot"
                         + (f" ({len(source.damaged)} damaged)" if source.damaged else ""))
    problem, count = no_evidence.most_common(1)[0]
    if problem:
        _say(f"{path}: no fault-comb evidence for {count} of {len(records)} snapshot(s): {problem}")
    summary = monitor.summary()
    summary["damaged"] = len(source.damaged)
    summary["end"] = records[-1].trend.t
    _report_baseline(path, monitor)
    if readable:
        print(trend_text(path, [r.to_json() for r in records], summary), flush=True)
    else:
        print(json.dumps({**tag, "summary": summary}), flush=True)
    return monitor, records, summary


def _report_baseline(path: str, monitor) -> None:
    b = monitor.tracker.baseline
    if b is None:
        _say(f"{path}: warning: the baseline never completed ({monitor.tracker.snapshots} snapshots); "
             "every state is healthy by assumption")
        return
    parts = [f"{n} {lo:.4g} (EWMA warning {w:.4g}, alarm {a:.4g}; median warning {mw:.4g}, alarm {ma:.4g})"
             for n, (lo, (w, a), (mw, ma)) in monitor.tracker.limits().items()]
    _say(f"{path}: baseline of {b.snapshots} snapshots, interval {b.interval:g} s: " + "; ".join(parts))


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (0 on success)."""
    from bearing_common.bearings import BearingError
    from bearing_recordings.recording import InputError

    from .trend import parse_baseline

    args = build_parser().parse_args(argv)
    try:
        try:
            parse_baseline(args.baseline)
        except ValueError as exc:
            raise ValueError(f"--{exc}") from None
        if not (math.isfinite(args.window) and args.window > 0):
            raise ValueError(f"--window must be a positive number of seconds, got {args.window:g}")
        if args.machine_class:
            from .iso20816 import machine_class
            machine_class(args.machine_class)
        if args.bearing:
            from bearing_common.bearings import load_bearing
            load_bearing(args.bearing)
        if args.units is not None and args.sensitivity is not None:
            raise ValueError("give --units or --sensitivity, not both")
        if args.sensitivity is not None:
            from bearing_recordings.measurement_units import parse_sensitivity
            parse_sensitivity(args.sensitivity)
    except (ValueError, BearingError) as exc:
        _say(f"error: {exc}")
        return EXIT_BAD_INPUT
    status, results = 0, []
    readable = not args.json and sys.stdout.isatty()
    for path in args.paths:
        tag = {"path": path} if len(args.paths) > 1 else {}
        try:
            results.append((path, *run_path(path, args, tag, readable)))
        except (InputError, BearingError, ValueError) as exc:
            _say(f"error: {exc}")
            status = EXIT_BAD_INPUT
    for option, write in (("plot", _write_figures), ("report", _write_reports)):
        if getattr(args, option) and results:
            try:
                write(results, getattr(args, option))
            except ImportError as exc:
                _say(f"error: --{option} needs matplotlib ({exc})")
                return 1
            except OSError as exc:
                _say(f"error: cannot write to {getattr(args, option)}: {exc}")
                return 1
    return status


def _write_figures(results: list, directory: str) -> None:
    from .trend_plot import write_trend_figure
    for path, monitor, records, _summary in results:
        _say(f"wrote {write_trend_figure(records, monitor, directory, path)}")


def _write_reports(results: list, directory: str) -> None:
    from pathlib import Path

    from ..reports.trend_page import write_trend_page
    names: set = set()
    for path, monitor, records, summary in results:
        stem = Path(path).stem or "trend"
        name, k = stem, 1
        while name in names:
            k += 1
            name = f"{stem}-{k}"
        names.add(name)
        _say(f"wrote {write_trend_page(path, records, monitor, summary, Path(directory) / f'{name}.html')}")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
