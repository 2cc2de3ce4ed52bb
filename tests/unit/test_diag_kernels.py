"""Compiled kernels of the decision against the NumPy / SciPy formulations they replace, bit for bit.

Each kernel (compiled with numba, next to the algorithm it serves) promises the exact result of a NumPy expression
(summation order included), so that the decisions did not change when they replaced it.
The references below are those expressions, as the decision computed them before.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy import signal, sparse

from bearing_common.bearings import CATALOG, fault_frequency
from bearing_diagnoser import decision, fold
from bearing_diagnoser.decision.pairwise_sum import row_sum
from bearing_diagnoser.decision.stream_blocks import EnergyEnvelope, block_sums, sos_filter
from bearing_diagnoser.decision.thesis_blocks import train_correlation
from bearing_diagnoser.diagnoser import STREAMS, Diagnoser
from bearing_diagnoser.fold.folding import (
    cfar_periodicity,
    explain_away,
    folded_peakiness,
    impact_phase_mask,
    period_grid,
)
from bearing_diagnoser.fold.scoring import window_sums
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.warm_up import warm_up

FE = 4000.0  # Hz, envelope rate
RNG = np.random.default_rng(20150101)


def envelope(n: int, period: int | None = None) -> np.ndarray:
    """An exponential 'noise envelope' of n blocks, with impacts every ``period`` blocks."""
    env = RNG.exponential(size=n) * 10.0 ** RNG.uniform(-6, 3)
    if period:
        env[::period] += 20.0 * env.mean()
    return env


def reference_peakiness(env, freqs, bins=16, smooth=2):
    """The sparse-matrix fold the kernels replaced."""
    f = np.asarray(np.round(freqs, 9), float)
    t = np.arange(env.size) / FE
    idx = np.minimum(((np.outer(f, t) % 1.0) * bins).astype(np.int64), bins - 1)
    rows = (idx + (np.arange(f.size) * bins)[:, None]).ravel()
    cnt = np.bincount(rows, minlength=f.size * bins).astype(float)
    m = sparse.csr_matrix((1.0 / np.maximum(cnt[rows], 1.0), (rows, np.tile(np.arange(env.size), f.size))),
                          shape=(f.size * bins, env.size))
    prof = (m @ env).reshape(f.size, bins)
    if smooth > 1:
        prof = sum(np.roll(prof, -k, axis=1) for k in range(smooth)) / smooth
    mean = prof.mean(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(mean > 0, (prof.max(axis=1) - mean) / mean, 0.0)


def test_row_sum_is_numpys_pairwise_sum():
    for n in [*range(0, 300), 511, 1000, 1025, 4096, 12345]:
        a = RNG.standard_normal((2, n + 3)) * 10.0 ** RNG.uniform(-5, 5, (2, n + 3))
        assert row_sum(a, 1, 2, n) == a[1, 2:2 + n].sum(), n


def test_band_pass_is_sosfilt_chunk_by_chunk():
    sos = signal.butter(4, [1500.0, 8000.0], btype="bandpass", fs=48000.0, output="sos")
    x = RNG.standard_normal(5000)
    want, _ = signal.sosfilt(sos, x, zi=np.zeros((sos.shape[0], 2)))
    zi, got = np.zeros((sos.shape[0], 2)), np.empty_like(x)
    for i in range(0, x.size, 333):
        sos_filter(sos, zi, x[i:i + 333], got[i:i + 333])
    assert_array_equal(got, want)


@pytest.mark.parametrize("d", [3, 12, 13, 200])
def test_block_sums_are_the_reshaped_sums_and_means(d):
    y, r, b = RNG.standard_normal((3, 40 * d))
    u = (RNG.random(40 * d) < 0.01) * 1.0
    out = np.empty((7, 40))
    block_sums(y, r, u, b, d, out)
    blocks = {k: a.reshape(-1, d) for k, a in {"y": y, "r": r, "u": u, "b": b}.items()}
    b2 = blocks["b"] ** 2
    want = [b2.mean(axis=1), (b2 * b2).mean(axis=1), blocks["y"].sum(axis=1), (blocks["y"] ** 2).sum(axis=1),
            (blocks["r"] * blocks["r"]).sum(axis=1), np.abs(blocks["r"]).sum(axis=1), blocks["u"].sum(axis=1)]
    assert_array_equal(out, np.array(want))


def test_energy_envelope_gives_the_same_blocks_whatever_the_chunking():
    y = RNG.standard_normal(4800)
    one = EnergyEnvelope(48000.0, (1500.0, 8000.0)).push(y)
    env = EnergyEnvelope(48000.0, (1500.0, 8000.0))
    parts = [env.push(y[i:i + 333]) for i in range(0, y.size, 333)]
    for k in one:
        assert_array_equal(np.concatenate([p[k] for p in parts]), one[k])


@pytest.mark.parametrize("n, period", [(200, None), (200, 37), (137, 25)])
def test_fold_and_cfar_are_the_sparse_fold(n, period):
    env = envelope(n, period)
    f0 = 107.0
    decoys = f0 * np.array([0.45, 0.62, 0.81, 1.23, 1.37, 1.71])
    grid = period_grid(f0, 0.05, 16)
    freqs = np.concatenate([[f0], decoys])
    for smooth in (1, 2, 3):
        want = reference_peakiness(env, freqs, 16, smooth)
        assert_array_equal(folded_peakiness(env, FE, freqs, smooth=smooth), want)
    pk = reference_peakiness(env, (freqs[:, None] * grid).ravel()).reshape(freqs.size, grid.size)
    best = pk.max(axis=1)
    ref = np.median(best[1:])
    assert cfar_periodicity(env, FE, f0, decoys, grid) == (best[0] / ref, best[0], f0 * grid[np.argmax(pk[0])])
    assert cfar_periodicity(np.zeros(0), FE, f0, decoys, grid) == (0.0, 0.0, f0 * grid[0])


def test_explain_away_masks_the_impact_phase_and_fills_in_the_median():
    env = envelope(200, 37)
    freq = FE / 37
    t = np.arange(env.size) / FE
    b = np.minimum(((t * freq) % 1.0 * 16).astype(np.int64), 15)
    prof = np.bincount(b, weights=env, minlength=16) / np.maximum(np.bincount(b, minlength=16), 1)
    peak = int(np.argmax(prof + np.roll(prof, -1)))
    want = np.isin(b, [(peak + k) % 16 for k in range(-1, 3)])
    mask = impact_phase_mask(env, FE, freq)
    assert_array_equal(mask, want)
    filled = env.copy()
    filled[mask] = np.median(env[~mask])
    assert_array_equal(explain_away(env, mask), filled)
    assert_array_equal(explain_away(env, np.ones(env.size, bool)), env)


def test_train_correlation_is_the_lagged_pearson_correlation():
    u = np.zeros(200)
    u[3::37] = 1.0
    a = np.roll(u, 2) * 3.0 + 0.1 * RNG.random(200)
    n, lags = 200, np.arange(9)
    want = max(np.corrcoef(a[k:], u[:n - k])[0, 1] for k in lags)
    assert_allclose(train_correlation(a, u, 8.0), want, rtol=1e-12)
    assert train_correlation(a, np.zeros(200), 8.0) == 0.0


def test_window_sums_are_numpys_sums():
    w, q = 200, 50
    env, b4, y, y2, r2 = RNG.exponential(size=(5, w))
    got = window_sums(env, b4, y, y2, r2, q)
    assert got == (y.sum(), y2.sum(), r2.sum(), env.sum(), env[:-q].sum(), env[-q:].sum(), b4.sum())
    assert window_sums(env, b4, y, y2, r2, w + 1)[4:6] == (0.0, env.sum())


def test_warm_up_compiles_every_signature_the_decision_uses():
    """The diagnoser node calls warm_up() before subscribing: afterwards, deciding must compile
    nothing more (a compile stalls it for a second or more)."""
    warm_up()
    kernels = compiled_kernels()
    before = {n: len(k.signatures) for n, k in kernels.items()}
    bearing = CATALOG["6205"]
    for model_set, fs in (("sim_48k", 48000.0), ("cwru_de_6205", 12000.0)):
        dg = Diagnoser(config_for(model_set), model_set, bearing, fs)
        dg.tell_speed(1800.0)
        y = RNG.standard_normal(int(0.8 * fs))
        chunk = int(0.01 * fs)
        for i in range(0, y.size, chunk):
            for h in STREAMS:
                part = y[i:i + chunk]
                dg.update(h, i, fs, part, 0.1 * part, (RNG.random(part.size) < 0.01) * 1.0,
                          fault_frequency(bearing, h, 1800.0))
        assert dg.history, "no window was decided"
    assert {n: len(k.signatures) for n, k in kernels.items()} == before


def compiled_kernels() -> dict:
    """Every compiled kernel of the decision's modules, by qualified name."""
    import importlib
    import pkgutil
    found = {}
    for package in (decision, fold):
        for info in pkgutil.iter_modules(package.__path__, package.__name__ + "."):
            module = importlib.import_module(info.name)
            found.update({f"{info.name}.{n}": k for n, k in vars(module).items()
                          if hasattr(k, "signatures") and getattr(k, "__module__", "") == info.name})
    assert len(found) >= 12, found  # the pairwise sums, block sums, folds, window sums, correlation
    return found
