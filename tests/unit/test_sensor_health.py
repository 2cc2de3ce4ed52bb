"""Sensor problems are told apart from bearing states: dead, disconnected, clipped, quantised, non-finite."""

from __future__ import annotations

import numpy as np
import pytest

from bearing_common.units import STANDARD_GRAVITY as G
from bearing_diagnoser.decision.sensor_health import MAX_CLIPPED, MIN_LEVELS, SensorWatch, check_window
from bearing_diagnoser.synthetic import burst_train, white_noise

FS = 12000.0
N = 3600  # 0.3 s


def healthy(seed=0):
    return white_noise(N / FS, FS, 4.5e-3, np.random.default_rng(seed))


@pytest.mark.parametrize("make, words", [
    (lambda: np.zeros(N), "flat signal"),
    (lambda: np.full(N, 0.37), "flat signal"),  # disconnected input held at an offset
    (lambda: 0.5 + 1e-12 * healthy(), "flat signal"),
    (lambda: 0.001 * G * np.round(0.05 * healthy() / (0.001 * G)), "quantised"),  # a few levels of 0.001 g
    (lambda: 10.0 * np.sign(np.sin(2 * np.pi * 50.0 * np.arange(N) / FS)), "rails"),  # rail-to-rail square wave
    (lambda: np.clip(40.0 * np.sin(2 * np.pi * 30.0 * np.arange(N) / FS) + healthy(), -20.0, 20.0), "rails"),
    (lambda: np.clip(healthy() * 3, -2.5, 2.5), "clipped"),  # amplifier saturating on the peaks
    (lambda: np.r_[healthy()[:-1], np.nan], "1 of 3600 samples not finite"),  # a dropout marked NaN
    (lambda: np.r_[np.inf, healthy()[1:]], "1 of 3600 samples not finite"),  # an overflow
])
def test_sensor_problems_are_named(make, words):
    check = check_window(make())
    assert not check.ok and words in check.problem, check


def test_healthy_and_faulty_vibration_pass():
    for x in (healthy(), healthy(1) + burst_train(N / FS, FS, 107.0, amplitude=30.0)):
        check = check_window(x)
        assert check.ok, check
        assert check.levels > 100 * MIN_LEVELS and check.clipped < MAX_CLIPPED / 10


def test_real_recording_windows_pass(cwru_record):
    from bearing_recordings.mat_files import load_mat
    x = load_mat(cwru_record("097_normal_0hp_DE48k.mat"), 48000.0).accel
    n = 14400
    assert all(check_window(x[i:i + n]).ok for i in range(0, x.size - n, n))


def test_empty_window():
    assert check_window(np.zeros(0)).problem == "no samples"


def test_the_watch_checks_the_samples_of_any_window_held_whichever_stream_brought_them():
    """The first stream to bring a sample wins (every observer stream carries the same measurement);
    a gap begins afresh: a window reaching before it is not held."""
    x = healthy()
    x[2000:2600] = 0.25  # the sensor stuck for 50 ms
    watch = SensorWatch()
    watch.push(0, x[:1200])
    watch.push(0, np.zeros(1200))  # the other stream's copy: seen already, skipped
    watch.push(600, x[600:2400])  # overlapping: its new part taken
    watch.push(2400, x[2400:3600])
    assert watch.check(0, 600).ok and watch.check(1200, 1800).ok
    assert "flat signal" in watch.check(2000, 2600).problem
    assert watch.check(3000, 3700) is None  # not all held yet
    watch.trim(1200)
    assert watch.check(600, 1200) is None and watch.check(1200, 1800).ok
    watch.push(5000, x[:600])  # a gap
    assert watch.check(3000, 3600) is None and watch.check(5000, 5600).ok
