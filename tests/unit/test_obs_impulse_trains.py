"""Fault impulse trains (eqs. 2.55, 2.58) in time units."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_observer.impulse_trains import TWO_PI, impact_times, impulse_train, modulated_train_components


def test_impact_times_follow_phase_definition():
    f = 100.0
    t_k, k = impact_times(0.0, 0.05, f, phase=-TWO_PI * 0.25)  # f t - 0.25 integer
    assert_allclose(t_k, [0.0025, 0.0125, 0.0225, 0.0325, 0.0425], atol=1e-15)
    assert_allclose(f * t_k - 0.25, k, atol=1e-12)


def test_on_grid_impulse_is_one_sample_of_height_one():
    fs, f = 1000.0, 50.0  # period 20 samples
    u = impulse_train(100, fs, f, phase=0.0)
    assert_allclose(np.flatnonzero(u), [0, 20, 40, 60, 80])
    assert_allclose(u[u > 0], 1.0, atol=1e-12)


def test_sub_sample_position_splits_area():
    fs, f = 1000.0, 50.0
    shift = 0.3 / fs  # impacts 0.3 sample after the grid
    u = impulse_train(40, fs, f, phase=-TWO_PI * f * shift)
    assert_allclose(u[[0, 1]], [0.7, 0.3], atol=1e-12)
    assert_allclose(u.sum(), 2.0, atol=1e-12)


def test_area_is_independent_of_sample_rate():
    """Pulse area = width (s): the sum of samples / fs is the same at every rate."""
    f, w = 107.5, 50e-6
    areas = [impulse_train(int(fs * 0.1), fs, f, phase=0.3, pulse_width=w).sum() / fs
             for fs in (12000.0, 48000.0, 1e6)]
    n_imp = impact_times(0.0, 0.1 - w, f, 0.3)[0].size
    assert_allclose(areas, n_imp * w, rtol=1e-9)


def test_start_time_continuity():
    """Two consecutive chunks equal one long train (time units, not sample counts)."""
    fs, f = 48000.0, 162.4567
    full = impulse_train(10000, fs, f, phase=1.234)
    a = impulse_train(4321, fs, f, phase=1.234)
    b = impulse_train(10000 - 4321, fs, f, phase=1.234, start_time=4321 / fs)
    assert_allclose(np.concatenate([a, b]), full, atol=1e-12)


def test_eq_2_58_weights_and_components():
    fs, f, fr, th, c = 48000.0, 162.0, 30.0, 0.7, 0.4
    u = impulse_train(4800, fs, f, phase=0.2, shaft_frequency=fr, shaft_phase=th, offset=c)
    t_k, _ = impact_times(0.0, 0.1, f, 0.2)
    expect = np.cos(TWO_PI * fr * t_k + th) + c
    got = np.array([u[int(np.floor(t * fs))] + u[int(np.floor(t * fs)) + 1] for t in t_k[:-1]])
    assert_allclose(got, expect[:-1], atol=1e-9)
    U = modulated_train_components(4800, fs, f, phase=0.2, shaft_frequency=fr)
    assert_allclose(np.cos(th) * U[0] - np.sin(th) * U[1] + c * U[2], u, atol=1e-12)


def test_bad_arguments():
    with pytest.raises(ValueError, match="fault_frequency"):
        impulse_train(10, 1000.0, 0.0)
    with pytest.raises(ValueError, match="pulse_width"):
        impulse_train(10, 1000.0, 10.0, pulse_width=0.0)
    assert impulse_train(0, 1000.0, 10.0).shape == (0,)
