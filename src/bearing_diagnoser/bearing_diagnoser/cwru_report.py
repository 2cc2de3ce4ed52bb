"""The README table of the CWRU results: ``python -m bearing_diagnoser.cwru_report [DIR]``.

For each shipped CWRU record (``../shared/data/cwru`` beside the repository, or
``$BEARING_CWRU_DIR``, or DIR): the truth, the state our model method gives (the state
covering most of the record) with its confidence and share of the record, the same for
the squared-envelope-spectrum reference (``--method envelope``), and the time to the
first decision of that state.  Thresholds are the same for every record (derived from
white noise, :mod:`.calibration`); nothing is tuned per record.

Record 97 (normal) was sampled at 48 kHz; it is diagnosed as given (resampled to
12 kHz by the pipeline) and decimated by 4 beforehand (anti-aliased), as the CWRU
README asks before comparing it with the 12 kHz fault records.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from bearing_common.states import FaultState
from bearing_recordings.load import load_recording
from bearing_recordings.recording import InputError, Recording
from bearing_recordings.resampling import resample

from .offline import diagnose_recording

#: (file, sample rate Hz, truth, note)
RECORDS = (
    ("105_IR007_0hp_DE12k.mat", 12000.0, FaultState.INNER_RACE, "IR 0.007 in, 0 hp"),
    ("130_OR007at6_0hp_DE12k.mat", 12000.0, FaultState.OUTER_RACE, "OR 0.007 in @6:00, 0 hp"),
    ("097_normal_0hp_DE48k.mat", 48000.0, FaultState.NORMAL, "normal, 48 kHz as given"),
    ("097_normal_0hp_DE48k.mat", 12000.0, FaultState.NORMAL, "normal, decimated to 12 kHz beforehand"),
    ("118_B007_0hp_DE12k.mat", 12000.0, FaultState.BALL, "ball 0.007 in (S&R: not diagnosable)"),
)


def default_cwru_dir() -> Path:
    """$BEARING_CWRU_DIR, else ``../shared/data/cwru`` beside the repository root."""
    env = os.environ.get("BEARING_CWRU_DIR")
    if env:
        return Path(env)
    here = Path(__file__).resolve()
    for parent in here.parents:
        cand = parent.parent / "shared" / "data" / "cwru"
        if (parent / "src").is_dir() and cand.is_dir():
            return cand
    return Path("../shared/data/cwru")


def load_record(directory, file: str, rate: float) -> Recording:
    """Load one record; ``rate`` below the file's 48 kHz means "decimate beforehand"."""
    native = 48000.0 if "48k" in file else 12000.0
    rec = load_recording(Path(directory) / file, sample_rate=native)
    if rate != native:
        rec = Recording(resample(rec.accel, native, rate), rate, rec.rpm, rec.source, None, rec.channel, rec.path)
    return rec


def summarise(result) -> dict:
    """Dominant state of an offline result: state, confidence, share, time to decision."""
    dur = {}
    for s in result.segments:
        dur[s.state] = dur.get(s.state, 0.0) + (s.end - s.start)
    state = max(dur, key=dur.get)
    segs = [s for s in result.segments if s.state == state]
    total = sum(s.end - s.start for s in result.segments)
    conf = float(np.average([s.confidence for s in segs], weights=[max(s.end - s.start, 1e-9) for s in segs]))
    return {"state": state, "confidence": conf, "share": dur[state] / total if total else 0.0,
            "decided_at": min(s.detected_at for s in segs), "segments": len(result.segments)}


def cwru_table(directory=None, methods=("model", "envelope")) -> list[dict]:
    """One row per entry of :data:`RECORDS` present in ``directory``."""
    directory = Path(directory) if directory else default_cwru_dir()
    rows = []
    for file, rate, truth, note in RECORDS:
        if not (directory / file).is_file():
            continue
        rec = load_record(directory, file, rate)
        row = {"record": file.split("_")[0], "file": file, "note": note, "truth": truth.label}
        for m in methods:
            row[m] = summarise(diagnose_recording(rec, method=m, quiet=True))
        rows.append(row)
    return rows


def markdown(rows: list[dict], methods=("model", "envelope")) -> str:
    """The table as Markdown."""
    head = "| record | input | truth | " + " | ".join(
        f"{m}: state (confidence, share of record) | {m}: time to decision" for m in methods) + " |"
    sep = "|" + "---|" * (3 + 2 * len(methods))
    lines = [head, sep]
    for r in rows:
        cells = [r["record"], r["note"], r["truth"]]
        for m in methods:
            s = r[m]
            ok = "" if s["state"].label == r["truth"] else " ✗"
            cells.append(f"{s['state'].label}{ok} ({s['confidence']:.2f}, {100 * s['share']:.0f} %, "
                         f"{s['segments']} segment{'s' if s['segments'] != 1 else ''})")
            cells.append(f"{s['decided_at']:.2f} s")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    """Print the Markdown table; exit 1 when no record is found."""
    argv = sys.argv[1:] if argv is None else argv
    directory = Path(argv[0]) if argv else default_cwru_dir()
    try:
        rows = cwru_table(directory)
    except InputError as exc:
        print(f"cwru_report: error: {exc}", file=sys.stderr)
        return 2
    if not rows:
        print(f"cwru_report: no CWRU records in {directory}", file=sys.stderr)
        return 1
    print(markdown(rows))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
