"""Parameters of the 29-DOF motor/bearing model (thesis ch. 2.1-2.3, appendix A).

One source of truth for the numbers of the appendix A listing (``modelpar.m``),
with names and units, the quantities derived from them, and the model
variants. Internal units are the listing's: inch, lbf, second, and mass in
lbf*s^2/in (= lbm / 386.4). The SI conversion constants used for the published
output live here too (REP-103: m, m/s^2, N).

Model variants (``ModelParameters.variant``), in the terms of
``model-notes.md``'s quirk table:

``"default"``
    The listing's housing block ``mh/2 +- Ith/(2L)`` (quirk 4 kept, because
    ``kh = mh*wn^2`` was tuned with it) and fixes 1-3: symmetric fan-end
    ball/shaft mass couplings (1), fan-end shaft mass ``8*mo + ms/2`` (2), the
    ball rows of C without the ``-+ m*Omega`` terms that cancel in the
    Lagrangian (3). Bearing radii from the bearing geometry
    (:mod:`bearing_common.bearings`, catalog entries ``6205`` and ``6203``).
``"listing"``
    Faithful to the listing, all four quirks kept, radii from the listing's
    defect-frequency ratios 3.5848 / 3.0530 (to reproduce the thesis).
``"lagrangian_housing"``
    As ``default`` but with the housing block of the Lagrangian,
    ``mh/4 +- Ith/(4 L^2)`` (housing modes move from 2.2-3.6 kHz to 2.7-6.5 kHz).

Departures from the listing common to all variants: the inner-race defect is
a kinematic defect fixed on the rotating inner ring (see
:mod:`bearing_sim.defects`); the project's IR defect has the OR defect's size
(0.007 in wide, 0.002 in deep; the listing's IR size is 0, an assumption).
"""

import math
from dataclasses import dataclass, field

import numpy as np

from bearing_common.bearings import CATALOG
from bearing_common.units import INCH

DRIVE_END = CATALOG["6205"]  #: the thesis' drive-end bearing (SKF 6205)
FAN_END = CATALOG["6203"]  #: the thesis' fan-end bearing (SKF 6203)

# --------------------------------------------------------------------------
# SI conversion (the only place): listing units -> SI
# --------------------------------------------------------------------------
M_PER_INCH = INCH  #: 0.0254 m per inch (in/s^2 -> m/s^2 too)
N_PER_LBF = 4.4482216152605  #: newton per pound-force
G_IN_PER_S2 = 386.4  #: listing's g (in/s^2); mass [lbf s^2/in] = lbm / 386.4

VARIANTS = ("default", "listing", "lagrangian_housing")

#: Broadband level of the real CWRU normal record 97 (about 0.07 g RMS over
#: 0-24 kHz), (m/s^2)/sqrt(Hz): the documented value to use when noise is wanted.
DEFAULT_NOISE_DENSITY = 4.5e-3

# --------------------------------------------------------------------------
# The listing's magic numbers, named (modelpar.m, appendix A)
# --------------------------------------------------------------------------
N_BALLS_DE = 9  #: ni, drive-end (inboard) balls
N_BALLS_FE = 8  #: no, fan-end (outboard) balls
BALL_MASS_DE = 4.4784e-3 / G_IN_PER_S2  #: mi, lbf s^2/in
BALL_MASS_FE = 2.7469e-3 / G_IN_PER_S2  #: mo, lbf s^2/in
BALL_DAMPING = 0.4  #: cv, lbf s/in, ball-raceway viscous damping
THETA_BALL1_DE = 0.2998  #: rad, initial angle of drive-end ball 1
THETA_BALL1_FE = 0.0  #: rad, initial angle of fan-end ball 1
K_INNER_DE = 23.2903e6  #: k1i, ball/inner-race Hertz stiffness, lbf/in^1.5
K_OUTER_DE = 24.5254e6  #: k2i, ball/outer-race, lbf/in^1.5
K_INNER_FE = 21.2248e6  #: k1o
K_OUTER_FE = 22.6897e6  #: k2o
BPFO_RATIO_DE_LISTING = 3.5848  #: odfri (only the "listing" variant uses it)
BPFO_RATIO_FE_LISTING = 3.0530  #: odfro
RADIAL_INTERFERENCE_DE = 0.00068022  #: in, outer-race radius reduction
RADIAL_INTERFERENCE_FE = 0.00049656  #: in
SHAFT_MASS = 3.0 / G_IN_PER_S2  #: ms
DISK_MASS = 6.0 / G_IN_PER_S2  #: md
UNBALANCE_MASS = 5e-4 / G_IN_PER_S2  #: mu
UNBALANCE_ECCENTRICITY = 1.0  #: e_mu, in
UNBALANCE_PHASE = 0.0  #: phi_mu, rad
SHAFT_MODULUS = 30e6  #: E, psi
DISK_OUTER_RADIUS = 1.8125  #: in (listing or_disk)
DISK_INNER_RADIUS = 0.4935  #: in (listing ir_disk; also the shaft radius in I)
DISK_LENGTH = 5.0  #: in
SHAFT_LENGTH = 8.0  #: in (L = half of it)
ROTOR_DAMPING_RATIO = 0.035
HOUSING_MASS = 48.0 / G_IN_PER_S2  #: mh
HOUSING_OUTER_RADIUS = 3.5  #: in
HOUSING_INNER_RADIUS = 2.0  #: in
HOUSING_LENGTH = 8.0  #: in
HOUSING_DAMPING_RATIO = 0.027
HOUSING_NATURAL_FREQ = 21916.0  #: rad/s
DEFECT_WIDTH = 0.007  #: in, default width of OR and IR defects
DEFECT_DEPTH = 0.002  #: in, default depth
IR_FIRST_HIT_TIME = 0.001  #: s, listing start_time: the IR defect meets ball 1 here

# --------------------------------------------------------------------------
# Layout of the packed parameter vector handed to the compiled code
# --------------------------------------------------------------------------
P_MI, P_MO, P_CV, P_K1I, P_K2I, P_K1O, P_K2O = 0, 1, 2, 3, 4, 5, 6
P_RHO1, P_RHO2, P_R1, P_R2, P_RR1, P_RR2 = 7, 8, 9, 10, 11, 12
P_OMI, P_OMO, P_OMD = 13, 14, 15  # cage speeds DE/FE and shaft speed, rad/s
P_MS_DE, P_MS_FE = 16, 17  # shaft-row masses M(1,1) and M(22,22)
P_KAPPA_FE = 18  # 1: fan-end ball rows coupled to the shaft (fix 1), 0: listing
P_KAPPA_C = 19  # 1: keep ball-row m*Omega terms in C (listing), 0: fix 3
P_MH_A, P_MH_B = 20, 21  # housing block diagonal / off-diagonal mass
P_CH, P_KH, P_KS, P_L = 22, 23, 24, 25
P_MD, P_ITD, P_IP, P_CROT = 26, 27, 28, 29
P_MUE, P_PHIMU, P_WHALF = 30, 31, 32  # mu*e, unbalance phase, half rotor weight (lbf)
P_RNOM1, P_RNOM2 = 33, 34  # nominal ball radial coordinates (state offset), in
N_PACKED = 35


@dataclass(frozen=True)
class ModelParameters:
    """All numbers of one model instance, in listing units (in, lbf, s).

    Build with :meth:`create`. ``pack()`` gives the float64 vector the compiled
    right-hand side reads (layout ``P_*`` above); ``theta0`` the 17 initial ball
    angles (rad, drive end first).
    """

    variant: str
    rpm: float
    or_defect_width: float = DEFECT_WIDTH
    or_defect_depth: float = DEFECT_DEPTH
    ir_defect_width: float = DEFECT_WIDTH
    ir_defect_depth: float = DEFECT_DEPTH
    # derived (filled by create)
    rho1: float = field(default=0.0)
    rho2: float = field(default=0.0)
    r1: float = field(default=0.0)
    r2: float = field(default=0.0)
    R1: float = field(default=0.0)
    R2: float = field(default=0.0)

    @classmethod
    def create(cls, variant="default", rpm=1800.0, or_defect_width=DEFECT_WIDTH,
               or_defect_depth=DEFECT_DEPTH, ir_defect_width=DEFECT_WIDTH,
               ir_defect_depth=DEFECT_DEPTH):
        """Derive the bearing radii for ``variant`` at shaft speed ``rpm`` (rev/min)."""
        if variant not in VARIANTS:
            raise ValueError(f"unknown model variant {variant!r}; expected one of {', '.join(VARIANTS)}")
        if not (math.isfinite(rpm) and rpm > 0):
            raise ValueError(f"rpm must be positive, got {rpm!r}")
        for name, v in (("or_defect_width", or_defect_width), ("or_defect_depth", or_defect_depth),
                        ("ir_defect_width", ir_defect_width), ("ir_defect_depth", ir_defect_depth)):
            if not (math.isfinite(v) and 0.0 <= v < 0.05):
                raise ValueError(f"{name} must be in [0, 0.05) inch, got {v!r}")
        rho1 = DRIVE_END.element_diameter / M_PER_INCH / 2.0  # ball radius (listing says "diameter")
        rho2 = FAN_END.element_diameter / M_PER_INCH / 2.0
        if variant == "listing":
            # r = 2*odf*rho/(n - 2*odf): inner-race radius from the BPFO ratio
            r1 = 2 * BPFO_RATIO_DE_LISTING * rho1 / (N_BALLS_DE - 2 * BPFO_RATIO_DE_LISTING)
            r2 = 2 * BPFO_RATIO_FE_LISTING * rho2 / (N_BALLS_FE - 2 * BPFO_RATIO_FE_LISTING)
        else:  # pitch radius minus ball radius, from the bearing geometry
            r1 = DRIVE_END.pitch_diameter / M_PER_INCH / 2.0 - rho1
            r2 = FAN_END.pitch_diameter / M_PER_INCH / 2.0 - rho2
        R1 = r1 + 2 * rho1 - RADIAL_INTERFERENCE_DE
        R2 = r2 + 2 * rho2 - RADIAL_INTERFERENCE_FE
        return cls(variant, float(rpm), or_defect_width, or_defect_depth, ir_defect_width,
                   ir_defect_depth, rho1, rho2, r1, r2, R1, R2)

    # ---- kinematics (rad/s) --------------------------------------------
    @property
    def shaft_speed(self) -> float:
        """omega_d = N*pi/30, rad/s."""
        return self.rpm * math.pi / 30.0

    @property
    def cage_speed_de(self) -> float:
        """thetadot_i = omega_d * r1 / (2 (r1 + rho1)), rad/s (FTF, eq. 2.51)."""
        return self.shaft_speed * self.r1 / (2.0 * (self.r1 + self.rho1))

    @property
    def cage_speed_fe(self) -> float:
        return self.shaft_speed * self.r2 / (2.0 * (self.r2 + self.rho2))

    @property
    def bpfo(self) -> float:
        """Drive-end outer-race ball pass frequency, Hz (eq. 2.53)."""
        return N_BALLS_DE * self.cage_speed_de / (2 * math.pi)

    @property
    def bpfi(self) -> float:
        """Drive-end inner-race ball pass frequency, Hz (eq. 2.54)."""
        return N_BALLS_DE * (self.shaft_speed - self.cage_speed_de) / (2 * math.pi)

    @property
    def theta_or(self) -> float:
        """Angular width of the OR defect, 2 asin(w / 2R1), rad."""
        return 2.0 * math.asin(self.or_defect_width / (2.0 * self.R1))

    @property
    def theta_ir(self) -> float:
        """Angular width of the IR defect on the inner ring, 2 asin(w / 2r1), rad."""
        return 2.0 * math.asin(self.ir_defect_width / (2.0 * self.r1))

    @property
    def theta0(self) -> np.ndarray:
        """Initial ball angles (rad): 9 drive-end then 8 fan-end."""
        de = THETA_BALL1_DE + 2 * math.pi / N_BALLS_DE * np.arange(N_BALLS_DE)
        fe = THETA_BALL1_FE + 2 * math.pi / N_BALLS_FE * np.arange(N_BALLS_FE)
        return np.concatenate([de, fe]).astype(np.float64)

    # ---- masses and stiffnesses ----------------------------------------
    @property
    def shaft_stiffness(self) -> float:
        """K(1,1) = 3 E I / L^3, lbf/in, with I = pi r^4/4 of the shaft."""
        L = SHAFT_LENGTH / 2
        inertia = math.pi * DISK_INNER_RADIUS**4 / 4
        return 3 * SHAFT_MODULUS * inertia / L**3

    def disk_inertias(self):
        """(Itd, Ip): transverse and polar inertia of the disk, lbf s^2 in."""
        md, ro, ri, ld = DISK_MASS, DISK_OUTER_RADIUS, DISK_INNER_RADIUS, DISK_LENGTH
        v1, v2 = math.pi * ro**2 * ld, math.pi * ri**2 * ld
        dens = md / (v1 - v2)
        itd = dens * (v1 * (3 * ro**2 + ld**2) - v2 * (3 * ri**2 + ld**2)) / 12
        ip = 0.5 * md * (ro**2 - ri**2)  # as in the listing
        return itd, ip

    def housing_block(self):
        """(diagonal, off-diagonal) of the housing 2x2 mass block, lbf s^2/in.

        Listing (quirk 4, default): mh/2 +- Ith/(2L); Lagrangian: mh/4 +- Ith/(4L^2).
        """
        mh, ro, ri, lh = HOUSING_MASS, HOUSING_OUTER_RADIUS, HOUSING_INNER_RADIUS, HOUSING_LENGTH
        v3, v4 = math.pi * ro**2 * lh, math.pi * ri**2 * lh
        dens = mh / (v3 - v4)
        ith = dens * (v3 * (3 * ro**2 + lh**2) - v4 * (3 * ri**2 + lh**2)) / 12
        L = SHAFT_LENGTH / 2
        if self.variant == "lagrangian_housing":
            return mh / 4 + ith / (4 * L**2), mh / 4 - ith / (4 * L**2)
        return mh / 2 + ith / (2 * L), mh / 2 - ith / (2 * L)

    @property
    def nominal_ball_radius_de(self) -> float:
        """r1 + rho1 - RI/2: ball-centre radial coordinate with both contacts
        equally compressed; the state holds deviations from it (in)."""
        return self.r1 + self.rho1 - 0.5 * RADIAL_INTERFERENCE_DE

    @property
    def nominal_ball_radius_fe(self) -> float:
        return self.r2 + self.rho2 - 0.5 * RADIAL_INTERFERENCE_FE

    def pack(self) -> np.ndarray:
        """Float64 vector for the compiled right-hand side (layout ``P_*``)."""
        p = np.zeros(N_PACKED)
        listing = self.variant == "listing"
        p[P_MI], p[P_MO], p[P_CV] = BALL_MASS_DE, BALL_MASS_FE, BALL_DAMPING
        p[P_K1I], p[P_K2I], p[P_K1O], p[P_K2O] = K_INNER_DE, K_OUTER_DE, K_INNER_FE, K_OUTER_FE
        p[P_RHO1], p[P_RHO2], p[P_R1], p[P_R2] = self.rho1, self.rho2, self.r1, self.r2
        p[P_RR1], p[P_RR2] = self.R1, self.R2
        p[P_OMI], p[P_OMO], p[P_OMD] = self.cage_speed_de, self.cage_speed_fe, self.shaft_speed
        p[P_MS_DE] = N_BALLS_DE * BALL_MASS_DE + SHAFT_MASS / 2
        # quirk 2: the listing's M(22,22) = 9*mo + ms/2 for an 8-ball bearing
        p[P_MS_FE] = (9 if listing else N_BALLS_FE) * BALL_MASS_FE + SHAFT_MASS / 2
        p[P_KAPPA_FE] = 0.0 if listing else 1.0  # quirk 1
        p[P_KAPPA_C] = 1.0 if listing else 0.0  # quirk 3
        p[P_MH_A], p[P_MH_B] = self.housing_block()
        kh = HOUSING_MASS * HOUSING_NATURAL_FREQ**2
        p[P_KH] = kh
        p[P_CH] = 2 * HOUSING_DAMPING_RATIO * HOUSING_MASS * HOUSING_NATURAL_FREQ
        ks = self.shaft_stiffness
        p[P_KS], p[P_L] = ks, SHAFT_LENGTH / 2
        itd, ip = self.disk_inertias()
        p[P_MD], p[P_ITD], p[P_IP] = DISK_MASS, itd, ip
        rotor_mass = SHAFT_MASS + DISK_MASS
        rotor_stiffness = 2 * ks  # listing: 6 E I / L^3
        p[P_CROT] = 2 * ROTOR_DAMPING_RATIO * rotor_mass * math.sqrt(rotor_stiffness / rotor_mass)
        p[P_MUE], p[P_PHIMU] = UNBALANCE_MASS * UNBALANCE_ECCENTRICITY, UNBALANCE_PHASE
        p[P_WHALF] = 0.5 * (SHAFT_MASS + DISK_MASS) * G_IN_PER_S2
        p[P_RNOM1], p[P_RNOM2] = self.nominal_ball_radius_de, self.nominal_ball_radius_fe
        return p

    def unbalance_force_y(self, t):
        """Physical unbalance force on the disk along +y, lbf: mu e w^2 sin(w t + phi)
        (the negative of the listing's F(27))."""
        w = self.shaft_speed
        return UNBALANCE_MASS * UNBALANCE_ECCENTRICITY * w * w * np.sin(w * np.asarray(t) + UNBALANCE_PHASE)
