"""Model parameters, right-hand side structure and static equilibrium (bearing_sim)."""

import math

import numpy as np
import pytest

from bearing_sim import rotor_rhs as R
from bearing_sim.model_parameters import (
    BALL_MASS_DE,
    BALL_MASS_FE,
    N_BALLS_DE,
    SHAFT_MASS,
    VARIANTS,
    ModelParameters,
)


def test_derived_geometry_matches_listing_numbers():
    p = ModelParameters.create("default", 1800.0)
    assert p.rho1 == pytest.approx(0.3126 / 2, rel=1e-12)
    assert p.r1 == pytest.approx(0.6122, abs=1e-4)
    assert p.R1 == pytest.approx(p.r1 + 2 * p.rho1 - 0.00068022, rel=1e-12)
    # fault frequencies from the geometry (model-notes: 107.544 Hz, 162.456 Hz at 1800 rpm)
    assert p.bpfo == pytest.approx(107.544, abs=2e-3)
    assert p.bpfi == pytest.approx(162.456, abs=2e-3)
    assert p.bpfo + p.bpfi == pytest.approx(N_BALLS_DE * 30.0, rel=1e-12)
    listing = ModelParameters.create("listing", 1800.0)
    assert listing.bpfo == pytest.approx(3.5848 * 30.0, rel=1e-12)


@pytest.mark.parametrize("kw", [dict(variant="nope"), dict(rpm=0.0), dict(rpm=-5.0),
                                dict(or_defect_depth=-1e-3)])
def test_parameter_validation(kw):
    with pytest.raises(ValueError):
        ModelParameters.create(**kw)


def _random_state(params, seed=0):
    rng = np.random.default_rng(seed)
    q = R.static_equilibrium(params)
    y = np.zeros(R.NSTATE)
    y[:R.NDOF] = q + 2e-5 * rng.standard_normal(R.NDOF)
    y[R.NDOF:] = 0.05 * rng.standard_normal(R.NDOF)
    return y


@pytest.mark.parametrize("variant", VARIANTS)
def test_fused_rhs_equals_reference(variant):
    params = ModelParameters.create(variant, 1500.0)
    p, ct0, st0 = R.make_rhs_args(params)
    y = _random_state(params)
    orel = np.zeros(9)
    orel[2] = 0.002
    irel = np.zeros(9)
    irel[6] = 0.002
    d1, d2 = np.zeros(58), np.zeros(58)
    R.rhs(0.0123, y, p, ct0, st0, orel, irel, d1, np.zeros(R.WORK_LEN))
    R.rhs_reference(0.0123, y, p, ct0, st0, orel, irel, d2, np.zeros(R.WORK_LEN))
    np.testing.assert_allclose(d1, d2, rtol=1e-10, atol=1e-9 * np.abs(d2).max())


def _dense_mass(params, t):
    """M(t) built entry by entry as in the appendix A listing (with the variant's fixes)."""
    M = np.zeros((29, 29))
    th = params.theta0
    mi, mo, ms = BALL_MASS_DE, BALL_MASS_FE, SHAFT_MASS
    M[0, 0] = M[1, 1] = 9 * mi + ms / 2
    for i in range(9):
        a = th[i] + params.cage_speed_de * t
        M[0, 4 + i] = M[4 + i, 0] = mi * math.cos(a)
        M[1, 4 + i] = M[4 + i, 1] = mi * math.sin(a)
        M[4 + i, 4 + i] = mi
    listing = params.variant == "listing"
    for i in range(8):
        a = th[9 + i] + params.cage_speed_fe * t
        M[21, 13 + i] = mo * math.cos(a)
        M[22, 13 + i] = mo * math.sin(a)
        if not listing:  # quirk 1: the listing copies zero drive-end entries here
            M[13 + i, 21] = M[21, 13 + i]
            M[13 + i, 22] = M[22, 13 + i]
        M[13 + i, 13 + i] = mo
    M[21, 21] = M[22, 22] = (9 if listing else 8) * mo + ms / 2  # quirk 2
    A, B = params.housing_block()
    for i, j in ((2, 23), (3, 24)):
        M[i, i] = M[j, j] = A
        M[i, j] = M[j, i] = B
    itd, _ = params.disk_inertias()
    M[25, 25] = M[26, 26] = 6.0 / 386.4
    M[27, 27] = M[28, 28] = itd
    return M


@pytest.mark.parametrize("variant", VARIANTS)
def test_block_mass_solve_matches_dense_matrix(variant):
    params = ModelParameters.create(variant, 1800.0)
    p, ct0, st0 = R.make_rhs_args(params)
    t = 0.0371
    rng = np.random.default_rng(3)
    b = rng.standard_normal(29)
    cs_de = np.cos(params.theta0[:9] + params.cage_speed_de * t)
    sn_de = np.sin(params.theta0[:9] + params.cage_speed_de * t)
    cs_fe = np.cos(params.theta0[9:] + params.cage_speed_fe * t)
    sn_fe = np.sin(params.theta0[9:] + params.cage_speed_fe * t)
    a = np.zeros(29)
    R.solve_mass(p, b, a, cs_de, sn_de, cs_fe, sn_fe)
    np.testing.assert_allclose(a, np.linalg.solve(_dense_mass(params, t), b), rtol=1e-9, atol=1e-12 * np.abs(a).max())


def test_housing_block_variants():
    a_l, b_l = ModelParameters.create("default").housing_block()
    a_g, b_g = ModelParameters.create("lagrangian_housing").housing_block()
    mh = 48 / 386.4
    assert a_l + b_l == pytest.approx(mh, rel=1e-12)  # listing: mh/2 + mh/2
    assert a_g + b_g == pytest.approx(mh / 2, rel=1e-12)  # Lagrangian: mh/4 + mh/4


def test_static_equilibrium_sag_and_ball_loads():
    params = ModelParameters.create("default", 1800.0)
    q = R.static_equilibrium(params)
    # model-notes: drive-end shaft sag about -3.0e-6 in
    assert q[1] == pytest.approx(-3.0e-6, rel=0.05)
    assert abs(q[0]) < 0.05 * abs(q[1])
    assert np.max(np.abs(R.static_forces(params, q))) < 1e-8
    inner, outer = R.ball_loads(params, q)
    # about 150 lbf preload per ball, gravity changes it by about +-1 lbf
    assert np.all(np.abs(inner - 150.0) < 3.0) and np.all(np.abs(outer - 150.0) < 3.0)
    spread = outer.max() - outer.min()
    assert 1.0 < spread < 3.0
    # ball at the bottom carries more load than the one at the top
    ang = np.mod(params.theta0[:9], 2 * np.pi)
    assert outer[np.argmin(np.sin(ang))] > outer[np.argmax(np.sin(ang))]
    # without defects the accelerations vanish at equilibrium (velocity zero)
    y = np.zeros(58)
    y[:29] = q
    acc = R.rhs_py(0.0, y, params)[29:]
    assert np.max(np.abs(acc[[0, 1, 2, 3, 21, 22, 23, 24]])) < 1e-3  # in/s^2


def test_outer_race_window_at_six_oclock():
    from bearing_sim.defects import outer_race_window
    params = ModelParameters.create("default", 1800.0)
    win = outer_race_window(params)
    sw = win.switch_times(0.0, 0.1)
    for t_in, t_out in zip(sw[::2], sw[1::2]):
        mid = 0.5 * (t_in + t_out)
        active = win.active(mid)
        assert active.sum() == 1
        i = int(np.argmax(active))
        ang = params.theta0[i] + params.cage_speed_de * mid
        assert math.cos(ang) == pytest.approx(0.0, abs=1e-9) and math.sin(ang) < 0  # 6 o'clock
        assert (t_out - t_in) * params.cage_speed_de == pytest.approx(params.theta_or, rel=1e-9)
    # one ball every 1/BPFO
    np.testing.assert_allclose(np.diff(sw[::2]), 1.0 / params.bpfo, rtol=1e-9)
    assert win.relief(0.5 * (sw[0] + sw[1])).max() == pytest.approx(0.002)


@pytest.mark.parametrize("rpm", [1800.0, 1500.0])
def test_inner_race_window_follows_listing_timing(rpm):
    """Balls 1, 2, 3, ... in turn every 1/BPFI from t = 1 ms, each for
    theta_IR / (omega_d - Omega_c) s (the listing's logic, BPFI from geometry)."""
    from bearing_sim.defects import inner_race_window
    params = ModelParameters.create("default", rpm)
    win = inner_race_window(params)
    sw = win.switch_times(0.0, 0.2)
    starts, ends = sw[::2], sw[1::2]
    assert starts[0] == pytest.approx(1e-3, abs=1e-12)
    np.testing.assert_allclose(np.diff(starts), 1.0 / params.bpfi, rtol=1e-9)
    dur = params.theta_ir / (params.shaft_speed - params.cage_speed_de)
    np.testing.assert_allclose(ends - starts, dur, rtol=1e-9)
    balls = [int(np.argmax(win.active(0.5 * (a + b)))) for a, b in zip(starts, ends)]
    assert balls[:12] == [0, 1, 2, 3, 4, 5, 6, 7, 8, 0, 1, 2]
    assert params.bpfi / (rpm / 60.0) == pytest.approx(5.4152, abs=2e-4)
