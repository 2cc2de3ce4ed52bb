"""Hammerstein-Wiener fault observer: thesis section 3.1, Fig. 3.1, eqs. 3.1-3.4.

Structure (one observer per fault hypothesis)::

    u (fault impulse train) -> f(.) -> w -> [delay nk] -> linear observer -> z_hat -> g(.) -> y_hat
    y (measurement, m/s²)   -> g^-1(.) -> z_tilde ------^ (correction L (z_tilde - z_hat))
    residual = y - y_hat

Discrete-time form of eqs. 3.1-3.4 (the thesis writes x-dot; appendix D runs the
difference equation)::

    x[n+1] = A x[n] + B w[n] + L (z_tilde[n] - z_hat[n])
    z_hat[n] = C x[n] + D w[n]

with ``(A, B, C, D)`` a balanced realization of ``B(q)/F(q)`` (the pure delay ``q^-nk`` is
applied to ``w`` by a carried sample buffer, not kept in the state vector). Substituting,
``z_hat`` is the output of one LTI system with two inputs, ``w`` and ``z_tilde``, and state
matrix ``A - L C``. With ``L = 0`` that system is ``B/F`` driven by ``w`` alone, run as a
difference equation (:func:`iir_filter`); otherwise it is run in modal form
(:class:`.realization.ModalFilter`). Both carry their state between calls, so chunked
processing equals one-shot processing, and no per-sample Python loop runs: both are
compiled loops (numba), as is the train input (:func:`drive_input`); :func:`warm_up`
compiles every kernel the observer runs.

Observer gain (pole choice, :func:`.realization.observer_gain`): ``"model"`` (default,
``L = 0``: the model's own poles; white measurement noise passes with gain 1),
``"contracted"`` (the model poles scaled towards the origin) or an array of poles. Every
construction checks that all eigenvalues of ``A - L C`` lie strictly inside the unit circle.

Fault frequency: :func:`fault_order` × shaft frequency; the order is the model's (measured
on its identification record, slip included) when the observer watches the bearing the
model was identified for, else the watched bearing's kinematic order (eqs. 2.53-2.54) with a
:class:`BearingMismatchWarning`.

Online phase and amplitude of the train (the thesis assumes them known): every
``update_interval`` seconds, at fixed sample counts (so results do not depend on how the
stream is chunked), :class:`.phase_amplitude_estimator.PhaseAmplitudeEstimator` estimates
them from the last ``window`` seconds of ``z_tilde = g^-1(y)`` (phase from a fold, gains
from a least-squares fit of the model's responses, used only when they explain at least
``min_explained`` of the window's energy: otherwise the drive is 0, the observer injects no
impulses of its own). The trains come from :class:`.train_cache.TrainCache` (cycle
coordinates from the speed anchor, rendered once per update interval).

The estimates apply from the next update boundary on (causal, one update of delay).
``drive="phase"`` stops after the phase: the train is published at the estimated phase and
nothing is subtracted (residual = y); model set ``none`` runs that way.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from numba import njit

from bearing_common.bearings import Bearing
from bearing_common.states import parse_fault

from .hw_model import HWModel, same_bearing
from .impulse_trains import TWO_PI, add_pulses
from .model_sets import NONE, load_model_set
from .noise_gain import analytic_noise_gain, measured_noise_gain
from .phase_amplitude_estimator import PhaseAmplitudeEstimator, fold_energy
from .piecewise_linear import interp_extended
from .realization import ModalFilter, balanced_realization, observer_gain, run_modes
from .train_cache import TrainCache


@dataclass
class ObserverOutput:
    """Result of :meth:`FaultObserver.process` for one chunk (all arrays the chunk's length).

    Attributes
    ----------
    residual : ndarray
        ``y - estimate`` (m/s²).
    estimate : ndarray
        ``y_hat = g(z_hat)`` (m/s²).
    impulse_train : ndarray
        Unit-height train (eq. 2.55 shape) at the fault frequency and the estimated phase
        (dimensionless); what the residual should align with under this fault.
    drive : ndarray
        The input actually applied to the model, ``f(u)`` with the estimated amplitude and
        (inner race) modulation; zero when no significant fault component is seen.
    """

    residual: np.ndarray
    estimate: np.ndarray
    impulse_train: np.ndarray
    drive: np.ndarray


class BearingMismatchWarning(UserWarning):
    """The observer watches another bearing than its model was identified for."""


def fault_order(model: HWModel, bearing: Bearing | None) -> tuple[float, str]:
    """Impacts per shaft revolution the observer uses, and a warning text ("" when none).

    The model's own order (measured on its identification record, slip included) when
    ``bearing`` is None or has the orders of the model's bearing; otherwise the kinematic
    order of ``bearing`` (eqs. 2.53-2.54), with a warning: the model's dynamics were then
    identified on a machine with another bearing (or on one whose bearing is not recorded).
    """
    if bearing is None or (model.bearing is not None and same_bearing(bearing, model.bearing)):
        return model.fault_order, ""
    identified_for = model.bearing.name if model.bearing is not None else "an unrecorded bearing"
    where = model.provenance.get("model_set", "this model")
    return bearing.orders().of(parse_fault(model.fault_type)), (
        f"{where} ({model.fault_type}) was identified for {identified_for}, not {bearing.name}: "
        f"using {bearing.name}'s kinematic fault frequency with the other machine's dynamics "
        "(identify a model set for this machine, or use model set 'none')")


class FaultObserver:
    """HW observer of one fault type (Fig. 3.1); streaming, chunk-invariant.

    Parameters
    ----------
    model : HWModel
        Identified model (its sample rate must equal ``sample_rate``).
    rpm : float, optional
        Shaft speed (rev/min); default the model's.
    sample_rate : float, optional
        Hz; must equal the model's.
    bearing : Bearing, optional
        The watched bearing; default the model's. Its fault order is :func:`fault_order`'s: another bearing
        than the model's gives a :class:`BearingMismatchWarning` and runs on.
    poles : "model" | "contracted" | array_like
        Observer pole choice (module docstring). Default ``"model"`` (L = 0).
    contraction : float
        For ``poles="contracted"``.
    window : float
        Length (s) of the recent window for the phase/amplitude estimate.
    update_interval : float
        Seconds between estimate updates (at fixed sample counts).
    min_explained : float
        Minimum explained energy fraction for the train drive to be used.
    drive : "adaptive" | "phase" | "off" | "fixed"
        ``adaptive``: online phase and amplitude; ``phase``: online phase, no train input
        (u = 0: the train is published, not subtracted); ``off``: no train input, the
        train at phase 0; ``fixed``: use ``phase`` and ``gains`` as given.
    phase : float, optional
        Fixed fault phase (rad) at the observer's time 0, for ``drive="fixed"``.
    gains : sequence of float, optional
        Fixed regressor gains for ``drive="fixed"``: ``(a,)`` for the outer race,
        ``(a cos th, -a sin th, a c)`` for the inner race (see
        :func:`~bearing_observer.impulse_trains.modulated_train_components`).
    """

    def __init__(self, model: HWModel, rpm: float | None = None, sample_rate: float | None = None,
                 bearing: Bearing | None = None, poles="model", contraction: float = 0.95, window: float = 0.1,
                 update_interval: float = 0.1, min_explained: float = 0.4,
                 drive: str = "adaptive", phase: float | None = None, gains=None):
        if sample_rate is not None and not math.isclose(sample_rate, model.sample_rate, rel_tol=1e-9):
            raise ValueError(f"model identified at {model.sample_rate:g} Hz, observer asked for "
                             f"{sample_rate:g} Hz: resample or pick a model set for that rate")
        if drive not in ("adaptive", "phase", "off", "fixed"):
            raise ValueError("drive must be 'adaptive', 'phase', 'off' or 'fixed'")
        self.model = model
        self.bearing = model.bearing if bearing is None else bearing
        self.fault_order, mismatch = fault_order(model, None if bearing is None else self.bearing)
        if mismatch:
            warnings.warn(mismatch, BearingMismatchWarning, stacklevel=2)
        self.sample_rate = float(model.sample_rate)
        self.fault = parse_fault(model.fault_type)
        self.poles_choice = poles
        self._contraction = float(contraction)
        self.drive_mode = drive
        self.min_explained = float(min_explained)
        self.window_n = max(16, int(round(window * self.sample_rate)))
        self.update_n = max(1, int(round(update_interval * self.sample_rate)))
        # state-space model and gain
        A, B, C, D = balanced_realization(model.b, model.f)
        self.A, self.B, self.C, self.D = A, B, C, D
        self.L, self.observer_poles = observer_gain(A, C, poles, contraction)
        Ao = A - self.L @ C
        self._modal = ModalFilter(Ao, B - self.L @ D, self.L, C, D) if np.any(self.L) else None
        # L = 0: z_hat = B/F w exactly; the identified polynomials run directly (zero-padded
        # to one length, normalised to f[0] = 1)
        k = max(model.b.size, model.f.size)
        self._iir = (np.pad(model.b, (0, k - model.b.size)) / model.f[0],
                     np.pad(model.f, (0, k - model.f.size)) / model.f[0])
        self._estimator = PhaseAmplitudeEstimator(model, self.window_n, self.min_explained)
        self._train = TrainCache(self.sample_rate, model.pulse_width, model.modulated,
                                 plain_only=drive in ("phase", "off"), update_n=self.update_n)
        self._noise_gain = None
        self._fixed_phase = phase
        self._fixed_gains = None if gains is None else np.asarray(gains, dtype=float).ravel()
        if drive == "fixed" and (phase is None or gains is None):
            raise ValueError("drive='fixed' needs phase and gains")
        self._n = 0  # samples processed since reset
        self.set_speed(model.rpm if rpm is None else rpm)
        self.reset()

    # ------------------------------------------------------------------------------------
    @classmethod
    def from_model_set(cls, set_name: str, fault_type: str, rpm: float | None = None,
                       sample_rate: float | None = None, bearing: Bearing | None = None,
                       root=None, **kwargs) -> FaultObserver:
        """Observer for ``fault_type`` from the model set ``set_name`` (:mod:`.model_sets`).

        Set ``none`` (no model) needs ``rpm`` and ``sample_rate`` and runs with
        ``drive="phase"``: residual = y, estimate = 0, the train's phase estimated online.
        """
        models = load_model_set(set_name, sample_rate=sample_rate, root=root, bearing=bearing)
        if set_name == NONE:
            if rpm is None:
                raise ValueError(f"model set {NONE!r} states no shaft speed: give rpm")
            kwargs.setdefault("drive", "phase")
        return cls(models[fault_type], rpm=rpm, sample_rate=sample_rate, bearing=bearing, **kwargs)

    # ------------------------------------------------------------------------------------
    @property
    def fault_frequency(self) -> float:
        """Current impact frequency (Hz): :attr:`fault_order` × shaft frequency."""
        return self._train.frequency

    @property
    def shaft_frequency(self) -> float:
        """Current shaft frequency (Hz)."""
        return self._train.shaft_frequency

    def set_speed(self, rpm: float) -> None:
        """Set the shaft speed (rev/min); the train's phase stays continuous."""
        rpm = float(rpm)
        if not (math.isfinite(rpm) and rpm > 0):
            raise ValueError(f"rpm must be finite and > 0, got {rpm!r}")
        self.rpm = rpm
        fr = rpm / 60.0
        self._train.set_speed(self._n, self.fault_order * fr, fr)

    def reset(self) -> None:
        """Zero the observer state and forget the phase/amplitude estimates."""
        if self._modal is not None:
            self._modal.reset()
        self._zi_tf = np.zeros(self._iir[0].size - 1)
        self._delay_buf = np.zeros(self.model.nk)
        self._n = 0
        self._train.reset()
        self._estimator.reset()
        if self.drive_mode == "fixed":
            self._train.set_phase(float(-self._fixed_phase / TWO_PI) % 1.0)
            self._set_gains(self._fixed_gains.copy())
        else:
            self._train.set_phase(0.0)
            self._set_gains(np.zeros(3 if self.model.modulated else 1))
        self.explained = 0.0  #: energy fraction the last amplitude fit explained

    @property
    def phase(self) -> float:
        """Estimated fault phase (rad) at the next sample: impacts where
        ``f t + phase / (2 pi)`` is an integer, ``t`` measured from the next sample."""
        return float(np.mod(TWO_PI * (self._train.cycles(self._n)[0] - self._train.phase_c), TWO_PI))

    @property
    def gains(self) -> np.ndarray:
        """Current train gains (see the ``gains`` parameter)."""
        return self._gains.copy()

    # ------------------------------------------------------------------------------------
    def _update_estimates(self) -> None:
        """Phase, then (``drive="adaptive"``) gains, from the estimator's window, which ends
        at the current sample (an update boundary)."""
        est, train = self._estimator, self._train
        if not est.ready:
            return
        first = self._n - est.window.size
        train.set_phase(est.phase(first - train.n_base, train.psi_base, train.frequency))
        if self.drive_mode == "phase":
            return  # the trains are rendered again at the new phase
        # the regressors over the window; the trains are rendered through the next update
        # interval in the same call
        _, trains = train.render(first, self._n + self.update_n)
        gains, self.explained = est.fit(trains[:, :est.window.size], train.frequency)
        self._set_gains(gains)

    def _set_gains(self, gains: np.ndarray) -> None:
        """Train gains from now on; the drive is on when any is non-zero (and not ``drive="off"``)."""
        self._gains = gains
        self._driving = self.drive_mode != "off" and bool(np.any(gains))

    def _process_block(self, y: np.ndarray, out_est, out_train, out_drive, sl) -> None:
        n = y.size
        g = self.model.output_nonlinearity
        f = self.model.input_nonlinearity
        z_t = g.inverse(y)
        unit, comps = self._train.block(self._n, n)
        u, w, zhat = out_drive[sl], np.empty(n), np.empty(n)
        # w = q^-nk f(u) while the drive is on, else 0 (nothing injected)
        drive_input(comps, self._gains, self._driving, f.x, f.y, f.slopes, self._delay_buf, u, w)
        if self._modal is not None:
            zhat = self._modal.run(w, z_t)
        elif self._zi_tf.size:
            iir_filter(self._iir[0], self._iir[1], w, self._zi_tf, zhat)
        else:  # a static gain B/F = b0 / f0
            np.multiply(w, self._iir[0][0] / self._iir[1][0], out=zhat)
        out_est[sl] = g(zhat)
        out_train[sl] = unit
        # bookkeeping: sample count and the estimation window
        self._n += n
        if self.drive_mode in ("adaptive", "phase"):
            self._estimator.push(z_t)
            if self._n % self.update_n == 0:
                self._update_estimates()

    def process(self, y) -> ObserverOutput:
        """Process the next chunk of measurements.

        Parameters
        ----------
        y : array_like, shape (n,)
            Consecutive drive-end acceleration samples (m/s²), float64.

        Returns
        -------
        ObserverOutput

        Raises
        ------
        ValueError
            Not 1-D, or NaN / inf in the chunk (the chunk is rejected, state unchanged).
        """
        y = np.asarray(y, dtype=float)
        if y.ndim != 1:
            raise ValueError(f"y must be 1-D, got shape {y.shape}")
        if not np.all(np.isfinite(y)):
            raise ValueError("y contains NaN or inf; chunk rejected")
        n = y.size
        est = np.empty(n)
        train = np.empty(n)
        drive = np.empty(n)
        i = 0
        while i < n:
            to_boundary = self.update_n - (self._n % self.update_n)
            m = min(n - i, to_boundary)
            sl = slice(i, i + m)
            self._process_block(y[sl], est, train, drive, sl)
            i += m
        return ObserverOutput(residual=y - est, estimate=est, impulse_train=train, drive=drive)

    # ------------------------------------------------------------------------------------
    @property
    def noise_gain(self) -> float:
        """Measured white-noise gain of the residual filter: RMS(residual) / RMS(noise)
        (:func:`.noise_gain.measured_noise_gain`, on a fresh copy of this observer with the
        train input off); 1.0 for ``poles="model"`` (L = 0)."""
        if self._noise_gain is None:
            self._noise_gain = measured_noise_gain(FaultObserver(
                self.model, rpm=self.rpm, poles=self.poles_choice, contraction=self._contraction, drive="off"))
        return self._noise_gain

    def noise_gain_analytic(self, n: int = 1 << 16) -> float:
        """H2 norm of the linearised map ``z_tilde -> z_tilde - z_hat`` (:func:`.noise_gain.analytic_noise_gain`)."""
        return analytic_noise_gain(self.A, self.B, self.C, self.D, self.L, n)


def warm_up() -> None:
    """Compile (first run after an install) or load from numba's cache every kernel the
    observer runs, with the argument types it passes. A node calls this before it
    subscribes, so that no chunk waits for a compile (about a second per kernel) and its
    queue never overflows."""
    z = np.zeros(8)
    out = np.zeros(8)
    add_pulses(np.zeros((2, 8)), np.array([1.5]), np.array([2.5]), np.ones((2, 1)), 2)
    interp_extended(np.array([-1.0, 1.0]), np.array([-1.0, 1.0]), np.array([1.0]), z, out)
    fold_energy(z, 0, 0.0, 100.0, 48000.0, 4)
    f = (np.array([-1.0, 1.0]), np.array([-1.0, 1.0]), np.array([1.0]))
    for comps in (np.zeros((1, 8)), np.zeros((3, 16))[:, 4:12]):  # the train cache's slices: either layout
        drive_input(comps, np.ones(comps.shape[0]), True, *f, np.zeros(1), z, out)
    iir_filter(np.ones(2), np.ones(2), z, np.zeros(1), out)
    modes = np.zeros(1, dtype=complex)
    run_modes(modes, modes, modes, modes, np.ones(1), 0.0, z, z, np.zeros(1, dtype=complex), out)


# compiled inner loops (numba; strict IEEE arithmetic, no fastmath)
@njit(cache=True)
def drive_input(comps: np.ndarray, gains: np.ndarray, active: bool, x: np.ndarray, y: np.ndarray,
                slopes: np.ndarray, delay: np.ndarray, u: np.ndarray, w: np.ndarray) -> None:
    """The observer's train input: ``u = gains @ comps``, ``w = q^-nk f(u)`` (thesis Fig. 3.1).

    ``u[i] = sum_j gains[j] comps[j, i]`` (in order of ``j``), ``f`` the piecewise-linear
    input nonlinearity of :func:`.piecewise_linear.interp_extended` through ``(x, y)``, and the pure delay of
    ``nk = delay.size`` samples: ``w[i] = delay[i]`` for ``i < nk``, ``f(u[i - nk])`` after;
    ``delay`` then holds the last ``nk`` values of ``f(u)`` for the next block. Not
    ``active`` (the drive off): ``u = 0`` and ``f(u)`` counts as 0, nothing is injected.

    Parameters
    ----------
    comps : ndarray, shape (p, n)
        Unit regressor trains (dimensionless).
    gains : ndarray, shape (p,)
        Train gains (units of ``u``).
    x, y, slopes : ndarray
        Breakpoints and segment slopes of ``f`` (see :func:`.piecewise_linear.interp_extended`).
    delay : ndarray, shape (nk,)
        ``f(u)`` of the last ``nk`` samples of the previous block; updated in place.
    u, w : ndarray, shape (n,)
        Drive and delayed nonlinear input, written in place.
    """
    n = u.size
    nk = delay.size
    last = x.size - 2
    j = 0
    fu = np.zeros(n)
    for i in range(n if active else 0):
        acc = 0.0
        for k in range(gains.size):
            acc += gains[k] * comps[k, i]
        u[i] = acc
        while j > 0 and acc < x[j]:
            j -= 1
        while j < last and acc >= x[j + 1]:
            j += 1
        fu[i] = slopes[j] * (acc - x[j]) + y[j]
    if not active:
        u[:] = 0.0
    for i in range(n):
        w[i] = delay[i] if i < nk else fu[i - nk]
    if nk:
        if n >= nk:
            delay[:] = fu[n - nk:]
        else:
            delay[:nk - n] = delay[n:].copy()
            delay[nk - n:] = fu


@njit(cache=True)
def iir_filter(b: np.ndarray, a: np.ndarray, x: np.ndarray, zi: np.ndarray, out: np.ndarray) -> None:
    """``B(q)/A(q)`` applied to ``x`` in transposed direct form II, state carried in ``zi``.

    The recursion of ``scipy.signal.lfilter(b, a, x, zi=zi)``: ``b`` and ``a`` of equal length
    ``K >= 2`` (zero-padded), ``a[0] = 1``; ``out[i] = zi[0] + b[0] x[i]``, then
    ``zi[k] = zi[k + 1] + b[k + 1] x[i] - a[k + 1] out[i]`` (``zi[K - 1]`` counting as 0).

    Parameters
    ----------
    b, a : ndarray, shape (K,)
        Numerator and denominator, ``a[0] = 1``.
    x : ndarray, shape (n,)
        Input.
    zi : ndarray, shape (K - 1,)
        Filter state; updated in place.
    out : ndarray, shape (n,)
        Output, written in place.
    """
    m = zi.size
    for i in range(x.size):
        xi = x[i]
        yi = zi[0] + b[0] * xi
        for k in range(m - 1):
            zi[k] = zi[k + 1] + b[k + 1] * xi - a[k + 1] * yi
        zi[m - 1] = b[m] * xi - a[m] * yi
        out[i] = yi
