"""Fault-model identification from a record of a known fault (thesis section 2.4, appendices B-C).

Pipeline (:func:`identify_fault_model`):

1. Fault frequency: the kinematic value of the given bearing (eqs. 2.53-2.54) refined on
   the data within ±3 % (slip on real machines) by maximising the envelope spectrum's
   harmonics.
2. Fault phase: the squared signal folded over the fault period; the impact time is the
   onset of the folded energy peak (the first bin before the peak below 10 % of it).
3. Periods: the record is cut into fault periods starting a little before each impact.
   A rank-1 decomposition of the period matrix (SVD) gives the common period template
   and one signed amplitude per impact.
   - Outer race (thesis: one representative period, Fig. 2.10): the identification data
     is the measured period that correlates best with the template.
   - Inner race (thesis: average of 38 periods, appendix B, Figs. 2.8-2.9): the per-impact
     amplitudes are fitted by eq. 2.58, ``a (cos(2 pi f_s t_k + theta) + c)``; the
     identification data is the *modulation-weighted* average of 38 consecutive periods,
     ``sum_k m_k y_k / sum_k m_k^2`` with ``m_k = cos(2 pi f_s t_k + theta) + c``: the
     least-squares estimate of the response to one unit-weight impact. The plain average
     of appendix B keeps only the ``c`` part of the impacts (it cancels the part whose sign
     follows the shaft angle); its energy relative to the weighted average is reported as
     ``plain_average_energy_ratio``.
4. HW fit of the train to the identification data (:func:`.system_identification.hw_fit`).

Identifiability (the project's decision, ``shared/model-notes.md``): an impulse train takes
two values (0 and the pulse height), so a piecewise-linear input nonlinearity is not
identifiable from it: only ``f(0)`` and ``f(1)`` matter. ``f`` is therefore a gain, fixed to
1 (``f(u) = u``), the train's scale being carried by ``B``.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass

import numpy as np
from scipy import signal

from bearing_common.bearings import Bearing
from bearing_common.states import FaultState, parse_fault

from .hw_model import HWModel, ModelFit
from .impulse_trains import TWO_PI, impact_times, impulse_train
from .piecewise_linear import MonotonePiecewiseLinear
from .system_identification import N_BREAKPOINTS, fit_percent, hw_fit

#: Default orders (nb, nf, nk) per fault type, chosen with the order search on the
#: simulator at 48 kHz (see ``identify_cli --order-search``).
DEFAULT_ORDERS = {"outer_race": (8, 8, 0), "inner_race": (8, 8, 0)}
#: Number of periods averaged for the inner race (appendix B).
N_AVERAGE_IR = 38


def envelope(y: np.ndarray) -> np.ndarray:
    """Squared-magnitude envelope ``|y + j H(y)|^2`` minus its mean (m²/s⁴)."""
    e = np.abs(signal.hilbert(np.asarray(y, dtype=float))) ** 2
    return e - e.mean()


def refine_fault_frequency(y, sample_rate: float, nominal: float, search: float = 0.03,
                           harmonics: int = 3, n_grid: int = 301) -> float:
    """Fault frequency (Hz) within ``nominal (1 ± search)`` that maximises the summed
    envelope-spectrum magnitude at its first ``harmonics`` multiples."""
    e = envelope(y)
    # the envelope lines of interest lie below harmonics * 1.03 * nominal: block-average it
    # down to about 8x that rate (cheap low-pass and decimation) before the grid search
    q = max(1, int(sample_rate // (8.0 * harmonics * nominal * (1.0 + search))))
    m = e.size // q
    e = e[: m * q].reshape(m, q).mean(axis=1)
    t = (np.arange(m) * q + 0.5 * (q - 1)) / sample_rate
    grid = nominal * np.linspace(1.0 - search, 1.0 + search, n_grid)
    score = np.zeros(grid.size)
    for h in range(1, harmonics + 1):
        for i0 in range(0, grid.size, 50):
            fr = grid[i0:i0 + 50]
            score[i0:i0 + 50] += np.abs(np.exp(-2j * np.pi * h * fr[:, None] * t[None, :]) @ e)
    f0 = float(grid[int(np.argmax(score))])
    # fine stage: ±1 coarse step at 1/20 of it (a 0.01 % error drifts 0.1 period in 10 s)
    step = grid[1] - grid[0]
    fine = f0 + np.linspace(-step, step, 41)
    fscore = np.zeros(fine.size)
    for h in range(1, harmonics + 1):
        fscore += np.abs(np.exp(-2j * np.pi * h * fine[:, None] * t[None, :]) @ e)
    return float(fine[int(np.argmax(fscore))])


def fold(values: np.ndarray, sample_rate: float, frequency: float, n_bins: int,
         start_time: float = 0.0) -> np.ndarray:
    """Mean of ``values`` per phase bin of the cycle ``frequency`` (Hz); bin 0 at cycle 0."""
    t = start_time + np.arange(values.size) / sample_rate
    pos = np.mod(t * frequency, 1.0)
    idx = np.minimum((pos * n_bins).astype(np.int64), n_bins - 1)
    s = np.bincount(idx, weights=values, minlength=n_bins)
    c = np.bincount(idx, minlength=n_bins)
    return s / np.maximum(c, 1)


def estimate_fault_phase(y, sample_rate: float, frequency: float, onset_level: float = 0.1,
                         smooth_s: float = 1e-4) -> float:
    """Fault phase (rad, impulse_trains convention) of the impacts in ``y``.

    Folds the smoothed squared signal over the fault period and takes the onset of the
    energy peak: the last bin before the peak where the folded energy is below
    ``onset_level`` of the way from its floor (median) to the peak.
    """
    n_bins = max(16, int(round(sample_rate / frequency)))
    e = np.asarray(y, dtype=float) ** 2
    k = max(1, int(round(smooth_s * sample_rate)))
    if k > 1:
        e = np.convolve(e, np.ones(k) / k, mode="same")
    prof = fold(e, sample_rate, frequency, n_bins)
    ip = int(np.argmax(prof))
    floor = float(np.median(prof))
    level = floor + onset_level * (prof[ip] - floor)
    i = ip
    for _ in range(n_bins):
        if prof[i % n_bins] < level:
            break
        i -= 1
    onset_cycle = ((i + 1) % n_bins) / n_bins  # cycle position of the onset
    # impulse_trains: impacts where f t + phi/(2 pi) is an integer -> phi = -2 pi * onset
    return float(np.mod(-TWO_PI * onset_cycle, TWO_PI))


@dataclass
class Periods:
    """Fault periods cut from a record."""

    starts: np.ndarray        # first sample of each period segment
    impact_times: np.ndarray  # impact time (s) in each segment
    length: int               # samples per segment
    pre: int                  # samples kept before the impact
    matrix: np.ndarray        # (K, length) segments of y


def cut_periods(y, sample_rate: float, frequency: float, phase: float,
                pre_s: float = 2e-4) -> Periods:
    """Cut ``y`` into fault periods, each starting ``pre_s`` seconds before its impact."""
    y = np.asarray(y, dtype=float)
    length = int(math.floor(sample_rate / frequency))
    pre = int(round(pre_s * sample_rate))
    t_k, _ = impact_times(0.0, y.size / sample_rate, frequency, phase)
    starts = np.floor(t_k * sample_rate).astype(np.int64) - pre
    ok = (starts >= 0) & (starts + length <= y.size)
    starts, t_k = starts[ok], t_k[ok]
    mat = y[starts[:, None] + np.arange(length)[None, :]] if starts.size else np.zeros((0, length))
    return Periods(starts, t_k, length, pre, mat)


def rank1(matrix: np.ndarray):
    """Rank-1 decomposition ``matrix ≈ amps[:, None] * template``; template unit-norm."""
    u, s, vt = np.linalg.svd(matrix, full_matrices=False)
    template = vt[0]
    amps = u[:, 0] * s[0]
    if np.sum(amps) < 0:
        template, amps = -template, -amps
    return amps, template


def fit_modulation(amps, t_k, shaft_frequency: float):
    """Fit eq. 2.58 weights ``A (cos(2 pi f_s t_k + theta) + c)`` to per-impact amplitudes.

    Returns ``(A, theta, c, r2)`` with ``A >= 0``; ``r2`` is the explained fraction.
    """
    ang = TWO_PI * shaft_frequency * np.asarray(t_k)
    X = np.column_stack([np.cos(ang), np.sin(ang), np.ones_like(ang)])
    p, *_ = np.linalg.lstsq(X, amps, rcond=None)
    a = float(math.hypot(p[0], p[1]))
    theta = float(math.atan2(-p[1], p[0]))
    c = float(p[2] / a) if a > 0 else 0.0
    res = amps - X @ p
    r2 = 1.0 - float(res @ res) / max(float(amps @ amps), 1e-300)
    return a, theta, c, r2


# ---------------------------------------------------------------------------------------
# Whole pipeline
# ---------------------------------------------------------------------------------------
@dataclass
class Preprocessing:
    """What :func:`identify_fault_model` measured on the record before the fit.

    Frequencies in Hz, phases in rad (:mod:`.impulse_trains` convention). The inner-race
    fields (eq. 2.58 fit of the per-impact amplitudes) and the outer-race fields
    (representative period) are None for the other fault. Stored in the model file's
    provenance (``preprocessing``, None fields left out).
    """

    kinematic_frequency: float
    fault_frequency: float
    phase: float
    periods: int
    shaft_phase: float | None = None
    offset: float | None = None
    modulation_amplitude: float | None = None
    modulation_r2: float | None = None
    n_average: int | None = None
    plain_average_energy_ratio: float | None = None
    representative_period: int | None = None
    representative_correlation: float | None = None
    mode: str = "thesis"
    phase_refined: float | None = None
    identification_seconds: float | None = None

    def to_dict(self) -> dict:
        """The fields that apply, in field order."""
        return {k: v for k, v in asdict(self).items() if v is not None}


@dataclass
class IdentificationResult:
    """Everything :func:`identify_fault_model` found (the model plus diagnostics)."""

    model: HWModel
    u_id: np.ndarray
    y_id: np.ndarray
    yhat_id: np.ndarray
    u_series: np.ndarray
    y_series: np.ndarray
    yhat_series: np.ndarray
    id_mask: np.ndarray
    preprocessing: Preprocessing


@dataclass(frozen=True)
class _Train:
    """The train the fault model is identified with: impacts at ``frequency`` (Hz), inner
    race weighted by eq. 2.58 with ``shaft_frequency`` (Hz), ``shaft_phase`` (rad) and
    ``offset``; pulses ``pulse_width`` (s) wide."""

    modulated: bool
    sample_rate: float
    frequency: float
    shaft_frequency: float
    shaft_phase: float
    offset: float
    pulse_width: float

    def render(self, n: int, phase: float, start_time: float = 0.0) -> np.ndarray:
        """``n`` samples of the train (eq. 2.58 weights for the inner race, else eq. 2.55)
        at fault phase ``phase`` (rad), the first at ``start_time`` (s)."""
        if self.modulated:
            return impulse_train(n, self.sample_rate, self.frequency, phase, start_time,
                                 shaft_frequency=self.shaft_frequency, shaft_phase=self.shaft_phase,
                                 offset=self.offset, pulse_width=self.pulse_width)
        return self.unit(n, phase, start_time)

    def unit(self, n: int, phase: float, start_time: float = 0.0) -> np.ndarray:
        """The same impacts with unit weights (eq. 2.55)."""
        return impulse_train(n, self.sample_rate, self.frequency, phase, start_time, pulse_width=self.pulse_width)


def identify_fault_model(y, sample_rate: float, rpm: float, fault, bearing: Bearing, orders=None,
                         n_breakpoints: int = N_BREAKPOINTS, n_average: int = N_AVERAGE_IR,
                         refine_frequency: bool = True, provenance: dict | None = None, mode: str = "thesis",
                         n_series: int = 8) -> IdentificationResult:
    """Identify the HW model of one fault type from a record of that fault.

    Parameters
    ----------
    y : ndarray, shape (n,)
        Drive-end acceleration (m/s²) while the fault is present.
    sample_rate : float
        Hz.
    rpm : float
        Shaft speed (rev/min).
    fault : FaultState or str
        ``outer_race`` or ``inner_race``.
    bearing : Bearing
        The machine's bearing: gives the kinematic fault frequency; recorded in the model's provenance.
    orders : (nb, nf, nk), optional
        Linear-block orders; default :data:`DEFAULT_ORDERS`.
    n_breakpoints : int
        Breakpoints of the output nonlinearity.
    n_average : int
        Periods averaged for the inner race (appendix B: 38).
    refine_frequency : bool
        Search the fault frequency within ±3 % of the kinematic one (real machines slip).
    mode : "thesis" | "series"
        ``thesis``: identification data as in the thesis (OR one representative period,
        IR the modulation-weighted average of ``n_average`` periods), input one unit impulse.
        ``series``: the record itself over ``n_series`` (OR) or ``n_average`` (IR)
        consecutive periods with the full (modulated) train as input; the impacts then fall
        at varying sub-sample positions, which generalises better at low sample rates.
    n_series : int
        Periods used by ``mode="series"`` for the outer race.
    provenance : dict, optional
        Stored in the model file.

    Returns
    -------
    IdentificationResult
    """
    t0 = time.perf_counter()
    state, y = _checked_record(fault, y)
    is_ir = state == FaultState.INNER_RACE
    nb, nf, nk = orders or DEFAULT_ORDERS[state.label]
    fs = float(sample_rate)
    fr = rpm / 60.0
    # steps 1-3 (module docstring): fault frequency, phase, periods, identification data
    f_kin = bearing.frequencies(rpm).of(state)
    freq, phase, per = _fault_periods(y, fs, f_kin, refine_frequency)
    prep = Preprocessing(float(f_kin), float(freq), float(phase), int(per.matrix.shape[0]))
    if is_ir:
        sel, y_id, theta, c = _weighted_average(per, fr, n_average, prep)
    else:
        (sel, y_id), theta, c = _representative_period(per, prep), 0.0, 0.0
    train = _Train(is_ir, fs, freq, fr, theta, c, 1.0 / fs)
    sel, u_id, y_id = _identification_data(mode, y, per, sel, y_id, train, phase,
                                           n_average if is_ir else n_series)
    prep.mode = mode
    # step 4: the HW fit, then the strictly periodic train aligned with the whole record
    fit = hw_fit(u_id, y_id, nb, nf, nk, n_breakpoints)
    model = HWModel(fault_type=state.label, sample_rate=fs, rpm=float(rpm), fault_frequency=freq,
                    fault_order=freq / fr, b=fit.b, f=fit.f, nk=nk,
                    input_nonlinearity=MonotonePiecewiseLinear.gain(1.0), output_nonlinearity=fit.g,
                    train_offset=c, pulse_width=train.pulse_width)
    yhat_id = model.simulate(u_id)
    phase = refine_phase(model, y, phase, fr, theta, c)  # sub-sample phase scan, ±1/4 period
    prep.phase_refined = phase
    u_series = train.render(y.size, phase)
    yhat_series = model.simulate(u_series)
    id_mask = _identification_mask(y.size, per, sel, mode)
    model.fit = _model_fit(fit, y, yhat_series, per, sel, id_mask, y_id.size, fs)
    prep.identification_seconds = time.perf_counter() - t0
    model.provenance = _provenance(provenance, bearing, prep)
    return IdentificationResult(model, u_id, y_id, yhat_id, u_series, y, yhat_series, id_mask, prep)


def _checked_record(fault, y) -> tuple[FaultState, np.ndarray]:
    """The fault (outer or inner race) and the record as a finite 1-D float array; ValueError
    for another fault or another record."""
    state = parse_fault(fault) if isinstance(fault, str) else FaultState(fault)
    if state not in (FaultState.OUTER_RACE, FaultState.INNER_RACE):
        raise ValueError(f"no HW model for fault {state.label}")
    y = np.asarray(y, dtype=float)
    if y.ndim != 1 or not np.all(np.isfinite(y)):
        raise ValueError("y must be a finite 1-D array")
    return state, y


def _fault_periods(y, sample_rate: float, kinematic_frequency: float, refine_frequency: bool):
    """Steps 1-3 up to the cut: the fault frequency (Hz; the kinematic one refined on the
    data, or not), the fault phase (rad) and the record's whole fault periods (at least 3,
    else ValueError)."""
    freq = refine_fault_frequency(y, sample_rate, kinematic_frequency) if refine_frequency else kinematic_frequency
    phase = estimate_fault_phase(y, sample_rate, freq)
    per = cut_periods(y, sample_rate, freq, phase)
    if per.matrix.shape[0] < 3:
        raise ValueError("record too short: need at least 3 whole fault periods")
    return freq, phase, per


def _weighted_average(per: Periods, shaft_frequency: float, n_average: int, prep: Preprocessing):
    """Inner race (module docstring, step 3): the eq. 2.58 fit of the per-impact amplitudes
    and the modulation-weighted average of the first ``n_average`` periods.

    Returns (indices of the periods used, the average, shaft phase theta (rad), offset c);
    the fit and the plain average's energy ratio go into ``prep``.
    """
    amps, _ = rank1(per.matrix)
    a, theta, c, r2 = fit_modulation(amps, per.impact_times, shaft_frequency)
    m = np.cos(TWO_PI * shaft_frequency * per.impact_times + theta) + c
    n_avg = min(n_average, per.matrix.shape[0])
    sel = np.arange(n_avg)
    y_id = (m[sel] @ per.matrix[sel]) / float(m[sel] @ m[sel])
    plain = per.matrix[sel].mean(axis=0)
    prep.shaft_phase, prep.offset, prep.modulation_amplitude, prep.modulation_r2 = theta, c, a, r2
    prep.n_average = int(n_avg)
    prep.plain_average_energy_ratio = float(plain @ plain) / max(float(y_id @ y_id), 1e-300)
    return sel, y_id, theta, c


def _representative_period(per: Periods, prep: Preprocessing):
    """Outer race (module docstring, step 3): the measured period that correlates best with
    the rank-1 template; returns (its index as a 1-array, the period), noted in ``prep``."""
    _, template = rank1(per.matrix)
    corr = (per.matrix @ template) / np.maximum(np.linalg.norm(per.matrix, axis=1), 1e-300)
    best = int(np.argmax(corr))
    prep.representative_period, prep.representative_correlation = best, float(corr[best])
    return np.array([best]), per.matrix[best].copy()


def _identification_data(mode: str, y, per: Periods, sel, y_id, train: _Train, phase: float, n_series: int):
    """Input and output of the HW fit for ``mode`` (:func:`identify_fault_model`) and the
    periods they cover: ``thesis`` keeps ``y_id`` of ``sel`` with the unit train over its
    segment (the impact ``per.pre`` samples in); ``series`` takes the record over the first
    ``n_series`` periods with the full train."""
    if mode == "thesis":
        s0 = per.starts[sel[0]]
        return sel, train.unit(per.length, phase, start_time=s0 / train.sample_rate), y_id
    if mode == "series":
        sel = np.arange(min(n_series, per.matrix.shape[0]))
        s0, s1 = per.starts[sel[0]], per.starts[sel[-1]] + per.length
        return sel, train.render(s1 - s0, phase, start_time=s0 / train.sample_rate), y[s0:s1].copy()
    raise ValueError(f"mode must be 'thesis' or 'series', got {mode!r}")


def _identification_mask(n: int, per: Periods, sel, mode: str) -> np.ndarray:
    """Samples of the record that the fit saw (the periods ``sel``; ``series``: their span)."""
    id_mask = np.zeros(n, dtype=bool)
    for s in per.starts[sel]:
        id_mask[s:s + per.length] = True
    if mode == "series":
        id_mask[per.starts[sel[0]]:per.starts[sel[-1]] + per.length] = True
    return id_mask


def _model_fit(fit, y, yhat_series, per: Periods, sel, id_mask, n_identification: int, sample_rate: float) -> ModelFit:
    """Fit figures of the model: on its identification data (``fit``, the HW fit), on the
    held-back samples from the first whole period on, per held-back period, and on the
    whole series from the first period on (``yhat_series``: the model driven by the
    strictly periodic train)."""
    held = ~id_mask
    held[: per.starts[0]] = False  # before the first whole period: no full model response
    used = set(sel.tolist())
    per_fits = [fit_percent(y[s:s + per.length], yhat_series[s:s + per.length])
                for i, s in enumerate(per.starts) if i not in used]
    return ModelFit(
        identification=fit.fit,
        identification_linear_only=fit.fit_linear,
        held_back=fit_percent(y[held], yhat_series[held]),
        held_back_periods_median=float(np.median(per_fits)) if per_fits else None,
        time_series=fit_percent(y[per.starts[0]:], yhat_series[per.starts[0]:]),
        # the same with the single least-squares amplitude: how much a strictly periodic
        # train can explain at all (real impacts wander; see shared/diagnosis-notes.md)
        time_series_ls_amplitude=_ls_scaled_fit(y[per.starts[0]:], yhat_series[per.starts[0]:]),
        identification_samples=int(n_identification),
        held_back_samples=int(held.sum()),
        series_seconds=y.size / sample_rate,
    )


def _provenance(given: dict | None, bearing: Bearing, prep: Preprocessing) -> dict:
    """The model file's provenance: ``given``, the date (UTC, unless given), the bearing and
    the preprocessing."""
    out = dict(given or {})
    out.setdefault("date", time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    out["bearing"] = bearing.to_dict()
    out["preprocessing"] = prep.to_dict()
    return out


def _ls_scaled_fit(y, yhat) -> tuple[float, float]:
    """(fit %, gain) of ``gain * yhat`` with the least-squares gain."""
    den = float(np.sum(yhat * yhat))
    gain = float(np.sum(y * yhat)) / den if den > 0 else 0.0
    return fit_percent(y, gain * yhat), gain


def refine_phase(model: HWModel, y, phase: float, shaft_frequency: float, theta: float,
                 c: float, span: float = 0.25, step_samples: float = 0.25,
                 max_seconds: float = 2.0) -> float:
    """Fault phase (rad) within ``phase ± span`` periods that maximises the time-series fit
    of ``model`` on (the first ``max_seconds`` of) ``y``; grid step ``step_samples``."""
    fs, freq = model.sample_rate, model.fault_frequency
    n = int(min(y.size, max_seconds * fs))
    yy = y[:n]
    period = fs / freq
    best, best_fit = phase, -np.inf

    train = _Train(model.modulated, fs, freq, shaft_frequency, theta, c, model.pulse_width)

    def scan(center, half, step):
        nonlocal best, best_fit
        for d in np.arange(-half, half + 1e-9, step) / period * TWO_PI:
            fit = fit_percent(yy, model.simulate(train.render(n, center + d)))
            if fit > best_fit:
                best, best_fit = center + d, fit

    # coarse step: 2 samples at 48 kHz, 40 us in general (a quarter of a 6 kHz cycle), so the
    # coarse scan cannot step over the fit's oscillating lobes at low sample rates
    coarse = max(step_samples, min(2.0, 4e-5 * fs))
    scan(phase, span * period, coarse)          # coarse over ±span periods
    scan(best, coarse, step_samples)            # fine: every step_samples around the best
    return float(np.mod(best, TWO_PI))
