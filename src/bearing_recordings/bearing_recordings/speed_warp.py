"""Constant-speed recordings warped in time along a speed profile: test data for changing speed.

A record taken at the shaft speed ω₀ is a function of the shaft angle φ = ω₀·t. Played
back along a profile ω(t) with angle Φ(t) = ∫ω dt it becomes y(t) = x(Φ(t)/ω₀): the
shaft lines and the fault combs follow the profile exactly as on a machine changing speed,
and the profile's ω(t) is the exact tachometer of the result when the record's shaft held ω₀.

A real shaft does not hold its speed exactly: the CWRU shafts wander by ±0.15 % within a
second about their mean, which itself differs from the label. Given the record's own shaft
speed ω_r(τ) per sample (measured, e.g. by the tacho-less tracker on the constant-speed
record), the result's shaft angle is the record's angle at τ(t) = (Φ(t) − Φ(start))/ω₀, so
its tachometer is ω(t)/ω₀ · ω_r(τ(t)): what a tachometer on that shaft would have read.

**Unlike a real ramp**, everything in the record moves with the speed: the structural
resonances (and any electrical line such as CWRU's 60 Hz mains, which becomes an order)
scale by ω(t)/ω₀ too, and the impacts keep the strength they had at ω₀. On a machine the
resonances stay put and the impact energy changes with speed. Results on warped records
therefore test the speed handling (tracking, order tracking, accumulation across a speed
change), not the signal physics of a real run-up; say so wherever they are shown.

Method: the record is sampled at the instants Φ(t)/ω₀ by band-limited interpolation
(:func:`.resampling.sample_at`), anti-aliased where the record is played faster (cutoff
min(fs/2, fs/(2.2·ω/ω₀)) of the record's frequencies, so nothing folds back above the
output's Nyquist frequency); the output keeps the record's sample rate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bearing_common.shaft_angle import RPM_TO_RAD_S, SpeedProfile

from .resampling import sample_at


@dataclass
class WarpedSignal:
    """``accel`` (the record's units) and ``shaft_speed`` (rad/s), one value per sample at
    ``sample_rate`` Hz; ``start``: the profile time (s) of the first sample."""

    accel: np.ndarray
    shaft_speed: np.ndarray
    sample_rate: float
    start: float


def warp(x, sample_rate: float, rpm: float, profile: SpeedProfile, start: float = 0.0,
         end: float | None = None, own_speed=None) -> WarpedSignal:
    """Record ``x`` (taken at ``rpm`` rev/min, ``sample_rate`` Hz) played along ``profile`` from
    profile time ``start`` to ``end`` s (default: the profile's last knot), or until the record
    runs out, whichever is first. ``own_speed``: the record's shaft speed per sample (rad/s, as
    long as ``x``; module docstring), whose change the tachometer then carries; None: ``rpm`` held.
    Raises ValueError when the record is too short for one sample.
    """
    x = np.asarray(x, dtype=float)
    fs, w0 = float(sample_rate), float(rpm) * RPM_TO_RAD_S
    if not (w0 > 0 and np.isfinite(w0)):
        raise ValueError(f"the record's speed must be positive, got {rpm!r} rev/min")
    end = float(profile.times[-1]) if end is None else float(end)
    last = float(profile.time_at_angle(profile.angle(start) + (x.size - 1) / fs * w0))  # record runs out
    n = int(np.floor((min(end, last) - start) * fs)) + 1
    if n < 1 or end <= start:
        raise ValueError("the record is too short for the profile (or end <= start)")
    t = start + np.arange(n) / fs
    tau = (profile.angle(t) - profile.angle(start)) / w0  # the record's time at each output sample
    tau = np.minimum(tau, (x.size - 1) / fs)
    ratio = profile.omega(t) / w0
    cutoff = np.minimum(0.5 * fs, fs / (2.2 * ratio))
    speed = profile.omega(t)
    if own_speed is not None:
        own = np.asarray(own_speed, dtype=float)
        if own.shape != x.shape:
            raise ValueError(f"the record's own speed needs one value per sample ({x.size}), got {own.shape}")
        speed = speed / w0 * np.interp(tau, np.arange(x.size) / fs, own)
    return WarpedSignal(sample_at(x, fs, tau, cutoff), speed, fs, start)


def centred_span(profile: SpeedProfile, rpm: float, record_seconds: float, start: float = 0.0,
                 end: float | None = None) -> tuple[float, float]:
    """The span [a, b] of the profile between ``start`` and ``end`` (default: its last knot) that a
    record of ``record_seconds`` s taken at ``rpm`` covers, centred in shaft angle on the span's
    middle angle; the whole span when the record is long enough."""
    end = float(profile.times[-1]) if end is None else float(end)
    phi_a, phi_b = float(profile.angle(start)), float(profile.angle(end))
    have = record_seconds * float(rpm) * RPM_TO_RAD_S
    if have >= phi_b - phi_a:
        return start, end
    mid = 0.5 * (phi_a + phi_b)
    return float(profile.time_at_angle(mid - 0.5 * have)), float(profile.time_at_angle(mid + 0.5 * have))
