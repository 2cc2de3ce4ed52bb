"""Condition indicators on closed-form signals, and the ISO 20816-3 zones."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_diagnoser.health.indicators import condition_indicators, default_envelope_band
from bearing_diagnoser.health.iso20816 import ZONE_LIMITS_MM_S, iso_zone, machine_class

FS = 25600.0


def sine(freq, amp, duration, fs=FS, phase=0.3):
    t = np.arange(int(round(duration * fs))) / fs
    return amp * np.sin(2 * np.pi * freq * t + phase)


def test_sine_rms_peak_crest_and_kurtosis():
    # 100 Hz over exactly 10 periods: RMS A/√2, peak A (to the sampling of the crest), crest √2, kurtosis 3/2
    ind = condition_indicators(sine(100.0, 2.0, 0.1), FS)
    assert_allclose(ind.rms, 2.0 / math.sqrt(2.0), rtol=1e-12)
    assert_allclose(ind.peak, 2.0, rtol=1e-4)  # the highest sample is within half a sample of the crest
    assert_allclose(ind.crest_factor, math.sqrt(2.0), rtol=1e-4)
    assert_allclose(ind.kurtosis, 1.5, rtol=1e-12)


def test_mean_is_removed():
    ind = condition_indicators(sine(100.0, 2.0, 0.1) + 7.0, FS)
    assert_allclose(ind.rms, math.sqrt(2.0), rtol=1e-12)


def test_gaussian_kurtosis_is_three_within_its_standard_error():
    # the sample kurtosis of n Gaussian values has standard error √(24/n); 4 standard errors
    n = 200_000
    x = np.random.default_rng(7).standard_normal(n)
    ind = condition_indicators(x, FS)
    assert abs(ind.kurtosis - 3.0) < 4.0 * math.sqrt(24.0 / n)
    # and the test can fail: a Laplace signal (kurtosis 6) is far outside
    lap = condition_indicators(np.random.default_rng(8).laplace(size=n), FS)
    assert abs(lap.kurtosis - 3.0) > 40 * math.sqrt(24.0 / n)


@pytest.mark.parametrize("freq,duration", [(100.0, 1.0), (160.0, 0.1), (500.0, 0.5), (30.0, 1.0)])
def test_velocity_rms_of_a_sine_acceleration(freq, duration):
    # a(t) = A sin(2πft) integrates to v = A/(2πf) · cos: RMS A / (2πf √2). Bin-centred tones; the
    # Hann window spreads a tone over 3 bins weighted by 1/f² at f ± df: relative bias of the mean
    # square below (df/f)² (0.4 % at 160 Hz in 0.1 s), so rtol 0.5 % + that
    amp = 3.0
    ind = condition_indicators(sine(freq, amp, duration), FS)
    expected = amp / (2 * math.pi * freq * math.sqrt(2.0))
    df = 1.0 / duration
    assert_allclose(ind.velocity_rms, expected, rtol=0.005 + (df / freq) ** 2)


def test_velocity_band_edges_and_what_a_short_snapshot_cannot_see():
    # 0.1 s: bins 10 Hz apart, the lowest counted is 2·df = 20 Hz; 1 s: 10 Hz as ISO asks
    assert condition_indicators(sine(100.0, 1.0, 0.1), FS).velocity_band == pytest.approx((20.0, 1000.0))
    assert condition_indicators(sine(100.0, 1.0, 1.0), FS).velocity_band == pytest.approx((10.0, 1000.0))
    # a 15 Hz tone is inside the ISO band of a 1 s window; a 0.1 s snapshot holds 1.5 of its periods
    # and cannot resolve it: part is lost below 20 Hz, part leaks into the bins above (about half read)
    one_second = condition_indicators(sine(15.0, 1.0, 1.0), FS).velocity_rms
    assert_allclose(one_second, 1.0 / (2 * math.pi * 15.0 * math.sqrt(2.0)), rtol=0.01)
    short = condition_indicators(sine(15.0, 1.0, 0.1), FS).velocity_rms
    assert 0.3 < short / one_second < 0.7
    # a 2 kHz tone is above the band
    assert condition_indicators(sine(2000.0, 1.0, 1.0), FS).velocity_rms < 1e-3 / (2 * math.pi * 2000.0)


def test_envelope_rms_of_an_amplitude_modulated_carrier():
    # (1 + m cos 2π fm t) cos 2π fc t: the envelope is 1 + m cos(...), its fluctuation's RMS m/√2
    t = np.arange(int(FS)) / FS
    m, fm, fc = 0.4, 120.0, 6000.0
    x = (1 + m * np.cos(2 * np.pi * fm * t)) * np.cos(2 * np.pi * fc * t)
    ind = condition_indicators(x, FS, envelope_band=(4000.0, 8000.0))
    assert_allclose(ind.envelope_rms, m / math.sqrt(2.0), rtol=1e-3)
    assert ind.envelope_band == (4000.0, 8000.0)
    # a band that misses the carrier sees (next to) nothing
    assert condition_indicators(x, FS, envelope_band=(9000.0, 11000.0)).envelope_rms < 1e-6


def test_envelope_of_gaussian_noise_is_rayleigh():
    # band-limited Gaussian noise: the envelope is Rayleigh, sd √((4 − π)/2) = 0.655 × the band's RMS
    x = np.random.default_rng(3).standard_normal(2 ** 18)
    band = default_envelope_band(FS)
    X = np.fft.rfft(x)
    f = np.fft.rfftfreq(x.size, 1 / FS)
    x_band = np.fft.irfft(np.where((f >= band[0]) & (f <= band[1]), X, 0), x.size)
    ind = condition_indicators(x, FS)
    assert_allclose(ind.envelope_rms / x_band.std(), math.sqrt((4 - math.pi) / 2), rtol=0.01)


def test_default_envelope_band_rule():
    assert default_envelope_band(25600.0) == (3200.0, 9600.0)
    assert default_envelope_band(12000.0) == (1500.0, 4500.0)
    assert default_envelope_band(12000.0, f_top=2000.0) == (2000.0, 4500.0)
    assert default_envelope_band(12000.0, f_top=5000.0) is None
    # a band narrower than two bins has no envelope
    assert math.isnan(condition_indicators(sine(100.0, 1.0, 0.1), FS, envelope_band=(4800.0, 4801.0)).envelope_rms)


def test_bad_windows_are_refused():
    with pytest.raises(ValueError, match="at least"):
        condition_indicators(np.ones(3), FS)
    with pytest.raises(ValueError, match="non-finite"):
        condition_indicators(np.r_[np.ones(100), np.nan], FS)


def test_json_has_units_in_keys_and_no_nan():
    ind = condition_indicators(sine(100.0, 1.0, 0.1), FS, envelope_band=(4800.0, 4801.0))
    out = ind.to_json()
    assert out["envelope_rms_m_s2"] is None
    assert_allclose(out["velocity_rms_mm_s"], ind.velocity_rms * 1e3)


# ----------------------------------------------------------------------------------------
# ISO 20816-3


def test_iso_zone_limits_as_the_standard_tables():
    assert ZONE_LIMITS_MM_S == {"group1-rigid": (2.3, 4.5, 7.1), "group1-flexible": (3.5, 7.1, 11.0),
                                "group2-rigid": (1.4, 2.8, 4.5), "group2-flexible": (2.3, 4.5, 7.1)}


@pytest.mark.parametrize("mm_s,zone", [(0.0, "A"), (1.39, "A"), (1.4, "B"), (2.79, "B"), (2.8, "C"),
                                       (4.49, "C"), (4.5, "D"), (40.0, "D")])
def test_iso_zone_of_group2_rigid(mm_s, zone):
    assert iso_zone(mm_s / 1000.0, "group2-rigid") == zone


def test_iso_zone_depends_on_the_machine_class():
    assert iso_zone(5.0e-3, "group1-rigid") == "C"
    assert iso_zone(5.0e-3, "group1-flexible") == "B"
    assert iso_zone(float("nan")) == ""
    assert machine_class("Group2_Flexible") == "group2-flexible"
    with pytest.raises(ValueError, match="machine class"):
        machine_class("group3")
