"""Sensor problems are told apart from bearing states: dead, disconnected, clipped, quantised."""

from __future__ import annotations

import numpy as np
import pytest

from bearing_common.units import STANDARD_GRAVITY as G
from bearing_diagnoser.decision.sensor_health import MAX_CLIPPED, MIN_LEVELS, check_window
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
