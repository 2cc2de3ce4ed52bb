"""``bearing-diagnose``: offline diagnosis of recordings, one JSON object per state segment.

    bearing-diagnose PATH... [--jobs N] [--progress | --no-progress] [--rpm RPM] [--sample-rate HZ]
                     [--channel NAME] [--bearing NAME|FILE.yaml] [--units g|m/s2 | --sensitivity S]
                     [--model-set NAME] [--speed-channel NAME --speed-units rpm|rad/s|hz|pulses
                     [--pulses-per-rev N]] [--method model|envelope] [--plot DIR] [--report DIR] [--json]
                     [--baseline HEALTHY_PATH|REF.json [--save-baseline REF.json]]

PATH is a .npz (a real machine's recording unless its ``source`` says ``simulator``, as
``bearing-sim`` writes: ``bearing_recordings.npz_files``), a MATLAB recording (CWRU, MFPT, or
one signal such as HIT-SM; see ``bearing_recordings.mat_files``), a CSV/TSV table or a WAV file
(``bearing_recordings.table_files``, ``wav_files``), a rosbag2 directory, or a folder of any of
these (walked: ``bearing_recordings.recording_files``). Stdout: one JSON object per line
(``shared/CONTRACT.md``) when it is not a terminal or with ``--json``, else the verdict and its
evidence in words (:mod:`.reports.terminal_text`); with several paths or a folder, each JSON
line also carries ``"file"``, in the order of the files whatever ``--jobs`` runs in parallel.
``--report DIR`` writes one HTML page per file (:mod:`.reports.diagnosis_page`). Stderr: the
model set, bearing, any resampling, the speed, the windows not diagnosed (each file's prefixed
with it in a batch), and per file that cannot be diagnosed one ``error:`` line. The options
apply to every file as they would to it alone, so a file's lines in a batch are those of its
own run.

``--baseline`` judges every file against the machine's own healthy reference
(:mod:`.spectral.machine_reference`): learnt once from a healthy recording of the same machine, read
with the same options as the files (its first 60 s), or loaded from a reference saved before with
``--save-baseline``. Each JSON line then carries ``"reference"`` (what was learnt, from where), and
stderr says which reference is in force; without it the blind decision runs.

Every readable recording gets a verdict. A window the decision cannot diagnose (the sensor
signal dead, clipped, quantised; the shaft speed not confirmed; a snapshot too short to
resolve any fault line) takes no part in the segments; when no window of a recording could
be diagnosed, its one segment covers it all with ``"state": "unknown"``, ``"confidence": 0``
and ``"not_diagnosed": {"kind": "sensor"|"speed"|"resolution", "reason": "..."}`` (the most
frequent kind, with its first reason), and the exit status is 0. A segment that was
diagnosed carries no ``not_diagnosed``.

Exit status 0; 2 when any file was bad input: what cannot be read (no such file, not a
recording, a channel or sample rate missing, non-finite samples) or cannot be analysed
whatever it holds (a sample rate too low for the bearing's fault lines, a record shorter than
one analysis window, an unknown bearing or model set); 1 when any failed otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import replace
from pathlib import Path

EXIT_BAD_INPUT = 2

PROG = "bearing-diagnose"


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``bearing-diagnose``."""
    p = argparse.ArgumentParser(prog=PROG, description="Diagnose bearing vibration recordings offline.")
    p.add_argument("paths", nargs="+", metavar="PATH",
                   help=".npz (bearing-sim's or a real machine's), MATLAB .mat (CWRU, MFPT, one signal), CSV/TSV "
                        "table, WAV file, rosbag2 directory, or a folder of these (walked)")
    p.add_argument("--jobs", "-j", type=_jobs, default=1, metavar="N",
                   help="diagnose N files at a time in worker processes (default 1; 0: one per available core)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="a progress line on stderr (default: for several files when stderr is a terminal)")
    p.add_argument("--rpm", type=float, help="shaft speed (rev/min); default from the file, else estimated")
    p.add_argument("--rpm-tolerance", type=float, metavar="FRACTION",
                   help="relative accuracy of --rpm (default 0.10, a nameplate's; the speed is measured from the "
                        "vibration within it, and beyond it reported); a file's own speed keeps the file's")
    p.add_argument("--sample-rate", type=float, help="input sample rate (Hz); required where the file has none")
    p.add_argument("--channel", help="channel: .mat variable (e.g. X105_DE_time; default the drive end), CSV column "
                                     "name or number, WAV channel number, bag vibration topic")
    p.add_argument("--bearing", metavar="NAME|FILE.yaml",
                   help="monitored bearing: catalog name (6205, 6203, mfpt, za2115), YAML file or "
                        "'N,d,D,angle' (default: the recording's, else 6205)")
    p.add_argument("--units", choices=("g", "m/s2"),
                   help="what the numbers of a file that does not say it measure: one-signal .mat, CSV (default g, "
                        "or the column name's unit), WAV (no default)")
    p.add_argument("--sensitivity", metavar="S",
                   help="instead of --units, the numbers are a sensor's output: e.g. 100mV/g or 10.2mV/(m/s2) "
                        "(numbers in volts), 0.05/g (plain numbers, e.g. WAV integer PCM as fractions of full scale)")
    p.add_argument("--speed-channel", metavar="NAME",
                   help="the file's speed or tachometer channel, sampled with the vibration (.mat variable, "
                        ".npz array): the measured shaft speed per sample (then no --rpm)")
    p.add_argument("--speed-units", choices=("rpm", "rad/s", "hz", "pulses"),
                   help="units of --speed-channel; pulses: a tachometer signal (edges detected)")
    p.add_argument("--pulses-per-rev", type=int, default=1, metavar="N",
                   help="tachometer pulses per shaft revolution of --speed-units pulses (default 1)")
    p.add_argument("--track-speed", metavar="LO:HI[:RATE]", type=_speed_range,
                   help="no measured speed, but the speed changes within LO-HI rev/min (narrower than an octave), "
                        "by at most RATE %% per second (default 15: a run-up from half speed in 10 s; a drive's "
                        "ramp time gives it): track it from the vibration (the shaft's harmonics) and follow it; "
                        "where too few of the tracker's frames show a shaft comb, the record is not diagnosed "
                        "(kind speed) (docs/changing-speed.md)")
    p.add_argument("--model-set", help="sim_48k, sim_12k, cwru_de_6205 or none (default: from the input)")
    p.add_argument("--method", choices=("model", "envelope"), default="model",
                   help="model: observers + envelope-spectrum decision (default); envelope: textbook reference")
    p.add_argument("--plot", metavar="DIR", help="write figures to DIR (with several files: DIR/<file name>/)")
    p.add_argument("--report", metavar="DIR",
                   help="write one self-contained HTML page per file to DIR/<file name>.html")
    p.add_argument("--baseline", metavar="HEALTHY_PATH|REF.json",
                   help="judge against this machine's own healthy reference: a healthy recording of the same machine "
                        "(read with the same options as PATH), or a reference saved with --save-baseline")
    p.add_argument("--save-baseline", metavar="REF.json",
                   help="save the reference of --baseline to REF.json, for reuse (e.g. --baseline REF.json)")
    p.add_argument("--json", action="store_true",
                   help="JSON lines on stdout also on a terminal (they are the default when stdout is not one)")
    return p


def _jobs(text: str) -> int:
    """``--jobs``: a count of worker processes, 0 for one per core this process may run on."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"must be 0 (one per core) or more, got {n}")
    if n == 0:
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return n


def _speed_range(text: str) -> tuple[float, float, float]:
    """``LO:HI[:RATE]``: rev/min with 0 < LO < HI < 2·LO (narrower than an octave: the tracker could settle
    on half or twice the speed otherwise), and the largest speed change RATE in % per second (default
    15); returned as (LO, HI, RATE / 100)."""
    parts = text.split(":")
    try:
        lo, hi, rate = (float(v) for v in parts + ["15"] * (3 - len(parts)))
    except ValueError:
        lo = hi = rate = -1.0
    if not 2 <= len(parts) <= 3 or not (0.0 < lo < hi < 2.0 * lo and 0.0 < rate <= 100.0):
        raise argparse.ArgumentTypeError(f"expected LO:HI[:RATE] with 0 < LO < HI < 2 LO rev/min and 0 < RATE <= 100 "
                                         f"%/s, got {text!r}")
    return lo, hi, rate / 100.0


def _options(args):
    """The run's :class:`.batch_diagnosis.FileOptions`, checked once for every file (InputError,
    BearingError)."""
    from bearing_common.bearings import load_bearing
    from bearing_recordings.measurement_units import parse_sensitivity
    from bearing_recordings.recording import InputError, check_rate, check_rpm

    from .batch_diagnosis import FileOptions, load_baseline

    if args.rpm_tolerance is not None and not 0.0 < args.rpm_tolerance < 0.5:
        raise InputError(f"--rpm-tolerance must be in (0, 0.5), got {args.rpm_tolerance:g}")
    if (args.speed_channel is None) != (args.speed_units is None):
        raise InputError("--speed-channel and --speed-units go together")
    if args.pulses_per_rev < 1:
        raise InputError(f"--pulses-per-rev must be >= 1, got {args.pulses_per_rev}")
    if args.speed_channel is not None and args.rpm is not None:
        raise InputError("give either --rpm or --speed-channel, not both")
    if args.track_speed is not None and args.speed_channel is not None:
        raise InputError("give either --speed-channel or --track-speed, not both")
    if args.units is not None and args.sensitivity is not None:
        raise InputError("give --units or --sensitivity, not both")
    if args.sensitivity is not None:
        parse_sensitivity(args.sensitivity)
    if args.save_baseline and not args.baseline:
        raise InputError("--save-baseline needs --baseline (the healthy recording to learn from)")
    options = FileOptions(sample_rate=None if args.sample_rate is None else check_rate(args.sample_rate),
                       rpm=None if args.rpm is None else check_rpm(args.rpm), rpm_tolerance=args.rpm_tolerance,
                       channel=args.channel, units=args.units, sensitivity=args.sensitivity,
                       speed_channel=args.speed_channel, speed_units=args.speed_units,
                       pulses_per_rev=args.pulses_per_rev, track_speed=args.track_speed,
                       bearing=load_bearing(args.bearing) if args.bearing else None, model_set=args.model_set,
                       method=args.method)
    if not args.baseline:
        return options
    reference = load_baseline(args.baseline, options)
    if args.save_baseline:
        try:
            reference.save(args.save_baseline)
        except OSError as exc:
            raise InputError(f"cannot save the machine reference to {args.save_baseline}: {exc.strerror}") from None
    return replace(options, baseline=reference)


def _file_names(paths: list[str]) -> list[str]:
    """A name per file: its stem (numbered from -2 on where two files share one)."""
    out, used = [], set()
    for path in paths:
        stem = Path(path).stem or Path(path).name
        name, k = stem, 1
        while name in used:
            k += 1
            name = f"{stem}-{k}"
        used.add(name)
        out.append(name)
    return out


def _plot_dirs(root: str | None, paths: list[str], batch: bool) -> list | None:
    """Each file's figure directory: ``root`` itself for one file, else ``root``/<file name>."""
    if root is None:
        return None
    return [str(Path(root) / name) for name in _file_names(paths)] if batch else [root]


def _report_paths(root: str | None, paths: list[str]) -> list | None:
    """Each file's HTML report: ``root``/<file name>.html."""
    return None if root is None else [str(Path(root) / f"{name}.html") for name in _file_names(paths)]


class _Console:
    """Stdout and stderr of a run, kept clear of the progress line (if any)."""

    def __init__(self, bar):
        self.bar = bar

    def write(self, text: str, stream) -> None:
        if self.bar is not None:
            self.bar.clear()
        print(text, file=stream, flush=True)
        if self.bar is not None:
            self.bar.draw()

    def note(self, text: str) -> None:
        self.write(f"{PROG}: {text}", sys.stderr)


def _untagged(message: str, path: str) -> str:
    """``message`` without a leading ``path:`` (the loaders name the file; a batch's line names it first)."""
    return message[len(path) + 2:] if message.startswith(f"{path}: ") else message


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (0 on success)."""
    args = build_parser().parse_args(argv)
    # one BLAS thread per process, workers included (read when numpy is first imported): the diagnosis'
    # BLAS calls are small (dot products of a health window, the observers' fits), and a second thread
    # only spins: 6-14 % of a --jobs 1 batch's CPU over six CWRU 12 kHz files, with the same output
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    from bearing_common.bearings import BearingError
    from bearing_common.progress_bar import ProgressBar
    from bearing_recordings.recording import InputError
    from bearing_recordings.recording_files import expand, is_folder

    from .batch_diagnosis import run_batch
    from .reports.terminal_text import diagnosis_text

    batch = len(args.paths) > 1 or any(is_folder(p) for p in args.paths)
    readable = not args.json and sys.stdout.isatty()
    try:
        options = _options(args)
    except (InputError, BearingError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    paths, empty = expand(args.paths)
    show = args.progress if args.progress is not None else batch and sys.stderr.isatty()
    bar = ProgressBar(len(paths), sys.stderr, PROG, live=sys.stderr.isatty()) if show and paths else None
    out = _Console(bar)
    status = EXIT_BAD_INPUT if empty else 0
    for folder in empty:
        out.note(f"error: {folder}: not a rosbag2 recording (no metadata.yaml), and no recordings "
                 "(.mat, .npz, rosbag2 directories) in it")
    tag = (lambda path: f"{path}: ") if batch else (lambda path: "")
    signal_s = cpu_s = 0.0
    failed = 0
    try:
        for report in run_batch(paths, options, args.jobs, _plot_dirs(args.plot, paths, batch),
                                on_done=bar and (lambda r: bar.advance(r.signal_s, bool(r.error))),
                                emit=lambda path, note: out.note(tag(path) + note),
                                report_paths=_report_paths(args.report, paths)):
            if readable and report.lines:
                out.write(diagnosis_text(report.path, report.lines, report.summary), sys.stdout)
            for line in report.lines if not readable else ():
                out.write(json.dumps({"file": report.path} | line if batch else line), sys.stdout)
            if report.error:
                out.note(f"error: {tag(report.path)}{_untagged(report.error, report.path) if batch else report.error}")
            status = max(status, report.status)
            failed += bool(report.error)
            signal_s += report.signal_s
            cpu_s += report.cpu_s
    except KeyboardInterrupt:
        out.note("interrupted")
        return 130
    finally:
        if bar is not None:
            bar.clear()
    if batch and paths:
        speed = f", {signal_s / cpu_s:.0f} x real time per core" if cpu_s > 0 else ""
        out.note(f"{len(paths)} files: {len(paths) - failed} diagnosed, {failed} failed "
                 f"({signal_s:.1f} s of signal{speed})")
    return status


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
