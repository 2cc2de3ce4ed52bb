"""The shaft angle φ(t) = ∫ω dt (rad) from what a machine tells about its speed.

Three sources, one idea (the simulator, the observers and the order tracking all need it):

* :class:`SpeedProfile` — a *schedule*: ω(t) piecewise linear through knots (t_i, ω_i),
  constant before the first and after the last. The angle is exact (piecewise quadratic)
  and so is its inverse (the time at which the shaft reaches an angle), so a simulator or a
  tachometer model can step exactly onto angles. Spec strings ``"T0:RPM0,T1:RPM1,..."``
  (seconds:rev/min) give ramps, run-ups, coast-downs and steps (a short ramp);
  :meth:`SpeedProfile.with_wobble` adds a slow sinusoidal speed wobble.
* :func:`angle_from_speed` — a speed measured per sample (rad/s), integrated by the
  trapezoidal rule (exact for a speed linear between samples).
* :func:`angle_from_pulses` — tachometer pulse times (s), ``pulses_per_rev`` per revolution.
  Pulse k marks the angle 2π k / pulses_per_rev exactly; its *time* carries the timing
  jitter. The times are smoothed by a local quadratic least-squares fit of pulse time
  against pulse angle over 2M + 1 pulses (the regressor, the angle, is exact: no
  errors-in-variables bias). On a symmetric window the fitted speed's relative noise is
  σ/(P·√(M(M+1)(2M+1)/3)) for jitter σ and pulse period P, 7.5 times below differencing
  consecutive pulses (√2·σ/P) for the default M = 3, while the quadratic follows a ramp's
  curvature (bias 2e-5 of the speed on a 900→1800 rev/min run-up over 10 s; with 20 µs
  jitter the speed error is 2e-4 RMS there, against 7e-4 without the fit). Between pulses
  the angle is the cubic Hermite interpolant through the smoothed times with the fitted
  speeds as slopes (C¹).

Units: s, rad, rad/s; ``rpm`` = rev/min. Angles are 0 at t = 0 unless stated.
"""

from __future__ import annotations

import math

import numpy as np

RPM_TO_RAD_S = math.pi / 30.0  #: rad/s per rev/min

#: Knots per period of a sinusoidal wobble: the piecewise-linear speed stays within
#: 1 - cos(π/32) = 0.48 % of the wobble's amplitude of the sine.
WOBBLE_KNOTS_PER_PERIOD = 32


class SpeedProfile:
    """Shaft speed ω(t) (rad/s), piecewise linear through (times[i], omegas[i]).

    ``times`` strictly increasing (s), ``omegas`` > 0 and finite (rad/s); one knot = a
    constant speed. ω is held at its first value before ``times[0]`` and at its last after
    ``times[-1]``. Raises ValueError with the reason otherwise.
    """

    def __init__(self, times, omegas, _rpms=None):
        t = np.atleast_1d(np.asarray(times, dtype=float))
        w = np.atleast_1d(np.asarray(omegas, dtype=float))
        if t.ndim != 1 or t.shape != w.shape or t.size == 0:
            raise ValueError("a speed profile needs matching, non-empty lists of times and speeds")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(w))):
            raise ValueError("speed profile times and speeds must be finite")
        if np.any(np.diff(t) <= 0.0):
            raise ValueError("speed profile times must increase strictly (a speed step is a short ramp, "
                             "e.g. '1:1800,1.05:1500')")
        if np.any(w <= 0.0):
            raise ValueError(f"shaft speed must stay positive, got {w.min() / RPM_TO_RAD_S:g} rev/min")
        self.times, self.omegas = t, w
        # the knots' rev/min as given (from_rpm_points), so that rpm() returns them exactly
        self._rpms = w / RPM_TO_RAD_S if _rpms is None else np.atleast_1d(np.asarray(_rpms, dtype=float))
        self._slopes = np.diff(w) / np.diff(t)  # rad/s^2 per piece
        # G_i = integral of omega from times[0] to times[i]; angle(t) = G(t) - G(0)
        self._g = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
        self._g0 = float(self._g_at(np.array([0.0]))[0])

    # ---------------------------------------------------------------- builders
    @classmethod
    def constant(cls, rpm: float) -> SpeedProfile:
        """A constant speed of ``rpm`` rev/min."""
        return cls.from_rpm_points([(0.0, rpm)])

    @classmethod
    def from_rpm_points(cls, points) -> SpeedProfile:
        """From ``[(seconds, rev/min), ...]``."""
        pts = list(points)
        rpms = [_rpm(r) for _, r in pts]
        return cls([float(t) for t, _ in pts], [r * RPM_TO_RAD_S for r in rpms], rpms)

    @classmethod
    def parse(cls, spec: str) -> SpeedProfile:
        """``"T0:RPM0,T1:RPM1,..."`` (seconds:rev/min, piecewise linear), e.g. a run-up
        ``"0:900,10:1800"``, a coast-down ``"2:1800,12:300"``, a step ``"1:1800,1.05:1500"``."""
        if not isinstance(spec, str) or not spec.strip():
            raise ValueError("empty speed profile; expected 'T0:RPM0,T1:RPM1,...' e.g. '0:900,10:1800'")
        points = []
        for item in spec.split(","):
            seconds, sep, rpm = item.strip().partition(":")
            try:
                if not sep:
                    raise ValueError
                points.append((float(seconds), float(rpm)))
            except ValueError:
                raise ValueError(f"speed profile item {item.strip()!r} is not of the form seconds:rpm") from None
        return cls.from_rpm_points(points)

    @classmethod
    def ramp(cls, rpm0: float, rpm1: float, duration: float, start: float = 0.0) -> SpeedProfile:
        """``rpm0`` until ``start`` s, linearly to ``rpm1`` over ``duration`` s, then ``rpm1``
        (a run-up or a coast-down)."""
        if not duration > 0:
            raise ValueError(f"ramp duration must be positive, got {duration!r} s")
        return cls.from_rpm_points([(start, rpm0), (start + duration, rpm1)])

    def with_wobble(self, amplitude: float, period: float, until: float) -> SpeedProfile:
        """This profile times (1 + ``amplitude``·sin(2π t / ``period``)) over [0, ``until``] s.

        The product is sampled into :data:`WOBBLE_KNOTS_PER_PERIOD` linear pieces per
        period (plus the profile's own knots); after ``until`` the speed is constant.
        """
        if not 0.0 <= amplitude < 1.0:
            raise ValueError(f"wobble amplitude must be in [0, 1) of the speed, got {amplitude!r}")
        if amplitude == 0.0:
            return self
        if not (period > 0 and until > 0 and math.isfinite(period) and math.isfinite(until)):
            raise ValueError(f"wobble period and duration must be positive, got {period!r} s, {until!r} s")
        n = int(math.ceil(until / period * WOBBLE_KNOTS_PER_PERIOD))
        grid = np.linspace(0.0, until, n + 1)
        inner = self.times[(self.times > 0.0) & (self.times < until)]
        t = np.union1d(np.union1d(grid, inner), self.times[self.times < 0.0])
        w = self.omega(t) * (1.0 + amplitude * np.sin(2.0 * np.pi * np.maximum(t, 0.0) / period))
        return SpeedProfile(t, w)

    # ---------------------------------------------------------------- queries
    @property
    def is_constant(self) -> bool:
        """True when the speed never changes."""
        return bool(np.all(self.omegas == self.omegas[0]))

    @property
    def knots(self) -> np.ndarray:
        """Times (s) where the acceleration may jump (a stepping integrator stops there)."""
        return self.times

    def omega(self, t) -> np.ndarray:
        """Shaft speed (rad/s) at time(s) ``t`` (s)."""
        return np.interp(t, self.times, self.omegas)

    def alpha(self, t) -> np.ndarray:
        """Shaft angular acceleration (rad/s²) at ``t``: constant per piece, the later piece's at a knot."""
        if self.times.size == 1:
            return np.zeros_like(np.asarray(t, dtype=float))
        i = np.searchsorted(self.times, t, side="right") - 1
        inside = (i >= 0) & (i < self.times.size - 1)
        return np.where(inside, self._slopes[np.clip(i, 0, self._slopes.size - 1)], 0.0)

    def rpm(self, t) -> np.ndarray:
        """Shaft speed (rev/min) at ``t`` (at a knot given in rev/min: exactly that number)."""
        return np.interp(t, self.times, self._rpms)

    def angle(self, t) -> np.ndarray:
        """Shaft angle φ(t) = ∫₀ᵗ ω dt (rad), exact."""
        return self._g_at(np.asarray(t, dtype=float)) - self._g0

    def time_at_angle(self, phi) -> np.ndarray:
        """The time (s) at which φ(t) = ``phi`` (rad): the exact inverse of :meth:`angle`."""
        g = np.asarray(phi, dtype=float) + self._g0
        t, w, gk = self.times, self.omegas, self._g
        i = np.searchsorted(gk, g, side="right") - 1
        before, after = i < 0, i >= t.size - 1
        j = np.clip(i, 0, max(t.size - 2, 0))
        out = np.empty(np.shape(g))
        out[...] = t[0] + g / w[0]
        out = np.where(after, t[-1] + (g - gk[-1]) / w[-1], out)
        if t.size > 1:
            dg = g - gk[j]
            # the root of w d + a d^2 / 2 = dg in its stable form (no cancellation when a -> 0)
            d = 2.0 * dg / (w[j] + np.sqrt(np.maximum(w[j] ** 2 + 2.0 * self._slopes[j] * dg, 0.0)))
            out = np.where(before | after, out, t[j] + d)
        return out

    def mean_rpm(self, t0: float, t1: float) -> float:
        """Mean speed (rev/min) over [t0, t1] s: the angle turned over the time."""
        if not t1 > t0:
            raise ValueError(f"need t1 > t0, got {t0!r}, {t1!r}")
        return float((self.angle(t1) - self.angle(t0)) / (t1 - t0)) / RPM_TO_RAD_S

    def _g_at(self, t: np.ndarray) -> np.ndarray:
        tk, w, gk = self.times, self.omegas, self._g
        i = np.searchsorted(tk, t, side="right") - 1
        out = w[0] * (t - tk[0])
        out = np.where(i >= tk.size - 1, gk[-1] + w[-1] * (t - tk[-1]), out)
        if tk.size > 1:
            j = np.clip(i, 0, tk.size - 2)
            d = t - tk[j]
            inside = (i >= 0) & (i < tk.size - 1)
            out = np.where(inside, gk[j] + w[j] * d + 0.5 * self._slopes[j] * d * d, out)
        return out

    def __repr__(self) -> str:
        pts = ",".join(f"{t:g}:{w / RPM_TO_RAD_S:g}" for t, w in zip(self.times[:6], self.omegas[:6]))
        return f"SpeedProfile('{pts}{',...' if self.times.size > 6 else ''}')"


def _rpm(value) -> float:
    try:
        rpm = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"shaft speed {value!r} is not a number") from None
    if not (math.isfinite(rpm) and rpm > 0.0):
        raise ValueError(f"shaft speed must be a positive number of rev/min, got {value!r}")
    return rpm


def angle_from_speed(speed, sample_rate: float) -> np.ndarray:
    """Shaft angle (rad, 0 at the first sample) from a speed per sample (rad/s) at ``sample_rate`` Hz:
    the cumulative trapezoidal rule, exact for a speed linear between samples."""
    w = np.asarray(speed, dtype=float)
    if w.ndim != 1 or w.size == 0:
        raise ValueError("speed must be a non-empty 1-D array")
    out = np.empty(w.size)
    out[0] = 0.0
    np.cumsum(0.5 * (w[1:] + w[:-1]) / float(sample_rate), out=out[1:])
    return out


#: Default half-width M (pulses) of the local fit of :func:`angle_from_pulses`.
PULSE_FIT_HALF_WIDTH = 3


def fit_pulses(pulse_times, pulses_per_rev: int = 1, half_width: int = PULSE_FIT_HALF_WIDTH):
    """Smoothed pulse times (s) and the shaft speed at each pulse (rad/s).

    Pulse k marks the angle 2π k / ``pulses_per_rev``; the time is fitted as a quadratic in
    the angle over pulses k - M .. k + M by least squares (the window shifts inwards at the
    ends, M = ``half_width``, at most what the pulses allow). Raises ValueError on fewer than
    2 pulses or times that do not increase strictly.
    """
    tk = np.asarray(pulse_times, dtype=float).ravel()
    if tk.size < 2:
        raise ValueError(f"need at least 2 tachometer pulses, got {tk.size}")
    if not np.all(np.isfinite(tk)) or np.any(np.diff(tk) <= 0.0):
        raise ValueError("tachometer pulse times must be finite and increase strictly")
    if int(pulses_per_rev) < 1:
        raise ValueError(f"pulses per revolution must be >= 1, got {pulses_per_rev!r}")
    step = 2.0 * math.pi / int(pulses_per_rev)
    n = tk.size
    m = int(min(max(half_width, 0), (n - 1) // 2))
    if m == 0:
        return tk.copy(), _difference_speed(tk, step)
    width = 2 * m + 1
    start = np.clip(np.arange(n) - m, 0, n - width)  # window of each pulse
    idx = start[:, None] + np.arange(width)[None, :]
    x = (idx - np.arange(n)[:, None]) * step  # angle relative to the pulse's, rad
    design = np.stack([np.ones_like(x), x, x * x], axis=-1)  # (n, width, 3)
    gram = np.einsum("nwi,nwj->nij", design, design)
    rhs = np.einsum("nwi,nw->ni", design, tk[idx])
    sol = np.linalg.solve(gram, rhs[..., None])[..., 0]
    return sol[:, 0], 1.0 / sol[:, 1]


def _difference_speed(tk: np.ndarray, step: float) -> np.ndarray:
    """Speed at each pulse from central differences (ends one-sided), rad/s."""
    return step / np.gradient(tk)


def angle_from_pulses(pulse_times, t, pulses_per_rev: int = 1, half_width: int = PULSE_FIT_HALF_WIDTH):
    """Shaft angle (rad) at times ``t`` (s) from tachometer pulse times (s), and the speed (rad/s).

    Angle 0 at the first pulse; pulses smoothed by :func:`fit_pulses`; between pulses the
    cubic Hermite interpolant of (smoothed time, angle) with the fitted speeds as slopes;
    before the first and after the last pulse the angle continues at the end pulses' speed.
    Returns ``(angle, speed)`` at ``t``.
    """
    ts, ws = fit_pulses(pulse_times, pulses_per_rev, half_width)
    step = 2.0 * math.pi / int(pulses_per_rev)
    t = np.asarray(t, dtype=float)
    phi_k = step * np.arange(ts.size)
    i = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, ts.size - 2)
    h = ts[i + 1] - ts[i]
    s = (t - ts[i]) / h
    # cubic Hermite basis on [0, 1] and its derivative
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    d00, d10, d01, d11 = 6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1, -6 * s**2 + 6 * s, 3 * s**2 - 2 * s
    angle = h00 * phi_k[i] + h10 * h * ws[i] + h01 * phi_k[i + 1] + h11 * h * ws[i + 1]
    speed = (d00 * phi_k[i] + d01 * phi_k[i + 1]) / h + d10 * ws[i] + d11 * ws[i + 1]
    before, after = t < ts[0], t > ts[-1]
    angle = np.where(before, ws[0] * (t - ts[0]), angle)
    angle = np.where(after, phi_k[-1] + ws[-1] * (t - ts[-1]), angle)
    speed = np.where(before, ws[0], np.where(after, ws[-1], speed))
    return angle, speed


def pulse_times(profile: SpeedProfile, t0: float, t1: float, pulses_per_rev: int = 1,
                phase: float = 0.0) -> np.ndarray:
    """Exact times (s) in [t0, t1) at which ``profile``'s shaft angle passes ``phase`` +
    2π k / ``pulses_per_rev`` for a whole k (an ideal tachometer; angle 0 at t = 0)."""
    step = 2.0 * math.pi / int(pulses_per_rev)
    a0, a1 = float(profile.angle(t0)), float(profile.angle(t1))
    k = np.arange(math.ceil((a0 - phase) / step), math.ceil((a1 - phase) / step))
    times = profile.time_at_angle(phase + step * k)
    return times[(times >= t0) & (times < t1)]
