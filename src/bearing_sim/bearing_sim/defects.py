"""Defect windows of the drive-end bearing and their switching times.

Both defects are described the same way: ball i is "over the defect" while its
phase ``alpha_i(t) = a_i + w t`` (rad) lies in [0, width) modulo 2*pi. The
phases follow the shaft and cage kinematics from t = 0 of the simulation,
continuously across segments, so the switching times are known in advance and
the integrator steps exactly onto them.

Outer race (listing ``model.m``, "set outer race defect"): a window of angular
width ``theta_OR = 2 asin(w_d / 2 R1)`` centred at 6 o'clock (3*pi/2, bottom of
the raceway, path of greatest static load); ball angle ``theta_i + Omega_c t``
(cage speed Omega_c, eq. 2.51). A ball inside sees the outer-race radius
increased by the defect depth (radial relief).

Inner race: departure from the listing, which switches the balls 1..9 in turn
every ``1/BPFI`` (hard-coded 5.4152 x shaft) for ``theta_IR/(omega_d - Omega_c)``
seconds. Here the defect is a window of width ``theta_IR = 2 asin(w_d / 2 r1)``
fixed on the rotating inner ring (angle ``psi0 + omega_d t``); ball i is over it
while the relative angle ``psi - phi_i`` lies in the window. This gives the same
timing (consecutive balls, interval 1/BPFI with BPFI from the geometry, eq. 2.54,
same duration) but stays correct whatever segment the defect appears in.
``psi0`` is chosen so that, as in the listing (``start_time = 1 ms``,
``starting_element = 1``), the defect reaches ball 1 at t = 1 ms. A ball over
the defect sees the inner-race radius reduced by the defect depth.
"""

import math

import numpy as np

from .model_parameters import IR_FIRST_HIT_TIME, N_BALLS_DE

TWO_PI = 2.0 * math.pi


class DefectWindow:
    """Phases ``a + w t`` (rad) of the 9 drive-end balls relative to one defect.

    ``width`` (rad) is the angular size, ``depth`` (in) the radius change.
    """

    def __init__(self, a, w, width, depth):
        self.a = np.asarray(a, dtype=np.float64)
        self.w = float(w)
        self.width = float(width)
        self.depth = float(depth)

    def active(self, t):
        """Boolean (9,): balls over the defect at time t (s)."""
        m = np.mod(self.a + self.w * t, TWO_PI)
        return m < self.width

    def relief(self, t):
        """Per-ball radius change (in) at time t: depth where active, else 0."""
        return np.where(self.active(t), self.depth, 0.0)

    def switch_times(self, t0, t1):
        """Sorted times in (t0, t1] (s) at which any ball enters or leaves the window."""
        if self.width <= 0.0 or self.depth <= 0.0 or t1 <= t0:
            return np.empty(0)
        out = []
        for level in (0.0, self.width):
            # a + w t = level + 2 pi k
            k0 = np.ceil((self.a + self.w * t0 - level) / TWO_PI)
            k1 = np.floor((self.a + self.w * t1 - level) / TWO_PI)
            for ai, ka, kb in zip(self.a, k0, k1):
                for kk in range(int(ka), int(kb) + 1):
                    out.append((level + TWO_PI * kk - ai) / self.w)
        times = np.array(out)
        times = times[(times > t0) & (times <= t1)]
        return np.sort(times)


def outer_race_window(params):
    """OR defect window at 6 o'clock on the stationary outer ring."""
    th = params.theta_or
    a = params.theta0[:N_BALLS_DE] - (1.5 * math.pi - 0.5 * th)
    return DefectWindow(a, params.cage_speed_de, th, params.or_defect_depth)


def inner_race_window(params, first_hit=IR_FIRST_HIT_TIME):
    """IR defect window fixed on the inner ring; reaches ball 1 at ``first_hit`` s."""
    th = params.theta_ir
    w = params.shaft_speed - params.cage_speed_de
    theta = params.theta0[:N_BALLS_DE]
    # relative phase of ball i: (psi0 - theta_i) + w t + th/2, zero when the
    # defect's leading edge reaches the ball; ball 1 at t = first_hit
    a = (theta[0] - theta) - w * first_hit
    return DefectWindow(a, w, th, params.ir_defect_depth)
