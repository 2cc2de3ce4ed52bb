"""The fold front end's window statistics and the window label (simulator model sets).

Per window and hypothesis h (OUTER_RACE, INNER_RACE) on the energy-envelope blocks of
:class:`bearing_diagnoser.decision.stream_blocks.EnergyEnvelope`:

* ``c_h`` — CFAR periodicity: the band-passed energy envelope folded at the fault period
  (phase and ±3 % of period searched), divided by the same statistic at decoy periods clear
  of every bearing line (:mod:`.folding`, :mod:`.decoys`); its threshold comes
  from a stated per-window false-alarm probability on white noise (:mod:`.calibration`);
  its significance is c_h / threshold (≥ 1 = significant);
* ``E_h`` — "the model explains the data": 1 − ‖r‖²/‖y − ȳ‖², the fraction of measurement
  energy the train-driven observer removes (thesis 3.2.3: an observer injecting its own
  impulses in NORMAL operation gives E < 0); breaks ties between hypotheses;
* ``xcorr_h`` — the thesis-literal cross-correlation of |r| with the train (section 3.2),
  reported, not decided on (the feasibility study measured 0/56 with it).

Explain-away: every hypothesis but the strongest is re-tested after the strongest one's
impact phases are masked (IR impacts fold into three phase clusters at the OR period
because 2·BPFI ≈ 3·BPFO).

Label: NORMAL if the window RMS is below ``rms_floor``, or its newest quarter is quiet (the
activity stopped), or nothing is significant (unless the band-passed kurtosis exceeds its
noise threshold: UNKNOWN = impulsive but aperiodic); the significant hypothesis if only one
is; if both are, the one ``dominance`` times stronger, else the one the model explains
better by ``explained_margin``, else UNKNOWN. Confidence (0..1): for a fault,
(1 − threshold/c) × clarity (how far c exceeds the other hypothesis' c relative to
``dominance``); for NORMAL, how far the largest c is below the threshold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from bearing_common.bearings import Bearing, fault_frequency
from bearing_common.states import FaultState

from ..decision.pairwise_sum import row_sum
from ..decision.scores import THESIS_SUMMARY_KEYS, WindowScores
from ..decision.thesis_blocks import explained_fraction, train_correlation
from .decoys import decoy_frequencies
from .envelope_reference import cfar_ses
from .folding import FoldBank, explain_away, impact_phase_mask, period_grid
from .settings import FoldSettings

#: The hypotheses the fold front end tests.
HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE)


@dataclass
class FoldScores(WindowScores):
    """:class:`~bearing_diagnoser.decision.scores.WindowScores` of the fold: per hypothesis the CFAR
    statistic after explaining the strongest hypothesis away (``cfar``) and before (``cfar_raw``)
    and the frequency (Hz) that folded best; for the window, the newest quarter's share of the
    band energy (``tail_ratio``) and the band-passed kurtosis."""

    cfar: dict = field(default_factory=dict)
    cfar_raw: dict = field(default_factory=dict)
    hz: dict = field(default_factory=dict)
    tail_ratio: float = 1.0
    kurtosis: float = 0.0

    SUMMARY_KEYS = (*(h.label for h in HYPOTHESES), *THESIS_SUMMARY_KEYS, "kurtosis")

    def as_dict(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for h in self.cfar:
            out.update({f"{h.label}_cfar": self.cfar[h], f"{h.label}_cfar_raw": self.cfar_raw[h],
                        f"{h.label}_hz": self.hz[h]})
            if h in self.explained:
                out.update({f"{h.label}_explained": self.explained[h], f"{h.label}_xcorr": self.xcorr[h]})
        out.update(rms=self.rms, tail_ratio=self.tail_ratio, kurtosis=self.kurtosis)
        out.update({h.label: v for h, v in self.significance.items()})
        return out


class FoldScorer:
    """Window statistics and labels of the folding front end for one bearing.

    ``thresholds`` = (CFAR threshold, kurtosis threshold), from :func:`.calibration.calibrate`
    or the settings.
    """

    def __init__(self, settings: FoldSettings, bearing: Bearing, thresholds: tuple[float, float]):
        self.settings = settings
        self.bearing = bearing
        self.thresholds = thresholds
        self._decoy_ratio: dict = {}
        self._banks: dict = {}  # hypothesis -> ((fault Hz, window blocks, envelope rate), FoldBank)

    def decoys(self, hypothesis: FaultState, fault_hz: float) -> np.ndarray:
        """Decoy frequencies (Hz) for ``hypothesis`` at ``fault_hz``: fixed multiples of it
        (every bearing line scales with speed), computed once at the nominal speed."""
        s = self.settings
        if hypothesis not in self._decoy_ratio:
            f0 = fault_frequency(self.bearing, hypothesis, s.nominal_rpm)
            self._decoy_ratio[hypothesis] = decoy_frequencies(
                f0, s.nominal_rpm, self.bearing, s.n_decoys, s.window_s, s.search) / f0
        return self._decoy_ratio[hypothesis] * fault_hz

    def ses_harmonics(self, hypothesis: FaultState) -> tuple[int, ...]:
        """Harmonics 1..``ses_harmonics`` of the hypothesis' frequency, minus those within 3 % of
        a harmonic (1..5) of the other race frequency (6205: OR keeps 1, 2; IR keeps 1, 3)."""
        s = self.settings
        f = fault_frequency(self.bearing, hypothesis, s.nominal_rpm)
        other = [fault_frequency(self.bearing, h, s.nominal_rpm) for h in HYPOTHESES if h != hypothesis]
        return tuple(k for k in range(1, s.ses_harmonics + 1)
                     if all(abs(k * f / (m * g) - 1.0) > 0.03 for g in other for m in range(1, 6)))

    def _cfar(self, h: FaultState, env: np.ndarray, fe: float, fault_hz: float):
        s = self.settings
        if s.statistic == "ses":
            return cfar_ses(env, fe, fault_hz, self.decoys(h, fault_hz), s.search, self.ses_harmonics(h))
        key = (fault_hz, env.size, fe)
        bank = self._banks.get(h)
        if bank is None or bank[0] != key:  # built when the speed (or the window) changes
            grid = period_grid(fault_hz, s.window_s, s.bins, s.search)
            bank = self._banks[h] = key, FoldBank(fault_hz, self.decoys(h, fault_hz), grid, env.size, fe, s.bins)
        return bank[1].cfar(env)

    def scores(self, windows: dict, fault_hz: dict, has_model: dict, decimation: int, b0: int,
               fe: float) -> FoldScores:
        """Statistics of one window from the block arrays of each hypothesis stream.

        ``windows``: {hypothesis: {key: block array}} (:class:`.StreamBlocks.window`);
        ``fault_hz``: the streams' fault frequencies (Hz); ``has_model``: whether a stream
        carries an observer estimate.
        """
        s = self.settings
        scores = FoldScores()
        for h, win in windows.items():
            env = win["env"]
            w = env.size
            n = w * decimation
            q = max(1, int(round(s.quiet_tail * w)))
            sy, sy2, sr2, se, s_older, s_tail, sb4 = window_sums(env, win["b4"], win["y"], win["y2"], win["r2"], q)
            ratio, _, best_hz = self._cfar(h, env, fe, fault_hz[h])
            scores.cfar[h] = scores.cfar_raw[h] = ratio
            scores.hz[h] = best_hz
            if has_model[h]:
                scores.explained[h] = explained_fraction(sy, sy2, sr2, n)
                scores.xcorr[h] = train_correlation(win["ar"], win["u"], s.xcorr_lag_s * fe)
            if len(scores.cfar) == 1:  # the window's own statistics, from the first stream's samples
                var_y = sy2 - sy * sy / n
                scores.rms = float(math.sqrt(max(var_y, 0.0) / n))
                m2 = se / w
                older = s_older / (w - q) if w > q else m2
                scores.tail_ratio = float(s_tail / min(q, w) / older) if older > 0 else 1.0
                scores.kurtosis = float(sb4 / w / (m2 * m2)) if m2 > 0 else 0.0
        if len(windows) > 1 and s.explain_away:
            best = max(windows, key=lambda h: scores.cfar[h])
            mask = impact_phase_mask(windows[best]["env"], fe, scores.hz[best], b0, s.bins)
            for h in windows:
                if h != best:
                    env = explain_away(windows[h]["env"], mask)
                    scores.cfar[h] = self._cfar(h, env, fe, fault_hz[h])[0]
        return scores

    def label(self, scores: FoldScores, hypotheses) -> tuple[FaultState, float]:
        """Window label and its confidence in [0, 1]; sets the significance c_h / threshold in ``scores``."""
        s = self.settings
        thr, kthr = self.thresholds
        c = {h: scores.cfar.get(h, float("nan")) for h in hypotheses}
        for h in hypotheses:
            scores.significance[h] = c[h] / thr
        valid = {h: v for h, v in c.items() if math.isfinite(v)}
        cmax = max(valid.values()) if valid else 0.0
        normal_conf = _unit((thr - cmax) / max(thr - 1.0, 1e-9))
        if scores.rms < s.rms_floor:
            return FaultState.NORMAL, 1.0
        if scores.tail_ratio < s.quiet_ratio:
            return FaultState.NORMAL, float(1.0 - scores.tail_ratio / s.quiet_ratio)
        significant = sorted((h for h, v in valid.items() if v >= thr), key=lambda h: valid[h], reverse=True)
        if not significant:
            if s.use_kurtosis and scores.kurtosis > kthr:
                return FaultState.UNKNOWN, _unit(1.0 - kthr / scores.kurtosis)
            return FaultState.NORMAL, normal_conf
        best = significant[0]
        others = [v for h, v in valid.items() if h != best]
        dom = valid[best] / max(others) if others and max(others) > 0 else float("inf")
        strength = _unit(1.0 - thr / valid[best])
        clarity = _unit((dom - 1.0) / (s.dominance - 1.0))
        if len(significant) == 1 or dom >= s.dominance:
            return best, strength * clarity
        second = significant[1]
        eb = scores.explained.get(best)
        es = scores.explained.get(second)
        if eb is not None and es is not None:
            if eb - es >= s.explained_margin:
                return best, 0.5 * strength
            if es - eb >= s.explained_margin:
                return second, 0.5 * _unit(1.0 - thr / valid[second])
        return FaultState.UNKNOWN, _unit(1.0 - 1.0 / dom)


def _unit(x: float) -> float:
    """``x`` clipped to [0, 1] (``np.clip`` of one number, without its per-call cost)."""
    return min(max(x, 0.0), 1.0)


@njit(cache=True)
def window_sums(env: np.ndarray, b4: np.ndarray, y: np.ndarray, y2: np.ndarray, r2: np.ndarray, q: int):
    """The sums a fold window's scores need, each ``x.sum()`` bit for bit
    (:func:`~bearing_diagnoser.decision.pairwise_sum.row_sum`).

    Returns ``(Σy, Σy², Σr², Σenv, Σenv[:-q], Σenv[-q:], Σb4)`` over the window's blocks,
    ``q`` >= 1 the newest blocks (all of them when q >= the window; the older part is then
    empty, sum 0).
    """
    w = env.size
    e = env.reshape(1, w)
    tail = min(q, w)
    return (row_sum(y.reshape(1, w), 0, 0, w), row_sum(y2.reshape(1, w), 0, 0, w),
            row_sum(r2.reshape(1, w), 0, 0, w), row_sum(e, 0, 0, w), row_sum(e, 0, 0, w - tail),
            row_sum(e, 0, w - tail, tail), row_sum(b4.reshape(1, w), 0, 0, w))


@njit(cache=True)
def all_finite(x: np.ndarray) -> bool:
    """``np.all(np.isfinite(x))``."""
    for v in x:
        if not np.isfinite(v):
            return False
    return True
