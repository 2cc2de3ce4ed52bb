"""FEMTO-ST PRONOSTIA snapshot files (``acc_NNNNN.csv``, IEEE PHM 2012 challenge).

One file is one snapshot: rows of ``hour, minute, second, microsecond, horizontal, vertical``
(the wall clock of each sample; acceleration in g), comma-separated (some files of the
challenge's test set use ``;``), no header; 2560 rows = 0.1 s at 25.6 kHz in the original
data. The snapshot's time is the clock of its first sample; its sample rate is what the
sample clock shows, (n − 1) / (t_last − t_first).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bearing_common.bearings import CATALOG
from bearing_common.units import STANDARD_GRAVITY, sample_rate_problem

from .recording import InputError, Recording, check_rate, check_rpm

#: Column of each acceleration channel.
CHANNELS = {"horizontal": 4, "vertical": 5}

#: The channel read when none is named: the horizontal accelerometer, the one the data set's
#: README and the PHM 2012 literature report (its degradation shows first in most bearings).
DEFAULT_CHANNEL = "horizontal"

#: File names of acceleration snapshots (``temp_*.csv`` beside them hold temperatures).
FILE_PATTERN = re.compile(r"acc_(\d+)\.csv", re.IGNORECASE)

#: Fewest rows a snapshot must hold to be scored (below that it is a cut file).
MIN_ROWS = 64

SECONDS_PER_DAY = 86400.0


class SnapshotFileError(ValueError):
    """One snapshot file cannot be used (the reason, one line)."""


@dataclass(frozen=True)
class FemtoSnapshot:
    """One snapshot: ``clock`` = time of day of the first sample (s), ``samples`` in m/s²."""

    clock: float
    samples: np.ndarray
    sample_rate: float


def snapshot_files(folder: Path) -> list[Path]:
    """The ``acc_*.csv`` files of ``folder``, in the order of their numbers."""
    found = [(int(m.group(1)), p) for p in folder.iterdir() if (m := FILE_PATTERN.fullmatch(p.name))]
    return [p for _n, p in sorted(found)]


def read_snapshot(path: Path, channel: str = DEFAULT_CHANNEL) -> FemtoSnapshot:
    """Read one ``acc_*.csv``; raises :class:`SnapshotFileError` with the reason."""
    column = CHANNELS[channel]
    try:
        text = path.read_text(encoding="ascii")
    except (OSError, UnicodeDecodeError) as exc:
        raise SnapshotFileError(f"cannot read ({exc.__class__.__name__}: {exc})") from None
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines:
        raise SnapshotFileError("empty file")
    delimiter = ";" if ";" in lines[0] else ","
    try:
        rows = np.loadtxt(lines, delimiter=delimiter, ndmin=2)
    except ValueError as exc:
        raise SnapshotFileError(f"not a table of numbers ({' '.join(str(exc).split())})") from None
    if rows.shape[0] < MIN_ROWS:
        raise SnapshotFileError(f"{rows.shape[0]} rows, fewer than the {MIN_ROWS} a snapshot needs")
    if rows.shape[1] != 6:
        raise SnapshotFileError(f"{rows.shape[1]} columns; expected 6 (hour, minute, second, microsecond, "
                                "horizontal, vertical)")
    if not np.isfinite(rows).all():
        raise SnapshotFileError("non-finite values (NaN/inf)")
    clock = rows[:, 0] * 3600.0 + rows[:, 1] * 60.0 + rows[:, 2] + rows[:, 3] * 1e-6
    clock = np.where(clock < clock[0] - SECONDS_PER_DAY / 2, clock + SECONDS_PER_DAY, clock)  # past midnight
    span = clock[-1] - clock[0]
    if not (span > 0 and np.all(np.diff(clock) >= -1e-6)):
        raise SnapshotFileError("the sample clock does not advance through the file")
    rate = (rows.shape[0] - 1) / span
    problem = sample_rate_problem(rate)
    if problem:
        raise SnapshotFileError(f"the sample clock shows a {problem}")
    return FemtoSnapshot(float(clock[0]), rows[:, column] * STANDARD_GRAVITY, float(rate))


def load_snapshot_recording(path: Path, sample_rate: float | None = None, rpm: float | None = None,
                            channel: str | None = None):
    """One ``acc_*.csv`` snapshot as a :class:`~.recording.Recording` (``bearing-diagnose`` on one file):
    the bearing is PRONOSTIA's (catalog ``femto``), the sample rate the sample clock's unless given."""
    channel = (channel or DEFAULT_CHANNEL).lower()
    if channel not in CHANNELS:
        raise InputError(f"{path}: FEMTO snapshots have channels {', '.join(CHANNELS)}, not {channel!r}")
    try:
        snap = read_snapshot(Path(path), channel)
    except SnapshotFileError as exc:
        raise InputError(f"{path}: {exc}") from None
    fs = check_rate(snap.sample_rate if sample_rate is None else sample_rate)
    return Recording(snap.samples, fs, None if rpm is None else check_rpm(rpm), "femto", None, channel, str(path),
                     start_time=snap.clock, bearing=CATALOG["femto"],
                     notes=[f"FEMTO snapshot, {channel} channel (g read as m/s²), {fs:g} Hz"])
