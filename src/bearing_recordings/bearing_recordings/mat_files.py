"""MATLAB recordings of the three public rigs (and any one-signal file), with one channel rule.

Kinds, told apart by their variables:

* **MFPT** — a struct ``bearing`` with ``gs`` (acceleration, g), ``sr`` (sample rate, Hz),
  ``rate`` (shaft, Hz) and ``load``: nothing else is needed; the bearing is the rig's
  (catalog ``mfpt``).
* **CWRU** — variables ``X<rec>_DE_time``, ``X<rec>_FE_time``, ``X<rec>_BA_time`` (g) and
  ``X<rec>RPM``; the sample rate is not stored (12 or 48 kHz) and must be given. The bearing
  is the one the channel's accelerometer sits on: the drive end's SKF 6205 (``_DE_`` and the
  base ``_BA_``), the fan end's SKF 6203 (``_FE_``).
* **one signal** — exactly one numeric vector variable, whatever its name (HIT-SM:
  ``z15_1``, ``VarName3``, ...); sample rate must be given, units assumed g unless stated.

The channel rule (used by ``bearing-diagnose``, ``bearing-bag from-mat`` and
``bearing-identify`` alike): ``channel`` names the variable (MFPT: ``gs``) when given.
Otherwise a CWRU file gives its *record's* drive-end channel, the record being the one
whose ``X<rec>RPM`` the file holds, else the number the file name starts with (some CWRU
files also carry another record's variables; the first ``*_DE_time`` key is not a rule);
a one-signal file gives its signal; anything else is an error listing the variables.
"""

from __future__ import annotations

import io
import re
import struct
import zlib
from pathlib import Path

import numpy as np

from bearing_common.bearings import CATALOG
from bearing_common.units import STANDARD_GRAVITY

from .measurement_units import value_scale
from .recording import MEASURED_RPM_TOLERANCE, InputError, Recording, check_rate, check_rpm, check_samples

_CWRU_CHANNEL = re.compile(r"X(\d+)_(DE|FE|BA)_time")
_CWRU_RPM = re.compile(r"X(\d+)RPM")

#: MAT-file v5 element types (miMATRIX, miCOMPRESSED) and the byte size of numeric ones.
_MI_MATRIX, _MI_COMPRESSED = 14, 15
_ITEM_SIZE = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8}
#: mx classes: cell, struct; the numeric ones (double ... uint64).
_MX_CELL, _MX_STRUCT, _MX_NUMERIC = 1, 2, range(6, 16)


def _elements(data: bytes, start: int, end: int, order: str):
    """(type, body offset, size) of each data element in ``data[start:end]``; ValueError when one overruns."""
    pos = start
    while pos < end:
        if pos + 8 > end:
            raise ValueError(f"element tag at byte {pos} cut short")
        kind, size = struct.unpack_from(order + "II", data, pos)
        if kind >> 16:  # small data element: type and size in one word, payload in the next
            kind, size = kind & 0xFFFF, kind >> 16
            if size > 4:
                raise ValueError(f"small element at byte {pos} claims {size} bytes")
            yield kind, pos + 4, size
            pos += 8
            continue
        body = pos + 8
        if body + size > end:
            raise ValueError(f"element at byte {pos} claims {size} bytes, {end - body} left")
        yield kind, body, size
        pos = body + size + (0 if kind == _MI_COMPRESSED else -size % 8)  # compressed elements are not padded


def _check_matrix(data: bytes, body: int, end: int, order: str, depth: int) -> None:
    """An miMATRIX element as scipy reads it: flags, dimensions, name, then data that fits them."""
    parts = _elements(data, body, end, order)
    kind, at, size = next(parts, (None, 0, 0))
    if kind != 6 or size != 8:
        raise ValueError(f"array at byte {body} has no array flags")
    mx_class = data[at] if order == "<" else data[at + 3]
    kind, at, size = next(parts, (None, 0, 0))
    if kind != 5 or size < 8 or size % 4:
        raise ValueError(f"array at byte {body} has no dimensions")
    count = int(np.prod(np.frombuffer(data, order.replace("<", "<i4").replace(">", ">i4"), size // 4, at),
                        dtype=np.int64))
    if count < 0:
        raise ValueError(f"array at byte {body} has negative dimensions")
    if next(parts, (None,))[0] != 1:
        raise ValueError(f"array at byte {body} has no name")
    rest = list(parts)
    if mx_class in _MX_NUMERIC:
        if not rest or rest[0][0] not in _ITEM_SIZE or rest[0][2] != count * _ITEM_SIZE[rest[0][0]]:
            raise ValueError(f"array at byte {body}: data does not match its {count} elements")
    elif mx_class in (_MX_CELL, _MX_STRUCT):
        for kind, at, size in rest:
            if kind == _MI_MATRIX and depth < 8:
                _check_matrix(data, at, at + size, order, depth + 1)


def _check_structure(data: bytes) -> None:
    """Refuse a MAT-file v5 whose element sizes, dimensions or data disagree (ValueError).

    scipy's reader trusts them and has crashed the process (segmentation fault) on a file
    cut short and padded; such files are refused here with the reason instead.
    """
    order = "<" if data[126:128] == b"IM" else ">"
    for kind, at, size in _elements(data, 128, len(data), order):
        if kind == _MI_COMPRESSED:
            inner = zlib.decompress(data[at:at + size])
            for k, a, n in _elements(inner, 0, len(inner), order):
                if k == _MI_MATRIX:
                    _check_matrix(inner, a, a + n, order, 0)
        elif kind == _MI_MATRIX:
            _check_matrix(data, at, at + size, order, 0)


def _read(path) -> dict:
    from scipy.io import loadmat
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.__class__.__name__}: {exc})") from None
    if data[:19] == b"MATLAB 7.3 MAT-file":
        raise InputError(f"{path}: MATLAB v7.3 (HDF5) files are not supported; save it with save(..., '-v7')")
    if not data.startswith(b"MATLAB 5.0 MAT-file") or len(data) < 128 or data[126:128] not in (b"IM", b"MI"):
        raise InputError(f"{path}: not a MATLAB 5/7 MAT-file (no MAT-file header)")
    try:
        _check_structure(data)
        return loadmat(io.BytesIO(data))
    except Exception as exc:  # scipy raises ValueError, TypeError, OSError, ... on damaged files
        raise InputError(f"{path}: not a readable MATLAB file ({exc.__class__.__name__}: "
                         f"{' '.join(str(exc).split())})") from None


def _scalar(value, what: str, path) -> float:
    arr = np.asarray(value)
    if arr.dtype == object:
        arr = np.asarray(arr.ravel()[0]) if arr.size == 1 else arr
    try:
        return float(np.asarray(arr, dtype=float).ravel()[0])
    except (TypeError, ValueError, IndexError):
        raise InputError(f"{path}: {what} is not a number") from None


def load_mat(path, sample_rate: float | None = None, rpm: float | None = None,
             channel: str | None = None, units: str | None = None, sensitivity: str | None = None) -> Recording:
    """Load a MATLAB recording (MFPT, CWRU or one signal) in m/s².

    ``sample_rate`` (Hz) is required for CWRU and one-signal files and overrides MFPT's
    ``sr``; ``rpm`` overrides the file's speed; ``units`` (``g`` or ``m/s2``) or
    ``sensitivity`` (:mod:`.measurement_units`) states what a one-signal file's numbers
    measure (default g, said in the recording's notes).
    """
    m = _read(path)
    keys = sorted(k for k in m if not k.startswith("__"))
    if "bearing" in keys and getattr(m["bearing"], "dtype", None) is not None and m["bearing"].dtype.names:
        return _load_mfpt(path, m["bearing"], sample_rate, rpm, channel)
    if any(_CWRU_CHANNEL.fullmatch(k) for k in keys):
        return _load_cwru(path, m, keys, sample_rate, rpm, channel)
    return _load_single(path, m, keys, sample_rate, rpm, channel, units, sensitivity)


def read_channel(path, name: str) -> np.ndarray:
    """The values of variable ``name`` (an MFPT file: a field of its struct ``bearing``), e.g. a
    speed or tachometer channel; :class:`InputError` listing what there is otherwise."""
    m = _read(path)
    keys = sorted(k for k in m if not k.startswith("__"))
    struct = m.get("bearing")
    fields = struct.dtype.names if getattr(struct, "dtype", None) is not None and struct.dtype.names else ()
    if name in fields:
        return np.asarray((struct[0, 0] if struct.ndim == 2 else struct.ravel()[0])[name])
    if name in keys:
        return np.asarray(m[name])
    raise InputError(f"{path}: no channel {name!r}; available: {', '.join(list(fields) + keys)}")


def _need_rate(path, sample_rate, hint: str) -> float:
    if sample_rate is None:
        raise InputError(f"{path}: the file does not store its sample rate; give --sample-rate ({hint})")
    return check_rate(sample_rate)


def _load_mfpt(path, struct, sample_rate, rpm, channel) -> Recording:
    fields = struct.dtype.names
    missing = [f for f in ("gs", "sr", "rate") if f not in fields]
    if missing:
        raise InputError(f"{path}: MFPT struct 'bearing' lacks {', '.join(missing)} (has {', '.join(fields)})")
    rec = struct[0, 0] if struct.ndim == 2 else struct.ravel()[0]
    ch = channel or "gs"
    if ch not in fields:
        raise InputError(f"{path}: no channel {ch!r} in the MFPT struct (has {', '.join(fields)})")
    fs = check_rate(sample_rate if sample_rate is not None else _scalar(rec["sr"], "bearing.sr", path))
    speed = check_rpm(rpm) if rpm is not None else check_rpm(60.0 * _scalar(rec["rate"], "bearing.rate", path))
    x = check_samples(rec[ch], f"{path}:bearing.{ch}") * STANDARD_GRAVITY
    return Recording(x, fs, speed, "mfpt", None, ch, str(path), bearing=CATALOG["mfpt"],
                     rpm_tolerance=None if rpm is not None else MEASURED_RPM_TOLERANCE)


def _cwru_record(path, keys) -> str:
    records_with_rpm = sorted({_CWRU_RPM.fullmatch(k).group(1) for k in keys if _CWRU_RPM.fullmatch(k)})
    if len(records_with_rpm) == 1:
        return records_with_rpm[0]
    channels = {_CWRU_CHANNEL.fullmatch(k).group(1) for k in keys if _CWRU_CHANNEL.fullmatch(k)}
    lead = re.match(r"0*(\d+)", Path(path).name)
    if lead:
        for rec in channels:
            if int(rec) == int(lead.group(1)):
                return rec
    if len(channels) == 1:
        return channels.pop()
    raise InputError(f"{path}: holds several CWRU records ({', '.join(sorted(channels))}); "
                     f"give --channel (available: {', '.join(keys)})")


def _load_cwru(path, m, keys, sample_rate, rpm, channel) -> Recording:
    fs = _need_rate(path, sample_rate, "CWRU: 12000 or 48000")
    if channel is None:
        channel = f"X{_cwru_record(path, keys)}_DE_time"
    if channel not in keys:
        raise InputError(f"{path}: no channel {channel!r}; available: {', '.join(keys)}")
    if rpm is not None:
        speed = check_rpm(rpm)
    else:
        rec = _CWRU_CHANNEL.fullmatch(channel)
        key = f"X{rec.group(1)}RPM" if rec else None
        speed = check_rpm(_scalar(m[key], key, path)) if key in m else None
    x = check_samples(m[channel], f"{path}:{channel}") * STANDARD_GRAVITY
    return Recording(x, fs, speed, "cwru", None, channel, str(path),
                     bearing=CATALOG["6203" if "_FE_" in channel else "6205"],
                     rpm_tolerance=MEASURED_RPM_TOLERANCE if rpm is None and speed is not None else None)


def _load_single(path, m, keys, sample_rate, rpm, channel, units, sensitivity) -> Recording:
    signals = [k for k in keys if np.asarray(m[k]).dtype.kind in "fiu" and np.asarray(m[k]).size > 1]
    if channel is None:
        if len(signals) != 1:
            raise InputError(f"{path}: cannot tell which variable is the vibration signal; give --channel "
                             f"(available: {', '.join(keys) or 'none'})")
        channel = signals[0]
    if channel not in keys:
        raise InputError(f"{path}: no channel {channel!r}; available: {', '.join(keys)}")
    fs = _need_rate(path, sample_rate, "the rig's documentation states it")
    scale, note = value_scale(units, sensitivity, channel)
    x = check_samples(m[channel], f"{path}:{channel}") * scale
    return Recording(x, fs, None if rpm is None else check_rpm(rpm), "mat", None, channel, str(path),
                     notes=[note] if note else [])
