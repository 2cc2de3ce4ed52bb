"""Constant-speed recordings warped along speed profiles (bearing_recordings.speed_warp) and the
changing-speed test data built from them (benchmarks.speed_ramps)."""

import numpy as np
import pytest

from bearing_common.shaft_angle import RPM_TO_RAD_S, SpeedProfile
from bearing_diagnoser.order_tracking import order_spectrum, resample_to_angle
from bearing_recordings.load import load_recording
from bearing_recordings.speed_warp import centred_span, warp
from benchmarks.speed_ramps import ramp_profiles

FS = 12000.0


def test_a_warped_sinusoid_is_the_chirp_of_the_profile():
    """A line at 3 x the shaft of a 1800 rpm record, played along 1620 -> 1980 rpm: cos(3 phi(t)) exactly
    (band-limited interpolation: within 3e-5)."""
    w0 = 1800 * RPM_TO_RAD_S
    t = np.arange(int(12 * FS)) / FS
    x = np.cos(3 * w0 * t + 0.4)
    profile = SpeedProfile.parse("0:1620,10:1980")
    w = warp(x, FS, 1800.0, profile)
    assert w.accel.size == int(10 * FS) + 1
    tt = np.arange(w.accel.size) / FS
    inner = (tt > 0.1) & (tt < 9.9)
    np.testing.assert_allclose(w.accel[inner], np.cos(3 * profile.angle(tt[inner]) + 0.4), atol=3e-5)
    np.testing.assert_array_equal(w.shaft_speed, profile.omega(tt))


def test_a_record_whose_shaft_wanders_gets_the_tachometer_of_its_own_shaft():
    """A record whose shaft wanders by ±0.15 % about 1800 rpm (as the CWRU shafts do), with a line at
    3 x its shaft, played along 1620 -> 1980 rpm with its own speed: the tachometer's angle psi(t) puts the
    line at cos(3 psi(t)) (within 3e-5); with the profile's alone (the label held) the angle is off by up to
    0.13 rad and the line by up to 0.38."""
    w0 = 1800 * RPM_TO_RAD_S
    t = np.arange(int(12 * FS)) / FS
    own = w0 * (1.0 + 0.0015 * np.sin(2 * np.pi * 0.7 * t))
    phi = np.r_[0.0, np.cumsum(0.5 * (own[1:] + own[:-1]) / FS)]
    x = np.cos(3 * phi + 0.4)
    profile = SpeedProfile.parse("0:1620,10:1980")
    w = warp(x, FS, 1800.0, profile, own_speed=own)
    inner = slice(int(0.1 * FS), int(9.9 * FS))
    for speed, close in ((w.shaft_speed, True), (profile.omega(np.arange(w.accel.size) / FS), False)):
        psi = np.r_[0.0, np.cumsum(0.5 * (speed[1:] + speed[:-1]) / FS)]
        error = np.abs(w.accel[inner] - np.cos(3 * psi[inner] + 0.4)).max()
        assert (error < 3e-5) if close else (error > 0.3), error
    with pytest.raises(ValueError, match="one value per sample"):
        warp(x, FS, 1800.0, profile, own_speed=own[:-1])


def test_played_faster_the_record_is_anti_aliased():
    """A line at 0.45 fs played 1.3 times faster would fold to 0.415 fs: it is removed instead."""
    t = np.arange(int(3 * FS)) / FS
    w = warp(np.cos(2 * np.pi * 0.45 * FS * t), FS, 1000.0, SpeedProfile.constant(1300.0), end=2.0)
    assert np.std(w.accel[2000:-2000]) < 1e-4


def test_a_short_record_covers_the_middle_of_the_profile():
    profile = SpeedProfile.parse("0:900,10:1100")
    a, b = centred_span(profile, 1000.0, 4.0)
    assert profile.angle(b) - profile.angle(a) == pytest.approx(4.0 * 1000 * RPM_TO_RAD_S, rel=1e-12)
    assert profile.angle(a) + profile.angle(b) == pytest.approx(profile.angle(0.0) + profile.angle(10.0), rel=1e-12)
    assert centred_span(profile, 1000.0, 11.0) == (0.0, 10.0)
    with pytest.raises(ValueError, match="too short"):
        warp(np.ones(1), FS, 1000.0, profile, 5.0, 5.0)


def test_the_profiles_of_the_test_data():
    p = ramp_profiles(1800.0)
    assert sorted(p) == ["down10", "down20", "down40", "runup", "up10", "up20", "up40"]
    assert float(p["up20"].rpm(0.0)) == pytest.approx(1620.0) and float(p["up20"].rpm(10.0)) == pytest.approx(1980.0)
    assert p["down40"].mean_rpm(0.0, 10.0) == pytest.approx(1800.0)
    assert float(p["runup"].rpm(0.0)) == pytest.approx(900.0) and float(p["runup"].rpm(10.0)) == pytest.approx(1800.0)


def test_a_warped_cwru_record_has_its_shaft_line_where_the_profile_puts_it(cwru_record):
    """CWRU 105 (IR, 1797 rpm, 10 s) played along a +20 % ramp: order-tracked with the profile's angle,
    the 1x line stands at order 1 as sharp and as strong as in the constant-speed record (the record's
    own shaft line sits within 0.2 % of its stated speed); a spectrum that assumes one speed smears it."""
    rec = load_recording(cwru_record("105_IR007_0hp_DE12k.mat"), sample_rate=FS)
    profile = ramp_profiles(rec.rpm)["up20"]
    a, b = centred_span(profile, rec.rpm, rec.duration)
    w = warp(rec.accel, FS, rec.rpm, profile, a, b)
    angle = profile.angle(a + np.arange(w.accel.size) / FS) - profile.angle(a)
    warped = resample_to_angle(w.accel, FS, angle, 64)
    original = resample_to_angle(rec.accel, FS, rec.rpm * RPM_TO_RAD_S * np.arange(rec.accel.size) / FS, 64)
    lines = []
    for sig in (warped, original):
        n = 256 * 64  # 256 revolutions each
        orders, amp = order_spectrum(sig.samples[:n], 64)
        band = (orders > 0.9) & (orders < 1.1)
        lines.append((orders[band][np.argmax(amp[band])], amp[band].max()))
    (o_w, a_w), (o_c, a_c) = lines
    assert abs(o_w - 1.0) <= 0.002 and abs(o_c - 1.0) <= 0.002
    assert a_w == pytest.approx(a_c, rel=0.1)
    # one speed assumed: the line spreads over the ramp's +-10 %, its peak falls
    naive = resample_to_angle(w.accel, FS, np.mean(w.shaft_speed) * np.arange(w.accel.size) / FS, 64)
    orders, amp = order_spectrum(naive.samples[:256 * 64], 64)
    assert amp[(orders > 0.85) & (orders < 1.15)].max() < 0.5 * a_w


def test_a_test_case_file_reads_back_with_its_tachometer(tmp_path):
    from benchmarks.speed_ramps import Case
    profile = ramp_profiles(1500.0, ramps=(20,), run_up=False)["down20"]
    t = np.arange(int(2 * FS)) / FS
    case = Case("x", np.cos(profile.angle(t)), FS, profile.omega(t), np.full(t.size, 1), "cwru", profile, "note")
    rec = load_recording(case.save(tmp_path))
    np.testing.assert_array_equal(rec.shaft_speed, profile.omega(t))
    assert rec.speed_varies and rec.rpm == pytest.approx(float(np.mean(profile.rpm(t))), rel=1e-12)
    np.testing.assert_array_equal(rec.truth, 1)
    with np.load(tmp_path / "x.npz") as z:
        assert str(z["source"]) == "cwru" and str(z["profile"]).startswith("0:1650,10:1350")
