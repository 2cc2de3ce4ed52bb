"""The spectral decision's last window (:class:`.spectral.envelope_view.EnvelopeView`) into a
``bearing_msgs/msg/EnvelopeSpectrum``, decimated for plotting (no rclpy import: the message objects
are the caller's).

Decimation: the tested range [2/T, f_top] of the normalised SES (one bin per 1/T Hz, about 180 bins
for a 6205 at any speed: T and f_top both scale with the shaft period; :data:`FIRST_BIN`) is cut into runs of
p = ceil(n / :data:`MAX_VALUES`) consecutive bins, and each run is max-held: its value is its
largest bin, placed at the run's centre. A line is never lost (a plain every-p-th-bin sample
would drop it two times in three at p = 3) and its frequency is known to within p/T Hz. At most
:data:`MAX_VALUES` values remain, so PlotJuggler's default array limit keeps the whole spectrum.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_common.stamps import to_stamp

#: First bin shown: bins 0 and 1 lie in the Hann main lobe (±2 bins) of the envelope's DC, where
#: the window's mean leaks (up to 10⁵ times the noise level on simulator output); no comb line is
#: that low (the lowest, a 6205's BPFO, lies at 3.6 shaft orders = 14 bins).
FIRST_BIN = 2

#: Values per published spectrum at most: PlotJuggler's default array size limit (it drops longer arrays).
MAX_VALUES = 100


def max_hold(values: np.ndarray, max_values: int = MAX_VALUES) -> tuple[np.ndarray, np.ndarray, int]:
    """``values`` (n,) max-held in runs of p = ceil(n / ``max_values``) (the last run may be shorter).

    Returns ``(held, centres, p)``: each run's largest value, the index of each run's centre (the
    mean of its first and last index: fractional when p is even) and p.
    """
    values = np.asarray(values, dtype=float)
    if values.ndim != 1 or values.size == 0:
        raise ValueError(f"max_hold needs a non-empty 1-D array, got shape {values.shape}")
    if max_values < 1:
        raise ValueError(f"max_values must be >= 1, got {max_values}")
    n = values.size
    p = -(-n // max_values)
    starts = np.arange(0, n, p)
    held = np.maximum.reduceat(values, starts)
    ends = np.minimum(starts + p, n) - 1
    return held, 0.5 * (starts + ends), p


def decimated_spectrum(view, max_values: int = MAX_VALUES) -> tuple[np.ndarray, np.ndarray, int]:
    """``(frequency Hz, magnitude, bins per value)`` of ``view``'s shown range (module docstring)."""
    n = min(view.ses.size, int(math.ceil(view.f_top / view.bin_width)) + 1)
    held, centres, p = max_hold(view.ses[FIRST_BIN:n], max_values)
    return (centres + FIRST_BIN) * view.bin_width, held, p


def fill_spectrum_message(msg, view, stamp: float, frame_id: str, line_type, max_values: int = MAX_VALUES):
    """Fill ``msg`` (an ``EnvelopeSpectrum``) from ``view``, stamped ``stamp`` (s, the window's end);
    ``line_type`` makes the ``FaultLines`` entries. Returns ``msg``."""
    freq, mag, p = decimated_spectrum(view, max_values)
    msg.header.stamp = to_stamp(stamp)
    msg.header.frame_id = frame_id
    msg.window_duration = view.length / view.sample_rate
    msg.bin_width = float(view.bin_width)
    msg.bins_per_value = int(p)
    msg.frequency_resolution = float(p * view.bin_width)
    msg.band_low, msg.band_high = (float(f) for f in view.band)
    msg.told_shaft_rate = math.nan if view.told_hz is None else float(view.told_hz)
    msg.shaft_rate = float(view.shaft_hz)
    msg.shaft_rate_source = view.shaft_source
    msg.frequency = [float(f) for f in freq]
    msg.magnitude = [float(v) for v in mag]
    msg.lines = [line_type(hypothesis=h.label,
                           told=[] if view.told_hz is None else [float(f) for f in view.lines(h, view.told_hz)],
                           measured=[float(f) for f in view.lines(h, view.shaft_hz)],
                           carrier=[bool(c) for c in terms[:, 2]], rho=float(view.rho.get(h, math.nan)))
                 for h, terms in view.terms.items()]
    return msg
