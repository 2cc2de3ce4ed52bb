"""Computed order tracking in front of the spectral core: a stream of samples resampled, as it
arrives, to equal increments of shaft angle.

When the shaft speed changes, the lines of a fault comb move with it and smear over a window,
and the long horizon cannot add windows whose combs sit at other frequencies. Resampled to
equal angle increments Δφ, the signal is a function of the shaft angle: every line locked to
the shaft (its harmonics, the fault combs, whose frequencies are fixed multiples of the
shaft rate up to the rolling elements' slip) stands at a fixed *order* however the speed
moves. :class:`AngleStream` hands the spectral core (:class:`.evidence_stream.EvidenceStream`,
unchanged) such a signal as if it were sampled at the input's rate fs while the shaft turned
at a constant *nominal* rate f₀: Δφ = 2π·f₀/fs, so a line of order k appears at k·f₀ "Hz" and
every comb at its constant-speed frequency for f₀. The core's windows, slip search, band
choice and long horizon then work in the angle domain as they do at constant speed, and the
long horizon accumulates across the speed change (its geometry, f₀, never moves).

The angle φ(t) = ∫ω dt comes from the measured speed per input sample (a tachometer, the
``shaft_speed`` topic, a recording's speed channel, or :func:`..order_tracking.track_speed`),
integrated by the trapezoidal rule (:func:`bearing_common.shaft_angle.angle_from_speed`) from
the points it is told (:class:`SpeedPoints`: linear between them, held beyond the newest). The
output instants are where φ reaches k·Δφ (linear interpolation of the per-sample angle), the
values band-limited interpolation (:func:`bearing_recordings.resampling.sample_at`)
anti-aliased at R/2.2 for the local output rate R = ω/Δφ, as in
:func:`..order_tracking.resample_to_angle`. Causal: an output is made once the input holds the
interpolation kernel's half-width beyond its instant (24 zero crossings of the cutoff: 26
samples at the nominal speed, more below it), a delay of a few milliseconds.

What does not follow the shaft moves in the angle domain: a structural resonance, fixed in Hz,
sits at order F/f(t), i.e. at F·f₀/f(t) "Hz" of the angle signal. The core re-chooses its
demodulation band every second on the last two (:mod:`.band_choice`), so the band follows the
resonance's drift; within one window a resonance moves by the relative speed change over the
window (a ±20 % ramp over 10 s at 1800 rev/min: 0.7 % in 0.33 s), far less than a band's
width. The sensor's usable bandwidth B (Hz) maps to B·f₀/f_hi in the angle domain at the highest
speed f_hi the stream is expected to reach (:meth:`AngleStream.usable_bandwidth`): above it an
angle "frequency" may hold what the sensor does not measure.

Indices: the input's are sample indices of the stream; the angle stream's own indices count
the increments Δφ from the first output (0), with a jump over a gap in the input (the angle
turned through the gap at the speed told there), so that the core sees the gap and restarts
its schedule. :meth:`AngleStream.input_index` maps an angle index back to the (fractional)
input index where the shaft reached it.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_common.chunk_stream import StreamCursor
from bearing_common.indexed_buffer import IndexedBuffer
from bearing_recordings.resampling import SINC_ZEROS, sample_at

#: Cutoff of the anti-aliasing low-pass relative to the output rate (:mod:`..order_tracking`'s ANTI_ALIAS).
ANTI_ALIAS = 1.0 / 2.2

#: Input index ↔ angle index pairs kept for :meth:`AngleStream.input_index` (one per pushed chunk:
#: 100 a second of live 0.01 s chunks, so an hour).
MAP_POINTS = 360_000


class SpeedPoints:
    """The measured shaft speed over input sample indices: points (index, rad/s), linear between
    them and held beyond the first and the newest (a speed message arrives before or after the
    samples it applies to)."""

    def __init__(self):
        self._index = np.zeros(0)
        self._rad_s = np.zeros(0)

    def add(self, index, rad_s) -> None:
        """Points at input indices ``index`` (increasing, fractional allowed) with speeds ``rad_s``
        (rad/s, > 0); points at or before the newest held are dropped (a late or repeated message)."""
        index, rad_s = np.atleast_1d(np.asarray(index, dtype=float)), np.atleast_1d(np.asarray(rad_s, dtype=float))
        if self._index.size:
            keep = index > self._index[-1]
            index, rad_s = index[keep], rad_s[keep]
        self._index, self._rad_s = np.r_[self._index, index], np.r_[self._rad_s, rad_s]

    @property
    def known(self) -> bool:
        return self._index.size > 0

    def at(self, index) -> np.ndarray:
        """rad/s at input indices ``index``."""
        return np.interp(index, self._index, self._rad_s)

    def forget_before(self, index: float) -> None:
        """Drop points no longer needed for indices ≥ ``index`` (one before it stays)."""
        cut = int(np.searchsorted(self._index, index, side="right")) - 1
        if cut > 0:
            self._index, self._rad_s = self._index[cut:], self._rad_s[cut:]


class AngleStream:
    """Streaming resampling of one channel to equal shaft-angle increments (module docstring).

    Parameters
    ----------
    sample_rate : float
        fs, Hz: the input's rate, and the angle signal's nominal rate.
    nominal_hz : float
        f₀, the shaft rate (Hz) the angle signal is presented at: Δφ = 2π·f₀/fs rad per output.
    """

    def __init__(self, sample_rate: float, nominal_hz: float):
        if not (nominal_hz > 0 and math.isfinite(nominal_hz)):
            raise ValueError(f"the nominal shaft rate must be positive, got {nominal_hz!r} Hz")
        self.fs = float(sample_rate)
        self.nominal_hz = float(nominal_hz)
        self.step = 2.0 * math.pi * self.nominal_hz / self.fs  # rad per output sample
        self.speed = SpeedPoints()
        self._held = IndexedBuffer(2)  # rows: the input samples and the shaft angle at each (rad)
        self._cursor = StreamCursor()
        self._next_k: int | None = None  # angle index (from angle 0) of the next output
        self._k0: int | None = None  # angle index of output 0
        self._map_in: list[float] = []  # input index ↔ angle index (output numbering) pairs
        self._map_out: list[float] = []

    # -- samples in, angle samples out ---------------------------------------------------
    def push(self, first_index: int, y) -> tuple[int, np.ndarray]:
        """Input samples ``y`` from input index ``first_index`` (their speed told before, by
        :attr:`speed`); returns (angle index of the first output, the outputs that became due).
        ValueError while no speed has been told or when it is not positive."""
        if not self.speed.known:
            raise ValueError("the angle domain needs the shaft speed of its samples: none told yet")
        y = np.asarray(y, dtype=float)
        offset = self._cursor.offset(first_index)
        if offset is not None and offset < 0:  # overlap: keep only new samples
            y, first_index = y[-offset:], first_index - offset
        if y.size == 0:
            return self._next_out(), np.zeros(0)
        w = self.speed.at(first_index + np.arange(y.size))
        if not np.all(w > 0.0):
            raise ValueError("the angle domain needs a positive shaft speed")
        if offset is None:  # the first samples: angle 0 at the first
            phi0 = 0.0
            self._held.clear(first=first_index)
        else:  # continue (or jump a gap at the speed told there: the trapezoid over the gap)
            last = self._held.end - 1
            w_last = float(self.speed.at(last))
            phi_last = self._last_angle()
            phi0 = phi_last + 0.5 * (w_last + w[0]) * (first_index - last) / self.fs
            if offset > 0:
                self._held.clear(first=first_index)
        phi = phi0 + np.r_[0.0, np.cumsum(0.5 * (w[1:] + w[:-1]) / self.fs)]
        self._held.append(np.vstack([y, phi]))
        self._cursor.advance(first_index, y.size)
        if self._next_k is None:
            self._next_k = self._k0 = int(math.ceil(phi[0] / self.step))
        return self._resample(w)

    def _last_angle(self) -> float:
        end = self._held.end
        return float(self._held.view(end - 1, end)[1, 0])

    def _next_out(self) -> int:
        return 0 if self._next_k is None else self._next_k - self._k0

    def _resample(self, w: np.ndarray) -> tuple[int, np.ndarray]:
        """The outputs whose kernels the held input covers; trims what no output needs again."""
        first_held, end = self._held.end - self._held.held, self._held.end
        x, phi = self._held.view(first_held, end)
        cut_lo = min(0.5 * self.fs, ANTI_ALIAS * float(np.min(w)) / self.step)
        reach = 2 * int(math.ceil(SINC_ZEROS * self.fs / (2.0 * cut_lo))) + 2  # input samples past an instant
        k0 = self._next_out()
        if x.size <= reach:
            return k0, np.zeros(0)
        k_last = int(math.floor(phi[x.size - 1 - reach] / self.step))
        if k_last < self._next_k:
            return k0, np.zeros(0)
        angles = np.arange(self._next_k, k_last + 1) * self.step
        where = np.interp(angles, phi, np.arange(x.size, dtype=float))  # fractional held position
        lo = max(0, int(where[0]) - reach)
        rate = np.interp(where, np.arange(x.size, dtype=float), self.speed.at(first_held + np.arange(x.size))) \
            / self.step  # outputs per second
        cutoff = np.minimum(0.5 * self.fs, ANTI_ALIAS * rate)
        out = sample_at(x[lo:], self.fs, (where - lo) / self.fs, cutoff)
        self._map_in += [first_held + where[0], first_held + where[-1]]
        self._map_out += [float(k0), float(k0 + out.size - 1)]
        if len(self._map_in) > MAP_POINTS:
            del self._map_in[:-MAP_POINTS // 2], self._map_out[:-MAP_POINTS // 2]
        self._next_k = k_last + 1
        keep = first_held + int(where[-1]) - reach
        self._held.trim(keep)
        self.speed.forget_before(keep - 1)
        return k0, out

    @property
    def first_angle(self) -> float | None:
        """The shaft angle (rad, 0 at the first input sample) of angle index 0; None before any input."""
        return None if self._k0 is None else self._k0 * self.step

    # -- angle indices back to input indices ----------------------------------------------
    def input_index(self, angle_index) -> np.ndarray | float:
        """The (fractional) input index where the shaft reached angle index ``angle_index`` (linear
        between the chunks' first and last outputs; held beyond the oldest pair kept)."""
        return np.interp(angle_index, self._map_out, self._map_in)

    def usable_bandwidth(self, usable_hz: float, top_hz: float) -> float:
        """The angle signal's usable bandwidth ("Hz" at the nominal rate) for a sensor usable up to
        ``usable_hz`` Hz (0: 0.45·fs) and a shaft expected to turn at most at ``top_hz`` Hz."""
        usable = usable_hz or 0.45 * self.fs
        return min(usable, 0.45 * self.fs) * min(1.0, self.nominal_hz / top_hz)
