"""The envelope-spectrum front end (real machines): one measurement in, window verdicts out.

Either observer stream's measurement y = r + ŷ feeds one :class:`.evidence_stream.EvidenceStream`
(the first to bring a sample wins: either observer may lag or die). Each window's p-values
become a label, a confidence and a posterior over NORMAL, OUTER_RACE, INNER_RACE and BALL
(:mod:`.window_label`); the thesis' blocks of every observer stream that carries a model or
a train are measured over the same samples (:mod:`bearing_diagnoser.decision.thesis_blocks`).
A window whose sensor signal is unusable is reported as such and not diagnosed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bearing_common.bearings import Bearing
from bearing_common.states import FaultState

from ..decision.config import DiagnoserConfig
from ..decision.front_end import WindowVerdict
from ..decision.scores import THESIS_SUMMARY_KEYS, WindowScores
from ..decision.stream_blocks import StreamBlocks
from ..decision.thesis_blocks import XCORR_LAG_S, explained_fraction, train_correlation
from .band_choice import BandChoice
from .evidence_stream import EvidenceStream, WindowEvidence
from .fault_combs import HYPOTHESES
from .window_label import label_window, significance_level


@dataclass
class SpectralScores(WindowScores):
    """:class:`~bearing_diagnoser.decision.scores.WindowScores` of the envelope spectrum: per
    hypothesis the comb's best scale ρ of the kinematic frequencies and the posterior (with
    NORMAL's), the demodulation band and the shaft rate used (Hz) with its uncertainty."""

    rho: dict = field(default_factory=dict)
    posterior: dict = field(default_factory=dict)
    band: BandChoice | None = None
    speed_hz: float = math.nan
    speed_sigma_hz: float = math.nan

    SUMMARY_KEYS = (*(h.label for h in HYPOTHESES),
                    *(f"{h.label}_posterior" for h in (*HYPOTHESES, FaultState.NORMAL)),
                    "band_low_hz", "band_high_hz", "speed_hz", "speed_sigma_hz", *THESIS_SUMMARY_KEYS)

    def as_dict(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for h, v in self.significance.items():
            out[h.label] = v
            out[f"{h.label}_rho"] = self.rho[h]
        if self.band is not None:
            out.update(band_low_hz=self.band.low, band_high_hz=self.band.high, band_candidates=self.band.candidates)
        out.update(speed_hz=self.speed_hz, speed_sigma_hz=self.speed_sigma_hz, rms=self.rms)
        out.update(self.thesis_items())
        out.update({f"{h.label}_posterior": p for h, p in self.posterior.items()})
        return out


class SpectralFrontEnd:
    """The front end (:class:`bearing_diagnoser.decision.front_end.FrontEnd`) of :class:`.settings.SpectralSettings`.

    Parameters
    ----------
    config : DiagnoserConfig
        Its ``front_end`` (SpectralSettings), ``pfa`` (false-alarm probability per window, all
        hypotheses together) and ``usable_bandwidth`` (Hz; 0: up to 0.45·fs).
    sample_rate : float
        Hz.
    bearing : Bearing
    """

    envelope_band = None
    reads_blocks = False

    def __init__(self, config: DiagnoserConfig, sample_rate: float, bearing: Bearing):
        self.pfa = config.pfa
        self.fs = float(sample_rate)
        self.evidence = EvidenceStream(sample_rate, bearing, config.front_end, config.usable_bandwidth)

    def tell_speed(self, hz: float | None, tolerance: float | None = None) -> None:
        self.evidence.tell_speed(hz, tolerance)

    def warm_up(self) -> None:
        """Nothing to prepare: the p-value tables are filled by the node's warm-up."""

    def push(self, hypothesis: FaultState, first_index: int, y, streams: dict[FaultState, StreamBlocks],
             expected: set) -> list[WindowVerdict]:
        out = [self._verdict(w, streams) for w in self.evidence.push(first_index, y)]
        for st in streams.values():  # blocks before the evidence's buffer are never needed again
            st.trim(self.evidence.retained_from // st.env.decimation)
        return out

    def flush(self, streams: dict[FaultState, StreamBlocks], expected: set) -> list[WindowVerdict]:
        """Nothing pending: every window is decided when its last sample arrives."""
        return []

    def _verdict(self, w: WindowEvidence, streams: dict[FaultState, StreamBlocks]) -> WindowVerdict:
        t0, t1 = w.start / self.fs, w.end / self.fs
        level = significance_level(self.pfa, len(w.evidence)) if w.evidence else 1.0  # none: a sensor problem
        scores = SpectralScores(rms=w.sensor.rms, significance={h: e.log10p / level for h, e in w.evidence.items()},
                                rho={h: e.rho for h, e in w.evidence.items()}, band=w.band, speed_hz=w.speed_hz,
                                speed_sigma_hz=w.speed_sigma)
        _thesis_blocks(scores, streams, w.start, w.end)
        if not w.sensor.ok:
            return WindowVerdict(t0, t1, FaultState.UNKNOWN, 0.0, scores, sensor_problem=w.sensor.problem)
        label, confidence, post = label_window({h: e.log10p for h, e in w.evidence.items()}, self.pfa)
        scores.posterior = post
        return WindowVerdict(t0, t1, label, confidence, scores, posterior=post)


def _thesis_blocks(scores: WindowScores, streams: dict[FaultState, StreamBlocks], start: int, end: int) -> None:
    """The thesis' blocks per observer stream over samples [start, end) into ``scores``."""
    for h, st in streams.items():
        d = st.env.decimation
        win = st.window(-(-start // d), end // d)
        if win is None or not np.all(np.isfinite(win["y"])):
            continue
        n = win["y"].size * d
        if st.has_model:
            scores.explained[h] = explained_fraction(win["y"].sum(), win["y2"].sum(), win["r2"].sum(), n)
        if st.has_train:
            scores.xcorr[h] = train_correlation(win["ar"], win["u"], XCORR_LAG_S * st.env.envelope_rate)
