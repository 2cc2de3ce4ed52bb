"""A recording's speed or tachometer channel turned into the shaft speed per sample (rad/s).

``bearing-diagnose --speed-channel NAME --speed-units rpm|rad/s|hz|pulses [--pulses-per-rev N]``:
the channel NAME of the same file, sampled with the vibration (one value per sample), is

* a speed in ``rpm`` (rev/min), ``rad/s`` or ``hz`` (rev/s): converted; or
* ``pulses``: a tachometer's voltage, N pulses per revolution. Pulses are the rising edges
  through the middle of the signal's range (between its 1st and 99th percentiles), with a
  hysteresis of a quarter of that range against noise on the edges; each edge's time is
  interpolated linearly between the two samples around the crossing (sub-sample). The
  shaft angle and speed then come from :func:`bearing_common.shaft_angle.angle_from_pulses`
  (pulse times smoothed by a local quadratic fit; jitter and quantisation averaged out).

Where the file comes from does not matter: a reader of a file kind only has to give the
named channel's values (``read_channel`` of :mod:`.mat_files` and :mod:`.npz_files`; a
CSV reader gives a column the same way).
"""

from __future__ import annotations

import numpy as np

from bearing_common.shaft_angle import angle_from_pulses

from .recording import RAD_S_PER_RPM, InputError

#: Units of a speed channel: rad/s per unit, or None for a pulse train.
SPEED_UNITS = {"rpm": RAD_S_PER_RPM, "rad/s": 1.0, "hz": 2.0 * np.pi, "pulses": None}

#: Edges pass the mid level between these percentiles of the pulse signal.
_PULSE_PERCENTILES = (1.0, 99.0)

#: Hysteresis of the edge detector, as a fraction of the signal's range.
_HYSTERESIS = 0.25


def speed_from_channel(values, sample_rate: float, units: str, pulses_per_rev: int = 1,
                       what: str = "speed channel") -> np.ndarray:
    """Shaft speed per sample (rad/s) from a speed or pulse channel (module docstring);
    :class:`InputError` with the reason when it cannot be used."""
    if units not in SPEED_UNITS:
        raise InputError(f"unknown speed units {units!r}; expected one of {', '.join(SPEED_UNITS)}")
    v = np.asarray(values)
    if v.dtype.kind not in "fiu":
        raise InputError(f"{what}: not numeric (dtype {v.dtype})")
    v = v.astype(float).ravel()
    if SPEED_UNITS[units] is not None:
        return v * SPEED_UNITS[units]
    if int(pulses_per_rev) < 1:
        raise InputError(f"pulses per revolution must be >= 1, got {pulses_per_rev!r}")
    times = pulse_edges(v, sample_rate)
    if times.size < 3:
        raise InputError(f"{what}: found {times.size} tachometer pulses; need at least 3 to tell the speed")
    t = np.arange(v.size) / float(sample_rate)
    try:
        return angle_from_pulses(times, t, int(pulses_per_rev))[1]
    except ValueError as exc:
        raise InputError(f"{what}: {exc}") from None


def pulse_edges(v: np.ndarray, sample_rate: float) -> np.ndarray:
    """Times (s) of the rising edges of a pulse train sampled at ``sample_rate`` Hz (module docstring)."""
    lo, hi = np.percentile(v, _PULSE_PERCENTILES)
    if not hi > lo:
        return np.empty(0)
    mid, band = 0.5 * (lo + hi), 0.5 * _HYSTERESIS * (hi - lo)
    # Schmitt trigger: the state is high after the last excursion above mid + band, low after
    # one below mid - band (samples in between keep the state)
    level = np.where(v > mid + band, 1, np.where(v < mid - band, 0, -1))
    known = np.flatnonzero(level >= 0)
    if known.size == 0:
        return np.empty(0)
    state = level[known[np.maximum(np.searchsorted(known, np.arange(v.size), side="right") - 1, 0)]]
    rises = np.flatnonzero((state[1:] == 1) & (state[:-1] == 0)) + 1  # first sample of each high state
    # the crossing of mid before that sample: the last sample at or below mid, then interpolate
    below = np.flatnonzero(v <= mid)
    j = below[np.maximum(np.searchsorted(below, rises, side="right") - 1, 0)]
    j = np.minimum(j, v.size - 2)
    frac = (mid - v[j]) / np.where(v[j + 1] != v[j], v[j + 1] - v[j], 1.0)
    return (j + np.clip(frac, 0.0, 1.0)) / float(sample_rate)
