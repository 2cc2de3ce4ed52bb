"""Many recordings diagnosed in one run: one file's whole diagnosis as a report, over a pool of worker processes.

:func:`diagnose_file` is what ``bearing-diagnose`` does for one file — load it, pick the
bearing, run :func:`.recording_diagnosis.diagnose_recording`, write any figures and HTML
report — and returns a :class:`FileReport`: the segments' JSON objects, their evidence in
physical terms (:mod:`.reports.diagnosis_summary`) and what stderr should say. A file that
cannot be diagnosed is a report with its error line, never an exception, so that one bad
file does not end a batch.

:func:`run_batch` runs it over many files, in this process (``jobs=1``) or in ``jobs``
worker processes, each importing the diagnosis once (forked from this one, which has
imported it) and taking file after file. Reports come back in the order of the files,
whatever order they finish in. A worker process that dies (killed, out of memory) breaks
the pool: the files it was running are then run again, each alone in a fresh worker, so
that the one that kills its worker is the one reported, and the others go on.
"""

from __future__ import annotations

import logging
import math
import multiprocessing
import time
import traceback
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

from bearing_common.bearings import Bearing, BearingError

from .spectral.machine_reference import MachineReference

#: Exit status of a file that is bad input (as ``bearing-diagnose`` exits for it).
EXIT_BAD_INPUT = 2

#: Exit status of a file that failed otherwise (figures not written, an unexpected error).
EXIT_FAILED = 1

#: The loggers whose messages are a file's notes (what the run assumed, what the loader saw).
NOTE_LOGGERS = ("bearing_diagnoser", "bearing_recordings")


@dataclass(frozen=True)
class FileOptions:
    """The options of a run, applied to every file as to one file alone (so that a file's lines in a
    batch are those of its own run): sample rate (Hz), shaft speed (rev/min) and its relative
    tolerance, channel, units or sensitivity of a file that does not state what its numbers measure,
    the file's speed or tachometer channel (its units, pulses per revolution), the range to track a
    changing speed in when none is measured (rev/min, None: the speed is taken as one), bearing (None: the
    recording's), model set, method, the machine's healthy reference (None: blind)."""

    sample_rate: float | None = None
    rpm: float | None = None
    rpm_tolerance: float | None = None
    channel: str | None = None
    units: str | None = None
    sensitivity: str | None = None
    speed_channel: str | None = None
    speed_units: str | None = None
    pulses_per_rev: int = 1
    track_speed: tuple[float, float, float] | None = None  # rev/min, rev/min, 1/s
    bearing: Bearing | None = None
    model_set: str | None = None
    method: str = "model"
    baseline: MachineReference | None = None


@dataclass
class FileReport:
    """One file's outcome: ``lines``, the JSON objects of its segments; ``summary``, the verdict's
    evidence in physical terms (:func:`.reports.diagnosis_summary.summarise`; empty when it
    failed); ``notes``, its stderr lines in order (without the program's name); ``error``, the
    one-line reason it failed ("" when it did not) and ``status`` the exit status it asks for (0,
    :data:`EXIT_BAD_INPUT` or :data:`EXIT_FAILED`); ``signal_s`` the recording's length (s) and
    ``cpu_s`` the CPU time (s) its diagnosis took."""

    path: str
    lines: list = field(default_factory=list)
    summary: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    error: str = ""
    status: int = 0
    signal_s: float = 0.0
    cpu_s: float = 0.0


class _Notes(logging.Handler):
    """Collects the note loggers' messages as a file's notes, and hands each to ``emit`` as it comes."""

    def __init__(self, report: FileReport, live: Callable[[str], None] | None):
        super().__init__(logging.INFO)
        self.report, self.live = report, live

    def emit_note(self, text: str) -> None:
        self.report.notes.append(text)
        if self.live is not None:
            self.live(text)

    def emit(self, record: logging.LogRecord) -> None:  # noqa: D102 (logging.Handler's)
        self.emit_note(record.getMessage())


def diagnose_file(path: str, options: FileOptions, plot_dir: str | None = None, report_path: str | None = None,
                  emit: Callable[[str], None] | None = None) -> FileReport:
    """Diagnose the recording at ``path`` (module docstring); ``plot_dir``: write its figures there;
    ``report_path``: write its HTML report there; ``emit``: called with each note as it arises
    (else they are only collected)."""
    from bearing_recordings.recording import InputError

    from .recording_diagnosis import diagnose_recording
    from .reports.diagnosis_summary import summarise

    report = FileReport(path)
    notes = _Notes(report, emit)
    loggers = [logging.getLogger(name) for name in NOTE_LOGGERS]
    levels = [log.level for log in loggers]
    for log in loggers:
        log.addHandler(notes)
        log.setLevel(logging.INFO)
    cpu = time.process_time()
    try:
        rec = _load(path, options)
        report.signal_s = rec.duration
        for note in rec.notes or ():
            notes.emit_note(note)
        if rec.speed_varies:
            lo, hi = rec.shaft_speed.min() * 30.0 / math.pi, rec.shaft_speed.max() * 30.0 / math.pi
            notes.emit_note(f"the measured shaft speed varies from {lo:.0f} to {hi:.0f} rpm "
                            f"({100 * rec.speed_spread:.1f} % of its mean): decided in the shaft-angle domain "
                            f"(order tracking), at {rec.rpm:.0f} rpm nominal")
        res = diagnose_recording(rec, model_set=options.model_set, method=options.method, rpm=options.rpm,
                                 bearing=options.bearing or rec.bearing,
                                 keep_streams=plot_dir is not None, rpm_tolerance=options.rpm_tolerance,
                                 baseline=options.baseline, track_speed=options.track_speed)
    except (InputError, BearingError) as exc:
        report.error, report.status = str(exc), EXIT_BAD_INPUT
        return report
    finally:
        report.cpu_s = time.process_time() - cpu
        for log, level in zip(loggers, levels):
            log.removeHandler(notes)
            log.setLevel(level)
    for start, end, problem in res.not_diagnosed[:1]:
        notes.emit_note(f"warning: {len(res.not_diagnosed)} of {len(res.decisions)} windows not diagnosed, first at "
                        f"{start:.3f}-{end:.3f} s: {problem}")
    said = {"reference": res.reference} if res.reference else {}
    report.lines = [seg.to_json() | said for seg in res.segments]
    report.summary = summarise(res, rec, res.bearing)
    if plot_dir is not None:
        _write_figures(res, plot_dir, report, notes)
    if report_path is not None:
        _write_report(res, rec, report_path, report, notes)
    return report


def _load(path: str, options: FileOptions):
    """The recording at ``path`` read with ``options`` (InputError when it cannot be)."""
    from bearing_recordings.load import load_recording

    return load_recording(path, sample_rate=options.sample_rate, rpm=options.rpm, channel=options.channel,
                          units=options.units, sensitivity=options.sensitivity, speed_channel=options.speed_channel,
                          speed_units=options.speed_units, pulses_per_rev=options.pulses_per_rev)


def load_baseline(path: str, options: FileOptions) -> MachineReference:
    """The machine reference of ``--baseline``: a saved one (``.json``), else learnt from the healthy
    recording at ``path`` read with the run's ``options`` like every file; InputError (one line)."""
    from bearing_recordings.recording import InputError

    from .recording_diagnosis import learn_recording_reference
    from .spectral.machine_reference import MachineReferenceError, load_reference

    if path.lower().endswith(".json"):
        try:
            return load_reference(path)
        except MachineReferenceError as exc:
            raise InputError(str(exc)) from None
    rec = _load(path, options)
    return learn_recording_reference(rec, options.model_set, options.rpm, options.bearing or rec.bearing,
                                     options.rpm_tolerance)


def _write_figures(res, plot_dir: str, report: FileReport, notes: _Notes) -> None:
    try:
        from .plots import write_figures
        paths = write_figures(res, plot_dir)
        notes.emit_note(f"wrote {len(paths)} figures to {plot_dir}")
    except ImportError as exc:
        report.error, report.status = f"--plot needs matplotlib ({exc})", EXIT_FAILED
    except OSError as exc:
        report.error, report.status = f"cannot write figures to {plot_dir}: {exc}", EXIT_FAILED


def _write_report(res, rec, report_path: str, report: FileReport, notes: _Notes) -> None:
    try:
        from .reports.diagnosis_page import write_diagnosis_page
        write_diagnosis_page(res, rec, report.lines, report.summary, report_path)
        notes.emit_note(f"wrote the report {report_path}")
    except ImportError as exc:
        report.error, report.status = f"--report needs matplotlib ({exc})", EXIT_FAILED
    except OSError as exc:
        report.error, report.status = f"cannot write the report {report_path}: {exc}", EXIT_FAILED


def _guarded(task: tuple, emit: Callable[[str], None] | None = None) -> FileReport:
    """:func:`diagnose_file` for one task of a batch: an unexpected error (a defect, not the input's)
    becomes the file's report too, with the exception's type and where it arose."""
    path, options, plot_dir, report_path = task
    try:
        return diagnose_file(path, options, plot_dir, report_path, emit)
    except Exception as exc:  # a defect on one file must not end the batch: reported, exit status 1
        where = traceback.extract_tb(exc.__traceback__)[-1]
        place = f"{where.name} ({where.filename.rsplit('/', 1)[-1]}:{where.lineno})"
        return FileReport(path, error=f"unexpected {type(exc).__name__} at {place}: {exc}", status=EXIT_FAILED)


def run_batch(paths: list[str], options: FileOptions, jobs: int = 1, plot_dirs: list | None = None,
              on_done: Callable[[FileReport], None] | None = None, emit: Callable[[str, str], None] | None = None,
              report_paths: list | None = None) -> Iterator[FileReport]:
    """Reports of ``paths``, in their order (module docstring); ``plot_dirs``: each file's figure
    directory (None: no figures); ``report_paths``: each file's HTML report (None: none);
    ``on_done``: called with each report as its file finishes (in the order they finish); ``emit``:
    called with (path, note) for each note, as it arises when ``jobs`` is 1, else just before its
    report is yielded (the workers' notes come with their reports)."""
    tasks = [(p, options, d, r) for p, d, r in zip(paths, plot_dirs or [None] * len(paths),
                                                   report_paths or [None] * len(paths))]
    done = on_done or (lambda report: None)
    if jobs <= 1 or len(tasks) <= 1:
        for task in tasks:
            live = None if emit is None else (lambda note, path=task[0]: emit(path, note))
            # one file: a defect shows its traceback; in a batch it is that file's report
            report = diagnose_file(*task, live) if len(tasks) == 1 else _guarded(task, live)
            done(report)
            yield report
        return
    for report in _pooled(tasks, jobs, done):
        for note in report.notes if emit is not None else ():
            emit(report.path, note)
        yield report


def _pool(jobs: int) -> ProcessPoolExecutor:
    """Worker processes forked from this one (the diagnosis already imported), where the platform forks."""
    from . import recording_diagnosis  # noqa: F401  (imported once here, inherited by every worker)
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    return ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context(method))


def _alone(task: tuple) -> FileReport:
    """``task`` in a worker of its own: its report, or the report that it kills its worker."""
    with _pool(1) as pool:
        try:
            return pool.submit(_guarded, task).result()
        except BrokenProcessPool:
            return FileReport(task[0], error="the worker process diagnosing it died (killed, or out of memory)",
                              status=EXIT_FAILED)


def _pooled(tasks: list, jobs: int, done: Callable[[FileReport], None]) -> Iterator[FileReport]:
    """Reports of ``tasks`` run by ``jobs`` workers, in order; at most two tasks per worker queued."""
    pool = _pool(jobs)
    queued = list(enumerate(tasks))[::-1]  # popped from the end: first task first
    running: dict = {}  # future -> (index, task)
    finished: dict[int, FileReport] = {}
    next_out = 0
    try:
        while next_out < len(tasks):
            while queued and len(running) < 2 * jobs:
                i, task = queued.pop()
                running[pool.submit(_guarded, task)] = (i, task)
            ready, _ = wait(running, return_when=FIRST_COMPLETED)
            broken = []
            for future in ready:
                i, task = running.pop(future)
                try:
                    finished[i] = future.result()
                except BrokenProcessPool:
                    broken.append((i, task))
                    continue
                done(finished[i])
            if broken:  # every task still running in the broken pool is lost with it: each again alone
                broken += running.values()
                running.clear()
                pool.shutdown(wait=True)
                for i, task in sorted(broken, key=lambda item: item[0]):
                    finished[i] = _alone(task)
                    done(finished[i])
                pool = _pool(jobs)
            while next_out in finished:
                yield finished.pop(next_out)
                next_out += 1
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
