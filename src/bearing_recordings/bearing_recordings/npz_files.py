"""``bearing-sim`` output files (.npz: ``t``, ``accel``, ``unbalance``, ``sample_rate``, ``rpm``, ``truth``;
with a changing speed ``shaft_speed``, rad/s per sample, read as a tachometer)."""

from __future__ import annotations

import numpy as np

from .recording import MEASURED_RPM_TOLERANCE, InputError, Recording, check_rate, check_rpm, check_samples


def _contents(path) -> dict:
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except Exception as exc:  # zipfile / pickle / OS errors
        raise InputError(f"{path}: not a readable .npz file ({exc.__class__.__name__}: {exc})") from None


def read_channel(path, name: str) -> np.ndarray:
    """The array ``name`` of the file (e.g. a speed or tachometer channel); :class:`InputError` otherwise."""
    data = _contents(path)
    if name not in data:
        raise InputError(f"{path}: no channel {name!r}; available: {', '.join(sorted(data))}")
    return data[name]


def load_npz(path, sample_rate: float | None = None, rpm: float | None = None,
             channel: str | None = None) -> Recording:
    """Load a ``bearing-sim`` .npz; ``channel`` defaults to ``accel`` (m/s²)."""
    data = _contents(path)
    ch = channel or "accel"
    if ch not in data:
        raise InputError(f"{path}: no channel {ch!r}; available: {', '.join(sorted(data))}")
    fs = sample_rate
    if fs is None and "sample_rate" in data and data["sample_rate"].size == 1:
        fs = data["sample_rate"].item()
    if fs is None and "t" in data and data["t"].size > 1:
        fs = 1.0 / float(np.median(np.diff(data["t"])))
    if fs is None:
        raise InputError(f"{path}: no sample_rate in the file; give --sample-rate")
    fs = check_rate(fs)
    told = rpm is not None
    if rpm is None and "rpm" in data and data["rpm"].size == 1:
        rpm = data["rpm"].item()
    x = check_samples(data[ch], f"{path}:{ch}")
    truth = data.get("truth")
    if truth is not None and (truth.size != x.size or truth.dtype.kind not in "iu"):
        truth = None
    rec = Recording(x, fs, None if rpm is None else check_rpm(rpm), "simulator",
                    None if truth is None else truth.astype(int).ravel(), ch, str(path),
                    rpm_tolerance=None if told or rpm is None else MEASURED_RPM_TOLERANCE)
    try:
        speed = data["shaft_speed"]
    except KeyError:
        return rec
    if told:
        rec.notes = [f"the shaft speed was given ({rpm:g} rpm): the file's shaft_speed series is not used"]
    else:
        rec.set_shaft_speed(speed, f"{path}:shaft_speed")
    return rec
