"""The HW fault observer (Fig. 3.1, eqs. 3.1-3.4): streaming, stability, noise, phase."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_observer.fault_identification import identify_fault_model
from bearing_observer.impulse_trains import TWO_PI, impulse_train
from bearing_observer.model_sets import load_model_set
from bearing_observer.observer import FaultObserver
from bearing_observer.realization import ModalFilter, balanced_realization
from bearing_recordings.mat_files import load_mat
from bearing_sim.simulator import SimulationConfig, simulate

FS = 48000.0


@pytest.fixture(scope="module")
def sim48():
    return load_model_set("sim_48k", sample_rate=FS)


@pytest.fixture(scope="module")
def sim_data():
    cfg = SimulationConfig(rpm=1800, sample_rate=FS, noise_density=0.0)
    return {f.label: np.asarray(simulate(cfg, [(f, 0.4)])["accel"])
            for f in (FaultState.OUTER_RACE, FaultState.INNER_RACE)}


# --- structure ---------------------------------------------------------------------------
def test_balanced_realization_reproduces_b_over_f(sim48):
    m = sim48["outer_race"]
    A, B, C, D = balanced_realization(m.b, m.f)
    assert np.linalg.cond(A) < 1e3
    imp = np.zeros(400)
    imp[0] = 1.0
    x = np.zeros((A.shape[0], 1))
    h = []
    for v in imp:
        h.append((C @ x)[0, 0] + D[0, 0] * v)
        x = A @ x + B * v
    # companion-form lfilter vs balanced modal state space: agree to 1e-7 of the peak
    assert_allclose(h, m.simulate_linear(imp), rtol=0, atol=1e-7 * np.max(np.abs(h)))


@pytest.mark.parametrize("poles", ["model", "contracted"])
def test_observer_poles_strictly_stable(sim48, poles):
    obs = FaultObserver(sim48["outer_race"], poles=poles)
    assert np.max(np.abs(obs.observer_poles)) < 1.0
    assert_allclose(np.abs(np.linalg.eigvals(obs.A - obs.L @ obs.C)),
                    np.abs(obs.observer_poles), rtol=1e-9)


def test_bad_poles_rejected(sim48):
    m = sim48["outer_race"]
    n = balanced_realization(m.b, m.f)[0].shape[0]
    with pytest.raises(ValueError, match="inside the unit circle"):
        FaultObserver(m, poles=np.full(n, 1.2))
    with pytest.raises(ValueError, match="need"):
        FaultObserver(m, poles=[0.5])
    with pytest.raises(ValueError, match="12000 Hz"):
        FaultObserver(m, sample_rate=12000.0)


def test_modal_filter_matches_per_sample_loop(sim48):
    """Vectorised error dynamics == the appendix D difference equation, to 1e-12."""
    obs = FaultObserver(sim48["inner_race"], poles="contracted")
    A, B, C, D, L = obs.A, obs.B, obs.C, obs.D, obs.L
    rng = np.random.default_rng(3)
    w, z = rng.standard_normal(2000), rng.standard_normal(2000)
    out = ModalFilter(A - L @ C, B - L @ D, L, C, D).run(w, z)
    x = np.zeros((A.shape[0], 1))
    ref = []
    for wi, zi in zip(w, z):
        zh = (C @ x)[0, 0] + D[0, 0] * wi
        ref.append(zh)
        x = A @ x + B * wi + L * (zi - zh)
    assert_allclose(out, ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))


# --- streaming ---------------------------------------------------------------------------
@pytest.mark.parametrize("poles", ["model", "contracted"])
def test_chunked_equals_one_shot(sim48, poles):
    m = sim48["outer_race"]
    rng = np.random.default_rng(0)
    u = impulse_train(24000, FS, m.fault_frequency, phase=1.0)
    y = m.simulate(u) + 0.1 * rng.standard_normal(u.size)
    one = FaultObserver(m, poles=poles).process(y)
    obs = FaultObserver(m, poles=poles)
    cuts = np.sort(rng.choice(np.arange(1, y.size), 40, replace=False))
    parts = [obs.process(c) for c in np.split(y, cuts)]
    for field in ("residual", "estimate", "impulse_train", "drive"):
        got = np.concatenate([getattr(p, field) for p in parts])
        assert_allclose(got, getattr(one, field), rtol=0, atol=1e-12 * max(1.0, np.max(np.abs(y))))
    assert np.any(one.drive)  # the adaptive drive was active in this run


def test_nan_chunk_rejected_without_changing_state(sim48):
    m = sim48["outer_race"]
    y = m.simulate(impulse_train(4800, FS, m.fault_frequency))
    a = FaultObserver(m)
    b = FaultObserver(m)
    a.process(y[:2000])
    b.process(y[:2000])
    bad = y[2000:2500].copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        b.process(bad)
    with pytest.raises(ValueError, match="1-D"):
        b.process(np.zeros((2, 2)))
    assert_allclose(a.process(y[2000:]).residual, b.process(y[2000:]).residual, atol=0)


def test_error_converges_from_wrong_initial_state(sim48):
    """The plant runs 0.1 s before the observer starts (observer state 0 = wrong). The
    error decays with either pole choice, faster with the correction (contracted poles)."""
    m = sim48["outer_race"]
    f = m.fault_frequency
    n0 = 4800
    u = impulse_train(n0 + 24000, FS, f, phase=0.4)
    y = m.simulate(u)[n0:]
    rms = np.sqrt(np.mean(y ** 2))
    phase_obs = 0.4 + TWO_PI * f * n0 / FS  # the same train in the observer's time
    early, late = {}, {}
    for poles in ("model", "contracted"):
        obs = FaultObserver(m, poles=poles, drive="fixed", phase=phase_obs, gains=[1.0])
        r = obs.process(y).residual
        early[poles] = np.sqrt(np.mean(r[:200] ** 2))
        late[poles] = np.sqrt(np.mean(r[-4800:] ** 2))
    assert early["model"] > 1e-2 * rms            # the wrong initial state is visible
    assert late["model"] < 1e-6 * rms and late["contracted"] < 1e-6 * rms
    assert early["contracted"] < 0.5 * early["model"]


# --- noise ---------------------------------------------------------------------------------
def test_noise_gain_measured(sim48):
    obs = FaultObserver(sim48["outer_race"], poles="model")
    assert obs.noise_gain == pytest.approx(1.0, abs=1e-12)  # L = 0: residual = y
    obs = FaultObserver(sim48["outer_race"], poles="contracted", contraction=0.95)
    # a strictly causal predictor cannot reduce white noise: gain >= 1; matches the H2 norm
    assert 1.0 <= obs.noise_gain < 2.0
    assert obs.noise_gain == pytest.approx(obs.noise_gain_analytic(), rel=0.03)


def test_no_injection_on_noise(sim48):
    rng = np.random.default_rng(7)
    y = 4.5e-3 * np.sqrt(FS / 2) * rng.standard_normal(int(0.5 * FS))  # CWRU-normal level
    for ft, m in sim48.items():
        out = FaultObserver(m).process(y)
        assert not np.any(out.drive), ft
        assert_allclose(out.residual, y, atol=1e-12)


def test_set_speed_and_reset(sim48):
    obs = FaultObserver(sim48["inner_race"], rpm=1800.0)
    f0 = obs.fault_frequency
    obs.set_speed(900.0)
    assert obs.fault_frequency == pytest.approx(f0 / 2)
    with pytest.raises(ValueError):
        obs.set_speed(float("nan"))
    obs.process(np.ones(100))
    obs.reset()
    assert_allclose(obs.gains, 0.0)


# --- simulator: which observer explains which fault ---------------------------------------------
def _reduction(obs, y):
    out = obs.process(y)
    s = slice(y.size // 2, None)
    return 1.0 - np.std(out.residual[s]) / np.std(y[s]), out


def test_or_and_ir_observers_discriminate_on_simulator(sim48, sim_data):
    """Energy removed by each observer (second half of 0.4 s): the matching observer
    removes most of the signal, the other one injects nothing (reduction exactly 0)."""
    red = {}
    for data in ("outer_race", "inner_race"):
        for ft in ("outer_race", "inner_race"):
            red[data, ft], out = _reduction(FaultObserver(sim48[ft]), sim_data[data])
    assert red["outer_race", "outer_race"] > 0.6, red
    assert red["inner_race", "inner_race"] > 0.5, red
    assert abs(red["outer_race", "inner_race"]) < 1e-12, red
    assert abs(red["inner_race", "outer_race"]) < 1e-12, red


@pytest.mark.parametrize("fault", ["outer_race", "inner_race"])
def test_phase_recovered_on_simulator(sim48, sim_data, fault):
    y = sim_data[fault]
    ident = identify_fault_model(y, FS, 1800.0, fault, CATALOG["6205"], refine_frequency=False)
    obs = FaultObserver(sim48[fault])
    obs.process(y)
    # obs.phase refers to the next sample; advance the identified phase to the same time
    expect = ident.preprocessing.phase_refined + TWO_PI * obs.fault_frequency * y.size / FS
    err = np.angle(np.exp(1j * (obs.phase - expect)))
    assert abs(err) / TWO_PI * FS / obs.fault_frequency < 1.0  # samples


# --- CWRU ----------------------------------------------------------------------------------
def test_cwru_phase_locks_only_on_matching_fault(cwru_record):
    """Resultant length of the phase estimates over 0.05 s updates (1 = locked): the OR
    observer locks on record 130 (OR) and not on 105 (IR), and vice versa."""
    models = load_model_set("cwru_de_6205", sample_rate=12000.0)
    lock = {}
    paths = {rec: cwru_record(name)  # skips with the reason when a record is absent
             for rec, name in (("130", "130_OR007at6_0hp_DE12k.mat"), ("105", "105_IR007_0hp_DE12k.mat"))}
    for rec, path in paths.items():
        record = load_mat(path, 12000.0)
        y, rpm = record.accel[:60000], record.rpm
        for ft, m in models.items():
            obs = FaultObserver(m, rpm=rpm)
            phases = []
            for i in range(0, y.size, 600):
                obs.process(y[i:i + 600])
                # phase referred to a fixed time (the record start): steady when locked
                phases.append(obs.phase - TWO_PI * obs.fault_frequency * (i + 600) / 12000.0)
            lock[rec, ft] = abs(np.mean(np.exp(1j * np.array(phases[4:]))))
    assert lock["130", "outer_race"] > 0.9 and lock["105", "inner_race"] > 0.9, lock
    assert lock["130", "inner_race"] < 0.4 and lock["105", "outer_race"] < 0.4, lock


def test_pure_delay_kept_out_of_state_and_chunk_exact(sim48):
    """nk = 3: the delay is a carried buffer; with L = 0 and a fixed drive the estimate is
    the HW model's own response (exactly), in chunks or in one go."""
    import copy

    m = copy.deepcopy(sim48["outer_race"])
    m.nk = 3
    f = m.fault_frequency
    u = impulse_train(9600, FS, f, phase=0.7)
    y = m.simulate(u)
    one = FaultObserver(m, drive="fixed", phase=0.7, gains=[1.0]).process(y)
    # (phase 0.7 vs 0.7 - 2 pi: impact times equal up to rounding, amplified by the
    # lightly damped model to ~1e-9 of the peak)
    assert_allclose(one.estimate, y, rtol=0, atol=1e-7 * np.max(np.abs(y)))
    obs = FaultObserver(m, drive="fixed", phase=0.7, gains=[1.0])
    assert obs.A.shape == (m.nf, m.nf)  # state order = nf: no delay states
    parts = [obs.process(c) for c in np.array_split(y, [1, 2, 3, 500, 4801])]
    assert_allclose(np.concatenate([p.estimate for p in parts]), one.estimate, rtol=0, atol=0)


def test_speed_change_keeps_train_phase_continuous(sim48):
    m = sim48["outer_race"]
    obs = FaultObserver(m, drive="off")
    a = obs.process(np.zeros(1000)).impulse_train
    obs.set_speed(1700.0)
    b = obs.process(np.zeros(20000)).impulse_train
    # impact times: the first impact after the change follows from the cycle position
    t_imp = np.flatnonzero(np.concatenate([a, b]) > 0)
    gaps = np.diff(t_imp)
    gaps = gaps[gaps > 2]  # ignore the 2-sample splits of sub-sample pulses
    period_old, period_new = FS / m.fault_frequency, FS / obs.fault_frequency
    assert np.all((gaps > min(period_old, period_new) - 2) & (gaps < max(period_old, period_new) + 2))
