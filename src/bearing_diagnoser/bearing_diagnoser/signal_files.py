"""Loading vibration recordings for offline diagnosis: bearing-sim .npz, CWRU-style .mat, rosbag2.

Every loader returns a :class:`Recording` in SI units (m/s², Hz, rev/min, s) or raises
:class:`InputError` with a one-line message meant for the user.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
import re

import numpy as np

#: Standard gravity (m/s² per g): CWRU files store acceleration in g.
STANDARD_GRAVITY = 9.80665


class InputError(ValueError):
    """The input file or its options cannot be used (message is user-facing, one line)."""


@dataclass
class Recording:
    """One vibration channel ready for diagnosis.

    Attributes
    ----------
    accel : ndarray, shape (n,)
        Acceleration (m/s²).
    sample_rate : float
        Hz.
    rpm : float or None
        Shaft speed (rev/min) if known.
    source : str
        ``simulator``, ``cwru`` or ``bag``: picks the default model set.
    truth : ndarray of int or None
        Per-sample true state (simulator only; FaultState integers).
    channel : str
        Channel name (e.g. ``X105_DE_time``, ``accel``).
    path : str
    start_time : float
        Stamp of the first sample (s; bags), 0 otherwise.  Segment times are relative
        to the first sample.
    """

    accel: np.ndarray
    sample_rate: float
    rpm: float | None
    source: str
    truth: np.ndarray | None = None
    channel: str = ""
    path: str = ""
    start_time: float = 0.0

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.accel.size / self.sample_rate


def _check_rate(rate) -> float:
    try:
        rate = float(rate)
    except (TypeError, ValueError):
        raise InputError(f"invalid sample rate {rate!r}") from None
    if not np.isfinite(rate) or rate <= 0:
        raise InputError(f"sample rate must be a positive number of Hz, got {rate:g}")
    return rate


def _check_data(x, what: str) -> np.ndarray:
    x = np.asarray(x)
    if x.dtype.kind not in "fiu":
        raise InputError(f"{what}: data is not numeric (dtype {x.dtype})")
    x = x.astype(float).ravel()
    if x.size == 0:
        raise InputError(f"{what}: no samples")
    bad = ~np.isfinite(x)
    if bad.any():
        raise InputError(f"{what}: {int(bad.sum())} non-finite samples (NaN/inf), first at index {int(np.argmax(bad))}")
    return x


def load_npz(path, sample_rate: float | None = None, rpm: float | None = None,
             channel: str | None = None) -> Recording:
    """Load a ``bearing-sim`` .npz (keys t, accel, unbalance, truth, sample_rate, rpm)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except Exception as exc:  # zipfile / pickle / OS errors
        raise InputError(f"{path}: not a readable .npz file ({exc.__class__.__name__}: {exc})") from None
    ch = channel or "accel"
    if ch not in data:
        raise InputError(f"{path}: no channel {ch!r}; available: {', '.join(sorted(data))}")
    fs = sample_rate if sample_rate is not None else (data["sample_rate"].item() if "sample_rate" in data else None)
    if fs is None and "t" in data and data["t"].size > 1:
        fs = 1.0 / float(np.median(np.diff(data["t"])))
    if fs is None:
        raise InputError(f"{path}: no sample_rate in the file; give --sample-rate")
    fs = _check_rate(fs)
    if rpm is None and "rpm" in data:
        rpm = float(data["rpm"].item())
    truth = data.get("truth")
    x = _check_data(data[ch], f"{path}:{ch}")
    if truth is not None and truth.size != x.size:
        truth = None
    return Recording(x, fs, rpm, "simulator", None if truth is None else truth.astype(int).ravel(), ch, str(path))


def load_mat(path, sample_rate: float | None = None, rpm: float | None = None,
             channel: str | None = None) -> Recording:
    """Load a CWRU-style MATLAB file: acceleration in g → m/s² (× 9.80665).

    The sample rate is not stored in these files and must be given.  Without
    ``channel``, the drive-end channel of the record named by the ``X<rec>RPM`` variable
    is used (``X<rec>_DE_time``); the rpm comes from that variable unless given.
    """
    from scipy.io import loadmat
    if sample_rate is None:
        raise InputError(f"{path}: .mat files do not store their sample rate; give --sample-rate "
                         "(CWRU: 12000 or 48000)")
    fs = _check_rate(sample_rate)
    try:
        m = loadmat(path)
    except Exception as exc:
        raise InputError(f"{path}: not a readable MATLAB file ({exc.__class__.__name__}: {exc})") from None
    keys = [k for k in m if not k.startswith("__")]
    rpm_keys = [k for k in keys if re.fullmatch(r"X\d+RPM", k)]
    if channel is None:
        if len(rpm_keys) == 1:
            channel = rpm_keys[0][:-3] + "_DE_time"
        else:
            de = [k for k in keys if k.endswith("_DE_time")]
            if len(de) != 1:
                raise InputError(f"{path}: cannot tell which drive-end channel to use; give --channel "
                                 f"(available: {', '.join(sorted(keys))})")
            channel = de[0]
    if channel not in m:
        raise InputError(f"{path}: no channel {channel!r}; available: {', '.join(sorted(keys))}")
    if rpm is None:
        rec = re.match(r"(X\d+)_", channel)
        key = f"{rec.group(1)}RPM" if rec else None
        if key in m:
            rpm = float(np.asarray(m[key]).ravel()[0])
        elif len(rpm_keys) == 1:
            rpm = float(np.asarray(m[rpm_keys[0]]).ravel()[0])
    x = _check_data(m[channel], f"{path}:{channel}") * STANDARD_GRAVITY
    return Recording(x, fs, rpm, "cwru", None, channel, str(path))


def load_bag(path, sample_rate: float | None = None, rpm: float | None = None,
             channel: str | None = None) -> Recording:
    """rosbag2 directory recorded from the graph, via :func:`.bag_files.load_bag`.

    ``channel`` is the relative VibrationChunk topic (default ``vibration/drive_end``);
    the source (model set) comes from the chunks, the rpm from ``shaft_speed``.
    """
    try:
        from .bag_files import load_bag as _load_bag
    except ImportError as exc:
        raise InputError(f"{path}: rosbag2 input is not available ({exc}); convert the bag to .npz") from None
    rec = _load_bag(path, channel=channel)
    if sample_rate is not None:
        rec.sample_rate = _check_rate(sample_rate)
    if rpm is not None:
        rec.rpm = rpm
    rec.accel = _check_data(rec.accel, f"{path}:{channel or 'vibration/drive_end'}")
    return rec


def load_recording(path, sample_rate: float | None = None, rpm: float | None = None,
                   channel: str | None = None) -> Recording:
    """Load ``path`` by kind: directory → rosbag2, ``.npz`` → simulator, ``.mat`` → CWRU.

    ``sample_rate`` (Hz) overrides the file's (and is required for .mat); ``rpm``
    overrides the file's speed.  Raises :class:`InputError`.
    """
    p = Path(path)
    if sample_rate is not None:
        sample_rate = _check_rate(sample_rate)
    if rpm is not None and not (np.isfinite(rpm) and rpm > 0):
        raise InputError(f"rpm must be positive, got {rpm:g}")
    if not p.exists():
        raise InputError(f"{path}: no such file or directory")
    if p.is_dir():
        if (p / "metadata.yaml").is_file():
            return load_bag(p, sample_rate, rpm, channel)
        raise InputError(f"{path}: a directory but not a rosbag2 (no metadata.yaml)")
    suffix = p.suffix.lower()
    if suffix == ".npz":
        return load_npz(p, sample_rate, rpm, channel)
    if suffix == ".mat":
        return load_mat(p, sample_rate, rpm, channel)
    raise InputError(f"{path}: unknown file type {suffix or '(none)'}; expected .npz, .mat or a rosbag2 directory")
