"""Compiled right-hand side of the 29-DOF model, eq. 2.50 / 2.20:

    M(t) q'' + C(t) q' + K(t) q + F(q, t) = 0        (listing units: in, lbf, s)

as a first-order system y = [q, q'] (58 states). DOF order (0-based here; the
listing is 1-based): 0-1 drive-end shaft x,y; 2-3 drive-end housing x,y (3 is
the measured output); 4-12 drive-end ball radial coordinates (9); 13-20 fan-end
ball radial coordinates (8); 21-22 fan-end shaft x,y; 23-24 fan-end housing
x,y; 25-26 disk x,y; 27-28 disk tilts.

Ball radial coordinates are stored as deviations from the nominal radius
``r + rho - RI/2`` (both contacts equally compressed), so that every state is
small and one absolute tolerance per kind fits all of them; the physics uses
the absolute radius.

No matrix is built: ``generalized_forces`` evaluates C q' + K q + F directly
from the listing's entries, and ``solve_mass`` applies M(t)^-1 in O(n) through
its block structure: per bearing an arrow block (shaft x,y coupled to its
balls) reduced to a 2x2 Schur complement, two 2x2 housing blocks and the
diagonal disk block.

``F`` holds the Hertzian contacts k*delta^1.5 (compression only) of all 17
balls on both races (eqs. 2.9-2.10), gravity (half the rotor weight at each
bearing, as in the listing) and the unbalance. Defects enter as per-ball radius
changes that are constant between switching times (see :mod:`defects`):
``or_rel[i]`` is added to the drive-end outer-race radius seen by ball i (a ball
over the OR defect is relieved radially by the defect depth), ``ir_rel[i]``
subtracted from the inner-race radius (IR defect).

Two implementations of the same equations: ``rhs_reference`` (separate
``generalized_forces`` and ``solve_mass``, entries as in the listing, the
contact distance computed directly) and the fused fast path ``rhs`` /
``rhs_trig`` / ``rhs_into`` (the last one inlined into the integrator; one pass
per bearing; the contact distance expanded to O(tn^4) < 1e-15 relative; sum c^2
= sum s^2 = N/2 for the equally spaced balls). The unit tests hold them equal to
1e-10.
"""

import math

import numpy as np
from numba import njit

from .model_parameters import (
    P_CH,
    P_CROT,
    P_CV,
    P_IP,
    P_ITD,
    P_K1I,
    P_K1O,
    P_K2I,
    P_K2O,
    P_KAPPA_C,
    P_KAPPA_FE,
    P_KH,
    P_KS,
    P_L,
    P_MD,
    P_MH_A,
    P_MH_B,
    P_MI,
    P_MO,
    P_MS_DE,
    P_MS_FE,
    P_MUE,
    P_OMD,
    P_OMI,
    P_OMO,
    P_PHIMU,
    P_R1,
    P_R2,
    P_RHO1,
    P_RHO2,
    P_RNOM1,
    P_RNOM2,
    P_RR1,
    P_RR2,
    P_WHALF,
)

#: LLVM fast-math flags for the compiled code: reassociation, contraction etc.,
#: but not 'nnan'/'ninf', so that non-finite states are still detected. The
#: compiled functions also use error_model="numpy" (no zero-division checks).
FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}

NDOF = 29
NSTATE = 58
DOF_HOUSING_Y_DE = 3  #: the measured output (listing DOF 4, xdot(33) its acceleration)
NB_DE = 9
NB_FE = 8
BALL0_DE = 4
BALL0_FE = 13


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def _bearing_forces(t, q, v, p, ct0, st0, rel_out, rel_in, G, cs, sn, de):
    """Contact, damping and stiffness terms of one bearing (rows of G).

    de=True: drive end (shaft 0,1; housing 2,3; balls 4-12), else fan end
    (shaft 21,22; housing 23,24; balls 13-20). ``cs``/``sn`` receive the ball
    angle cosines/sines (used again by the mass solve).
    """
    if de:
        ix, iy, hx, hy, b0, nb, boff = 0, 1, 2, 3, BALL0_DE, NB_DE, 0
        m, om, k_in, k_out = p[P_MI], p[P_OMI], p[P_K1I], p[P_K2I]
        rho, r_in, r_out, rnom = p[P_RHO1], p[P_R1], p[P_RR1], p[P_RNOM1]
    else:
        ix, iy, hx, hy, b0, nb, boff = 21, 22, 23, 24, BALL0_FE, NB_FE, NB_DE
        m, om, k_in, k_out = p[P_MO], p[P_OMO], p[P_K1O], p[P_K2O]
        rho, r_in, r_out, rnom = p[P_RHO2], p[P_R2], p[P_RR2], p[P_RNOM2]
    cv = p[P_CV]
    kap_c = p[P_KAPPA_C]
    ca = math.cos(om * t)
    sa = math.sin(om * t)
    xs, ys, xh, yh = q[ix], q[iy], q[hx], q[hy]
    vxs, vys, vxh, vyh = v[ix], v[iy], v[hx], v[hy]
    mom2 = m * om * om
    fx = 0.0
    fy = 0.0
    g_ix = 0.0
    g_iy = 0.0
    g_hx = 0.0
    g_hy = 0.0
    for i in range(nb):
        c = ct0[boff + i] * ca - st0[boff + i] * sa
        s = st0[boff + i] * ca + ct0[boff + i] * sa
        cs[i] = c
        sn[i] = s
        r = rnom + q[b0 + i]
        vb = v[b0 + i]
        dx = xs - xh + r * c
        dy = ys - yh + r * s
        X = math.sqrt(dx * dx + dy * dy)
        # ball row: damping, centrifugal stiffness -m*Omega^2 r, contacts
        gb = (2.0 * cv * vb + (cv * c - kap_c * m * om * s) * vxs + (cv * s + kap_c * m * om * c) * vys
              - cv * c * vxh - cv * s * vyh - mom2 * r)
        d_out = X - (r_out + (rel_out[i] if de else 0.0) - rho)
        if d_out > 0.0:
            f = k_out * d_out * math.sqrt(d_out) / X
            fx += f * dx
            fy += f * dy
            gb += f * (c * dx + s * dy)
        d_in = r_in - (rel_in[i] if de else 0.0) + rho - r
        if d_in > 0.0:
            gb -= k_in * d_in * math.sqrt(d_in)
        G[b0 + i] = gb
        # shaft rows: C(1,i) = cv c - 2 m Om s, C(2,i) = cv s + 2 m Om c; K(1,i) = -m Om^2 c
        g_ix += (cv * c - 2.0 * m * om * s) * vb - mom2 * c * r
        g_iy += (cv * s + 2.0 * m * om * c) * vb - mom2 * s * r
        g_hx -= cv * c * vb
        g_hy -= cv * s * vb
    ncv = nb * cv
    ch = p[P_CH]
    kh = p[P_KH]
    ks = p[P_KS]
    w_half = p[P_WHALF]
    G[ix] = g_ix + ncv * (vxs - vxh) + ks * xs + fx
    G[iy] = g_iy + ncv * (vys - vyh) + ks * ys + fy + w_half
    G[hx] = g_hx - ncv * vxs + (ncv + ch) * vxh + kh * xh - fx
    G[hy] = g_hy - ncv * vys + (ncv + ch) * vyh + kh * yh - fy - w_half


@njit(cache=True, error_model="numpy", fastmath=FASTMATH)
def generalized_forces(t, y, p, ct0, st0, or_rel, ir_rel, G, cs_de, sn_de, cs_fe, sn_fe):
    """G = C(t) q' + K(t) q + F(q, t) (lbf), listing appendix A, all 29 rows."""
    q = y[:NDOF]
    v = y[NDOF:]
    _bearing_forces(t, q, v, p, ct0, st0, or_rel, ir_rel, G, cs_de, sn_de, True)
    _bearing_forces(t, q, v, p, ct0, st0, or_rel, ir_rel, G, cs_fe, sn_fe, False)
    ks = p[P_KS]
    L = p[P_L]
    # shaft-disk coupling (K(1,26), K(1,29), K(2,27), K(2,28), K(22,26), ...)
    G[0] += -ks * q[25] + ks * L * q[28]
    G[1] += -ks * q[26] - ks * L * q[27]
    G[21] += -ks * q[25] - ks * L * q[28]
    G[22] += -ks * q[26] + ks * L * q[27]
    wd = p[P_OMD]
    ph = wd * t + p[P_PHIMU]
    fu = p[P_MUE] * wd * wd
    crot = p[P_CROT]
    ipw = p[P_IP] * wd
    G[25] = crot * v[25] - ks * q[0] + 2 * ks * q[25] - ks * q[21] - fu * math.cos(ph)
    G[26] = crot * v[26] - ks * q[1] + 2 * ks * q[26] - ks * q[22] - fu * math.sin(ph)
    G[27] = ipw * v[28] - ks * L * q[1] + ks * L * q[22] + 2 * ks * L * L * q[27]
    G[28] = -ipw * v[27] + ks * L * q[0] - ks * L * q[21] + 2 * ks * L * L * q[28]


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def _solve_arrow(b, a, ix, iy, b0, nb, m, ms, kappa, cs, sn):
    """Solve the arrow block of one bearing: shaft rows [ms, 0, m c_i; 0, ms, m s_i],
    ball rows [kappa m c_i, kappa m s_i, m] (kappa = 0: listing quirk 1), by the
    2x2 Schur complement of the (diagonal) ball block."""
    s11 = ms
    s12 = 0.0
    s22 = ms
    r1 = b[ix]
    r2 = b[iy]
    for i in range(nb):
        c = cs[i]
        s = sn[i]
        s11 -= kappa * m * c * c
        s12 -= kappa * m * c * s
        s22 -= kappa * m * s * s
        r1 -= c * b[b0 + i]
        r2 -= s * b[b0 + i]
    det = s11 * s22 - s12 * s12
    ax = (s22 * r1 - s12 * r2) / det
    ay = (s11 * r2 - s12 * r1) / det
    a[ix] = ax
    a[iy] = ay
    for i in range(nb):
        a[b0 + i] = b[b0 + i] / m - kappa * (cs[i] * ax + sn[i] * ay)


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def solve_mass(p, b, a, cs_de, sn_de, cs_fe, sn_fe):
    """a = M(t)^-1 b using the block structure (O(n))."""
    _solve_arrow(b, a, 0, 1, BALL0_DE, NB_DE, p[P_MI], p[P_MS_DE], 1.0, cs_de, sn_de)
    _solve_arrow(b, a, 21, 22, BALL0_FE, NB_FE, p[P_MO], p[P_MS_FE], p[P_KAPPA_FE], cs_fe, sn_fe)
    A = p[P_MH_A]
    B = p[P_MH_B]
    det = A * A - B * B
    b2, b23, b3, b24 = b[2], b[23], b[3], b[24]
    a[2] = (A * b2 - B * b23) / det
    a[23] = (A * b23 - B * b2) / det
    a[3] = (A * b3 - B * b24) / det
    a[24] = (A * b24 - B * b3) / det
    a[25] = b[25] / p[P_MD]
    a[26] = b[26] / p[P_MD]
    a[27] = b[27] / p[P_ITD]
    a[28] = b[28] / p[P_ITD]


@njit(cache=True, error_model="numpy", fastmath=FASTMATH)
def rhs_reference(t, y, p, ct0, st0, or_rel, ir_rel, dy, work):
    """dy = f(t, y) via the separate steps generalized_forces -> solve_mass
    (clear reference for :func:`rhs`); ``work`` scratch of length >= WORK_LEN."""
    G = work[:NDOF]
    cs_de = work[NDOF:NDOF + 9]
    sn_de = work[NDOF + 9:NDOF + 18]
    cs_fe = work[NDOF + 18:NDOF + 26]
    sn_fe = work[NDOF + 26:NDOF + 34]
    generalized_forces(t, y, p, ct0, st0, or_rel, ir_rel, G, cs_de, sn_de, cs_fe, sn_fe)
    for i in range(NDOF):
        G[i] = -G[i]
        dy[i] = y[NDOF + i]
    solve_mass(p, G, dy[NDOF:], cs_de, sn_de, cs_fe, sn_fe)


WORK_LEN = NDOF + 34


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def _bearing_fused(ca, sa, y, p, ct0, st0, rel_o, rel_i, use_rel, dy, o, cs, sn,
                   ix, b0, nb, boff, m, om, k_in, k_out, rho, r_in, r_out, rnom, kappa):
    """One bearing of the fast path: contact/damping/stiffness terms, ball rows of
    -G written to dy[o:o + 58], and the sums the Schur complement needs.

    Returns (Gx, Gy, Ghx, Ghy) of the shaft and housing rows and
    (sum c b, sum s b, sum c^2, sum c s, sum s^2) over the balls."""
    cv = p[P_CV]
    kap_c = p[P_KAPPA_C]
    xs = y[ix]; ys = y[ix + 1]; xh = y[ix + 2]; yh = y[ix + 3]
    vxs = y[29 + ix]; vys = y[30 + ix]; vxh = y[31 + ix]; vyh = y[32 + ix]
    rx = xs - xh
    ry = ys - yh
    mom = m * om
    mom2 = mom * om
    fx = 0.0; fy = 0.0
    scv = 0.0; ssv = 0.0; scr = 0.0; ssr = 0.0
    scb = 0.0; ssb = 0.0
    dvx = vxs - vxh
    dvy = vys - vyh
    for i in range(nb):
        c = ct0[boff + i] * ca - st0[boff + i] * sa
        s = st0[boff + i] * ca + ct0[boff + i] * sa
        cs[i] = c
        sn[i] = s
        r = rnom + y[b0 + i]
        vb = y[29 + b0 + i]
        # shaft-housing offset (rx, ry) in the ball's radial/tangential frame;
        # the contact distance X = |(rx, ry) + r e_r| = sqrt(ru^2 + w^2) is
        # expanded in tn = w/ru (|w| < 1e-4 in << ru ~ 0.4-0.8 in): X = ru (1 + tn^2/2),
        # direction e_r (1 - tn^2/2) + e_t tn; neglected terms O(tn^4) < 1e-15
        # relative. Saves one sqrt per ball against the direct form (rhs_reference).
        u = c * rx + s * ry
        w = c * ry - s * rx
        ru = r + u
        tn = w / ru
        half_t2 = 0.5 * tn * tn
        X = ru * (1.0 + half_t2)
        ro = r_out - rho
        ri = r_in + rho
        if use_rel:
            ro += rel_o[i]
            ri -= rel_i[i]
        gb = 2.0 * cv * vb + cv * (c * dvx + s * dvy) + kap_c * mom * (c * vys - s * vxs) - mom2 * r
        # Hertz k delta^1.5 (eqs. 2.9-2.10) for compression only, branch-free:
        # delta = max(d, 0) gives exactly 0 for a ball out of contact (no
        # mispredicted branches as balls enter and leave the load zone)
        d_out = max(X - ro, 0.0)
        f = k_out * d_out * math.sqrt(d_out)
        rad = f * (1.0 - half_t2)
        tan = f * tn
        fx += c * rad - s * tan
        fy += s * rad + c * tan
        d_in = max(ri - r, 0.0)
        gb += rad
        gb -= k_in * d_in * math.sqrt(d_in)
        b = -gb
        dy[o + 29 + b0 + i] = b
        scb += c * b
        ssb += s * b
        scv += c * vb
        ssv += s * vb
        scr += c * r
        ssr += s * r
    # C(1,i) = cv c - 2 m Om s, C(2,i) = cv s + 2 m Om c, C(3,i) = -cv c, ...;
    # K(1,i) = -m Om^2 c, K(2,i) = -m Om^2 s
    gx = cv * scv - 2.0 * mom * ssv - mom2 * scr
    gy = cv * ssv + 2.0 * mom * scv - mom2 * ssr
    ghx = -cv * scv
    ghy = -cv * ssv
    # equally spaced balls (N >= 3): sum c^2 = sum s^2 = N/2, sum c s = 0 exactly
    scc = 0.5 * nb
    scs = 0.0
    sss = 0.5 * nb
    ncv = nb * cv
    ch = p[P_CH]; kh = p[P_KH]; ks = p[P_KS]; wh = p[P_WHALF]
    Gx = gx + ncv * dvx + ks * xs + fx
    Gy = gy + ncv * dvy + ks * ys + fy + wh
    Ghx = ghx - ncv * dvx + ch * vxh + kh * xh - fx
    Ghy = ghy - ncv * dvy + ch * vyh + kh * yh - fy - wh
    return Gx, Gy, Ghx, Ghy, scb, ssb, scc, scs, sss


@njit(cache=True, error_model="numpy", fastmath=FASTMATH)
def rhs(t, y, p, ct0, st0, or_rel, ir_rel, dy, work):
    """dy = f(t, y) for y = [q, q'] (58 states): see :func:`rhs_trig`."""
    trig = work[34:40]
    trig_at(t, p, trig)
    rhs_trig(y, p, ct0, st0, or_rel, ir_rel, dy, work, trig)


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def trig_at(t, p, trig):
    """cos/sin of the drive-end cage angle, fan-end cage angle and unbalance phase at t."""
    a = p[P_OMI] * t
    trig[0] = math.cos(a)
    trig[1] = math.sin(a)
    a = p[P_OMO] * t
    trig[2] = math.cos(a)
    trig[3] = math.sin(a)
    a = p[P_OMD] * t + p[P_PHIMU]
    trig[4] = math.cos(a)
    trig[5] = math.sin(a)


@njit(cache=True, error_model="numpy", fastmath=FASTMATH)
def rhs_trig(y, p, ct0, st0, or_rel, ir_rel, dy, work, trig):
    """dy = f(t, y) for y = [q, q'] (58 states): the fast, fused path, see
    :func:`rhs_into` (here with dy of its own, offset 0)."""
    rhs_into(y, p, ct0, st0, or_rel, ir_rel, dy, 0, work, trig)


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def _arrow_into(dy, o, ix, b0, nb, m, ms, kappa, Gx, Gy, scb, ssb, scc, scs, sss, cs, sn):
    """Accelerations of one bearing's arrow block into dy[o + 29 + ...] by the 2x2 Schur
    complement (as :func:`_solve_arrow`), from the sums of :func:`_bearing_fused`; the
    ball rows enter holding -G and leave holding accelerations."""
    s11 = ms - kappa * m * scc
    s12 = -kappa * m * scs
    s22 = ms - kappa * m * sss
    r1 = -Gx - scb
    r2 = -Gy - ssb
    det = s11 * s22 - s12 * s12
    ax = (s22 * r1 - s12 * r2) / det
    ay = (s11 * r2 - s12 * r1) / det
    dy[o + 29 + ix] = ax
    dy[o + 30 + ix] = ay
    im = 1.0 / m
    for i in range(nb):
        dy[o + 29 + b0 + i] = dy[o + 29 + b0 + i] * im - kappa * (cs[i] * ax + sn[i] * ay)


@njit(cache=True, error_model="numpy", fastmath=FASTMATH, inline="always")
def rhs_into(y, p, ct0, st0, or_rel, ir_rel, dy, o, work, trig):
    """dy[o:o + 58] = f(t, y) for y = [q, q'] (58 states): the fast, fused path.

    Inlined into its callers; the offset ``o`` lets the integrator keep all its
    stage derivatives in one flat array (a row view would cost reference
    counting per call).

    Time enters only through ``trig`` = (cos, sin) of Omega_i t, Omega_o t and
    omega_d t + phi_mu (see :func:`trig_at`; the integrator rotates them to its
    stage times instead of calling cos/sin 6 times per stage).

    Same equations as :func:`rhs_reference` (G = C q' + K q + F, then
    M(t)^-1 by blocks) in one pass per bearing: the ball rows and the sums of the
    arrow-block Schur complement are accumulated in the contact loop.
    ``work``: scratch, length >= WORK_LEN. Units: in, in/s, in/s^2.
    """
    cs1 = work[0:9]; sn1 = work[9:18]; cs2 = work[18:26]; sn2 = work[26:34]
    Gx1, Gy1, Ghx1, Ghy1, scb1, ssb1, scc1, scs1, sss1 = _bearing_fused(
        trig[0], trig[1], y, p, ct0, st0, or_rel, ir_rel, True, dy, o, cs1, sn1,
        0, 4, 9, 0, p[P_MI], p[P_OMI], p[P_K1I], p[P_K2I], p[P_RHO1], p[P_R1], p[P_RR1], p[P_RNOM1], 1.0)
    Gx2, Gy2, Ghx2, Ghy2, scb2, ssb2, scc2, scs2, sss2 = _bearing_fused(
        trig[2], trig[3], y, p, ct0, st0, or_rel, ir_rel, False, dy, o, cs2, sn2,
        21, 13, 8, 9, p[P_MO], p[P_OMO], p[P_K1O], p[P_K2O], p[P_RHO2], p[P_R2], p[P_RR2], p[P_RNOM2], 1.0)
    ks = p[P_KS]; L = p[P_L]
    q25 = y[25]; q26 = y[26]; q27 = y[27]; q28 = y[28]
    Gx1 += -ks * q25 + ks * L * q28
    Gy1 += -ks * q26 - ks * L * q27
    Gx2 += -ks * q25 - ks * L * q28
    Gy2 += -ks * q26 + ks * L * q27
    wd = p[P_OMD]
    fu = p[P_MUE] * wd * wd
    crot = p[P_CROT]
    ipw = p[P_IP] * wd
    v = 29
    G25 = crot * y[v + 25] - ks * y[0] + 2 * ks * q25 - ks * y[21] - fu * trig[4]
    G26 = crot * y[v + 26] - ks * y[1] + 2 * ks * q26 - ks * y[22] - fu * trig[5]
    G27 = ipw * y[v + 28] - ks * L * y[1] + ks * L * y[22] + 2 * ks * L * L * q27
    G28 = -ipw * y[v + 27] + ks * L * y[0] - ks * L * y[21] + 2 * ks * L * L * q28
    for i in range(29):
        dy[o + i] = y[29 + i]
    # arrow blocks (kappa = 1 at the drive end; listing quirk 1 at the fan end)
    _arrow_into(dy, o, 0, BALL0_DE, NB_DE, p[P_MI], p[P_MS_DE], 1.0,
                Gx1, Gy1, scb1, ssb1, scc1, scs1, sss1, cs1, sn1)
    _arrow_into(dy, o, 21, BALL0_FE, NB_FE, p[P_MO], p[P_MS_FE], p[P_KAPPA_FE],
                Gx2, Gy2, scb2, ssb2, scc2, scs2, sss2, cs2, sn2)
    A = p[P_MH_A]; B = p[P_MH_B]
    idet = 1.0 / (A * A - B * B)
    dy[o + 31] = (-A * Ghx1 + B * Ghx2) * idet
    dy[o + 52] = (-A * Ghx2 + B * Ghx1) * idet
    dy[o + 32] = (-A * Ghy1 + B * Ghy2) * idet
    dy[o + 53] = (-A * Ghy2 + B * Ghy1) * idet
    imd = 1.0 / p[P_MD]; iit = 1.0 / p[P_ITD]
    dy[o + 54] = -G25 * imd
    dy[o + 55] = -G26 * imd
    dy[o + 56] = -G27 * iit
    dy[o + 57] = -G28 * iit


def make_rhs_args(params):
    """(p, ct0, st0) for the compiled functions from a ModelParameters."""
    th = params.theta0
    return params.pack(), np.cos(th), np.sin(th)


def rhs_py(t, y, params, or_rel=None, ir_rel=None):
    """Convenience (slow path): f(t, y) as a new array."""
    p, ct0, st0 = make_rhs_args(params)
    or_rel = np.zeros(NB_DE) if or_rel is None else np.asarray(or_rel, float)
    ir_rel = np.zeros(NB_DE) if ir_rel is None else np.asarray(ir_rel, float)
    dy = np.zeros(NSTATE)
    rhs(float(t), np.asarray(y, float), p, ct0, st0, or_rel, ir_rel, dy, np.zeros(WORK_LEN))
    return dy


def static_forces(params, q, t=0.0):
    """Static part K q + F(q, t) with q' = 0 (lbf), for the equilibrium solve."""
    p, ct0, st0 = make_rhs_args(params)
    y = np.zeros(NSTATE)
    y[:NDOF] = q
    w = np.zeros(WORK_LEN)
    z = np.zeros(NB_DE)
    generalized_forces(float(t), y, p, ct0, st0, z, z, w[:NDOF], w[29:38], w[38:47], w[47:55], w[55:63])
    return w[:NDOF].copy()


def static_equilibrium(params, t=0.0, tol=1e-9, max_iter=50):
    """Static equilibrium K(t) q + F(q, t) = 0 at time ``t`` (no defect).

    Newton's method with a finite-difference Jacobian, from the nominal state
    (all q = 0, balls at their nominal radius). Includes gravity, the
    centrifugal ball terms and the unbalance force at ``t`` (quasi-static: the
    rotor modes are far above the shaft speed). Returns q (29, inch; ball
    entries as deviations from the nominal radius). Raises RuntimeError if
    Newton does not converge to ``tol`` lbf.
    """
    q = np.zeros(NDOF)
    eps = 1e-10
    for _ in range(max_iter):
        g = static_forces(params, q, t)
        if np.max(np.abs(g)) < tol:
            return q
        J = np.empty((NDOF, NDOF))
        for j in range(NDOF):
            dq = q.copy()
            dq[j] += eps
            J[:, j] = (static_forces(params, dq, t) - g) / eps
        q = q - np.linalg.solve(J, g)
    g = static_forces(params, q, t)
    if np.max(np.abs(g)) < 1e-6:
        return q
    raise RuntimeError(f"static equilibrium did not converge (residual {np.max(np.abs(g)):.3g} lbf)")


def ball_loads(params, q, t=0.0):
    """Contact loads (lbf) of the drive-end balls at state q: (inner, outer), each (9,)."""
    th = params.theta0[:NB_DE] + params.cage_speed_de * t
    c, s = np.cos(th), np.sin(th)
    r = params.nominal_ball_radius_de + q[BALL0_DE:BALL0_DE + NB_DE]
    dx = q[0] - q[2] + r * c
    dy = q[1] - q[3] + r * s
    X = np.hypot(dx, dy)
    d_out = np.maximum(X - (params.R1 - params.rho1), 0.0)
    d_in = np.maximum(params.r1 + params.rho1 - r, 0.0)
    from .model_parameters import K_INNER_DE, K_OUTER_DE
    return K_INNER_DE * d_in**1.5, K_OUTER_DE * d_out**1.5
