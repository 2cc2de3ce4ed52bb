"""NumPy .npz recordings: a real machine's, or the simulator's when the file says so.

The file holds ``accel`` (m/s², or the ``channel`` given) and ``sample_rate`` (Hz; else a
``t`` array in s, else ``--sample-rate``); it may hold ``rpm`` (a speed the rig measured),
``truth`` (per-sample states) and ``source``. It is a real machine's recording unless
``source`` is ``simulator`` (``bearing-sim`` writes that, with ``t``, ``unbalance``,
``truth``): a ``truth`` array is no proof of the simulator, a labelled real recording may
carry one. Any other ``source`` (e.g. ``cwru``) is kept as the recording's source, which
picks the model set; without one the source is ``npz`` (no model set: the real-machine
decision). A file with the simulator's arrays but no ``source`` (``bearing-sim`` before it
wrote one) is read as real too, and a note says how to read it as the simulator's
(``--model-set``).
With a changing speed it may hold ``shaft_speed`` (rad/s per sample), read as a tachometer.
"""

from __future__ import annotations

import numpy as np

from .recording import MEASURED_RPM_TOLERANCE, InputError, Recording, check_rate, check_rpm, check_samples

#: ``source`` of the simulator's files.
SIMULATOR = "simulator"

#: Source of a .npz that names none.
UNNAMED_SOURCE = "npz"


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
    """Load a .npz recording (module docstring); ``channel`` defaults to ``accel`` (m/s²)."""
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
    source, notes = _source(path, data)
    rec = Recording(x, fs, None if rpm is None else check_rpm(rpm), source,
                    None if truth is None else truth.astype(int).ravel(), ch, str(path), notes=notes,
                    rpm_tolerance=None if told or rpm is None else MEASURED_RPM_TOLERANCE)
    try:
        speed = data["shaft_speed"]
    except KeyError:
        return rec
    if told:
        rec.notes = notes + [f"the shaft speed was given ({rpm:g} rpm): the file's shaft_speed series is not used"]
    else:
        rec.set_shaft_speed(speed, f"{path}:shaft_speed")
    return rec


def _source(path, data: dict) -> tuple[str, list]:
    """The recording's source (module docstring) and what the user should know of it."""
    if "source" not in data:
        if {"t", "unbalance", "truth"} <= data.keys():  # the simulator's arrays
            return UNNAMED_SOURCE, ["no source in the file: read as a real machine's recording; an older bearing-sim "
                                    "file? --model-set sim_48k (or sim_12k) reads it as the simulator's"]
        return UNNAMED_SOURCE, []
    s = data["source"]
    if s.dtype.kind not in "US" or s.size != 1:
        raise InputError(f"{path}: source must be one text (e.g. 'simulator'), got an array of {s.dtype} "
                         f"shape {s.shape}")
    text = str(s.item().decode(errors="replace") if s.dtype.kind == "S" else s.item()).strip()
    if text.lower() == SIMULATOR:
        return SIMULATOR, []
    return text or UNNAMED_SOURCE, []
