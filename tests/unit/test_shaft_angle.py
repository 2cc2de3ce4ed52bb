"""Shaft angle from a speed schedule, a speed per sample and tachometer pulses (bearing_common.shaft_angle)."""

import math

import numpy as np
import pytest

from bearing_common.shaft_angle import (
    RPM_TO_RAD_S,
    WOBBLE_KNOTS_PER_PERIOD,
    SpeedProfile,
    angle_from_pulses,
    angle_from_speed,
    fit_pulses,
    pulse_times,
)


def test_ramp_angle_and_inverse_are_exact():
    """900 -> 1800 rpm over 10 s from t = 1 s: phi = w0 t before, then w0 t + a (t-1)^2 / 2, then linear."""
    p = SpeedProfile.parse("1:900,11:1800")
    w0, w1 = 900 * RPM_TO_RAD_S, 1800 * RPM_TO_RAD_S
    a = (w1 - w0) / 10.0
    t = np.array([-0.5, 0.0, 0.7, 1.0, 3.3, 11.0, 12.5])
    d = np.clip(t - 1.0, 0.0, 10.0)
    expected = w0 * np.minimum(t, 1.0) + w0 * d + 0.5 * a * d**2 + w1 * np.maximum(t - 11.0, 0.0)
    np.testing.assert_allclose(p.angle(t), expected, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(p.time_at_angle(expected), t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.omega(t), np.interp(t, [1, 11], [w0, w1]), rtol=1e-14)
    np.testing.assert_allclose(p.alpha(np.array([0.5, 1.0, 6.0, 11.0])), [0.0, a, a, 0.0], rtol=1e-14)
    assert p.mean_rpm(1.0, 11.0) == pytest.approx(1350.0, rel=1e-13)
    assert not p.is_constant


def test_constant_profile_is_omega_t():
    p = SpeedProfile.constant(1800.0)
    t = np.linspace(0.0, 3.0, 7)
    np.testing.assert_allclose(p.angle(t), 1800 * RPM_TO_RAD_S * t, rtol=1e-15)
    assert p.is_constant and p.alpha(t).tolist() == [0.0] * 7
    assert SpeedProfile.parse("0:1500,2:1500").is_constant


def test_wobble_follows_the_sine_within_the_stated_bound():
    base = SpeedProfile.constant(1800.0)
    p = base.with_wobble(0.05, 2.0, 10.0)
    t = np.linspace(0.0, 10.0, 20001)
    exact = 1800 * RPM_TO_RAD_S * (1 + 0.05 * np.sin(2 * np.pi * t / 2.0))
    bound = 0.05 * 1800 * RPM_TO_RAD_S * (1 - math.cos(math.pi / WOBBLE_KNOTS_PER_PERIOD))
    assert np.max(np.abs(p.omega(t) - exact)) <= bound * 1.0001
    assert p.times.size == 5 * WOBBLE_KNOTS_PER_PERIOD + 1
    assert base.with_wobble(0.0, 2.0, 10.0) is base


@pytest.mark.parametrize("spec, match", [
    ("", "empty"), ("0:900,oops", "seconds:rpm"), ("0:900,0:1800", "increase strictly"),
    ("0:900,1:-5", "positive"), ("0:900,1:nan", "positive"),
])
def test_bad_profiles_are_refused_with_the_reason(spec, match):
    with pytest.raises(ValueError, match=match):
        SpeedProfile.parse(spec)


def test_angle_from_speed_is_exact_for_a_speed_linear_between_samples():
    fs = 1000.0
    t = np.arange(5000) / fs
    p = SpeedProfile.parse("0:600,5:1200")
    np.testing.assert_allclose(angle_from_speed(p.omega(t), fs), p.angle(t), rtol=1e-12, atol=1e-10)


def test_ideal_pulses_mark_whole_turns():
    p = SpeedProfile.parse("0:900,10:1800")
    times = pulse_times(p, 0.0, 10.0, pulses_per_rev=2)
    np.testing.assert_allclose(p.angle(times), np.pi * np.arange(times.size), atol=1e-9)
    assert times[0] == 0.0
    assert times.size == math.ceil(p.angle(10.0) / np.pi)


def test_pulses_give_the_angle_and_speed_of_a_ramp():
    """No jitter: speed within 2e-4 (bias of the local fit); the angle between pulses within 1e-4 rad."""
    p = SpeedProfile.parse("0:900,10:1800")
    pulses = pulse_times(p, 0.0, 10.0)
    t = np.linspace(1.0, 9.0, 4001)
    angle, speed = angle_from_pulses(pulses, t)
    np.testing.assert_allclose(angle, p.angle(t), atol=1e-4)
    np.testing.assert_allclose(speed, p.omega(t), rtol=2e-4)


def test_jitter_is_averaged_out():
    """20 us jitter: the fitted speed's RMS error is several times below that of plain pulse differences."""
    p = SpeedProfile.constant(1800.0)
    rng = np.random.default_rng(1)
    pulses = pulse_times(p, 0.0, 20.0) + 20e-6 * rng.standard_normal(600)
    _, fitted = fit_pulses(pulses, half_width=3)
    plain = 2 * np.pi / np.diff(pulses)
    w = 1800 * RPM_TO_RAD_S
    rms_fit = np.sqrt(np.mean((fitted[3:-3] / w - 1) ** 2))
    rms_plain = np.sqrt(np.mean((plain / w - 1) ** 2))
    # theory: sigma / (P sqrt(28)) for M = 3 against sqrt(2) sigma / P: 7.5 times smaller
    assert rms_fit < rms_plain / 5.0
    assert rms_plain == pytest.approx(math.sqrt(2) * 20e-6 * 30.0, rel=0.15)


def test_bad_pulses_are_refused():
    with pytest.raises(ValueError, match="at least 2"):
        fit_pulses([0.1])
    with pytest.raises(ValueError, match="increase strictly"):
        fit_pulses([0.1, 0.2, 0.2, 0.3])
    with pytest.raises(ValueError, match="per revolution"):
        fit_pulses([0.1, 0.2, 0.3], pulses_per_rev=0)
