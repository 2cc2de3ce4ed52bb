"""A machine's life as a sequence of snapshots: short waveforms, each stamped by the data's clock.

What a PATH holds, and what a snapshot is in it:

* **a folder of FEMTO ``acc_*.csv`` files** — one file is one snapshot (:mod:`.femto_files`);
  its time is the clock of its first sample, its rate what the sample clock shows.
* **a folder of ``.mat`` / ``.npz`` / ``.csv`` / ``.tsv`` / ``.wav`` recordings** (or one
  such file) — each file is a continuous recording, loaded as ``bearing-diagnose`` loads it
  (:func:`.load.load_recording`: channel rule, units, sample rate), and cut into windows as
  below. Files without a clock of their own (MATLAB and WAV files, ``bearing-sim`` output,
  tables without a time column: their time starts at 0) are taken in name order, each
  starting where the previous ended; the notes say so.
* **a rosbag2 directory** — the ``VibrationChunk`` s of the vibration topic (``channel``);
  chunks whose sample indices follow on from each other form one continuous stretch, a gap
  in the indices (or in the stamps) starts the next: a snapshot sensor's chunks with gaps
  between them are snapshots; a stream's chunks one long stretch. Time = the header stamps.

A continuous stretch shorter than two windows (``window`` s, default 1 s: the health topic's
rate on streams) is one snapshot of its own length; a longer one is cut into consecutive
windows of ``window`` s (the remainder, shorter than a window, is dropped). So a 0.1 s
snapshot is scored as it is, and a stream is scored once a second, by the same code.

A file that cannot be read in a folder that otherwise can is a *damaged snapshot*: skipped,
counted and listed in :attr:`SnapshotSource.damaged`, never fatal. A PATH that holds nothing
usable (no such path, an unknown kind, no snapshot at all, a bag that cannot be opened) raises
:class:`~.recording.InputError` with one line.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bearing_common.units import sample_rate_problem

from . import femto_files
from .recording import InputError, check_rate
from .recording_files import RECORDING_SUFFIXES
from .table_files import TABLE_SUFFIXES

#: Default window (s) a continuous stretch is cut into.
DEFAULT_WINDOW = 1.0


@dataclass(frozen=True)
class Snapshot:
    """One snapshot or window.

    Attributes
    ----------
    t : float
        Time of its first sample, s, on the data's own clock (FEMTO: seconds of the day of
        the first snapshot's date, continued past midnight; bags: header stamps).
    samples : ndarray, shape (n,)
        Acceleration, m/s².
    sample_rate : float
        Hz.
    name : str
        Where it comes from (file name, ``file@offset``, bag stamp), for messages.
    shaft_speed : ndarray, shape (n,), or None
        Measured shaft speed per sample (rad/s) when the data carry one (a recording's
        :attr:`~.recording.Recording.shaft_speed`, a bag's ``shaft_speed`` or tachometer pulses).
    """

    t: float
    samples: np.ndarray
    sample_rate: float
    name: str
    shaft_speed: np.ndarray | None = None

    @property
    def duration(self) -> float:
        """Length, s."""
        return self.samples.size / self.sample_rate


@dataclass
class SnapshotSource:
    """The snapshots of one PATH, read lazily (iterate over it once).

    ``damaged`` lists ``(name, reason)`` of the files skipped so far; ``notes`` what the
    reader assumed; ``source`` / ``bearing`` / ``rpm`` what the data say about the machine
    (``""`` / None when they do not).
    """

    path: str
    kind: str
    channel: str
    notes: list = field(default_factory=list)
    damaged: list = field(default_factory=list)
    source: str = ""
    bearing: str = ""
    rpm: float | None = None
    _items: Iterator | None = None

    def __iter__(self) -> Iterator[Snapshot]:
        if self._items is None:
            raise RuntimeError("a SnapshotSource is read once")
        items, self._items = self._items, None
        return items


def cut_stretch(t0: float, x: np.ndarray, fs: float, window: float, name: str,
                speed: np.ndarray | None = None) -> list[Snapshot]:
    """A continuous stretch starting at ``t0`` (s) as snapshots: itself, or windows of ``window`` s;
    ``speed``: its shaft speed per sample (rad/s), cut alike."""
    n = int(round(window * fs))
    if n < 1 or x.size < 2 * n:
        return [Snapshot(t0, x, fs, name, speed)]
    return [Snapshot(t0 + i * n / fs, x[i * n:(i + 1) * n], fs, f"{name}@{i * n / fs:g}s",
                     None if speed is None else speed[i * n:(i + 1) * n])
            for i in range(x.size // n)]


def open_snapshots(path, channel: str | None = None, sample_rate: float | None = None,
                   rpm: float | None = None, window: float = DEFAULT_WINDOW,
                   units: str | None = None, sensitivity: str | None = None) -> SnapshotSource:
    """The snapshots of ``path`` (see the module docstring); raises :class:`~.recording.InputError`.

    ``channel``: FEMTO ``horizontal`` (default) or ``vertical``; a ``.mat`` variable; a bag's
    relative vibration topic. ``sample_rate`` (Hz) overrides the files' (FEMTO: the sample
    clock's; required for files that store none); ``rpm`` the data's speed; ``units`` or
    ``sensitivity`` what the numbers of files that do not say it measure
    (:mod:`.measurement_units`).
    """
    p = Path(path)
    if sample_rate is not None:
        sample_rate = check_rate(sample_rate)
    if not window > 0:
        raise InputError(f"window must be a positive number of seconds, got {window!r}")
    if not p.exists():
        raise InputError(f"{path}: no such file or directory")
    if p.is_dir() and (p / "metadata.yaml").is_file():
        return _bag_source(p, channel, sample_rate, rpm, window)
    if p.is_dir():
        acc = femto_files.snapshot_files(p)
        if acc:
            return _femto_source(p, acc, channel, sample_rate, rpm)
        files = sorted(f for f in p.iterdir() if f.is_file() and f.suffix.lower() in RECORDING_SUFFIXES)
        if files:
            return _recordings_source(p, files, channel, sample_rate, rpm, window, units, sensitivity)
        raise InputError(f"{path}: no snapshots here: expected FEMTO acc_*.csv files, recordings "
                         f"({', '.join(RECORDING_SUFFIXES)}) or a rosbag2 recording (metadata.yaml)")
    if femto_files.FILE_PATTERN.fullmatch(p.name):
        return _femto_source(p.parent, [p], channel, sample_rate, rpm)
    if p.suffix.lower() in RECORDING_SUFFIXES + TABLE_SUFFIXES:
        return _recordings_source(p.parent, [p], channel, sample_rate, rpm, window, units, sensitivity)
    raise InputError(f"{path}: unknown kind of input; expected a folder of FEMTO acc_*.csv snapshots, "
                     f"a folder of recordings ({', '.join(RECORDING_SUFFIXES)}) or a rosbag2 directory")


def _femto_source(folder: Path, files: list, channel, sample_rate, rpm) -> SnapshotSource:
    channel = (channel or femto_files.DEFAULT_CHANNEL).lower()
    if channel not in femto_files.CHANNELS:
        raise InputError(f"{folder}: FEMTO snapshots have channels {', '.join(femto_files.CHANNELS)}, "
                         f"not {channel!r}")
    src = SnapshotSource(str(folder), "femto", channel, source="femto", bearing="femto", rpm=rpm)
    src.notes.append(f"{len(files)} FEMTO snapshot files, {channel} channel (g read as m/s²)"
                     + ("" if sample_rate is None else f", sample rate {sample_rate:g} Hz as given"))

    def items():
        last = None
        for f in files:
            try:
                snap = femto_files.read_snapshot(f, channel)
            except femto_files.SnapshotFileError as exc:
                src.damaged.append((f.name, str(exc)))
                continue
            clock = snap.clock
            while last is not None and clock < last - femto_files.SECONDS_PER_DAY / 2:
                clock += femto_files.SECONDS_PER_DAY  # the test ran past midnight
            if last is not None and clock <= last:
                src.damaged.append((f.name, f"its clock ({clock:.3f} s) is not after the previous snapshot's "
                                            f"({last:.3f} s)"))
                continue
            last = clock
            yield Snapshot(clock, snap.samples, sample_rate or snap.sample_rate, f.name)

    src._items = items()
    return src


def _recordings_source(folder: Path, files: list, channel, sample_rate, rpm, window, units,
                       sensitivity) -> SnapshotSource:
    from .load import load_recording

    src = SnapshotSource(str(folder if len(files) > 1 else files[0]), "recordings", channel or "")
    src.notes.append(f"{len(files)} recording file(s): each cut into {window:g} s windows when at least "
                     f"{2 * window:g} s long; files without a clock of their own laid end to end in name order")

    def items():
        t_next = 0.0
        for f in files:
            try:
                rec = load_recording(f, sample_rate=sample_rate, rpm=rpm, channel=channel, units=units,
                                     sensitivity=sensitivity)
            except InputError as exc:
                if len(files) == 1:
                    raise
                src.damaged.append((f.name, str(exc).removeprefix(f"{f}: ")))
                continue
            src.channel = src.channel or rec.channel
            src.source = src.source or rec.source
            src.bearing = src.bearing or rec.bearing
            src.rpm = src.rpm if src.rpm is not None else rec.rpm
            t0 = rec.start_time if rec.start_time else t_next
            t_next = t0 + rec.duration
            yield from cut_stretch(t0, rec.accel, rec.sample_rate, window, f.name, rec.shaft_speed)

    src._items = items()
    return src


def _bag_source(path: Path, channel, sample_rate, rpm, window) -> SnapshotSource:
    from bearing_common import topics

    from .bag_read import bag_bearing, read_bag

    contents = read_bag(path, vibration_topic=channel or topics.VIBRATION.name)
    if not contents.chunks:
        raise InputError(f"{path}: the bag holds no vibration chunks")
    src = SnapshotSource(str(path), "rosbag2", channel or topics.VIBRATION.name, source=contents.chunks[0].source,
                         bearing=bag_bearing(path), rpm=rpm if rpm is not None else contents.rpm)
    stretches = _contiguous(sorted(contents.chunks, key=lambda c: (c.stamp, c.first_sample_index)), src)
    src.notes.append(f"{len(contents.chunks)} vibration chunks in {len(stretches)} continuous stretch(es)")

    def items():
        for first, x, fs in stretches:
            rate = sample_rate or fs
            speed = contents.speed_at(first.stamp + np.arange(x.size) / rate)
            yield from cut_stretch(first.stamp, x, rate, window, f"chunk at {first.stamp:.6f} s", speed)

    src._items = items()
    return src


def _contiguous(chunks: list, src: SnapshotSource) -> list:
    """Chunks joined into stretches ``(first chunk, samples, rate)``: a chunk continues the previous
    when its first sample index and its stamp follow on from the previous chunk's end."""
    out, parts, first, end_index, end_stamp = [], [], None, None, None
    for c in chunks:
        fs = c.sample_rate
        problem = sample_rate_problem(fs) or ("no samples" if c.samples.size == 0 else "")
        if not problem and not np.isfinite(c.samples).all():
            problem = "non-finite samples (NaN/inf)"
        if problem:
            src.damaged.append((f"chunk at {c.stamp:.6f} s", problem))
            continue
        follows = (first is not None and fs == first.sample_rate and c.first_sample_index == end_index
                   and abs(c.stamp - end_stamp) <= max(2.0, 0.5 * c.samples.size) / fs)
        if not follows:
            if parts:
                out.append((first, np.concatenate(parts), first.sample_rate))
            parts, first = [], c
        parts.append(c.samples)
        end_index = c.first_sample_index + c.samples.size
        end_stamp = c.stamp + c.samples.size / fs
    if parts:
        out.append((first, np.concatenate(parts), first.sample_rate))
    return out
