"""Load any supported recording by its kind: rosbag2 directory, ``.npz`` (real or simulated), ``.mat``, CSV/TSV
table or WAV."""

from __future__ import annotations

from pathlib import Path

from .mat_files import load_mat
from .npz_files import load_npz
from .recording import InputError, Recording, check_rate, check_rpm
from .table_files import TABLE_SUFFIXES, load_table
from .wav_files import WAV_SUFFIXES, load_wav


def load_recording(path, sample_rate: float | None = None, rpm: float | None = None,
                   channel: str | None = None, units: str | None = None,
                   sensitivity: str | None = None) -> Recording:
    """Load ``path``: directory → rosbag2, ``.npz`` (:mod:`.npz_files`), ``.mat`` →
    MFPT/CWRU/one signal, ``.csv``/``.tsv``/``.txt`` → a table (a FEMTO ``acc_*.csv`` snapshot as
    such), ``.wav`` → WAV.

    ``sample_rate`` (Hz) overrides the file's (required where the file has none);
    ``rpm`` overrides the file's speed; ``channel`` picks the signal (see
    :mod:`.mat_files` for the rule, :mod:`.table_files`, :mod:`.wav_files`); ``units`` or
    ``sensitivity`` state what the numbers of a file measure that does not say it
    (:mod:`.measurement_units`). Raises :class:`~.recording.InputError`.
    """
    p = Path(path)
    if sample_rate is not None:
        sample_rate = check_rate(sample_rate)
    if rpm is not None:
        rpm = check_rpm(rpm)
    if not p.exists():
        raise InputError(f"{path}: no such file or directory")
    if p.is_dir():
        from .bag_read import load_bag  # rosbags is imported only for bags
        rec = load_bag(p, channel=channel)
        if sample_rate is not None:
            rec.sample_rate = sample_rate
        if rpm is not None:
            rec.rpm = rpm
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
