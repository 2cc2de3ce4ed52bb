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

#: A measured speed series *varies* when its spread (max − min) exceeds this fraction of its mean:
#: more than a measured constant speed is trusted to (:data:`MEASURED_RPM_TOLERANCE`).
SPEED_VARIATION = MEASURED_RPM_TOLERANCE

RAD_S_PER_RPM = 2.0 * math.pi / 60.0


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
    shaft_speed : ndarray, shape (n,), or None
        Measured shaft speed per sample (rad/s), like a tachometer: from a ``.npz``'s
        ``shaft_speed``, a speed or pulse channel (:mod:`.speed_channel`) or a bag's
        ``shaft_speed`` when it changes. ``rpm`` is then its mean, so a constant-speed
        decision still has one number, and :attr:`speed_varies` says whether that hides a
        change. None when the speed is one number only.
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
    shaft_speed: np.ndarray | None = None

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.accel.size / self.sample_rate

    @property
    def speed_spread(self) -> float:
        """(max − min) / mean of :attr:`shaft_speed` (0 without a series)."""
        if self.shaft_speed is None:
            return 0.0
        w = self.shaft_speed
        return float((w.max() - w.min()) / w.mean())

    @property
    def speed_varies(self) -> bool:
        """True when the measured speed changes by more than :data:`SPEED_VARIATION` of its mean."""
        return self.speed_spread > SPEED_VARIATION

    def set_shaft_speed(self, speed, what: str) -> None:
        """Attach a measured speed per sample (rad/s; checked by :func:`check_shaft_speed`): ``rpm``
        becomes its mean, measured (``rpm_tolerance`` = :data:`MEASURED_RPM_TOLERANCE`)."""
        self.shaft_speed = check_shaft_speed(speed, self.accel.size, what)
        self.rpm = mean_rpm(self.shaft_speed)
        self.rpm_tolerance = MEASURED_RPM_TOLERANCE


def mean_rpm(speed: np.ndarray) -> float:
    """Mean of a speed series (rad/s) in rev/min; a constant series gives its value exactly."""
    mean = speed[0] if np.all(speed == speed[0]) else np.mean(speed)
    return float(mean) / RAD_S_PER_RPM


def check_shaft_speed(speed, n: int, what: str) -> np.ndarray:
    """A float64 speed series (rad/s) of ``n`` finite, positive values; :class:`InputError` otherwise."""
    w = np.asarray(speed)
    if w.dtype.kind not in "fiu":
        raise InputError(f"{what}: the shaft speed is not numeric (dtype {w.dtype})")
    w = w.astype(float).ravel()
    if w.size != n:
        raise InputError(f"{what}: the shaft speed has {w.size} values for {n} samples (one per sample expected)")
    bad = ~np.isfinite(w) | (w <= 0.0)
    if bad.any():
        raise InputError(f"{what}: the shaft speed is not a positive finite number of rad/s at {int(bad.sum())} "
                         f"samples, first at index {int(np.argmax(bad))}")
    return w


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
