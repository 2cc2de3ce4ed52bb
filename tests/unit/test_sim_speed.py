"""The simulator at changing speed (bearing_sim with a SpeedProfile): angles = ∫ω dt, fault orders
that follow ω(t), the unbalance force of an accelerating shaft, equilibrium and decay at several
speeds, and the constant-speed path unchanged."""

import math
from functools import cache

import numpy as np
import pytest
from scipy import signal

from bearing_common.shaft_angle import RPM_TO_RAD_S, SpeedProfile, angle_from_speed
from bearing_common.states import FaultState as F
from bearing_diagnoser.order_tracking import order_spectrum, resample_to_angle
from bearing_sim import rotor_rhs as R
from bearing_sim.model_parameters import (
    N_BALLS_DE,
    N_PER_LBF,
    P_MUE,
    P_OMD,
    P_OMI,
    P_OMO,
    P_PHIMU,
    UNBALANCE_ECCENTRICITY,
    UNBALANCE_MASS,
    ModelParameters,
)
from bearing_sim.simulator import SPEED_ANGLE_TOL, SimulationConfig, Simulator, simulate

FS = 12000.0
RAMP = SpeedProfile.parse("0:1500,0.8:2100")  # +40 % in 0.8 s: steep, so that a short run shows it


@cache
def ramp_run(state):
    return simulate(SimulationConfig(sample_rate=FS, speed_profile=RAMP), [(state, 0.8)])


def test_a_constant_profile_runs_the_constant_speed_path_bit_for_bit():
    sched = [(F.OUTER_RACE, 0.02), (F.INNER_RACE, 0.02)]
    a = simulate(SimulationConfig(rpm=1500.0, sample_rate=FS), sched)
    b = simulate(SimulationConfig(sample_rate=FS, speed_profile=SpeedProfile.parse("0:1500,5:1500")), sched)
    for key in {"accel", "unbalance", "truth"}:
        assert np.array_equal(a[key], b[key]), key
    np.testing.assert_allclose(b["shaft_speed"], 1500 * RPM_TO_RAD_S, rtol=1e-15)


@pytest.mark.parametrize("state", [F.OUTER_RACE, F.INNER_RACE])
def test_the_changing_speed_path_agrees_with_the_constant_one_at_a_nearly_constant_speed(state):
    """A 1e-9 relative change over 100 s runs the re-anchored calls of 1 ms or less: the waveform must
    equal the constant-speed run within the integrator's tolerance (1.2e-4 RMS measured; bound 1e-3)."""
    sched = [(state, 0.05)]
    a = simulate(SimulationConfig(sample_rate=FS), sched)["accel"]
    slow = SpeedProfile.from_rpm_points([(0.0, 1800.0), (100.0, 1800.0 * (1 + 1e-9))])
    b = simulate(SimulationConfig(sample_rate=FS, speed_profile=slow), sched)["accel"]
    assert np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(a**2)) < 1e-3


def test_the_calls_angles_are_the_shaft_angle_shares_and_the_unbalance_carries_its_tangential_force():
    """Inside one integration call the compiled model turns the balls at a constant rate from the
    packed angles: within SPEED_ANGLE_TOL of theta0 + kappa * phi(t); its unbalance force
    mu e w^2 (cos, sin)(w t + phi_mu) equals mu e (w^2 e_r + alpha e_t) at the shaft angle."""
    sim = Simulator(SimulationConfig(sample_rate=FS, speed_profile=RAMP), [(F.NORMAL, 0.8)])
    params = sim.params
    t0 = 0.3137
    alpha = float(RAMP.alpha(t0))
    t1 = t0 + math.sqrt(8 * SPEED_ANGLE_TOL / alpha)
    p, ct0, st0, _ = sim._call_speed(t0, t1)
    ref = params.shaft_speed
    kappa = np.where(np.arange(17) < N_BALLS_DE, params.cage_speed_de, params.cage_speed_fe) / ref
    for t in np.linspace(t0, t1, 9):
        packed = np.arctan2(st0, ct0) + np.where(np.arange(17) < N_BALLS_DE, p[P_OMI], p[P_OMO]) * t
        exact = params.theta0 + kappa * float(RAMP.angle(t))
        assert np.max(np.abs(np.angle(np.exp(1j * (packed - exact))))) <= SPEED_ANGLE_TOL * 1.01
    w = float(RAMP.omega(t0))
    phi = float(RAMP.angle(t0))
    model = p[P_MUE] * p[P_OMD] ** 2 * np.array([math.cos(p[P_OMD] * t0 + p[P_PHIMU]),
                                                 math.sin(p[P_OMD] * t0 + p[P_PHIMU])])
    mue = UNBALANCE_MASS * UNBALANCE_ECCENTRICITY
    physics = mue * np.array([w * w * math.cos(phi) + alpha * math.sin(phi),
                              w * w * math.sin(phi) - alpha * math.cos(phi)])
    np.testing.assert_allclose(model, physics, rtol=2e-3)  # p[P_OMD] is the call's mean speed


def test_unbalance_output_and_shaft_speed_follow_the_profile():
    d = ramp_run(F.NORMAL)
    t = d["t"]
    w, a, phi = RAMP.omega(t), RAMP.alpha(t), RAMP.angle(t)
    mue = UNBALANCE_MASS * UNBALANCE_ECCENTRICITY
    np.testing.assert_allclose(d["unbalance"], mue * (w * w * np.sin(phi) - a * np.cos(phi)) * N_PER_LBF,
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(d["shaft_speed"], w)
    assert d["rpm"] == pytest.approx(1800.0, rel=1e-12)
    assert d["shaft_speed"].size == d["accel"].size


def _envelope(x):
    sos = signal.butter(4, [1500.0, 5500.0], btype="band", fs=FS, output="sos")
    return np.abs(signal.hilbert(signal.sosfiltfilt(sos, x)))


@pytest.mark.parametrize("state, order_of", [(F.OUTER_RACE, "bpfo"), (F.INNER_RACE, "bpfi")])
def test_fault_frequencies_follow_the_speed_lines_at_the_fault_orders(state, order_of):
    """On a +40 % ramp: the envelope's order spectrum (angle from the simulator's shaft_speed) peaks at
    the fault order from the geometry (eqs. 2.53-2.54) within one order bin, ten times above its
    median; and the envelope spectra of the first and the last 0.3 s peak at that order times the
    mean shaft rate of each (within a bin of 1/0.3 s), 27 % apart."""
    d = ramp_run(state)
    params = ModelParameters.create("default", 1800.0)
    order = getattr(params, order_of) / 30.0
    env = _envelope(d["accel"])
    tracked = resample_to_angle(env, FS, angle_from_speed(d["shaft_speed"], FS), 64)
    orders, amp = order_spectrum(tracked.samples, 64)
    band = (orders > order - 1.0) & (orders < order + 1.0)
    peak = orders[band][np.argmax(amp[band])]
    assert abs(peak - order) <= orders[1], (peak, order)
    assert amp[band].max() > 10 * np.median(amp[(orders > 1) & (orders < 12)])
    n = int(0.3 * FS)
    for part in (slice(0, n), slice(env.size - n, env.size)):
        e = env[part] - env[part].mean()
        spec = np.abs(np.fft.rfft(e * np.hanning(n), 8 * n))
        freqs = np.fft.rfftfreq(8 * n, 1.0 / FS)
        expected = order * float(np.mean(d["shaft_speed"][part])) / (2 * np.pi)
        near = (freqs > 0.85 * expected) & (freqs < 1.15 * expected)
        assert abs(freqs[near][np.argmax(spec[near])] - expected) <= FS / n, (expected, part)


@pytest.mark.parametrize("rpm", [900.0, 1800.0, 3600.0])
def test_static_equilibrium_at_several_speeds(rpm):
    """Sag about -3.0e-6 in (gravity on the preloaded bearings; the centrifugal ball terms change it
    little), forces balanced to 1e-8 lbf, ball loads 150 +- 3 lbf, accelerations zero at rest."""
    params = ModelParameters.create("default", rpm)
    q = R.static_equilibrium(params)
    assert q[1] == pytest.approx(-3.0e-6, rel=0.05)
    assert np.max(np.abs(R.static_forces(params, q))) < 1e-8
    inner, outer = R.ball_loads(params, q)
    assert np.all(np.abs(inner - 150.0) < 3.0) and np.all(np.abs(outer - 150.0) < 3.0)
    y = np.zeros(R.NSTATE)
    y[:R.NDOF] = q
    assert np.max(np.abs(R.rhs_py(0.0, y, params)[R.NDOF:][[0, 1, 2, 3, 21, 22, 23, 24]])) < 1e-3


@pytest.mark.parametrize("speed", [900.0, 1800.0, 3600.0, "0:1500,0.6:2100"],
                         ids=["900", "1800", "3600", "ramp+40%"])
def test_the_response_decays_after_a_fault_at_several_speeds(speed):
    """Energy: an OR segment, then normal operation: the response after the fault decays window by
    window (no energy put in by the changing speed or the re-anchored angles), down to below 1 % of
    the fault's level."""
    profile = SpeedProfile.parse(speed) if isinstance(speed, str) else None
    cfg = SimulationConfig(rpm=1800.0 if profile else speed, sample_rate=FS, speed_profile=profile)
    d = simulate(cfg, [(F.OUTER_RACE, 0.15), (F.NORMAL, 0.45)])
    x, t = d["accel"], d["t"]
    fault = np.std(x[(t > 0.05) & (t < 0.15)])
    w1, w2, w3 = (np.std(x[(t > a) & (t < b)]) for a, b in ((0.2, 0.3), (0.3, 0.45), (0.45, 0.6)))
    assert w3 < 0.9 * w2 < 0.9 * 0.9 * w1 and w3 < 0.01 * fault
    assert np.all(np.isfinite(x))


def test_output_does_not_depend_on_the_chunking_at_changing_speed():
    cfg = SimulationConfig(sample_rate=FS, speed_profile=SpeedProfile.parse("0:1600,0.1:2000"))
    a = simulate(cfg, [(F.INNER_RACE, 0.06)], chunk_seconds=0.0071)
    b = simulate(cfg, [(F.INNER_RACE, 0.06)], chunk_seconds=0.05)
    assert np.array_equal(a["accel"], b["accel"]) and np.array_equal(a["shaft_speed"], b["shaft_speed"])


def test_a_profile_beyond_the_supported_speed_is_refused():
    with pytest.raises(ValueError, match="6000"):
        SimulationConfig(speed_profile=SpeedProfile.parse("0:1800,1:7000"))
    with pytest.raises(ValueError, match="SpeedProfile"):
        SimulationConfig(speed_profile="0:1800,1:2000")
