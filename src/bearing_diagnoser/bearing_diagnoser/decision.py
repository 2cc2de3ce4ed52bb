"""The incremental fault-state decision (thesis section 3.2, with the fixes of diagnosis-notes.md).

:class:`Diagnoser` is fed, per fault hypothesis (OUTER_RACE, INNER_RACE), the chunks an
observer publishes (residual r, estimate ŷ, impulse train u; the measurement is rebuilt
as y = r + ŷ) and returns decisions as sliding windows become due.

Per window and hypothesis h it computes

* ``c_h`` — CFAR periodicity (decision statistic): the band-passed energy envelope of y
  folded at the fault period (phase and ±3 % period searched), divided by the same
  statistic at decoy periods clear of every bearing line (:mod:`.periodicity`,
  :mod:`.bearing_lines`).  The threshold comes from a stated per-window false-alarm
  probability on white noise (:mod:`.calibration`); scores are published as c_h / threshold
  (≥ 1 = significant).
* ``E_h`` — "the model explains the data": 1 − ‖r‖² / ‖y − ȳ‖² (fraction of measurement
  energy the train-driven observer removes).  It separates "the OR model explains the
  data" from "the OR observer injects its own impulses" (thesis 3.2.3: with a fixed drive
  gain, the residual matches the train even in NORMAL operation; E < 0 then).  Used to break
  ties between hypotheses, optionally to require the model to explain (``min_explained``).
* ``xcorr_h`` — the thesis-literal cross-correlation of |r| with u (section 3.2, Figs.
  3.9-3.12), evaluated per window at envelope-block resolution as the largest Pearson
  correlation over lags 0..2 ms (the impulse response follows its impulse).  Reported,
  not used for the decision: diagnosis-notes measured 0/56 correct with it.

Explain-away: every hypothesis but the strongest is re-tested after the strongest one's
impact phases are masked in the envelope (IR impacts fold into three phase clusters at
the OR period because 2·BPFI ≈ 3·BPFO; without this step simulated IR windows were
UNKNOWN about half the time).

Window label: NORMAL if the window RMS is below ``rms_floor``, or its newest quarter is
quiet (``quiet_ratio``: the activity stopped), or nothing is significant (unless the
band-passed kurtosis exceeds its noise threshold: UNKNOWN = impulsive but aperiodic);
the significant hypothesis if only one is; if both are, the one whose c is ``dominance``
times larger, else the one the model explains better by ``explained_margin``, else
UNKNOWN.  The first window sets the initial state; afterwards the published state
changes only when ``k_of_n[0]`` of the last ``k_of_n[1]`` window labels agree
(``unknown_k_of_n`` for UNKNOWN: hysteresis); the onset is back-dated to the middle
between the last window start with the old state and the first with the new one, plus
half a window (a window takes the label of the state filling most of it).

Confidence (0..1) of a window label: for a fault, (1 − threshold/c) × clarity, clarity =
how far c exceeds the other hypothesis' c relative to ``dominance``; for NORMAL, how far
the largest c is below the threshold; the published confidence is the mean over the
recent windows that agree with the state.

The default ``pfa`` per model set gives the same number of window exceedances per hour
(36 per hypothesis on white noise) at each set's hop: 1e-4 at 0.01 s, 5e-4 at 0.05 s.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np

from bearing_common.states import FaultState

from .bearing_lines import decoy_frequencies
from .calibration import calibrate
from .periodicity import (
    EnergyEnvelope,
    cfar_periodicity,
    cfar_ses,
    explain_away,
    impact_phase_mask,
    period_grid,
    train_correlation,
)

HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE)


@dataclass(frozen=True)
class DiagnoserConfig:
    """Parameters of the decision; see :data:`MODEL_SET_DEFAULTS` for the per-set values.

    Attributes
    ----------
    window_s, hop_s : float
        Sliding window length and hop (s).
    band : (lo, hi)
        Band-pass (Hz) before the energy envelope: the structural resonances the impacts excite.
    bins : int
        Phase bins of the folded profile.
    search : float
        Relative period search (± fraction) for slip and speed error.
    n_decoys : int
        Decoy periods per hypothesis.
    pfa : float
        False-alarm probability per window and hypothesis on white noise; sets
        ``threshold`` and ``kurtosis_threshold`` through :func:`.calibration.calibrate`.
    threshold, kurtosis_threshold : float or None
        Explicit thresholds (None = derive from ``pfa``).
    dominance : float
        Ratio of CFAR statistics needed to choose one hypothesis when both are significant.
    explained_margin : float
        Difference of model-explains fractions that breaks a tie between hypotheses.
    min_explained : float or None
        If set, a fault label also needs E_h ≥ this (the model must explain the data).
    rms_floor : float
        Window RMS (m/s²) below which the window is NORMAL without further test.
    k_of_n : (k, n)
        Hysteresis: k of the last n window labels must agree to change state.  The first
        window sets the initial state directly (unless it is UNKNOWN: the state starts
        NORMAL and UNKNOWN needs its votes).
    unknown_k_of_n : (k, n) or None
        The same for UNKNOWN, slower on purpose: windows that straddle a change often
        look "abnormal but neither model" for a moment, and one outlier sample raises the
        kurtosis of every overlapping window that holds it.  None (default): k =
        ceil(window/hop) + 1, n = k + 2, i.e. the evidence must span more than one
        window (sim sets: 6 of 8; CWRU set: 5 of 7).  Measured on 600 s of white noise
        at 48 kHz, 4 of 5 gave 2 UNKNOWN false alarms.
    quiet_tail, quiet_ratio : float
        A window whose newest ``quiet_tail`` fraction holds less than ``quiet_ratio`` times
        the mean band energy of the older part is labelled NORMAL ("the activity
        stopped"): lets fault → normal changes be seen before the last impacts leave
        the window.
    max_lag_s : float
        A window is decided without a lagging hypothesis stream once the other stream is
        this far (s) ahead of it.
    use_kurtosis : bool
        Label impulsive-but-aperiodic windows UNKNOWN (else NORMAL).
    statistic : ``"fold"`` or ``"ses"``
        Periodicity statistic: envelope folded at the fault period (default), or the
        classical squared envelope spectrum at the fault harmonics (``--method envelope``).
    ses_harmonics : int
        Highest harmonic tested by the envelope-spectrum statistic (default 3); harmonics
        within 3 % of a harmonic of the other race frequency are skipped
        (:meth:`Diagnoser.ses_harmonics`): 3·BPFO and 2·BPFI lie only 0.7 % apart.
    envelope_window_s : float
        Window of the envelope-spectrum reference (``--method envelope``): its frequency
        resolution is 1/window, so it needs longer windows than the folding statistic
        (0.05 s windows missed every simulated IR segment; 0.1 s found them).
    xcorr_lag_s : float
        Lags 0..this (s) searched by the thesis-literal correlation of |r| with u.
    explain_away : bool
        Test every hypothesis but the strongest after masking the strongest one's impact
        phases (IR impacts fold into three clusters at the OR period, since 2·BPFI ≈ 3·BPFO).
    nominal_rpm : float
        Speed (rev/min) at which the decoy ratios and the calibration are computed.
    """

    window_s: float = 0.05
    hop_s: float = 0.01
    band: tuple[float, float] = (1500.0, 8000.0)
    bins: int = 16
    search: float = 0.03
    n_decoys: int = 6
    pfa: float = 1e-4
    threshold: float | None = None
    kurtosis_threshold: float | None = None
    dominance: float = 1.5
    explained_margin: float = 0.1
    min_explained: float | None = None
    rms_floor: float = 1e-2
    k_of_n: tuple[int, int] = (2, 3)
    unknown_k_of_n: tuple[int, int] | None = None
    quiet_tail: float = 0.25
    quiet_ratio: float = 0.15
    max_lag_s: float = 1.0
    use_kurtosis: bool = True
    statistic: str = "fold"
    xcorr_lag_s: float = 2e-3
    ses_harmonics: int = 3
    envelope_window_s: float = 0.1
    explain_away: bool = True
    nominal_rpm: float = 1800.0


#: Defaults per model set, with reasons:
#: sim_48k / sim_12k: simulator output, strong clean impacts; 0.05 s windows, 0.01 s hop and
#:   2-of-3 hysteresis keep every detection within 0.05 s of the change (OR period 9.3 ms:
#:   5 impacts per window); band 1.5-8 kHz around the housing modes (2.2-3.6 kHz);
#:   rms_floor 0.05 m/s² (0.005 g), far below any real sensor noise (CWRU normal: 0.7 m/s²)
#:   but above the noise-free simulator's NORMAL state (≈ 2e-4 m/s²); pfa 1e-4.
#: cwru_de_6205: real 12 kHz recordings; 2·BPFI and 3·BPFO are only 0.7 % apart and real
#:   impacts wander, so 0.2 s windows (hop 0.05 s, 3-of-4 hysteresis; 21 OR impacts per
#:   window) keep IR energy out of the OR test; band 2-5 kHz where the CWRU impacts ring
#:   (README envelope check); pfa 5e-4 (same exceedances per hour as the sim sets).
MODEL_SET_DEFAULTS: dict[str, DiagnoserConfig] = {
    "sim_48k": DiagnoserConfig(window_s=0.05, hop_s=0.01, band=(1500.0, 8000.0), rms_floor=5e-2,
                               nominal_rpm=1800.0),
    "sim_12k": DiagnoserConfig(window_s=0.05, hop_s=0.01, band=(1500.0, 5500.0), rms_floor=5e-2,
                               nominal_rpm=1800.0),
    "cwru_de_6205": DiagnoserConfig(window_s=0.2, hop_s=0.05, band=(2000.0, 5000.0), rms_floor=1e-3,
                                    pfa=5e-4, k_of_n=(3, 4), envelope_window_s=0.2,
                                    nominal_rpm=1797.0),
}


def config_for(model_set: str, **overrides) -> DiagnoserConfig:
    """Defaults of ``model_set`` (unknown names get the sim_48k defaults) with overrides."""
    base = MODEL_SET_DEFAULTS.get(model_set, MODEL_SET_DEFAULTS["sim_48k"])
    return replace(base, **overrides) if overrides else base


@dataclass
class Decision:
    """One window's decision.

    Times in seconds of signal time (sample index / sample rate from stream start).
    ``state`` is the published (hysteresis-filtered) state, ``label`` the window's own
    label; ``scores`` maps names to dimensionless scores: ``outer_race`` / ``inner_race`` =
    CFAR periodicity / threshold (≥ 1 significant), ``*_explained`` = model-explains
    fraction, ``*_xcorr`` = thesis-literal correlation, ``kurtosis`` of the band-passed window.
    """

    time: float
    window_start: float
    window_end: float
    label: FaultState
    state: FaultState
    confidence: float
    onset: float
    changed: bool
    scores: dict[str, float] = field(default_factory=dict)
    detail: str = ""


class _Stream:
    """Envelope blocks of one hypothesis stream, indexed from the stream's sample 0."""

    def __init__(self, sample_rate: float, cfg: DiagnoserConfig):
        self.sample_rate = sample_rate
        self.env = EnergyEnvelope(sample_rate, cfg.band)
        self.next_sample = None  # index of the next expected sample
        self.first_block = None
        self.blocks: dict[str, list[np.ndarray]] = {k: [] for k in EnergyEnvelope.KEYS}
        self.arrays: dict[str, np.ndarray] = {k: np.zeros(0) for k in EnergyEnvelope.KEYS}
        self.fault_hz = None
        self.has_model = False

    @property
    def n_blocks(self) -> int:
        """Absolute index one past the last completed block."""
        if self.first_block is None:
            return 0
        return self.first_block + self.arrays["env"].size + sum(a.size for a in self.blocks["env"])

    def consolidate(self):
        if self.blocks["env"]:
            for k in EnergyEnvelope.KEYS:
                self.arrays[k] = np.concatenate([self.arrays[k]] + self.blocks[k])
                self.blocks[k] = []

    def push(self, first_index: int, y, r, u):
        d = self.env.decimation
        if self.next_sample is None:
            skip = (-first_index) % d  # align blocks to multiples of D
            self.first_block = (first_index + skip) // d
            y, r, u = y[skip:], r[skip:], u[skip:]
            self.next_sample = first_index + skip
        elif first_index > self.next_sample:  # gap: pad with NaN blocks, restart alignment
            self.consolidate()
            gap_blocks = (first_index - self.next_sample + d - 1) // d + 1
            for k in EnergyEnvelope.KEYS:
                self.arrays[k] = np.concatenate([self.arrays[k], np.full(gap_blocks, np.nan)])
            self.env = EnergyEnvelope(self.sample_rate, self.env.band, d)
            target = self.n_blocks * d
            skip = target - first_index
            y, r, u = y[skip:], r[skip:], u[skip:]
            first_index = target
            self.next_sample = target
        elif first_index < self.next_sample:  # overlap / repeat: drop what we have seen
            skip = self.next_sample - first_index
            y, r, u = y[skip:], r[skip:], u[skip:]
        if y.size == 0:
            return
        out = self.env.push(y, r, u)
        for k in EnergyEnvelope.KEYS:
            self.blocks[k].append(out[k])
        self.next_sample += y.size

    def window(self, b0: int, b1: int) -> dict[str, np.ndarray] | None:
        self.consolidate()
        i0, i1 = b0 - self.first_block, b1 - self.first_block
        if self.first_block is None or i0 < 0 or i1 > self.arrays["env"].size:
            return None
        return {k: v[i0:i1] for k, v in self.arrays.items()}

    def trim(self, keep_from_block: int):
        self.consolidate()
        cut = keep_from_block - self.first_block
        if cut > 0:
            for k in EnergyEnvelope.KEYS:
                self.arrays[k] = self.arrays[k][cut:]
            self.first_block += cut


class Diagnoser:
    """Incremental diagnoser: feed observer chunks, get decisions as windows become due.

    Parameters
    ----------
    config : DiagnoserConfig, optional
        Decision parameters (default: :func:`config_for` ``(model_set)``).
    model_set : str
        Name reported with decisions and used to pick defaults.
    hypotheses : sequence of FaultState
        Streams to expect (default OUTER_RACE and INNER_RACE).
    sample_rate : float, optional
        Hz of the streams, when known in advance (lets :meth:`thresholds` be derived before
        the first chunk); otherwise taken from the first chunk.

    Thresholds are derived on first use from ``config.pfa`` (:func:`.calibration.calibrate`,
    cached per configuration and sample rate).
    """

    def __init__(self, config: DiagnoserConfig | None = None, model_set: str = "sim_48k",
                 hypotheses=HYPOTHESES, sample_rate: float | None = None):
        self.model_set = model_set
        self.config = config or config_for(model_set)
        self.hypotheses = tuple(FaultState(h) for h in hypotheses)
        self._streams: dict[FaultState, _Stream] = {}
        self._sample_rate: float | None = None if sample_rate is None else float(sample_rate)
        self._next_window = 0  # index of the next window to decide
        self._unknown_k_of_n = self.config.unknown_k_of_n or self.default_unknown_k_of_n(self.config)
        self._labels: deque = deque(maxlen=max(self.config.k_of_n[1], self._unknown_k_of_n[1]))
        self._decided = False
        self.state = FaultState.NORMAL
        self.onset = 0.0
        self.confidence = 0.0
        self._last_window_of: dict[FaultState, float] = {}
        self._thresholds = None
        self._decoy_ratio: dict[FaultState, np.ndarray] = {}
        self.history: list[Decision] = []
        self.keep_history = True

    @staticmethod
    def default_unknown_k_of_n(cfg: DiagnoserConfig) -> tuple[int, int]:
        """UNKNOWN hysteresis spanning more than one window: (ceil(W/H) + 1, that + 2)."""
        k = int(math.ceil(cfg.window_s / cfg.hop_s - 1e-9)) + 1
        return k, k + 2

    # -- thresholds -------------------------------------------------------------------
    def thresholds(self) -> tuple[float, float]:
        """(CFAR threshold, kurtosis threshold) in use; derived from pfa on first call."""
        if self._thresholds is None:
            thr, kthr = self.config.threshold, self.config.kurtosis_threshold
            if thr is None or kthr is None:
                cal = calibrate(self.config, self._sample_rate or 48000.0, type(self))
                thr = cal["threshold"] if thr is None else thr
                kthr = cal["kurtosis_threshold"] if kthr is None else kthr
            self._thresholds = (float(thr), float(kthr))
        return self._thresholds

    def decoys(self, hypothesis: FaultState, fault_hz: float) -> np.ndarray:
        """Decoy frequencies (Hz) for ``hypothesis`` at fault frequency ``fault_hz``.

        Decoys are fixed multiples of the fault frequency (all bearing lines scale with
        speed), computed once at the nominal speed and rescaled.
        """
        if hypothesis not in self._decoy_ratio:
            from bearing_common.bearings import CATALOG, fault_frequency
            DRIVE_END_6205 = CATALOG["6205"]  # TODO(issue 11): bearing as input
            f0 = fault_frequency(DRIVE_END_6205, hypothesis, self.config.nominal_rpm)
            self._decoy_ratio[hypothesis] = decoy_frequencies(
                f0, self.config.nominal_rpm, self.config.n_decoys, self.config.window_s,
                self.config.search) / f0
        return self._decoy_ratio[hypothesis] * fault_hz

    def ses_harmonics(self, hypothesis: FaultState) -> tuple[int, ...]:
        """Harmonics of ``hypothesis``' frequency used by the envelope-spectrum statistic.

        1..``ses_harmonics``, minus every harmonic that lies within 3 % of a harmonic
        (1..5) of the other race frequency, where the other fault would pass for this
        one: for the 6205, OR keeps (1, 2) and IR keeps (1, 3) (3·BPFO ≈ 2·BPFI).
        """
        from bearing_common.bearings import CATALOG, fault_frequency
        DRIVE_END_6205 = CATALOG["6205"]  # TODO(issue 11): bearing as input
        f = fault_frequency(DRIVE_END_6205, hypothesis, self.config.nominal_rpm)
        other = [fault_frequency(DRIVE_END_6205, h, self.config.nominal_rpm) for h in HYPOTHESES if h != hypothesis]
        return tuple(k for k in range(1, self.config.ses_harmonics + 1)
                     if all(abs(k * f / (m * g) - 1.0) > 0.03 for g in other for m in range(1, 6)))

    # -- feeding ----------------------------------------------------------------------
    def update(self, hypothesis, first_sample_index: int, sample_rate: float, residual,
               estimate=None, impulse_train=None, fault_frequency: float | None = None) -> list[Decision]:
        """Feed one observer chunk; return the decisions that became due (oldest first).

        Parameters
        ----------
        hypothesis : FaultState or int
            OUTER_RACE (1) or INNER_RACE (2).
        first_sample_index : int
            Index of the chunk's first sample since the stream began (Residual message
            ``first_sample_index``); time = index / sample_rate.
        sample_rate : float
            Hz; must be the same for every chunk and stream.
        residual, estimate, impulse_train : array_like, shape (n,)
            r (m/s²), ŷ (m/s², None = 0: then y = r, e.g. a model-free stream), u
            (dimensionless, None = no train).  y = r + ŷ is the measurement.
        fault_frequency : float
            Hz at which the train was built (BPFO or BPFI at the current speed).
        """
        h = FaultState(hypothesis)
        if h not in self.hypotheses:
            raise ValueError(f"unexpected hypothesis {h.label}; expected {[x.label for x in self.hypotheses]}")
        if not (sample_rate and sample_rate > 0):
            raise ValueError(f"sample_rate must be > 0, got {sample_rate}")
        if self._sample_rate is None:
            self._sample_rate = float(sample_rate)
        elif abs(sample_rate - self._sample_rate) > 1e-9 * self._sample_rate:
            raise ValueError(f"sample rate changed from {self._sample_rate} to {sample_rate} Hz")
        if fault_frequency is None or not fault_frequency > 0:
            raise ValueError("fault_frequency (Hz) must be > 0")
        r = np.asarray(residual, dtype=float)
        e = np.zeros_like(r) if estimate is None else np.asarray(estimate, dtype=float)
        u = np.zeros_like(r) if impulse_train is None else np.asarray(impulse_train, dtype=float)
        if not (r.shape == e.shape == u.shape) or r.ndim != 1:
            raise ValueError("residual, estimate and impulse_train must be 1-D and of equal length")
        st = self._streams.get(h)
        if st is None:
            st = self._streams[h] = _Stream(self._sample_rate, self.config)
        st.fault_hz = float(fault_frequency)
        st.has_model = st.has_model or estimate is not None
        st.push(int(first_sample_index), r + e, r, u)
        return self._run()

    def flush(self) -> list[Decision]:
        """Decide every complete window with whatever streams exist (end of data)."""
        return self._run(final=True)

    # -- deciding ---------------------------------------------------------------------
    def _geometry(self):
        st = next(iter(self._streams.values()))
        fe = st.env.envelope_rate
        w = max(1, int(round(self.config.window_s * fe)))
        hop = max(1, int(round(self.config.hop_s * fe)))
        return fe, w, hop

    def _run(self, final: bool = False) -> list[Decision]:
        out: list[Decision] = []
        if not self._streams:
            return out
        fe, w, hop = self._geometry()
        lag_blocks = self.config.max_lag_s * fe
        while True:
            b0 = self._next_window * hop
            b1 = b0 + w
            ready = {h: s for h, s in self._streams.items() if s.n_blocks >= b1}
            if not ready:
                break
            missing = [h for h in self.hypotheses if h not in ready]
            if missing and not final:
                lead = max(s.n_blocks for s in self._streams.values())
                if lead - b1 < lag_blocks:
                    break
            d = self._decide(ready, b0, b1, fe, missing)
            if d is not None:
                out.append(d)
            self._next_window += 1
            for s in self._streams.values():
                s.trim(self._next_window * hop)
        if self.keep_history:
            self.history.extend(out)
        return out

    def _cfar(self, h: FaultState, env: np.ndarray, fe: float, b0: int, fault_hz: float):
        cfg = self.config
        if cfg.statistic == "ses":
            return cfar_ses(env, fe, fault_hz, self.decoys(h, fault_hz), cfg.search, self.ses_harmonics(h))
        grid = period_grid(fault_hz, cfg.window_s, cfg.bins, cfg.search)
        return cfar_periodicity(env, fe, fault_hz, self.decoys(h, fault_hz), grid, b0, cfg.bins)

    def window_scores(self, ready: dict, b0: int, b1: int, fe: float) -> dict[str, float] | None:
        """Statistics of one window (see module docstring); None if the window has gaps.

        ``<h>_cfar`` is the CFAR periodicity of hypothesis h; for every hypothesis but the
        strongest it is computed after explaining the strongest one away
        (:func:`.periodicity.impact_phase_mask`), ``<h>_cfar_raw`` keeps the value before.
        """
        cfg = self.config
        scores: dict[str, float] = {}
        wins = {}
        for h, st in ready.items():
            win = st.window(b0, b1)
            if win is None or not np.all(np.isfinite(win["env"])):
                return None
            wins[h] = win
            n = win["env"].size * st.env.decimation
            ratio, _, best_hz = self._cfar(h, win["env"], fe, b0, st.fault_hz)
            scores[f"{h.label}_cfar"] = scores[f"{h.label}_cfar_raw"] = ratio
            scores[f"{h.label}_hz"] = best_hz
            sy, sy2 = win["y"].sum(), win["y2"].sum()
            var_y = sy2 - sy * sy / n
            if st.has_model:
                scores[f"{h.label}_explained"] = float(1.0 - win["r2"].sum() / var_y) if var_y > 0 else 0.0
                scores[f"{h.label}_xcorr"] = train_correlation(win["ar"], win["u"], cfg.xcorr_lag_s * fe)
            if "rms" not in scores:
                scores["rms"] = float(math.sqrt(max(var_y, 0.0) / n))
                m2 = win["env"].mean()
                q = max(1, int(round(cfg.quiet_tail * win["env"].size)))
                older = win["env"][:-q].mean() if win["env"].size > q else m2
                scores["tail_ratio"] = float(win["env"][-q:].mean() / older) if older > 0 else 1.0
                scores["kurtosis"] = float(win["b4"].mean() / (m2 * m2)) if m2 > 0 else 0.0
        if len(wins) > 1 and cfg.explain_away:
            best = max(wins, key=lambda h: scores[f"{h.label}_cfar"])
            mask = impact_phase_mask(wins[best]["env"], fe, scores[f"{best.label}_hz"], b0, cfg.bins)
            for h in wins:
                if h != best:
                    env = explain_away(wins[h]["env"], mask)
                    scores[f"{h.label}_cfar"] = self._cfar(h, env, fe, b0, self._streams[h].fault_hz)[0]
        return scores

    def _label(self, scores: dict[str, float], hyps) -> tuple[FaultState, float]:
        """Window label and its confidence in [0, 1]."""
        cfg = self.config
        thr, kthr = self.thresholds()
        c = {h: scores.get(f"{h.label}_cfar", float("nan")) for h in hyps}
        for h in hyps:
            scores[h.label] = c[h] / thr
        valid = {h: v for h, v in c.items() if np.isfinite(v)}
        cmax = max(valid.values()) if valid else 0.0
        normal_conf = float(np.clip((thr - cmax) / max(thr - 1.0, 1e-9), 0.0, 1.0))
        if scores["rms"] < cfg.rms_floor:
            return FaultState.NORMAL, 1.0
        if scores.get("tail_ratio", 1.0) < cfg.quiet_ratio:
            return FaultState.NORMAL, float(1.0 - scores["tail_ratio"] / cfg.quiet_ratio)
        sig = [h for h, v in valid.items() if v >= thr]
        if cfg.min_explained is not None:
            sig = [h for h in sig if scores.get(f"{h.label}_explained", 1.0) >= cfg.min_explained]
        if not sig:
            if cfg.use_kurtosis and scores["kurtosis"] > kthr:
                return FaultState.UNKNOWN, float(np.clip(1.0 - kthr / scores["kurtosis"], 0.0, 1.0))
            return FaultState.NORMAL, normal_conf
        sig.sort(key=lambda h: valid[h], reverse=True)
        best = sig[0]
        others = [v for h, v in valid.items() if h != best]
        dom = valid[best] / max(others) if others and max(others) > 0 else float("inf")
        strength = float(np.clip(1.0 - thr / valid[best], 0.0, 1.0))
        clarity = float(np.clip((dom - 1.0) / (cfg.dominance - 1.0), 0.0, 1.0))
        if len(sig) == 1 or dom >= cfg.dominance:
            return best, strength * clarity
        second = sig[1]
        eb = scores.get(f"{best.label}_explained")
        es = scores.get(f"{second.label}_explained")
        if eb is not None and es is not None:
            if eb - es >= cfg.explained_margin:
                return best, 0.5 * strength
            if es - eb >= cfg.explained_margin:
                return second, 0.5 * float(np.clip(1.0 - thr / valid[second], 0.0, 1.0))
        return FaultState.UNKNOWN, float(np.clip(1.0 - 1.0 / dom, 0.0, 1.0))

    def _decide(self, ready, b0, b1, fe, missing) -> Decision | None:
        scores = self.window_scores(ready, b0, b1, fe)
        if scores is None:
            return None
        t0, t1 = b0 / fe, b1 / fe
        label, conf = self._label(scores, [h for h in self.hypotheses if h in ready])
        self._labels.append((label, conf, t0, t1))
        changed = False
        if not self._decided and label != FaultState.UNKNOWN:
            # the first window sets the initial state (no earlier state to hold on to);
            # UNKNOWN, the catch-all, still needs its votes
            self.state, self.onset, changed = label, t0, True
            self._decided = True
        else:
            self._decided = True
            k, n = self._unknown_k_of_n if label == FaultState.UNKNOWN else self.config.k_of_n
            recent = list(self._labels)[-n:]
            votes = [x for x in recent if x[0] == label]
            if label != self.state and len(votes) >= k:
                first_new = votes[0][2]
                last_old = self._last_window_of.get(self.state, self.onset)
                onset = 0.5 * (first_new + min(last_old, first_new)) + 0.5 * (t1 - t0)
                self.state, self.onset, changed = label, float(np.clip(onset, self.onset, t1)), True
                self._labels.clear()
                self._labels.extend(votes)
        if label == self.state:
            self._last_window_of[label] = t0
        same = [x[1] for x in self._labels if x[0] == self.state]
        self.confidence = float(np.mean(same)) if same else 0.0
        detail = ("decided without " + ", ".join(h.label for h in missing)) if missing else ""
        return Decision(time=t1, window_start=t0, window_end=t1, label=label, state=self.state,
                        confidence=self.confidence, onset=self.onset, changed=changed,
                        scores=scores, detail=detail)
