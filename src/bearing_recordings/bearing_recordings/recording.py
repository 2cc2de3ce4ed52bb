"""A vibration recording ready for diagnosis, and the checks every loader applies.

Every loader returns a :class:`Recording` in SI units (m/s², Hz, rev/min, s) or raises
:class:`InputError` with a one-line message meant for the user.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bearing_common.bearings import Bearing
from bearing_common.units import sample_rate_problem

#: Longest recording a loader accepts (samples): 1 hour at 100 kHz (2.9 GB as float64).
MAX_SAMPLES = 360_000_000


#: Relative accuracy of a shaft speed a rig measured and stored with its recording.
MEASURED_RPM_TOLERANCE = 0.02


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
        Shaft speed (rev/min) if known (from the file or the command line).
    source : str
        Where the data come from: ``simulator``, ``cwru``, ``mfpt``, ``mat`` (another
        MATLAB file) or the source recorded in a bag's chunks; picks the default model set.
    truth : ndarray of int or None
        Per-sample true state (simulator output and bags holding ``sim/truth``).
    channel : str
        Channel name (e.g. ``X105_DE_time``, ``accel``, ``gs``).
    path : str
    start_time : float
        Stamp of the first sample (s; bags), 0 otherwise. Segment times are relative
        to the first sample.
    notes : list of str
        What the loader assumed (units, speed), for the user's log.
    bearing : Bearing or None
        The bearing the recording monitors, when the file says (MFPT files, the CWRU
        channel's end, bags written by ``bearing-bag``), parsed by the loader; else None.
    rpm_tolerance : float or None
        Relative accuracy of ``rpm`` as the file states it: :data:`MEASURED_RPM_TOLERANCE` for a
        speed the rig measured (CWRU's, MFPT's, a bag's ``shaft_speed``, the simulator's); None
        for a speed from the user or a label (the decision then assumes a nameplate's).
    """

    accel: np.ndarray
    sample_rate: float
    rpm: float | None
    source: str
    truth: np.ndarray | None = None
    channel: str = ""
    path: str = ""
    start_time: float = 0.0
    notes: list | None = None
    bearing: Bearing | None = None
    rpm_tolerance: float | None = None

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.accel.size / self.sample_rate


def check_rate(rate, what: str = "sample rate") -> float:
    """A plausible number of Hz (:func:`bearing_common.units.sample_rate_problem`), else :class:`InputError`."""
    try:
        rate = float(rate)
    except (TypeError, ValueError):
        raise InputError(f"invalid {what} {rate!r}") from None
    problem = sample_rate_problem(rate)
    if problem:
        raise InputError(problem.replace("sample rate", what, 1))
    return rate


def check_rpm(rpm) -> float:
    """A positive, finite shaft speed (rev/min), else :class:`InputError`."""
    try:
        rpm = float(rpm)
    except (TypeError, ValueError):
        raise InputError(f"invalid shaft speed {rpm!r}") from None
    if not math.isfinite(rpm) or rpm <= 0:
        raise InputError(f"shaft speed must be a positive number of rev/min, got {rpm:g}")
    return rpm


def check_samples(x, what: str) -> np.ndarray:
    """1-D float64 copy of numeric, finite samples; :class:`InputError` otherwise."""
    x = np.asarray(x)
    if x.dtype.kind not in "fiu":
        raise InputError(f"{what}: data is not numeric (dtype {x.dtype})")
    if x.ndim > 1 and sum(s > 1 for s in x.shape) > 1:
        raise InputError(f"{what}: expected one signal, got an array of shape {x.shape}")
    x = x.astype(float).ravel()
    if x.size == 0:
        raise InputError(f"{what}: no samples")
    if x.size > MAX_SAMPLES:
        raise InputError(f"{what}: {x.size} samples is more than the {MAX_SAMPLES} this tool reads at once; "
                         "split the recording")
    bad = ~np.isfinite(x)
    if bad.any():
        raise InputError(f"{what}: {int(bad.sum())} non-finite samples (NaN/inf), first at index {int(np.argmax(bad))}")
    return x
