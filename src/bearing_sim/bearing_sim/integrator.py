"""Adaptive Dormand-Prince 5(4) integrator for the rotor model, compiled with numba.

The whole stepping loop runs in compiled code (scipy's ``solve_ivp`` around the
same right-hand side is about 10x slower: its per-step Python overhead
dominates). One call integrates over one *switching interval* [t, t_end]: the
caller cuts the time axis at every defect switching time (a ball entering or
leaving a defect window, a segment boundary) so no step straddles a switch; the
defect radius changes ``or_rel``/``ir_rel`` are constant inside a call. The
first stage is re-evaluated at the start of each call (FSAL does not hold
across a switch).

Error control: the usual mixed norm ``sqrt(mean((err_i / (atol_i + rtol*max|y_i|))^2)) <= 1``
with a PI step-size controller (Hairer & Wanner's DOPRI5 settings, beta = 0.04),
which keeps the step smooth near the stability limit set by the ball modes
(about 61 kHz on the fan end: steps of about 7 us).

Dense output: the output quantity is the acceleration of one DOF (the housing
y at the drive end). It is the time derivative of that DOF's velocity, so it is
read from the derivative of the method's 4th-order continuous extension
(Shampine's, as in Hairer's ``contd5``): a cubic in the step fraction through
the stage accelerations, exact at both step ends, costing no extra right-hand
side evaluation. It is written on a fixed uniform fine grid t_n = n * fine_dt.

Note for developers: numba's on-disk cache is keyed on each function's own
source file, and the right-hand side is compiled into this loop. After editing
``rotor_rhs.py`` delete ``bearing_sim/__pycache__`` (or touch this file).
"""

import numpy as np
from numba import njit

from .model_parameters import P_OMD, P_OMI, P_OMO
from .rotor_rhs import FASTMATH, rhs_into, rhs_trig, trig_at, NSTATE, NDOF, WORK_LEN

# Dormand-Prince 5(4) tableau
C2, C3, C4, C5 = 1 / 5, 3 / 10, 4 / 5, 8 / 9
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
A71, A73, A74, A75, A76 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
# error coefficients b5 - b4
E1, E3, E4, E5, E6, E7 = 71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40
# continuous extension: y(t + th h) = y + h sum_i k_i sum_j P[i, j] th^(j+1)
DENSE_P = np.array([
    [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0.0, 0.0, 0.0, 0.0],
    [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])
# its time derivative: dy/dt = sum_i k_i sum_j D[i, j] th^j
DENSE_D = DENSE_P * np.array([1.0, 2.0, 3.0, 4.0])

STAT_STEPS, STAT_REJECTS, STAT_RHS = 0, 1, 2


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def _rotate(base, om, d, trig):
    """trig = cos/sin of (angle_j + om_j * d) from base = cos/sin of angle_j, j = 0..2.

    The increment om_j * d (< 0.7 rad for any valid step and speed) uses Taylor
    series to x^14 (error < 1e-15), so the stage times cost no libm call.
    """
    for j in range(3):
        x = om[j] * d
        x2 = x * x
        sx = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (
            1.0 - x2 / 110.0 * (1.0 - x2 / 156.0 * (1.0 - x2 / 210.0)))))))
        cx = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0 * (
            1.0 - x2 / 90.0 * (1.0 - x2 / 132.0 * (1.0 - x2 / 182.0))))))
        c0 = base[2 * j]
        s0 = base[2 * j + 1]
        trig[2 * j] = c0 * cx - s0 * sx
        trig[2 * j + 1] = s0 * cx + c0 * sx


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def _dense_weight(s, th):
    """Weight of stage s in the dense-output derivative at step fraction th
    (``DENSE_D`` row s as a cubic in th; row 1 is zero, so k_1 never enters)."""
    return DENSE_D[s, 0] + th * (DENSE_D[s, 1] + th * (DENSE_D[s, 2] + th * DENSE_D[s, 3]))


@njit(cache=True, error_model="numpy", fastmath=FASTMATH)
def integrate_interval(t, t_end, y, h, h_max, p, ct0, st0, or_rel, ir_rel, rtol, atol,
                       fine_dt, n_next, fine_out, comp, stats, state):
    """Integrate y (in place) from t to exactly t_end.

    Writes ``fine_out[k] = d/dt y[comp]`` at t_n = (n_next + k) * fine_dt for every
    fine-grid time in (t, t_end]. ``state[0]`` carries the controller's previous
    error between calls. ``stats`` accumulates steps, rejections, rhs calls.
    Returns (h_next, n_written, ok); ok is False if the step size collapsed or the
    state became non-finite.
    """
    n = NSTATE
    # stage derivatives k_s in one flat array, k_s[i] = k[s * n + i] (written
    # through an offset: a row view k[s] would cost reference counting per call)
    k = np.empty(7 * n)
    ynew = np.empty(n)
    work = np.empty(WORK_LEN)
    base = np.empty(6)
    trig = np.empty(6)
    om = np.empty(3)
    om[0] = p[P_OMI]
    om[1] = p[P_OMO]
    om[2] = p[P_OMD]
    trig_at(t, p, base)
    rhs_trig(y, p, ct0, st0, or_rel, ir_rel, k[:n], work, base)  # once per call: not inlined
    stats[STAT_RHS] += 1
    n_written = 0
    err_old = state[0]
    rejected = False
    beta = 0.04
    expo1 = 0.2 - beta * 0.75
    h_keep = h
    while t < t_end:
        if h > h_max:
            h = h_max
        last = False
        h_keep = h
        if t + 1.01 * h >= t_end:
            h = t_end - t
            last = True
        if h < 1e-14:
            return h_keep, n_written, False
        # stages 2..7 (one inlined right-hand side in the loop); the stage states
        # go to ynew, the last one is the 5th-order solution whose derivative
        # k6 is the next step's first stage (FSAL)
        for st in range(1, 7):
            if st == 1:
                for i in range(n):
                    ynew[i] = y[i] + h * A21 * k[i]
                _rotate(base, om, C2 * h, trig)
            elif st == 2:
                for i in range(n):
                    ynew[i] = y[i] + h * (A31 * k[i] + A32 * k[1 * n + i])
                _rotate(base, om, C3 * h, trig)
            elif st == 3:
                for i in range(n):
                    ynew[i] = y[i] + h * (A41 * k[i] + A42 * k[1 * n + i] + A43 * k[2 * n + i])
                _rotate(base, om, C4 * h, trig)
            elif st == 4:
                for i in range(n):
                    ynew[i] = y[i] + h * (A51 * k[i] + A52 * k[1 * n + i] + A53 * k[2 * n + i] + A54 * k[3 * n + i])
                _rotate(base, om, C5 * h, trig)
            elif st == 5:
                for i in range(n):
                    ynew[i] = y[i] + h * (A61 * k[i] + A62 * k[1 * n + i] + A63 * k[2 * n + i] + A64 * k[3 * n + i]
                                          + A65 * k[4 * n + i])
                _rotate(base, om, h, trig)
            else:
                for i in range(n):
                    ynew[i] = y[i] + h * (A71 * k[i] + A73 * k[2 * n + i] + A74 * k[3 * n + i] + A75 * k[4 * n + i]
                                          + A76 * k[5 * n + i])
            rhs_into(ynew, p, ct0, st0, or_rel, ir_rel, k, st * n, work, trig)
        t_new = t_end if last else t + h
        stats[STAT_RHS] += 6
        err = 0.0
        for i in range(n):
            e = h * (E1 * k[i] + E3 * k[2 * n + i] + E4 * k[3 * n + i] + E5 * k[4 * n + i] + E6 * k[5 * n + i]
                     + E7 * k[6 * n + i])
            sc = atol[i] + rtol * max(abs(y[i]), abs(ynew[i]))
            err += (e / sc) ** 2
        err = np.sqrt(err / n)
        if not np.isfinite(err):
            stats[STAT_REJECTS] += 1
            h = 0.1 * h
            rejected = True
            continue
        fac11 = err ** expo1
        if err <= 1.0:
            stats[STAT_STEPS] += 1
            # dense output on the fine grid
            while True:
                tn = (n_next + n_written) * fine_dt
                if tn > t_new:
                    break
                if n_written >= fine_out.shape[0]:  # caller's buffer too small
                    return h, n_written, False
                th = (tn - t) / h
                fine_out[n_written] = (k[comp] * _dense_weight(0, th) + k[2 * n + comp] * _dense_weight(2, th)
                                       + k[3 * n + comp] * _dense_weight(3, th) + k[4 * n + comp] * _dense_weight(4, th)
                                       + k[5 * n + comp] * _dense_weight(5, th) + k[6 * n + comp] * _dense_weight(6, th))
                n_written += 1
            fac = fac11 / max(err_old, 1e-4) ** beta
            fac = max(0.1, min(5.0, fac / 0.9))
            h_new = h / fac
            if rejected:
                h_new = min(h_new, h)
            err_old = max(err, 1e-4)
            rejected = False
            t = t_new
            for i in range(n):
                y[i] = ynew[i]
                k[i] = k[6 * n + i]
            # the angles at the new t: the last stage's rotation (no libm call)
            for j in range(6):
                base[j] = trig[j]
            if last:
                h = max(h_new, h_keep) if err < 0.5 else h_new
                break
            h = h_new
        else:
            stats[STAT_REJECTS] += 1
            h = h / min(5.0, fac11 / 0.9)
            rejected = True
    state[0] = err_old
    for i in range(n):
        if not np.isfinite(y[i]):
            return h, n_written, False
    return h, n_written, True


def default_atol(rtol, pos_scale=1e-4, vel_scale=1.0):
    """Absolute tolerances per state (58,): rtol * scale, scales in in and in/s.

    Displacements are of order 1e-6..1e-4 in (ball compressions 3.4e-4 in),
    velocities up to about 1 in/s (ball modes at ~60 kHz).
    """
    a = np.empty(NSTATE)
    a[:NDOF] = rtol * pos_scale
    a[NDOF:] = rtol * vel_scale
    return a
