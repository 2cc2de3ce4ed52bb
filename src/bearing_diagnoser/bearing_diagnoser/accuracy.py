"""Accuracy of the diagnosis on labelled recordings (``bearing-accuracy MANIFEST.yaml``, :mod:`.accuracy_cli`).

A manifest lists recordings with their true state (YAML)::

    root: ../shared/data            # relative to the manifest's directory
    recordings:
      - {dataset: CWRU, file: cwru/105_IR007_0hp_DE12k.mat, truth: inner_race, bearing: "6205",
         sample_rate: 12000, note: "IR 0.007 in, 0 hp"}
      - {dataset: HIT-SM, file: hit-sm/spectraquest/Normal_600.mat, truth: normal, sample_rate: 51200, rpm: 600}

Per record and method the report gives the state covering most of the record's duration,
its confidence (duration-weighted), the time to the first decision of that state, the share
of windows whose published state was right, and on healthy records every window and
segment that raised an alarm. Totals per data set, false alarms on healthy records, and the
calibration of the published confidence (window decisions binned by confidence: the share
that was right in each bin) complete it. Every record runs with the same settings.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bearing_common.bearings import BearingError, load_bearing
from bearing_common.states import FaultState, parse_fault
from bearing_recordings.load import load_recording
from bearing_recordings.recording import InputError, Recording
from bearing_recordings.resampling import resample

from .front_ends import config_for
from .pipeline import choose_model_set
from .recording_diagnosis import diagnose_recording

#: Confidence bins of the calibration table.
CONFIDENCE_BINS = (0.0, 0.5, 0.7, 0.9, 0.99, 1.0 + 1e-9)


@dataclass(frozen=True)
class LabelledRecording:
    """One manifest entry (paths resolved)."""

    dataset: str
    name: str
    path: Path
    truth: FaultState
    bearing: str = "6205"
    rpm: float | None = None
    sample_rate: float | None = None
    channel: str | None = None
    resample_to: float | None = None
    note: str = ""

    def load(self) -> Recording:
        rec = load_recording(self.path, sample_rate=self.sample_rate, rpm=self.rpm, channel=self.channel)
        if self.resample_to:
            rec = replace(rec, accel=resample(rec.accel, rec.sample_rate, self.resample_to),
                          sample_rate=self.resample_to, truth=None)
        return rec


def load_manifest(path, root=None) -> list[LabelledRecording]:
    """Entries of a manifest file (see the module docstring); ``root`` overrides its ``root``.
    InputError on a malformed manifest."""
    import yaml
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
        root = Path(root) if root is not None else (path.parent / data.get("root", ".")).resolve()
        out = []
        for e in data["recordings"]:
            file = root / e["file"]
            out.append(LabelledRecording(
                str(e.get("dataset", "")), str(e.get("name", Path(e["file"]).stem)), file, parse_fault(e["truth"]),
                str(e.get("bearing", "6205")), e.get("rpm"), e.get("sample_rate"), e.get("channel"),
                e.get("resample_to"), str(e.get("note", ""))))
        return out
    except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{path}: not a usable manifest ({exc.__class__.__name__}: {exc})") from None


@dataclass
class RecordResult:
    """One record diagnosed by one method."""

    record: LabelledRecording
    method: str
    state: FaultState | None  # covering most of the record
    share: float  # of the record's duration
    confidence: float
    decided_at: float | None  # first decision of ``state`` (s)
    segments: int
    windows: int
    windows_right: int
    alarm_windows: int  # windows whose published state was not NORMAL
    alarm_segments: int
    window_states: list = field(default_factory=list)  # (published state, confidence) per window
    error: str = ""

    @property
    def correct(self) -> bool:
        return self.state == self.record.truth


def evaluate(record: LabelledRecording, method: str = "model", speed_told: bool = True, variant=None) -> RecordResult:
    """Diagnose ``record`` with ``method`` (``model``/``envelope``); ``variant`` maps a
    DiagnoserConfig to the one to use (ablations); without ``speed_told`` the speed is estimated."""
    try:
        rec = record.load()
        bearing = load_bearing(record.bearing)
        if not speed_told:
            rec.rpm = None
        config = None
        if variant is not None:
            config = variant(config_for(choose_model_set(rec.source, rec.sample_rate, bearing).name))
        res = diagnose_recording(rec, method=method, rpm=rec.rpm, bearing=bearing, config=config)
    except (InputError, BearingError) as exc:
        return RecordResult(record, method, None, 0.0, 0.0, None, 0, 0, 0, 0, 0, error=str(exc))
    duration = res.accel.size / res.sample_rate
    cover: dict = defaultdict(float)
    conf: dict = defaultdict(float)
    for s in res.segments:
        cover[s.state] += s.end - s.start
        conf[s.state] += (s.end - s.start) * s.confidence
    state = max(cover, key=cover.get) if cover else None
    windows = [(d.state, d.confidence) for d in res.decisions if d.diagnosed]
    first = next((s.detected_at for s in res.segments if s.state == state), None)
    return RecordResult(record, method, state, cover[state] / duration if state is not None else 0.0,
                        conf[state] / cover[state] if state is not None and cover[state] > 0 else 0.0, first,
                        len(res.segments), len(windows), sum(s == record.truth for s, _ in windows),
                        sum(s != FaultState.NORMAL for s, _ in windows),
                        sum(s.state != FaultState.NORMAL for s in res.segments), windows)


def totals(results: list[RecordResult]) -> dict:
    """Per data set: faults right / fault records (race and ball), healthy records without alarm /
    healthy records, and of the ball records those named BALL and those called a race fault."""
    out: dict = defaultdict(lambda: {"faults": 0, "faults_right": 0, "healthy": 0, "healthy_clean": 0,
                                     "alarm_windows": 0, "healthy_windows": 0, "ball": 0, "ball_right": 0,
                                     "ball_called_race": 0})
    races = (FaultState.OUTER_RACE, FaultState.INNER_RACE)
    for r in results:
        t = out[r.record.dataset]
        if r.record.truth == FaultState.NORMAL:
            t["healthy"] += 1
            t["healthy_clean"] += int(r.alarm_segments == 0 and not r.error)
            t["alarm_windows"] += r.alarm_windows
            t["healthy_windows"] += r.windows
        else:
            t["faults"] += 1
            t["faults_right"] += int(r.correct)
        if r.record.truth == FaultState.BALL:
            t["ball"] += 1
            t["ball_right"] += int(r.correct)
            t["ball_called_race"] += int(r.state in races)
    return dict(out)


def calibration(results: list[RecordResult], faults: bool) -> list[tuple[float, float, int, float]]:
    """(bin low, bin high, windows, share right) of the published confidence over all windows
    whose published state names a part (``faults``: OUTER_RACE, INNER_RACE, BALL) or is NORMAL
    (UNKNOWN's confidence is that something is wrong, not that a part is)."""
    parts = (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL)
    pairs = [(c, s == r.record.truth) for r in results for s, c in r.window_states
             if (s in parts if faults else s == FaultState.NORMAL)]
    conf = np.array([c for c, _ in pairs])
    right = np.array([ok for _, ok in pairs])
    rows = []
    for lo, hi in zip(CONFIDENCE_BINS[:-1], CONFIDENCE_BINS[1:]):
        sel = (conf >= lo) & (conf < hi) if conf.size else np.zeros(0, bool)
        rows.append((lo, min(hi, 1.0), int(sel.sum()), float(right[sel].mean()) if sel.any() else float("nan")))
    return rows


def summary_line(r: RecordResult) -> str:
    """One line per record and method, for progress output."""
    return f"{r.record.dataset} {r.record.name} {r.method}: {_cell(r)}"


def _cell(r: RecordResult) -> str:
    if r.error:
        return f"error: {r.error}"
    mark = "" if r.correct else " ✗"
    return (f"{r.state.label}{mark} ({r.confidence:.2f}, {100 * r.share:.0f} %, "
            f"{r.segments} segment{'s' if r.segments != 1 else ''})")


def markdown(results: list[RecordResult], methods=("model", "envelope")) -> str:
    """The report: per-record table (methods side by side), totals, calibration."""
    by_record: dict = defaultdict(dict)
    for r in results:
        by_record[(r.record.dataset, r.record.name, r.record.note)][r.method] = r
    head = "| data set | record | truth | " + " | ".join(
        f"{m}: state (confidence, share of record, segments) | {m}: time to decision" for m in methods) + " |"
    lines = [head, "|" + "---|" * (3 + 2 * len(methods))]
    for (dataset, name, note), row in by_record.items():
        truth = next(iter(row.values())).record.truth.label
        cells = []
        for m in methods:
            r = row.get(m)
            cells += [_cell(r) if r else "-", f"{r.decided_at:.2f} s" if r and r.decided_at is not None else "-"]
        label = f"{name} ({note})" if note else name
        lines.append(f"| {dataset} | {label} | {truth} | " + " | ".join(cells) + " |")
    lines += ["", "| data set | method | race faults diagnosed | ball records: named BALL, called a race fault "
              "| healthy records without alarm | alarm windows on healthy |", "|---|---|---|---|---|---|"]
    for m in methods:
        for dataset, t in totals([r for r in results if r.method == m]).items():
            race, race_right = t["faults"] - t["ball"], t["faults_right"] - t["ball_right"]
            ball = f"{t['ball_right']}/{t['ball']}, {t['ball_called_race']}/{t['ball']}" if t["ball"] else "-"
            lines.append(f"| {dataset} | {m} | {race_right}/{race} | {ball} | {t['healthy_clean']}/{t['healthy']} "
                         f"| {t['alarm_windows']}/{t['healthy_windows']} |")
    lines += ["", "| published confidence | fault states: windows | share right | NORMAL: windows | share right |",
              "|---|---|---|---|---|"]
    first = [r for r in results if r.method == methods[0]]
    for (lo, hi, n, share), (_, _, n0, share0) in zip(calibration(first, True), calibration(first, False)):
        lines.append(f"| {lo:.2f}-{hi:.2f} | {n} | {'-' if n == 0 else f'{100 * share:.1f} %'} | {n0} | "
                     f"{'-' if n0 == 0 else f'{100 * share0:.1f} %'} |")
    return "\n".join(lines) + "\n"


def run(records: list[LabelledRecording], methods=("model", "envelope"), progress=None) -> list[RecordResult]:
    """Every record with every method."""
    out = []
    for rec in records:
        for m in methods:
            out.append(evaluate(rec, m))
            if progress:
                progress(out[-1])
    return out
