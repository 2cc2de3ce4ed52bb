"""The incremental fault-state decision (thesis section 3.2, taken further): observer chunks in, decisions out.

:class:`Diagnoser` is fed, per observer stream (OUTER_RACE, INNER_RACE), the chunks an
observer publishes — residual r, estimate ŷ, impulse train u — and rebuilds the measurement
as y = r + ŷ. Windows are decided as they become due by one of two front ends
(:mod:`.decision_config`):

* ``spectral`` (real machines): y of either stream goes to :class:`.spectral_engine.SpectralEngine`
  (one measurement; either observer may lag or die); each window's p-values become a label
  (:mod:`.spectral_labels`) over OUTER_RACE, INNER_RACE and BALL;
* ``fold`` (simulator model sets): per-stream energy-envelope blocks, scored and labelled
  by :class:`.fold_scores.FoldScorer`; a stream that lags by more than ``max_lag_s`` is left
  out if it never arrived (one observer deployed), and holds the decision (no window is
  decided, the published state stands) if it went silent (a dead observer), until it is back.

Both report the thesis' own blocks per observer stream and window — ``<h>_explained``
(fraction of the measurement the train-driven model removes, 1 − ‖r‖²/‖y − ȳ‖²) and
``<h>_xcorr`` (cross-correlation of |r| with the train, section 3.2) — measured, not
decided on. Labels go through :class:`.state_tracker.StateTracker` (hysteresis, onsets).
"""

from __future__ import annotations

import math

import numpy as np

from bearing_common.bearings import Bearing, load_bearing
from bearing_common.states import FaultState
from bearing_common.units import sample_rate_problem
from bearing_observer.model_sets import NONE, SHIPPED

from . import kernels
from .calibration import calibrate
from .decision_config import DiagnoserConfig, config_for
from .fold_scores import FoldScorer
from .periodicity import XCORR_LAG_S, EnergyEnvelope, train_correlation
from .spectral_engine import SpectralEngine, WindowEvidence
from .spectral_labels import label_window, significance_level
from .state_tracker import Decision, StateTracker
from .window_buffer import StreamBlocks

#: The observer streams a diagnoser takes.
STREAMS = (FaultState.OUTER_RACE, FaultState.INNER_RACE)
_STREAM = {int(h): h for h in STREAMS}  # value or FaultState -> FaultState

__all__ = ["STREAMS", "Decision", "Diagnoser"]


class Diagnoser:
    """Incremental diagnoser: feed observer chunks, get decisions as windows become due.

    Parameters
    ----------
    config : DiagnoserConfig, optional
        Decision parameters (default: :func:`.decision_config.config_for` ``(model_set)``).
    model_set : str
        Name reported with decisions and used to pick defaults.
    bearing : Bearing or str, optional
        The monitored bearing (catalog name, YAML path or Bearing; default the 6205).
    sample_rate : float, optional
        Hz of the streams, when known in advance (lets :meth:`thresholds` be derived before
        the first chunk); otherwise taken from the first chunk.
    """

    def __init__(self, config: DiagnoserConfig | None = None, model_set: str = "",
                 bearing: Bearing | str | None = None, sample_rate: float | None = None):
        self.model_set = model_set
        self.config = config or config_for(model_set)
        self.bearing = load_bearing(bearing)
        self._sample_rate = None if sample_rate is None else float(sample_rate)
        self._streams: dict[FaultState, StreamBlocks] = {}
        self._speed: tuple[float, float] | None = None  # told (Hz, relative tolerance)
        self._engine: SpectralEngine | None = None
        self._scorer: FoldScorer | None = None
        self._next_window = 0  # fold: index of the next window to decide
        self._geometry: tuple[float, int, int] | None = None  # fold: see _fold_geometry
        self._tracker = StateTracker(self.config.k_of_n, self.config.normal_k_of_n, self._unknown_rule())
        self.history: list[Decision] = []
        self.keep_history = True
        #: Hypotheses whose streams are deployed though this core has not seen them yet (a restarted
        #: decision's earlier streams): missing, they hold the folding decision like a silent stream.
        self.expected: set = set()

    # -- configuration -----------------------------------------------------------------
    def _unknown_rule(self) -> tuple[int, int]:
        """UNKNOWN hysteresis: the configured one, else evidence spanning more than one window
        (fold: k = ceil(window/hop) + 1, n = k + 2; spectral, hop = window/2: 3 of 5)."""
        if self.config.unknown_k_of_n:
            return self.config.unknown_k_of_n
        if self.config.method == "fold":
            k = int(math.ceil(self.config.fold.window_s / self.config.fold.hop_s - 1e-9)) + 1
        else:
            k = 3
        return k, k + 2

    @property
    def state(self) -> FaultState:
        """The published state."""
        return self._tracker.state

    @property
    def confidence(self) -> float:
        return self._tracker.confidence

    @property
    def onset(self) -> float:
        return self._tracker.onset

    def thresholds(self) -> tuple[float, float]:
        """Fold front end: (CFAR threshold, kurtosis threshold) in use, derived on first call."""
        fold = self.config.fold
        if fold.threshold is not None and fold.kurtosis_threshold is not None:
            return fold.threshold, fold.kurtosis_threshold
        cal = calibrate(fold, self.config.pfa, self._sample_rate or 48000.0, self.bearing)
        return (fold.threshold if fold.threshold is not None else cal.threshold,
                fold.kurtosis_threshold if fold.kurtosis_threshold is not None else cal.kurtosis_threshold)

    def tell_speed(self, rpm: float | None, tolerance: float | None = None) -> None:
        """The shaft speed (rev/min) from a tachometer, the file or a nameplate, and its relative
        tolerance (default :attr:`.spectral_engine.SpectralSettings.told_tolerance`); None = unknown."""
        if rpm is not None and not (math.isfinite(rpm) and rpm > 0):
            raise ValueError(f"shaft speed must be a positive number of rev/min, got {rpm!r}")
        self._speed = None if rpm is None else (rpm / 60.0, tolerance)
        if self._engine is not None:
            self._engine.tell_speed(*(self._speed or (None,)))

    # -- feeding -----------------------------------------------------------------------
    def update(self, hypothesis, first_sample_index: int, sample_rate: float, residual,
               estimate=None, impulse_train=None, fault_frequency: float | None = None) -> list[Decision]:
        """Feed one observer chunk; return the decisions that became due (oldest first).

        Parameters
        ----------
        hypothesis : FaultState or int
            The observer stream: OUTER_RACE (1) or INNER_RACE (2).
        first_sample_index : int
            Index of the chunk's first sample since the stream began; time = index / rate.
        sample_rate : float
            Hz; the same for every chunk and stream.
        residual, estimate, impulse_train : array_like, shape (n,)
            r (m/s²), ŷ (m/s², None = 0: y = r, a model-free stream), u (None = no train).
        fault_frequency : float
            Hz at which the observer built its train (the fold front end folds there).
        """
        h = _STREAM.get(hypothesis)  # FaultState(hypothesis) costs 1 us, twice a chunk
        if h is None:
            raise ValueError(f"unexpected hypothesis {FaultState(hypothesis).label}; "
                             f"expected {[x.label for x in STREAMS]}")
        rate_problem = sample_rate_problem(sample_rate)
        if rate_problem:
            raise ValueError(rate_problem)
        shipped = SHIPPED.get(self.model_set)
        if self.config.method == "fold" and shipped and not math.isclose(sample_rate, shipped.sample_rate):
            raise ValueError(f"model set {self.model_set} decides {shipped.sample_rate:g} Hz streams, "
                             f"not {sample_rate:g} Hz")
        if self._sample_rate is None:
            self._sample_rate = float(sample_rate)
        elif abs(sample_rate - self._sample_rate) > 1e-9 * self._sample_rate:
            raise ValueError(f"sample rate changed from {self._sample_rate} to {sample_rate} Hz")
        if fault_frequency is None or not (math.isfinite(fault_frequency) and fault_frequency > 0):
            raise ValueError("fault_frequency (Hz) must be > 0")
        r = np.asarray(residual, dtype=float)
        e = np.zeros_like(r) if estimate is None else np.asarray(estimate, dtype=float)
        u = np.zeros_like(r) if impulse_train is None else np.asarray(impulse_train, dtype=float)
        if not (r.shape == e.shape == u.shape) or r.ndim != 1:
            raise ValueError("residual, estimate and impulse_train must be 1-D and of equal length")
        st = self._streams.get(h)
        if st is None:
            band = self.config.fold.band if self.config.method == "fold" else None
            st = self._streams[h] = StreamBlocks(EnergyEnvelope(self._sample_rate, band))
        st.fault_hz = float(fault_frequency)
        st.has_model = st.has_model or (estimate is not None and self.model_set != NONE)
        st.has_train = st.has_train or (impulse_train is not None and np.any(u != 0.0))
        y = r + e
        if self.config.method == "fold" or st.has_model or st.has_train:  # else the blocks are never read
            st.push(int(first_sample_index), y, r, u)
        if self.config.method == "spectral":
            return self._record(self._run_spectral(int(first_sample_index), y))
        return self._record(self._run_fold())

    def flush(self) -> list[Decision]:
        """Decide every complete window with whatever streams exist (end of data)."""
        if self.config.method == "spectral":
            return []
        return self._record(self._run_fold(final=True))

    def _record(self, decisions: list[Decision]) -> list[Decision]:
        if self.keep_history:
            self.history.extend(decisions)
        return decisions

    def _decision(self, label: FaultState, confidence: float, t0: float, t1: float, scores: dict,
                  detail: str = "", posterior: dict | None = None) -> Decision:
        changed = self._tracker.update(label, confidence, t0, t1, posterior)
        tr = self._tracker
        return Decision(time=t1, window_start=t0, window_end=t1, label=label, state=tr.state,
                        confidence=tr.confidence, onset=tr.onset, changed=changed, scores=scores, detail=detail)

    # -- spectral front end ------------------------------------------------------------
    def _run_spectral(self, first_index: int, y: np.ndarray) -> list[Decision]:
        if self._engine is None:
            self._engine = SpectralEngine(self._sample_rate, self.bearing, self.config.spectral)
            if self._speed is not None:
                self._engine.tell_speed(*self._speed)
        out = []
        for w in self._engine.push(first_index, y):
            fs = self._sample_rate
            t0, t1 = w.start / fs, w.end / fs
            scores = self._spectral_scores(w)
            if not w.sensor.ok:
                tr = self._tracker
                out.append(Decision(t1, t0, t1, FaultState.UNKNOWN, tr.state, tr.confidence, tr.onset, False,
                                    scores, f"sensor: {w.sensor.problem}"))
                continue
            label, confidence, post = label_window({h: e.log10p for h, e in w.evidence.items()}, self.config.pfa)
            for h, p in post.items():
                scores[f"{h.label}_posterior"] = p
            out.append(self._decision(label, confidence, t0, t1, scores, posterior=post))
        for st in self._streams.values():  # blocks before the engine's buffer are never needed again
            st.trim(self._engine.retained_from // st.env.decimation)
        return out

    def _spectral_scores(self, w: WindowEvidence) -> dict[str, float]:
        scores: dict[str, float] = {}
        for h, e in w.evidence.items():
            scores[h.label] = e.log10p / significance_level(self.config.pfa, len(w.evidence))  # >= 1: significant
            scores[f"{h.label}_rho"] = e.rho
        if w.band is not None:
            scores.update(band_low_hz=w.band.low, band_high_hz=w.band.high, band_candidates=w.band.candidates)
        scores.update(speed_hz=w.speed_hz, speed_sigma_hz=w.speed_sigma, rms=w.sensor.rms)
        scores.update(self._model_scores(w.start, w.end))
        return scores

    def _model_scores(self, start: int, end: int) -> dict[str, float]:
        """The thesis' blocks per observer stream over samples [start, end): explained, xcorr."""
        out = {}
        for h, st in self._streams.items():
            d = st.env.decimation
            win = st.window(-(-start // d), end // d)
            if win is None or not np.all(np.isfinite(win["y"])):
                continue
            n = win["y"].size * d
            var_y = win["y2"].sum() - win["y"].sum() ** 2 / n
            if st.has_model:
                out[f"{h.label}_explained"] = float(1.0 - win["r2"].sum() / var_y) if var_y > 0 else 0.0
            if st.has_train:
                out[f"{h.label}_xcorr"] = train_correlation(win["ar"], win["u"], XCORR_LAG_S * st.env.envelope_rate)
        return out

    # -- fold front end ----------------------------------------------------------------
    def _fold_geometry(self) -> tuple[float, int, int]:
        """(envelope rate Hz, window and hop in blocks), the same for every stream (one sample rate)."""
        if self._geometry is None:
            fe = next(iter(self._streams.values())).env.envelope_rate
            fold = self.config.fold
            self._geometry = fe, max(1, int(round(fold.window_s * fe))), max(1, int(round(fold.hop_s * fe)))
        return self._geometry

    def _run_fold(self, final: bool = False) -> list[Decision]:
        out: list[Decision] = []
        if not self._streams:
            return out
        if self._scorer is None:
            self._scorer = FoldScorer(self.config.fold, self.bearing, self.thresholds())
        fe, w, hop = self._fold_geometry()
        lag_blocks = self.config.max_lag_s * fe
        while True:
            b0 = self._next_window * hop
            b1 = b0 + w
            ready = {h: s for h, s in self._streams.items() if s.n_blocks >= b1}
            if not ready:
                break
            held = min(s.first_block for s in ready.values())
            if b0 < held:  # no stream holds this window (they began or resumed later): go to the first that may
                self._next_window = -(-held // hop)
                continue
            missing = [h for h in STREAMS if h not in ready]
            if missing and not final:
                lead = max(s.n_blocks for s in self._streams.values())
                if lead - b1 < lag_blocks:
                    break
            # a stream never seen (one observer deployed) leaves its hypothesis out; a stream that went
            # silent (a dead observer) or is expected back (a restarted producer's, not yet arrived)
            # holds the decision: deciding without it mistakes one fault for the other (the folding
            # statistic needs both to explain the stronger one away)
            outage = any(h in self._streams or h in self.expected for h in missing)
            wins = {h: s.window(b0, b1) for h, s in ready.items()}
            if not outage and all(win is not None and kernels.all_finite(win["env"]) for win in wins.values()):
                st = next(iter(ready.values()))
                scores = self._scorer.scores(wins, {h: s.fault_hz for h, s in ready.items()},
                                             {h: s.has_model for h, s in ready.items()}, st.env.decimation, b0, fe)
                label, confidence = self._scorer.label(scores, [h for h in STREAMS if h in ready])
                detail = ("decided without " + ", ".join(h.label for h in missing)) if missing else ""
                out.append(self._decision(label, confidence, b0 / fe, b1 / fe, scores, detail))
            self._next_window += 1
            for s in self._streams.values():
                s.trim(self._next_window * hop)
        return out
