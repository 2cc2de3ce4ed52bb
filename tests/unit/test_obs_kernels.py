"""The observer's compiled kernels reproduce the NumPy formulations their docstrings name.

Each kernel sits in the module of the algorithm it serves; :func:`bearing_observer.observer.warm_up`
compiles them all.
"""

import numpy as np
import pytest
from scipy import signal

from bearing_observer.observer import drive_input, iir_filter
from bearing_observer.phase_amplitude_estimator import fold_energy
from bearing_observer.piecewise_linear import interp_extended
from bearing_observer.realization import run_modes


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
    from bearing_observer import impulse_trains, observer, phase_amplitude_estimator, piecewise_linear, realization
    from bearing_observer.model_sets import load_model_set
    from bearing_observer.observer import FaultObserver

    observer.warm_up()
    kernels = (impulse_trains.add_pulses, piecewise_linear.interp_extended, phase_amplitude_estimator.fold_energy,
               realization.run_modes, observer.drive_input, observer.iir_filter)
    before = {k.__name__: len(k.signatures) for k in kernels}
    rng = np.random.default_rng(3)
    for model in load_model_set("sim_48k", 48000.0).values():
        for poles in ("model", "contracted"):
            obs = FaultObserver(model, poles=poles)
            y = rng.standard_normal(9600)
            for i in range(0, y.size, 480):
                obs.process(y[i:i + 480])
    assert {k.__name__: len(k.signatures) for k in kernels} == before


def test_iir_filter_equals_lfilter_over_chunks():
    b = np.array([0.02, -0.01, 0.03, 0.0, 0.005])
    a = np.array([1.0, -2.1, 1.9, -0.8, 0.12])
    x = np.random.default_rng(2).standard_normal(1500)
    expect = signal.lfilter(b, a, x)
    out, zi = np.empty_like(x), np.zeros(b.size - 1)
    for lo, hi in ((0, 7), (7, 480), (480, 481), (481, 1500)):
        iir_filter(b, a, x[lo:hi], zi, out[lo:hi])
    np.testing.assert_allclose(out, expect, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("nk", [0, 3])
def test_drive_input_is_the_delayed_nonlinear_train_sum(nk):
    rng = np.random.default_rng(3)
    comps, gains = rng.standard_normal((3, 200)), np.array([0.5, -1.2, 0.3])
    x, y = np.array([-1.0, 0.0, 2.0]), np.array([-0.5, 0.1, 3.0])  # f(0) = 0.1: no shortcut at u = 0
    slopes = np.diff(y) / np.diff(x)
    u_all = gains @ comps
    fu = np.empty_like(u_all)
    interp_extended(x, y, slopes, u_all, fu)
    expect_w = np.concatenate([np.zeros(nk), fu])[:200]
    delay, u, w = np.zeros(nk), np.empty(200), np.empty(200)
    for lo, hi in ((0, 2), (2, 150), (150, 200)):  # one block shorter than the delay
        drive_input(comps[:, lo:hi], gains, True, x, y, slopes, delay, u[lo:hi], w[lo:hi])
    np.testing.assert_allclose(u, u_all, rtol=1e-14)
    np.testing.assert_array_equal(w, expect_w)
    np.testing.assert_array_equal(delay, fu[200 - nk:])
    off_u, off_w = np.empty(5), np.empty(5)
    drive_input(comps[:, :5], gains, False, x, y, slopes, delay, off_u, off_w)
    assert not off_u.any()
    np.testing.assert_array_equal(off_w, np.concatenate([fu[200 - nk:], np.zeros(5)])[:5])
