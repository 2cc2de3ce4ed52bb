"""The fold front end (simulator model sets): per-stream energy envelopes in, window verdicts out.

Every observer stream's blocks carry the energy envelope of :attr:`.settings.FoldSettings.band`
(:mod:`bearing_diagnoser.decision.stream_blocks`); windows of ``window_s`` every ``hop_s``,
in envelope blocks, are scored and labelled by :class:`.scoring.FoldScorer` once every
stream holds them. A stream that lags by more than ``max_lag_s`` is left out if it never
arrived (one observer deployed), and holds the decision (no window is decided, the
published state stands) if it went silent (a dead observer) or is expected back (a
restarted producer's), until it is back: deciding without it mistakes one fault for the
other (the folding statistic needs both to explain the stronger one away).

Every window's samples are checked first (:mod:`bearing_diagnoser.decision.sensor_health`, as
the envelope-spectrum front end does): a dead, clipped, quantised or non-finite signal is not
diagnosed (``sensor``), never scored (the fold would call a flat line NORMAL, by its RMS floor).
"""

from __future__ import annotations

import math

from bearing_common.bearings import Bearing
from bearing_common.states import FaultState

from ..decision.config import DiagnoserConfig
from ..decision.front_end import WindowVerdict
from ..decision.not_diagnosed import SENSOR
from ..decision.schedule import WindowSchedule
from ..decision.sensor_health import SensorWatch
from ..decision.stream_blocks import StreamBlocks
from .calibration import calibrate
from .scoring import HYPOTHESES, FoldScorer, FoldScores, all_finite


class FoldFrontEnd:
    """The front end (:class:`bearing_diagnoser.decision.front_end.FrontEnd`) of :class:`.settings.FoldSettings`.

    Parameters
    ----------
    config : DiagnoserConfig
        Its ``front_end`` (FoldSettings) and ``pfa`` (false-alarm probability per window and
        hypothesis on white noise: the thresholds).
    sample_rate : float
        Hz of the streams; ValueError when the settings are for another rate.
    bearing : Bearing
    """

    reads_blocks = True

    def __init__(self, config: DiagnoserConfig, sample_rate: float, bearing: Bearing):
        settings = config.front_end
        if settings.sample_rate is not None and not math.isclose(sample_rate, settings.sample_rate):
            raise ValueError(f"these fold settings decide {settings.sample_rate:g} Hz streams, "
                             f"not {sample_rate:g} Hz")
        self.settings = settings
        self.pfa = config.pfa
        self.sample_rate = float(sample_rate)
        self.bearing = bearing
        self.envelope_band = settings.band
        self._scorer: FoldScorer | None = None
        self._schedule: WindowSchedule | None = None  # in envelope blocks, once the first stream exists
        self._sensor = SensorWatch()

    def thresholds(self) -> tuple[float, float]:
        """(CFAR threshold, kurtosis threshold) in use: the settings', else derived from ``pfa``."""
        s = self.settings
        if s.threshold is not None and s.kurtosis_threshold is not None:
            return s.threshold, s.kurtosis_threshold
        cal = calibrate(s, self.pfa, self.sample_rate, self.bearing)
        return (s.threshold if s.threshold is not None else cal.threshold,
                s.kurtosis_threshold if s.kurtosis_threshold is not None else cal.kurtosis_threshold)

    def tell_speed(self, hz: float | None, tolerance: float | None = None) -> None:
        """Not used: the fold folds at the frequencies the observers report."""

    def warm_up(self) -> None:
        """Derive the thresholds now (about 1 s), not on the first window."""
        self.thresholds()

    def push(self, hypothesis: FaultState, first_index: int, y, streams: dict[FaultState, StreamBlocks],
             expected: set, snapshot: bool = False) -> list[WindowVerdict]:
        """A snapshot is no different here: the pause before it is a gap its windows never straddle,
        so each snapshot is decided by the windows it holds alone."""
        self._sensor.push(first_index, y)
        return self._run(streams, expected)

    def flush(self, streams: dict[FaultState, StreamBlocks], expected: set) -> list[WindowVerdict]:
        """Decide every complete window with whatever streams exist."""
        return self._run(streams, expected, final=True)

    def envelope_view(self) -> None:
        """None: the fold folds an energy envelope at the fault periods, it computes no spectrum to plot."""
        return None

    def _run(self, streams: dict[FaultState, StreamBlocks], expected: set, final: bool = False) -> list[WindowVerdict]:
        out: list[WindowVerdict] = []
        if not streams:
            return out
        if self._scorer is None:
            self._scorer = FoldScorer(self.settings, self.bearing, self.thresholds())
        env = next(iter(streams.values())).env  # the same rate and blocks for every stream (one sample rate)
        fe, d = env.envelope_rate, env.decimation
        if self._schedule is None:
            s = self.settings
            self._schedule = WindowSchedule(0, max(1, int(round(s.window_s * fe))), max(1, int(round(s.hop_s * fe))))
            self._schedule.start()
        schedule = self._schedule
        lag_blocks = self.settings.max_lag_s * fe
        while True:
            b0, b1 = schedule.next_start, schedule.next_end
            ready = {h: s for h, s in streams.items() if s.n_blocks >= b1}
            if not ready:
                break
            held = min(s.first_block for s in ready.values())
            if b0 < held:  # no stream holds this window (they began or resumed later): go to the first that may
                schedule.skip_to(held)
                continue
            missing = [h for h in HYPOTHESES if h not in ready]
            if missing and not final:
                lead = max(s.n_blocks for s in streams.values())
                if lead - b1 < lag_blocks:
                    break
            outage = any(h in streams or h in expected for h in missing)
            wins = {h: s.window(b0, b1) for h, s in ready.items()}
            sensor = None if outage else self._sensor.check(b0 * d, b1 * d)  # None: samples before a gap
            if sensor is not None and not sensor.ok:
                out.append(WindowVerdict.undiagnosed(b0 / fe, b1 / fe, FoldScores(rms=sensor.rms, kurtosis=math.nan),
                                                     SENSOR, sensor.problem))
            elif not outage and all(win is not None and all_finite(win["env"]) for win in wins.values()):
                st = next(iter(ready.values()))
                scores = self._scorer.scores(wins, {h: s.fault_hz for h, s in ready.items()},
                                             {h: s.has_model for h, s in ready.items()}, st.env.decimation, b0, fe)
                label, confidence = self._scorer.label(scores, [h for h in HYPOTHESES if h in ready])
                detail = ("decided without " + ", ".join(h.label for h in missing)) if missing else ""
                out.append(WindowVerdict(b0 / fe, b1 / fe, label, confidence, scores, detail=detail))
            schedule.advance()
            for s in streams.values():
                s.trim(schedule.next_start)
            self._sensor.trim(schedule.next_start * d)
        return out
