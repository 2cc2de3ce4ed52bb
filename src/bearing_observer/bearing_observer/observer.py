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
difference equation (:func:`.kernels.iir_filter`); otherwise it is run in modal form (:class:`.realization.ModalFilter`,
a compiled loop). Both carry their state between calls, so chunked processing equals
one-shot processing, and no per-sample Python loop runs.

Observer gain (pole choice, :func:`.realization.observer_gain`): ``"model"`` (default,
``L = 0``: the model's own poles; white measurement noise passes with gain 1),
``"contracted"`` (the model poles scaled towards the origin) or an array of poles. Every
construction checks that all eigenvalues of ``A - L C`` lie strictly inside the unit circle.

Fault frequency: :func:`fault_order` × shaft frequency; the order is the model's (measured
on its identification record, slip included) when the observer watches the bearing the
model was identified for, else the watched bearing's kinematic order (eqs. 2.53-2.54) with a
:class:`BearingMismatchWarning`.

Online phase and amplitude of the train (the thesis assumes them known). Every
``update_interval`` seconds, at fixed sample counts (so results do not depend on how the
stream is chunked), the observer looks at the last ``window`` seconds of
``z_tilde = g^-1(y)``:

1. *Phase*: ``z_tilde²`` folded over the fault period is circularly cross-correlated with the
   fold of the model's squared unit-impulse response; the best lag is the impact phase.
2. *Amplitude*: the model's responses to the unit train(s) at that phase are the regressors
   of a least-squares fit of ``z_tilde`` (outer race: one regressor, eq. 2.55, gain clipped
   at >= 0; inner race: the three components of eq. 2.58, cos / sin of the shaft angle and
   constant, so the unknown shaft phase and offset are estimated too).
3. *Significance*: the drive is used only when the fit explains at least ``min_explained``
   of the window's energy (default 40 %). White noise explains about ``p/N`` ~ 1e-3
   (``N`` window samples, ``p`` regressors); on the simulator (0.4 s, 48 kHz) the matching
   observer explains 98 % and the other fault's observer 10-22 %, so 40 % keeps each
   observer from injecting on the other fault; otherwise the drive is 0: in NORMAL
   operation the observer injects no impulses of its own. On real CWRU data impacts
   wander 0.1-0.7 ms from a strictly periodic train, the signed least-squares fit
   explains little, and the drive is mostly off there (the phase still locks, see tests).

The estimates apply from the next update boundary on (causal, one update of delay).
``drive="phase"`` stops after step 1: the train is published at the estimated phase and
nothing is subtracted (residual = y); model set ``none`` runs that way.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import fft as sp_fft

from bearing_common.bearings import Bearing, load_bearing
from bearing_common.states import parse_fault

from .hw_model import HWModel, same_bearing
from .impulse_trains import TWO_PI, impulse_train, modulated_train_components
from .kernels import drive_input, fold_energy, iir_filter
from .model_sets import NONE, load_model_set
from .realization import ModalFilter, balanced_realization, observer_gain


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
    bearing : Bearing or str, optional
        The watched bearing (anything :func:`bearing_common.bearings.load_bearing` reads);
        default the model's. Its fault order is :func:`fault_order`'s: another bearing
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
                 bearing: Bearing | str | None = None, poles="model", contraction: float = 0.95, window: float = 0.1,
                 update_interval: float = 0.1, min_explained: float = 0.4,
                 drive: str = "adaptive", phase: float | None = None, gains=None):
        if sample_rate is not None and not math.isclose(sample_rate, model.sample_rate, rel_tol=1e-9):
            raise ValueError(f"model identified at {model.sample_rate:g} Hz, observer asked for "
                             f"{sample_rate:g} Hz: resample or pick a model set for that rate")
        if drive not in ("adaptive", "phase", "off", "fixed"):
            raise ValueError("drive must be 'adaptive', 'phase', 'off' or 'fixed'")
        self.model = model
        self.bearing = model.bearing if bearing is None else load_bearing(bearing)
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
        self._template_cache = {}  # folded unit-impulse response energy (phase estimation)
        self._noise_gain = None
        self._fixed_phase = phase
        self._fixed_gains = None if gains is None else np.asarray(gains, dtype=float).ravel()
        if drive == "fixed" and (phase is None or gains is None):
            raise ValueError("drive='fixed' needs phase and gains")
        self.set_speed(model.rpm if rpm is None else rpm)
        self.reset()

    # ------------------------------------------------------------------------------------
    @classmethod
    def from_model_set(cls, set_name: str, fault_type: str, rpm: float | None = None,
                       sample_rate: float | None = None, bearing: Bearing | str | None = None,
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
        return self._freq

    @property
    def shaft_frequency(self) -> float:
        """Current shaft frequency (Hz)."""
        return self._fr

    def set_speed(self, rpm: float) -> None:
        """Set the shaft speed (rev/min); the train's phase stays continuous."""
        rpm = float(rpm)
        if not (math.isfinite(rpm) and rpm > 0):
            raise ValueError(f"rpm must be finite and > 0, got {rpm!r}")
        if hasattr(self, "_n"):
            # re-anchor the cycle coordinates at the current sample: phase continuity
            self._psi_base, self._chi_base = self._cycles(self._n)
            self._n_base = self._n
        self.rpm = rpm
        self._cached_trains = None
        self._fr = rpm / 60.0
        self._freq = self.fault_order * self._fr

    def reset(self) -> None:
        """Zero the observer state and forget the phase/amplitude estimates."""
        if self._modal is not None:
            self._modal.reset()
        self._zi_tf = np.zeros(self._iir[0].size - 1)
        self._delay_buf = np.zeros(self.model.nk)
        self._n = 0                      # samples processed since reset
        # Cycle coordinates (fault psi, shaft chi, in cycles) are computed from the absolute
        # sample count since the last speed change, so any chunking gives identical values.
        self._n_base = 0
        self._psi_base = 0.0
        self._chi_base = 0.0
        self._win_z = np.zeros(0)        # recent z_tilde
        if self.drive_mode == "fixed":
            self._phase_c = float(-self._fixed_phase / TWO_PI) % 1.0
            self._set_gains(self._fixed_gains.copy())
        else:
            self._phase_c = 0.0          # impact cycle position estimate (cycles)
            self._set_gains(np.zeros(3 if self.model.modulated else 1))
        self.explained = 0.0
        self._cached_trains = None

    @property
    def phase(self) -> float:
        """Estimated fault phase (rad) at the next sample: impacts where
        ``f t + phase / (2 pi)`` is an integer, ``t`` measured from the next sample."""
        return float(np.mod(TWO_PI * (self._cycles(self._n)[0] - self._phase_c), TWO_PI))

    def _cycles(self, n_abs):
        """Fault and shaft cycle positions (cycles, in [0, 1)) at absolute sample(s) n_abs."""
        t = (np.asarray(n_abs) - self._n_base) / self.sample_rate
        return (np.mod(self._psi_base + self._freq * t, 1.0),
                np.mod(self._chi_base + self._fr * t, 1.0))

    @property
    def gains(self) -> np.ndarray:
        """Current train gains (see the ``gains`` parameter)."""
        return self._gains.copy()

    # ------------------------------------------------------------------------------------
    def _trains(self, n: int, n_start: int, plain_only: bool = False):
        """Unit plain train and regressor trains for ``n`` samples from absolute sample
        ``n_start`` (impact times from the speed anchor: independent of block boundaries)."""
        fs = self.sample_rate
        ph = TWO_PI * (self._psi_base - self._phase_c)
        i0 = int(n_start - self._n_base)
        if self.model.modulated and not plain_only:
            comps = modulated_train_components(n, fs, self._freq, ph, start_index=i0,
                                               shaft_frequency=self._fr,
                                               shaft_phase=TWO_PI * self._chi_base,
                                               pulse_width=self.model.pulse_width)
            return comps[2], comps
        unit = impulse_train(n, fs, self._freq, ph, start_index=i0,
                             pulse_width=self.model.pulse_width)
        return unit, unit[None, :]

    def _cache_trains(self, n_start: int, n_end: int) -> None:
        """Render the trains (see :meth:`_trains`) for absolute sample indices
        ``[n_start, n_end)`` in one call and keep them for the blocks up to the next update
        boundary (phase and speed are constant there; a speed change drops the cache).
        Pulse positions are computed per sample from the speed anchor, so a slice equals
        the block rendered on its own (to rounding of the sub-sample position, ~1e-12) and
        does not depend on how the stream is chunked."""
        plain_only = self.drive_mode in ("phase", "off")
        self._cached_trains = (n_start, n_end) + self._trains(n_end - n_start, n_start, plain_only)

    def _block_trains(self, n: int):
        """Unit train and regressor trains (see :meth:`_trains`) for the next ``n`` samples,
        which never cross an update boundary."""
        c = self._cached_trains
        if c is None or not (c[0] <= self._n and self._n + n <= c[1]):
            self._cache_trains(self._n, (self._n // self.update_n + 1) * self.update_n)
            c = self._cached_trains
        i = self._n - c[0]
        return c[2][i:i + n], c[3][:, i:i + n]

    def _template_spectrum(self, n_bins: int):
        """FFT length and conjugate spectrum of the zero-padded template fold (cached)."""
        key = (n_bins, self._freq)
        if key not in self._template_cache:
            if len(self._template_cache) > 16:
                self._template_cache.clear()
            n_fft = sp_fft.next_fast_len(2 * n_bins, real=True)
            self._template_cache[key] = (
                n_fft, np.conj(sp_fft.rfft(self._make_template(n_bins), n_fft)))
        return self._template_cache[key]

    def _make_template(self, n_bins: int) -> np.ndarray:
        period = self.sample_rate / self._freq
        n = int(math.ceil(period))
        imp = np.zeros(n)
        imp[0] = 1.0
        h2 = self.model.simulate_linear(imp) ** 2
        pos = np.arange(n) / period
        idx = np.minimum((pos * n_bins).astype(np.int64), n_bins - 1)
        return np.bincount(idx, weights=h2, minlength=n_bins)

    def _update_estimates(self) -> None:
        z = self._win_z
        if z.size < self.window_n // 2:
            return
        period = self.sample_rate / self._freq
        # two bins per sample of the period: every bin gets samples (another count leaves a
        # beat pattern of empty bins that the one-period template does not share)
        n_bins = int(min(1024, max(16, round(2 * period))))
        # fault cycle position of the window's samples (from the speed anchor; exact while
        # the speed is constant over the window)
        prof = fold_energy(z, self._n - z.size - self._n_base, self._psi_base, self._freq,
                           self.sample_rate, n_bins)
        # circular cross-correlation with the template, as the wrapped linear correlation
        # at a fast FFT length >= 2 n_bins (n_bins itself is often a large prime)
        n_fft, tmpl_f = self._template_spectrum(n_bins)
        lin = sp_fft.irfft(sp_fft.rfft(prof - prof.mean(), n_fft) * tmpl_f, n_fft)
        corr = lin[:n_bins] + lin[n_fft - n_bins:]
        lag = int(np.argmax(corr))
        # sub-bin refinement: vertex of the parabola through the peak and its neighbours
        c0, cm, cp = corr[lag], corr[lag - 1], corr[(lag + 1) % n_bins]
        den = cm - 2.0 * c0 + cp
        frac = 0.5 * (cm - cp) / den if den < 0 else 0.0
        self._phase_c = ((lag + min(max(float(frac), -0.5), 0.5)) / n_bins) % 1.0
        if self.drive_mode == "phase":
            self._cached_trains = None  # rendered again at the new phase
            return
        # regressors over the window (zero state at the window start; first part discarded);
        # the trains are rendered through the next update interval in the same call
        self._cache_trains(self._n - z.size, self._n + self.update_n)
        R = self.model.simulate_linear(self._cached_trains[3][:, :z.size])  # one row per regressor
        skip = min(z.size // 4, int(round(period)))
        Rw, zw = R[:, skip:], z[skip:]      # one regressor per row (contiguous rows)
        # normal equations (p <= 3 regressors), ridge-regularised at 1e-9 of the trace
        G = Rw @ Rw.T
        r = Rw @ zw
        ridge = 1e-9 * max(float(np.trace(G)), 1e-300) * np.eye(G.shape[0])
        p = np.linalg.solve(G + ridge, r)
        if not self.model.modulated:
            p = np.maximum(p, 0.0)
        # explained energy 1 - |zw - p Rw|^2 / |zw|^2, the residual energy expanded as
        # |zw|^2 - 2 p.r + p G p (no pass over the samples)
        e = float(zw @ zw)
        res_energy = max(e - 2.0 * float(p @ r) + float(p @ G @ p), 0.0)
        self.explained = 1.0 - res_energy / e if e > 0 else 0.0
        self._set_gains(p if self.explained >= self.min_explained else np.zeros_like(p))

    def _set_gains(self, gains: np.ndarray) -> None:
        """Train gains from now on; the drive is on when any is non-zero (and not ``drive="off"``)."""
        self._gains = gains
        self._driving = self.drive_mode != "off" and bool(np.any(gains))

    def _process_block(self, y: np.ndarray, out_est, out_train, out_drive, sl) -> None:
        n = y.size
        g = self.model.output_nonlinearity
        f = self.model.input_nonlinearity
        z_t = g.inverse(y)
        unit, comps = self._block_trains(n)
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
            W = self.window_n
            self._win_z = np.concatenate([self._win_z, z_t])[-W:]
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
        """Measured white-noise gain of the residual filter: RMS(residual) / RMS(noise).

        Seeded white Gaussian noise (RMS 1e-3 of the output nonlinearity's first breakpoint
        span, i.e. in g's local linear range) is run through a fresh copy of this observer
        with the train input off; 1.0 for ``poles="model"`` (L = 0).
        """
        if self._noise_gain is None:
            clone = FaultObserver(self.model, rpm=self.rpm, poles=self.poles_choice,
                                  contraction=self._contraction, drive="off")
            gx = self.model.output_nonlinearity
            sigma = 1e-3 * float(np.max(np.abs(gx.y)))
            rng = np.random.default_rng(12345)
            n = int(max(20000, 0.5 * self.sample_rate))
            v = sigma * rng.standard_normal(n)
            r = clone.process(v).residual
            skip = n // 10
            self._noise_gain = float(np.sqrt(np.mean(r[skip:] ** 2)) / np.sqrt(np.mean(v[skip:] ** 2)))
        return self._noise_gain

    def noise_gain_analytic(self, n: int = 1 << 16) -> float:
        """H2 norm of the linearised map ``z_tilde -> z_tilde - z_hat`` (impulse response)."""
        if self._modal is None:
            return 1.0
        imp = np.zeros(n)
        imp[0] = 1.0
        f = ModalFilter(self.A - self.L @ self.C, self.B - self.L @ self.D, self.L, self.C, self.D)
        h = imp - f.run(np.zeros(n), imp)
        return float(np.sqrt(np.sum(h * h)))
