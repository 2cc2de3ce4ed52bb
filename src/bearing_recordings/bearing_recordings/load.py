"""Load any supported recording by its kind: rosbag2 directory, ``.npz`` (real or simulated), ``.mat``, CSV/TSV
table or WAV."""

from __future__ import annotations

from pathlib import Path

from . import mat_files, npz_files
from .mat_files import load_mat
from .npz_files import load_npz
from .recording import InputError, Recording, check_rate, check_rpm
from .speed_channel import speed_from_channel
from .table_files import TABLE_SUFFIXES, load_table, read_table
from .wav_files import WAV_SUFFIXES, load_wav


def _table_channel(path, name: str):
    """A named (or numbered) column of a CSV/TSV table."""
    return read_table(path).column(name)


#: Readers of a named channel (a speed or tachometer channel) per file suffix.
CHANNEL_READERS = {".mat": mat_files.read_channel, ".npz": npz_files.read_channel,
                   **{suffix: _table_channel for suffix in TABLE_SUFFIXES}}


def load_recording(path, sample_rate: float | None = None, rpm: float | None = None,
                   channel: str | None = None, units: str | None = None, sensitivity: str | None = None,
                   speed_channel: str | None = None, speed_units: str | None = None,
                   pulses_per_rev: int = 1) -> Recording:
    """Load ``path``: directory → rosbag2, ``.npz`` (:mod:`.npz_files`), ``.mat`` →
    MFPT/CWRU/one signal, ``.csv``/``.tsv``/``.txt`` → a table (a FEMTO ``acc_*.csv`` snapshot as
    such), ``.wav`` → WAV.

    ``sample_rate`` (Hz) overrides the file's (required where the file has none);
    ``rpm`` overrides the file's speed; ``channel`` picks the signal (see
    :mod:`.mat_files` for the rule, :mod:`.table_files`, :mod:`.wav_files`); ``units`` or
    ``sensitivity`` state what the numbers of a file measure that does not say it
    (:mod:`.measurement_units`). ``speed_channel`` names the file's speed or tachometer
    channel, sampled with the vibration, in ``speed_units`` (``rpm``, ``rad/s``, ``hz`` or
    ``pulses``, with ``pulses_per_rev``; :mod:`.speed_channel`): the recording then carries the
    measured speed per sample (``shaft_speed``) and its mean as ``rpm``.
    Raises :class:`~.recording.InputError`.
    """
    p = Path(path)
    if sample_rate is not None:
        sample_rate = check_rate(sample_rate)
    if rpm is not None:
        rpm = check_rpm(rpm)
    if speed_channel is not None and rpm is not None:
        raise InputError("give either the shaft speed (--rpm) or a speed channel (--speed-channel), not both")
    if speed_channel is not None and speed_units is None:
        raise InputError("a speed channel needs its units (--speed-units rpm, rad/s, hz or pulses)")
    if not p.exists():
        raise InputError(f"{path}: no such file or directory")
    rec = _load(p, str(path), sample_rate, rpm, channel, units, sensitivity)
    if speed_channel is not None:
        reader = CHANNEL_READERS.get(p.suffix.lower()) if not p.is_dir() else None
        if reader is None:
            raise InputError(f"{path}: --speed-channel applies to .mat, .npz and CSV/TSV files (a bag carries "
                             "shaft_speed)")
        what = f"{path}:{speed_channel}"
        rec.set_shaft_speed(speed_from_channel(reader(p, speed_channel), rec.sample_rate, speed_units,
                                               pulses_per_rev, what), what)
    return rec


def _load(p: Path, path: str, sample_rate, rpm, channel, units, sensitivity) -> Recording:
    if p.is_dir():
        from .bag_read import load_bag  # rosbags is imported only for bags
        rec = load_bag(p, channel=channel)
        if sample_rate is not None:
            rec.sample_rate = sample_rate
        if rpm is not None:
            rec.rpm, rec.shaft_speed = rpm, None
        return rec
    suffix = p.suffix.lower()
    if suffix == ".npz":
        return load_npz(p, sample_rate, rpm, channel)
    if suffix == ".mat":
        return load_mat(p, sample_rate, rpm, channel, units, sensitivity)
    if suffix in TABLE_SUFFIXES:
        from . import femto_files
        if femto_files.FILE_PATTERN.fullmatch(p.name):
            return femto_files.load_snapshot_recording(p, sample_rate, rpm, channel)
        return load_table(p, sample_rate, rpm, channel, units, sensitivity)
    if suffix in WAV_SUFFIXES:
        return load_wav(p, sample_rate, rpm, channel, units, sensitivity)
    raise InputError(f"{path}: unknown file type {suffix or '(none)'}; expected .npz, .mat, .csv, .tsv, .wav "
                     "or a rosbag2 directory")
