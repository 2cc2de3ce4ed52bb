"""Load any supported recording by its kind: rosbag2 directory, ``.npz`` (real or simulated) or ``.mat``."""

from __future__ import annotations

from pathlib import Path

from .mat_files import load_mat
from .npz_files import load_npz
from .recording import InputError, Recording, check_rate, check_rpm


def load_recording(path, sample_rate: float | None = None, rpm: float | None = None,
                   channel: str | None = None, units: str | None = None) -> Recording:
    """Load ``path``: directory → rosbag2, ``.npz`` (:mod:`.npz_files`), ``.mat`` → MFPT/CWRU/one signal.

    ``sample_rate`` (Hz) overrides the file's (required where the file has none);
    ``rpm`` overrides the file's speed; ``channel`` picks the signal (see
    :mod:`.mat_files` for the rule); ``units`` states a one-signal .mat file's unit.
    Raises :class:`~.recording.InputError`.
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
        return load_mat(p, sample_rate, rpm, channel, units)
    raise InputError(f"{path}: unknown file type {suffix or '(none)'}; expected .npz, .mat or a rosbag2 directory")
