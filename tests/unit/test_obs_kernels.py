"""The observer's compiled kernels reproduce the NumPy formulations their docstrings name."""

import numpy as np
import pytest
from scipy import signal

from bearing_observer.kernels import fold_energy, interp_extended, run_modes


def test_interp_extended_matches_np_interp_inside_and_end_slopes_outside():
    x = np.array([-2.0, -0.5, 0.0, 1.0, 4.0])
    y = np.array([-3.0, -1.0, 0.0, 0.5, 2.0])
    slopes = np.diff(y) / np.diff(x)
    rng = np.random.default_rng(0)
    inside = np.cumsum(rng.normal(0.0, 0.3, 2000)).clip(-2.0, 4.0)  # smooth and jumpy
    out = np.empty_like(inside)
    interp_extended(x, y, slopes, inside, out)
    np.testing.assert_array_equal(out, np.interp(inside, x, y))
    outside = np.array([-10.0, 10.0])
    interp_extended(x, y, slopes, outside, out[:2])
    assert out[0] == pytest.approx(-3.0 + (-8.0) * slopes[0], rel=1e-15)
    assert out[1] == pytest.approx(2.0 + 6.0 * slopes[-1], rel=1e-15)


def test_fold_energy_matches_bincount():
    rng = np.random.default_rng(1)
    z = rng.standard_normal(4800)
    first, base, freq, fs, n_bins = 123_457, 0.37, 162.4567, 48_000.0, 591
    prof = fold_energy(z, first, base, freq, fs, n_bins)
    c = base + freq * (np.arange(first, first + z.size) / fs)
    idx = np.minimum(((c - np.floor(c)) * n_bins).astype(np.int64), n_bins - 1)
    expect = np.bincount(idx, z * z, n_bins) / np.maximum(np.bincount(idx, minlength=n_bins), 1)
    np.testing.assert_array_equal(prof, expect)


def test_run_modes_equals_per_mode_lfilter_and_carries_state():
    lam = np.array([0.9 + 0.3j, 0.5 + 0.0j])
    bw = np.array([1.0 - 0.5j, 0.2 + 0.0j])
    bz = np.array([0.1 + 0.2j, -0.3 + 0.0j])
    c = np.array([0.7 + 0.1j, 1.5 + 0.0j])
    weight = np.array([2.0, 1.0])
    rng = np.random.default_rng(2)
    w, z = rng.standard_normal((2, 300))
    expect = 0.25 * w
    for i in range(2):
        xi = signal.lfilter([0.0, 1.0], [1.0, -lam[i]], bw[i] * w + bz[i] * z)
        expect = expect + weight[i] * np.real(c[i] * xi)
    state = np.zeros(2, dtype=complex)
    out = np.empty(300)
    run_modes(lam, bw, bz, c, weight, 0.25, w[:120], z[:120], state, out[:120])
    run_modes(lam, bw, bz, c, weight, 0.25, w[120:], z[120:], state, out[120:])
    np.testing.assert_allclose(out, expect, rtol=0, atol=1e-12)


def test_warm_up_compiles_every_signature_the_observers_use():
    """The node calls warm_up() before subscribing: afterwards, observing a stream must
    compile nothing more (a compile stalls the node for about a second, longer than its
    input queue holds)."""
    from bearing_observer import kernels
    from bearing_observer.model_sets import load_model_set
    from bearing_observer.observer import FaultObserver

    kernels.warm_up()
    names = ("add_pulses", "interp_extended", "fold_energy", "run_modes")
    before = {n: len(getattr(kernels, n).signatures) for n in names}
    rng = np.random.default_rng(3)
    for model in load_model_set("sim_48k", 48000.0).values():
        for poles in ("model", "contracted"):
            obs = FaultObserver(model, poles=poles)
            y = rng.standard_normal(9600)
            for i in range(0, y.size, 480):
                obs.process(y[i:i + 480])
    assert {n: len(getattr(kernels, n).signatures) for n in names} == before
