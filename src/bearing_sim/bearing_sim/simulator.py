"""Streaming simulator of the 29-DOF bearing model (the API the node and CLI use).

    cfg = SimulationConfig(rpm=1800.0, sample_rate=48000.0)
    sim = Simulator(cfg, [(FaultState.OUTER_RACE, 0.2), (FaultState.INNER_RACE, 0.2)])
    while not sim.finished:
        chunk = sim.advance(4800)       # SimChunk(start_index, t0, accel, unbalance, truth)

Pipeline: static equilibrium at t = 0 (no settling period: output time 0 is
the equilibrium instant, :func:`rotor_rhs.static_equilibrium`) -> adaptive
Runge-Kutta 4(3) (:mod:`integrator`) over switching intervals (segment boundaries and the
instants balls enter/leave the active defect window, plus fixed 5 ms
checkpoints) -> drive-end housing y acceleration on a fine uniform grid ->
zero-delay anti-aliasing FIR decimation to ``sample_rate`` -> SI units
(+ optional white measurement noise).

Everything that shapes the samples (piece boundaries, FIR windows, the noise
stream) is defined on the absolute time/sample axis, so the output is
bit-identical whatever the chunk sizes passed to :meth:`Simulator.advance`.
Memory is bounded (one 5 ms piece plus the FIR history).

Changing speed (``SimulationConfig.speed_profile``, a
:class:`bearing_common.shaft_angle.SpeedProfile`): every angle of the model is its
share of the shaft angle φ(t) = ∫ω dt — the cage angles κ·φ (κ = Ω_c/ω from the
geometry, eq. 2.51), the unbalance phase φ + φ_μ — and the defect windows are
placed on it (:mod:`defects` in the clock τ = φ/ω(0), the time a shaft at the
initial speed would take; their switching times are mapped back through the exact
inverse of φ). The compiled model takes one speed per integration call, so the
calls are cut at the profile's knots and last at most Δ = √(8·tol/|α|) for the
angular acceleration α (:data:`SPEED_ANGLE_TOL`); each runs at the call's mean
speed with its angles re-anchored to the exact φ at its start. The angles are then
exact at every call boundary and within α·Δ²/8 ≤ tol = 1e-6 rad in between
(against the OR defect's 6e-3 rad width; Δ = 0.9 ms on a 900→1800 rev/min
run-up over 10 s). The speed-dependent terms (centrifugal and Coriolis
ball terms, gyroscopic disk, unbalance) follow ω² and ω, and the unbalance force
has its tangential part μe·dω/dt too: for an accelerating shaft it is
μe(ω² e_r + α e_t), a rotating force of magnitude μe·√(ω⁴ + α²) lagging the
unbalance by atan(α/ω²) (9 % of the radial part on a 300 rev/min step over 50 ms;
the ball rows' dω/dt terms cancel over the equally spaced balls and are left
out). A constant speed (no profile) runs the code path of a fixed speed unchanged.
"""

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from bearing_common.shaft_angle import RPM_TO_RAD_S, SpeedProfile
from bearing_common.states import FaultState

from .defects import inner_race_window, outer_race_window
from .integrator import STAT_REJECTS, STAT_RHS, STAT_STEPS, default_atol, integrate_interval
from .model_parameters import (
    DEFAULT_NOISE_DENSITY,  # noqa: F401  (re-exported: the simulator's documented noise level)
    DEFECT_DEPTH,
    DEFECT_WIDTH,
    M_PER_INCH,
    N_BALLS_DE,
    N_PER_LBF,
    P_MUE,
    P_OMD,
    P_OMI,
    P_OMO,
    P_PHIMU,
    UNBALANCE_ECCENTRICITY,
    UNBALANCE_MASS,
    UNBALANCE_PHASE,
    VARIANTS,
    ModelParameters,
)
from .resampling import design_lowpass, fine_factor, fir_decimate
from .rotor_rhs import DOF_HOUSING_Y_DE, NDOF, NSTATE, rhs_py, static_equilibrium
from .schedule import validate_schedule

MIN_SAMPLE_RATE = 4000.0  #: Hz: below this the BPFI harmonics and resonances are lost
MAX_SAMPLE_RATE = 1.0e6  #: Hz (the thesis' rate)
MAX_RPM = 6000.0
PIECE = 0.005  #: s, integration checkpoints (bounds memory and latency)
#: rad: at changing speed an integration call (one speed) lasts at most Δ = √(8 tol / |dω/dt|),
#: so that its angles stay within tol of ∫ω dt (Δ = 0.9 ms on a 900→1800 rev/min run-up in 10 s)
SPEED_ANGLE_TOL = 1e-6
_EPS_T = 1e-10  #: s, switching times closer than this to the current time are merged


@dataclass(frozen=True)
class SimulationConfig:
    """Settings of one simulation run (validated on construction).

    rpm: shaft speed, rev/min (0 < rpm <= 6000).
    sample_rate: output rate, Hz (4 kHz .. 1 MHz).
    variant: model variant, see :mod:`model_parameters` (``default``, ``listing``,
        ``lagrangian_housing``).
    noise_density: white measurement noise, (m/s^2)/sqrt(Hz), one-sided; 0 = off
        (default, thesis reproduction); :data:`DEFAULT_NOISE_DENSITY` = 4.5e-3
        matches the real CWRU normal record. RMS = density * sqrt(sample_rate/2).
    seed: seed of the noise generator.
    rtol: relative tolerance of the integrator (absolute tolerances scale with it);
        the default 1e-4 gives about 1e-4 relative RMS waveform error.
    max_step: largest integration step, s.
    *_defect_width / *_defect_depth: defect size, inch.
    speed_profile: a :class:`~bearing_common.shaft_angle.SpeedProfile` (ω(t) from t = 0,
        within (0, 6000] rev/min) for a changing speed; ``rpm`` is then not used.
        None (default): the constant ``rpm``.
    """

    rpm: float = 1800.0
    sample_rate: float = 48000.0
    variant: str = "default"
    noise_density: float = 0.0
    seed: int = 0
    rtol: float = 1e-4
    max_step: float = 2e-5
    or_defect_width: float = DEFECT_WIDTH
    or_defect_depth: float = DEFECT_DEPTH
    ir_defect_width: float = DEFECT_WIDTH
    ir_defect_depth: float = DEFECT_DEPTH
    speed_profile: SpeedProfile | None = None

    def __post_init__(self):
        def num(name):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise ValueError(f"{name} must be a number, got {v!r}")
            if not math.isfinite(float(v)):
                raise ValueError(f"{name} must be finite, got {v!r}")
            return float(v)

        rpm = num("rpm")
        if not 0.0 < rpm <= MAX_RPM:
            raise ValueError(f"rpm must be in (0, {MAX_RPM:g}], got {rpm:g}")
        fs = num("sample_rate")
        if fs <= 0.0:
            raise ValueError(f"sample_rate must be positive, got {fs:g} Hz")
        if fs < MIN_SAMPLE_RATE:
            raise ValueError(f"sample_rate {fs:g} Hz is too low for the fault signatures "
                             f"(need >= {MIN_SAMPLE_RATE:g} Hz)")
        if fs > MAX_SAMPLE_RATE:
            raise ValueError(f"sample_rate {fs:g} Hz is above the supported maximum {MAX_SAMPLE_RATE:g} Hz")
        if self.variant not in VARIANTS:
            raise ValueError(f"unknown variant {self.variant!r}; expected one of {', '.join(VARIANTS)}")
        if num("noise_density") < 0.0:
            raise ValueError(f"noise_density must be >= 0, got {self.noise_density!r}")
        if not isinstance(self.seed, (int, np.integer)) or isinstance(self.seed, bool) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")
        if not 1e-10 <= num("rtol") <= 1e-2:
            raise ValueError(f"rtol must be in [1e-10, 1e-2], got {self.rtol!r}")
        if not 1e-8 <= num("max_step") <= 1e-3:
            raise ValueError(f"max_step must be in [1e-8, 1e-3] s, got {self.max_step!r}")
        for name in ("or_defect_width", "or_defect_depth", "ir_defect_width", "ir_defect_depth"):
            if not 0.0 <= num(name) < 0.05:
                raise ValueError(f"{name} must be in [0, 0.05) inch, got {getattr(self, name)!r}")
        if self.speed_profile is not None:
            if not isinstance(self.speed_profile, SpeedProfile):
                raise ValueError(f"speed_profile must be a SpeedProfile, got {self.speed_profile!r}")
            top = float(self.speed_profile.omegas.max()) / RPM_TO_RAD_S
            if top > MAX_RPM:
                raise ValueError(f"speed profile reaches {top:g} rpm; the simulator supports up to {MAX_RPM:g}")

    @property
    def initial_rpm(self) -> float:
        """Shaft speed at t = 0 (rev/min): the model's reference speed."""
        return self.rpm if self.speed_profile is None else float(self.speed_profile.rpm(0.0))


@dataclass
class SimChunk:
    """A block of consecutive output samples.

    start_index: index of the first sample; t0: its time (s);
    accel: drive-end housing y acceleration (m/s^2), float64 (n,);
    unbalance: physical unbalance force on the disk along +y (N), float64 (n,);
    truth: fault state per sample (FaultState integers), int8 (n,);
    shaft_speed: shaft speed per sample (rad/s), float64 (n,).
    """

    start_index: int
    t0: float
    accel: np.ndarray
    unbalance: np.ndarray
    truth: np.ndarray
    shaft_speed: np.ndarray

    def __len__(self):
        return len(self.accel)


class Simulator:
    """Stream the model's output over a fault schedule [(FaultState, seconds), ...]."""

    def __init__(self, config, schedule):
        if not isinstance(config, SimulationConfig):
            raise TypeError("config must be a SimulationConfig")
        self.config = config
        self.schedule = validate_schedule(schedule)
        self.params = ModelParameters.create(
            config.variant, config.initial_rpm, config.or_defect_width, config.or_defect_depth,
            config.ir_defect_width, config.ir_defect_depth)
        profile = config.speed_profile
        self._profile = None if profile is None or profile.is_constant else profile
        self._speed_profile = None
        if self._profile is not None:  # the balls' angles as shares of the shaft angle (eq. 2.51)
            self._theta0 = self.params.theta0
            self._kappa = np.where(np.arange(len(self._theta0)) < N_BALLS_DE, self.params.cage_speed_de,
                                   self.params.cage_speed_fe) / self.params.shaft_speed
        self.sample_rate = float(config.sample_rate)
        ends = np.cumsum([d for _, d in self.schedule])
        self._bounds = ends  # segment end times, s
        self._states = np.array([int(s) for s, _ in self.schedule], dtype=np.int8)
        self.duration = float(ends[-1])
        self.total_samples = int(round(self.duration * self.sample_rate))
        self.samples_done = 0
        # compiled-model inputs
        self._p = self.params.pack()
        th = self.params.theta0
        self._ct0, self._st0 = np.cos(th), np.sin(th)
        self._or = outer_race_window(self.params)
        self._ir = inner_race_window(self.params)
        self._zero = np.zeros(N_BALLS_DE)
        self._sw_cache = {}
        self._rtol = float(config.rtol)
        self._atol = default_atol(self._rtol)
        # resampling
        self._D = fine_factor(self.sample_rate)
        self._fine_dt = 1.0 / (self._D * self.sample_rate)
        self._taps = design_lowpass(self._D)
        self._c = (len(self._taps) - 1) // 2
        # initial state: static equilibrium at t = 0, at rest
        q0 = static_equilibrium(self.params, 0.0)
        self._y = np.zeros(NSTATE)
        self._y[:NDOF] = q0
        a0 = rhs_py(0.0, self._y, self.params)[NDOF + DOF_HOUSING_Y_DE]
        # fine buffer, global fine index of its first element; history before t=0 = a0
        self._fbuf = np.full(self._c + 1, a0)
        self._fbuf_start = -self._c
        self._pending = []
        self._n_fine_next = 1
        self._t = 0.0
        self._h = 1e-6
        self._ctrl = np.array([1e-4])
        self._stats = np.zeros(3, dtype=np.int64)
        self._rng = np.random.default_rng(config.seed)
        self._noise_sigma = float(config.noise_density) * math.sqrt(self.sample_rate / 2.0)

    # ------------------------------------------------------------------ info
    @property
    def finished(self):
        """True once every sample of the schedule has been produced."""
        return self.samples_done >= self.total_samples

    @property
    def stats(self):
        """Integrator counters: accepted steps, rejected steps, rhs evaluations, time (s)."""
        return {"steps": int(self._stats[STAT_STEPS]), "rejected": int(self._stats[STAT_REJECTS]),
                "rhs_evals": int(self._stats[STAT_RHS]), "t": self._t}

    def set_noise_density(self, noise_density):
        """Change the measurement noise density ((m/s^2)/sqrt(Hz), >= 0) from the next sample on."""
        self.config = dataclasses.replace(self.config, noise_density=noise_density)
        self._noise_sigma = float(noise_density) * math.sqrt(self.sample_rate / 2.0)

    def state_at(self, t):
        """Fault state (int) scheduled at time(s) t; the last state continues after the end."""
        idx = np.searchsorted(self._bounds, t, side="right")
        return self._states[np.minimum(idx, len(self._states) - 1)]

    @property
    def speed_profile(self) -> SpeedProfile:
        """The shaft speed over the run (a constant profile at constant speed)."""
        if self._speed_profile is None:
            self._speed_profile = self.config.speed_profile or SpeedProfile.constant(self.config.rpm)
        return self._speed_profile

    def shaft_speed(self, t):
        """Shaft speed (rad/s) at time(s) t (s)."""
        if self._profile is None:
            return np.full(np.shape(t), self.params.shaft_speed)
        return self._profile.omega(t)

    def _clock(self, t):
        """tau(t) = shaft angle / initial shaft speed (s): the defect windows' time axis."""
        return t if self._profile is None else self._profile.angle(t) / self.params.shaft_speed

    # ------------------------------------------------------------ integration
    def _integrate_piece(self):
        t = self._t
        state = int(self.state_at(t + _EPS_T))
        checkpoint = (math.floor(t / PIECE) + 1) * PIECE
        if checkpoint <= t + _EPS_T:  # t just below a checkpoint
            checkpoint += PIECE
        cands = [checkpoint]
        idx = int(np.searchsorted(self._bounds, t + _EPS_T, side="right"))
        if idx < len(self._bounds):
            cands.append(float(self._bounds[idx]))
        if self._profile is not None:
            knots = self._profile.knots
            k = int(np.searchsorted(knots, t + _EPS_T, side="right"))
            if k < len(knots):
                cands.append(float(knots[k]))
            alpha = abs(float(self._profile.alpha(t + _EPS_T)))
            if alpha > 0.0:
                cands.append(t + math.sqrt(8.0 * SPEED_ANGLE_TOL / alpha))
        t_end = min(c for c in cands if c > t + _EPS_T)
        window = None
        if state == FaultState.OUTER_RACE:
            window = self._or
        elif state == FaultState.INNER_RACE:
            window = self._ir
        or_rel = ir_rel = self._zero
        if window is not None:
            sw = self._next_switch(window, t, t_end)
            if sw is not None:
                t_end = sw
        if self._profile is None:
            p, ct0, st0 = self._p, self._ct0, self._st0
            mid = 0.5 * (t + t_end)
        else:
            p, ct0, st0, mid = self._call_speed(t, t_end)
        if window is not None:
            rel = window.relief(mid)
            if window is self._or:
                or_rel = rel
            else:
                ir_rel = rel
        n_max = int((t_end - self._n_fine_next * self._fine_dt) / self._fine_dt) + 3
        out = np.empty(max(n_max, 1))
        h, nw, ok = integrate_interval(
            t, t_end, self._y, self._h, self.config.max_step, p, ct0, st0,
            or_rel, ir_rel, self._rtol, self._atol, self._fine_dt, self._n_fine_next, out,
            NDOF + DOF_HOUSING_Y_DE, self._stats, self._ctrl)
        if not ok:
            raise RuntimeError(f"integration failed near t = {t:.6g} s (step size collapsed or non-finite state)")
        self._h = h
        self._t = t_end
        self._n_fine_next += nw
        self._pending.append(out[:nw])

    def _call_speed(self, t, t_end):
        """(p, ct0, st0) of one integration call over [t, t_end] at changing speed, and the
        clock tau at its middle (s).

        The compiled model turns every angle at a constant rate from its packed speeds
        and initial angles: here the call's mean speed (the exact angle turned over
        the call), the ball angles and the unbalance phase shifted so that they are
        the exact φ-shares at t (module docstring), and the unbalance amplitude and
        lag that carry its tangential part μe·α.
        """
        prof, ref = self._profile, self.params.shaft_speed
        mid = 0.5 * (t + t_end)
        phi0, phi1, phi_mid = prof.angle(np.array([t, t_end, mid]))
        w = (phi1 - phi0) / (t_end - t)  # mean shaft speed over the call, rad/s
        alpha = float(prof.alpha(mid))
        ratio = w / ref
        p = self._p.copy()
        p[P_OMI] *= ratio
        p[P_OMO] *= ratio
        p[P_OMD] = w
        shift = phi0 - w * t  # rad of shaft angle: φ(t') = w t' + shift over the call
        p[P_MUE] = UNBALANCE_MASS * UNBALANCE_ECCENTRICITY * math.hypot(w * w, alpha) / (w * w)
        p[P_PHIMU] = UNBALANCE_PHASE + shift - math.atan2(alpha, w * w)
        theta = self._theta0 + self._kappa * shift
        return p, np.cos(theta), np.sin(theta), phi_mid / ref

    def _next_switch(self, window, t, t_end):
        """First switching time of ``window`` in (t + eps, t_end - eps], or None.

        The times are computed per 0.2 s span and cached (same formula, so the
        same values whatever span they come from); at changing speed on the clock
        tau and mapped back to time.
        """
        lo, hi, times = self._sw_cache.get(id(window), (0.0, -1.0, None))
        if times is None or t < lo or t_end > hi:
            lo, hi = t, max(t_end, t + 0.2)
            if self._profile is None:
                times = window.switch_times(lo, hi)
            else:
                ref = self.params.shaft_speed
                tau = window.switch_times(float(self._clock(lo)), float(self._clock(hi)))
                times = self._profile.time_at_angle(tau * ref)
            self._sw_cache[id(window)] = (lo, hi, times)
        i = int(np.searchsorted(times, t + _EPS_T, side="right"))
        if i < len(times) and times[i] <= t_end - _EPS_T:
            return float(times[i])
        return None

    def _fine_end(self):
        """Global fine index of the newest available fine sample."""
        return self._n_fine_next - 1

    # ----------------------------------------------------------------- output
    def advance(self, n_samples):
        """Produce the next ``n_samples`` output samples (fewer at the end of the schedule)."""
        n = int(n_samples)
        if n < 0:
            raise ValueError(f"n_samples must be >= 0, got {n_samples!r}")
        n = min(n, self.total_samples - self.samples_done)
        k0 = self.samples_done
        if n <= 0:
            e = np.empty(0)
            return SimChunk(k0, k0 / self.sample_rate, e, e.copy(), np.empty(0, np.int8), e.copy())
        D, c = self._D, self._c
        need = (k0 + n - 1) * D + c
        while self._fine_end() < need:
            self._integrate_piece()
        if self._pending:
            self._fbuf = np.concatenate([self._fbuf] + self._pending)
            self._pending = []
        out = np.empty(n)
        first = k0 * D + c - self._fbuf_start
        fir_decimate(self._fbuf, self._taps, D, first, n, out)
        keep_from = (k0 + n) * D - c
        drop = keep_from - self._fbuf_start
        if drop > 0:
            self._fbuf = self._fbuf[drop:].copy()
            self._fbuf_start = keep_from
        accel = out * M_PER_INCH
        if self._noise_sigma > 0.0:
            accel += self._noise_sigma * self._rng.standard_normal(n)
        t = (k0 + np.arange(n)) / self.sample_rate
        if self._profile is None:
            unbalance = self.params.unbalance_force_y(t) * N_PER_LBF
        else:
            unbalance = self._unbalance_force_y(t) * N_PER_LBF
        truth = self.state_at(t).astype(np.int8)
        self.samples_done = k0 + n
        return SimChunk(k0, k0 / self.sample_rate, accel, unbalance, truth, self.shaft_speed(t))

    def _unbalance_force_y(self, t):
        """Physical unbalance force on the disk along +y at changing speed (lbf):
        mu e (w^2 sin(phi + phi_mu) - alpha cos(phi + phi_mu)), phi = the shaft angle."""
        prof = self._profile
        w, alpha = prof.omega(t), prof.alpha(t)
        ph = prof.angle(t) + UNBALANCE_PHASE
        return UNBALANCE_MASS * UNBALANCE_ECCENTRICITY * (w * w * np.sin(ph) - alpha * np.cos(ph))


def simulate(config, schedule, chunk_seconds=0.05, progress=None):
    """Run a whole schedule; returns dict(t, accel, unbalance, truth, sample_rate, rpm), and
    ``shaft_speed`` (rad/s per sample) when the config has a speed profile (``rpm`` is then
    its mean over the run).

    ``progress(done, total)`` is called after every chunk when given.
    """
    sim = Simulator(config, schedule)
    n_chunk = max(1, int(round(chunk_seconds * sim.sample_rate)))
    parts = []
    while not sim.finished:
        parts.append(sim.advance(n_chunk))
        if progress is not None:
            progress(sim.samples_done, sim.total_samples)
    if parts:
        accel = np.concatenate([p.accel for p in parts])
        unb = np.concatenate([p.unbalance for p in parts])
        truth = np.concatenate([p.truth for p in parts])
    else:
        accel, unb, truth = np.empty(0), np.empty(0), np.empty(0, np.int8)
    out = {
        "t": np.arange(sim.total_samples) / sim.sample_rate,
        "accel": accel,
        "unbalance": unb,
        "truth": truth,
        "sample_rate": sim.sample_rate,
        "rpm": float(config.rpm),
    }
    if config.speed_profile is not None:
        out["shaft_speed"] = np.concatenate([p.shaft_speed for p in parts]) if parts else np.empty(0)
        out["rpm"] = config.speed_profile.mean_rpm(0.0, sim.duration)
    return out
