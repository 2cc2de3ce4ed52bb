"""The folding front end of the simulator model sets: window statistics and the window label.

Per window and hypothesis h (OUTER_RACE, INNER_RACE) on the energy-envelope blocks of
:class:`.periodicity.EnergyEnvelope`:

* ``c_h`` — CFAR periodicity: the band-passed energy envelope folded at the fault period
  (phase and ±3 % of period searched), divided by the same statistic at decoy periods clear
  of every bearing line (:mod:`.periodicity`, :mod:`.bearing_lines`); its threshold comes
  from a stated per-window false-alarm probability on white noise (:mod:`.calibration`);
  scores are published as c_h / threshold (≥ 1 = significant);
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
from dataclasses import dataclass

import numpy as np

from bearing_common.bearings import Bearing, fault_frequency
from bearing_common.states import FaultState

from . import kernels
from .bearing_lines import decoy_frequencies
from .periodicity import (
    XCORR_LAG_S,
    FoldBank,
    cfar_ses,
    explain_away,
    impact_phase_mask,
    period_grid,
    train_correlation,
)

#: The hypotheses the folding front end tests.
HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE)

#: Per hypothesis, the names of its scores (``<h>_cfar``, ...), spelt once instead of per window.
_NAMES = {h: {k: f"{h.label}_{k}" for k in ("cfar", "cfar_raw", "hz", "explained", "xcorr")} for h in HYPOTHESES}


@dataclass(frozen=True)
class FoldSettings:
    """Settings of the folding front end.

    Attributes
    ----------
    window_s, hop_s : float
        Sliding window length and hop (s).
    band : (lo, hi)
        Band-pass (Hz) before the energy envelope: the resonances the impacts excite.
    bins, search, n_decoys : int, float, int
        Phase bins of the folded profile; relative period search (±); decoy periods.
    threshold, kurtosis_threshold : float or None
        Explicit thresholds (None = derive from the configuration's pfa).
    dominance, explained_margin : float
        Ratio of CFAR statistics that picks one of two significant hypotheses; difference
        of model-explains fractions that breaks a remaining tie.
    rms_floor : float
        Window RMS (m/s²) below which the window is NORMAL without further test.
    quiet_tail, quiet_ratio : float
        A window whose newest ``quiet_tail`` holds less than ``quiet_ratio`` × the older
        part's mean band energy is NORMAL (the activity stopped).
    use_kurtosis : bool
        Label impulsive-but-aperiodic windows UNKNOWN (else NORMAL).
    statistic : ``"fold"`` or ``"ses"``
        Folded envelope (default) or the squared envelope spectrum at the fault harmonics
        (the textbook reference, ``--method envelope``).
    ses_harmonics, envelope_window_s : int, float
        Highest harmonic and shortest window of the envelope-spectrum reference.
    xcorr_lag_s : float
        Lags 0..this (s) of the thesis-literal correlation of |r| with u.
    explain_away : bool
        Re-test the weaker hypothesis with the stronger one's impact phases masked.
    nominal_rpm : float
        Speed (rev/min) at which the decoy ratios and the calibration are computed.
    """

    window_s: float = 0.05
    hop_s: float = 0.01
    band: tuple[float, float] = (1500.0, 8000.0)
    bins: int = 16
    search: float = 0.03
    n_decoys: int = 6
    threshold: float | None = None
    kurtosis_threshold: float | None = None
    dominance: float = 1.5
    explained_margin: float = 0.1
    rms_floor: float = 1e-2
    quiet_tail: float = 0.25
    quiet_ratio: float = 0.15
    use_kurtosis: bool = True
    statistic: str = "fold"
    ses_harmonics: int = 3
    envelope_window_s: float = 0.1
    xcorr_lag_s: float = XCORR_LAG_S
    explain_away: bool = True
    nominal_rpm: float = 1800.0


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
               fe: float) -> dict[str, float]:
        """Statistics of one window from the block arrays of each hypothesis stream.

        ``windows``: {hypothesis: {key: block array}} (:attr:`.periodicity.EnergyEnvelope.keys`);
        ``fault_hz``: the streams' fault frequencies (Hz); ``has_model``: whether a stream
        carries an observer estimate. ``<h>_cfar`` is the CFAR statistic after explaining the
        strongest hypothesis away, ``<h>_cfar_raw`` the one before.
        """
        s = self.settings
        scores: dict[str, float] = {}
        for h, win in windows.items():
            name = _NAMES[h]
            env = win["env"]
            w = env.size
            n = w * decimation
            q = max(1, int(round(s.quiet_tail * w)))
            sy, sy2, sr2, se, s_older, s_tail, sb4 = kernels.window_sums(env, win["b4"], win["y"], win["y2"],
                                                                         win["r2"], q)
            ratio, _, best_hz = self._cfar(h, env, fe, fault_hz[h])
            scores[name["cfar"]] = scores[name["cfar_raw"]] = ratio
            scores[name["hz"]] = best_hz
            var_y = sy2 - sy * sy / n
            if has_model[h]:
                scores[name["explained"]] = float(1.0 - sr2 / var_y) if var_y > 0 else 0.0
                scores[name["xcorr"]] = train_correlation(win["ar"], win["u"], s.xcorr_lag_s * fe)
            if "rms" not in scores:
                scores["rms"] = float(math.sqrt(max(var_y, 0.0) / n))
                m2 = se / w
                older = s_older / (w - q) if w > q else m2
                scores["tail_ratio"] = float(s_tail / min(q, w) / older) if older > 0 else 1.0
                scores["kurtosis"] = float(sb4 / w / (m2 * m2)) if m2 > 0 else 0.0
        if len(windows) > 1 and s.explain_away:
            best = max(windows, key=lambda h: scores[_NAMES[h]["cfar"]])
            mask = impact_phase_mask(windows[best]["env"], fe, scores[_NAMES[best]["hz"]], b0, s.bins)
            for h in windows:
                if h != best:
                    env = explain_away(windows[h]["env"], mask)
                    scores[_NAMES[h]["cfar"]] = self._cfar(h, env, fe, fault_hz[h])[0]
        return scores

    def label(self, scores: dict[str, float], hypotheses) -> tuple[FaultState, float]:
        """Window label and its confidence in [0, 1]; adds ``<h>`` = c_h / threshold to ``scores``."""
        s = self.settings
        thr, kthr = self.thresholds
        c = {h: scores.get(_NAMES[h]["cfar"], float("nan")) for h in hypotheses}
        for h in hypotheses:
            scores[h.label] = c[h] / thr
        valid = {h: v for h, v in c.items() if math.isfinite(v)}
        cmax = max(valid.values()) if valid else 0.0
        normal_conf = _unit((thr - cmax) / max(thr - 1.0, 1e-9))
        if scores["rms"] < s.rms_floor:
            return FaultState.NORMAL, 1.0
        if scores.get("tail_ratio", 1.0) < s.quiet_ratio:
            return FaultState.NORMAL, float(1.0 - scores["tail_ratio"] / s.quiet_ratio)
        significant = sorted((h for h, v in valid.items() if v >= thr), key=lambda h: valid[h], reverse=True)
        if not significant:
            if s.use_kurtosis and scores["kurtosis"] > kthr:
                return FaultState.UNKNOWN, _unit(1.0 - kthr / scores["kurtosis"])
            return FaultState.NORMAL, normal_conf
        best = significant[0]
        others = [v for h, v in valid.items() if h != best]
        dom = valid[best] / max(others) if others and max(others) > 0 else float("inf")
        strength = _unit(1.0 - thr / valid[best])
        clarity = _unit((dom - 1.0) / (s.dominance - 1.0))
        if len(significant) == 1 or dom >= s.dominance:
            return best, strength * clarity
        second = significant[1]
        eb = scores.get(_NAMES[best]["explained"])
        es = scores.get(_NAMES[second]["explained"])
        if eb is not None and es is not None:
            if eb - es >= s.explained_margin:
                return best, 0.5 * strength
            if es - eb >= s.explained_margin:
                return second, 0.5 * _unit(1.0 - thr / valid[second])
        return FaultState.UNKNOWN, _unit(1.0 - 1.0 / dom)


def _unit(x: float) -> float:
    """``x`` clipped to [0, 1] (``np.clip`` of one number, without its per-call cost)."""
    return min(max(x, 0.0), 1.0)
