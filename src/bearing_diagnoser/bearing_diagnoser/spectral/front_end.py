"""The envelope-spectrum front end (real machines): one measurement in, window verdicts out.

Either observer stream's measurement y = r + ŷ feeds one :class:`.evidence_stream.EvidenceStream`
(the first to bring a sample wins: either observer may lag or die). Every window brings two
horizons of evidence per hypothesis: the window's own (short: a change is seen within a
window or two) and the long horizon's (:mod:`.accumulation`: a weak stationary fault
becomes plain over seconds). A hypothesis' p-value is the smaller of the two, and both
kinds of test are counted in one false-alarm budget: with R = ``false_alarm_rate`` per hour,
T the window (s), hop T/2, the short tests run 7200/T times an hour and the long-horizon
evaluations 3600/T (each already paying for its two staggered accumulations), so each test
runs at α = R·T/10800 — by the union bound at most R false significant tests an hour of
Gaussian noise, whatever their dependence. The p-values then become a label, a confidence
and a posterior over NORMAL, OUTER_RACE, INNER_RACE and BALL (:mod:`.window_label`).

A change the short horizon sees — a fault significant in the window other than the one the
long horizon names — restarts the long horizon at that window, so that the old condition
does not dilute the new one (a new fault in a healthy machine is diluted by at most the
long horizon's length, :mod:`.accumulation`). A state that only the long horizon carries dates its evidence from
the start of the horizon (``evidence_since``): the onset is when the evidence began, not
when it became significant.

A snapshot shorter than one window tests only the hypotheses its resolution separates
(:func:`.fault_combs.untestable`; the others are ``untested`` in its scores, and it is not
diagnosed when none is left: ``resolution``); its tests pay for its own length in
the budget above, which counts a window every T/2 and so overstates a snapshot sensor's
tests an hour: conservative.

A nameplate speed the vibration has not confirmed (no shaft line family in the raw or the
envelope spectrum, :func:`.shaft_speed.confirm_speed`) is tested over its whole tolerance,
paid for (the combs slide over it and each p-value pays for the wider search,
:mod:`.fault_combs`), and the scores and ``/diagnostics`` say that the speed is unconfirmed.
Such a window can be NORMAL, but a comb significant there is not called: sliding over ±10 %
it can fit the machine's own lines (measured on HIT-SM's healthy records told 7 % off: an
inner-race comb on the shaft harmonics of the true speed). The window is then not diagnosed
(``speed``), until the speed is confirmed. So is a window with evidence at a speed two lines of a
buffer shorter than 2 s confirmed (``provisional``, :mod:`.evidence_stream`), until the full buffer
confirms it.

A changing speed. Told the measured speed per sample (a tachometer, ``shaft_speed``, a
recording's speed channel, or the speed tracked from the vibration offline), the front end decides
in the shaft-angle domain (:meth:`SpectralFrontEnd.follow_speed`, :mod:`.angle_domain`): each
sample is resampled to equal shaft-angle increments as it arrives, and the unchanged core sees a
shaft turning at a fixed nominal speed, so the combs are fixed orders and the long horizon
accumulates across the change. Window times, the thesis' blocks and onsets are mapped back to the
input's samples; the false-alarm budget counts a window's real duration (a faster shaft: more
windows an hour, each tested at a smaller α); the reported speed is the window's mean.
Without a measured speed the decision holds one speed (the told one, refined every second from
the shaft lines, a measurement held while two of its lines still stand where it put them). So every second (at the first
window ending a second after the last check) the shaft rate is measured on the first and the
last half second of the last two seconds (:func:`.shaft_speed.estimate_speed`, within twice the
told tolerance: half a second, so that a ramp of 4 %/s smears the third harmonic of 30 Hz by
one 2 Hz bin at most). When both are found and differ significantly (beyond 3 σ of the two) at
a rate at which the highest comb term moves by more than one frequency bin over one window —
|dfr/dt|/fr > 1/(k_top·fr·T²) for the highest term's order k_top and window T: 1.7 %/s at
1800 rev/min for a 6205, 0.6 %/s at 600 — the windows' combs smear and their speed is stale:
they are not diagnosed (``speed``, "shaft speed changing") until a check finds one speed again.
Where the shaft lines are too weak to be measured on half a second, the check cannot see the
change; but a measurement is held only while the buffer shows its lines where it put them, so the
told speed then stands unconfirmed, and no comb is called (HIT-SM Normal_1200 warped along a 20 %
ramp down: a speed measured in the first second was held for 4 s while the shaft slowed by 9 %, and
BALL was called).

The thesis' blocks of every observer stream that carries a model or a train are measured
over the same samples (:mod:`bearing_diagnoser.decision.thesis_blocks`). A window whose
sensor signal is unusable is reported as such and not diagnosed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bearing_common.bearings import Bearing
from bearing_common.states import FaultState

from ..decision.config import DiagnoserConfig
from ..decision.front_end import WindowVerdict
from ..decision.not_diagnosed import RESOLUTION, SENSOR, SPEED
from ..decision.scores import THESIS_SUMMARY_KEYS, WindowScores
from ..decision.stream_blocks import StreamBlocks
from ..decision.thesis_blocks import XCORR_LAG_S, explained_fraction, train_correlation
from .angle_domain import AngleStream
from .band_choice import BandChoice
from .envelope_view import EnvelopeView
from .evidence_stream import UNSURE_SPEED, EvidenceStream, WindowEvidence
from .fault_combs import HYPOTHESES
from .shaft_speed import estimate_speed
from .window_label import label_window, significance_level

#: Two measurements of the shaft rate differ significantly beyond this many standard uncertainties of
#: their difference (the speed-changing check, module docstring).
SPEED_CHANGE_SIGMAS = 3.0

#: The speed-changing check measures the shaft rate on the first and the last CHECK_PART_S of the last
#: CHECK_SPAN_S seconds (module docstring).
CHECK_SPAN_S, CHECK_PART_S = 2.0, 0.5


@dataclass
class SpectralScores(WindowScores):
    """:class:`~bearing_diagnoser.decision.scores.WindowScores` of the envelope spectrum: per
    hypothesis the comb's best scale ρ of the kinematic frequencies, the long horizon's
    significance alone (``long``: its statistic ÷ threshold) and the posterior (with NORMAL's);
    the window's demodulation band; the shaft rate used (Hz) with its uncertainty, the told
    rate (NaN: none told), whether the measured one disagrees with it beyond the told
    tolerance (1) or not (0), and whether the told one is unconfirmed (1: tested over its whole
    tolerance, :data:`UNSURE_SPEED`); the seconds of signal the long horizon rests on (snapshots: the
    seconds they hold, not the pauses between them)."""

    rho: dict = field(default_factory=dict)
    long: dict = field(default_factory=dict)
    posterior: dict = field(default_factory=dict)
    band: BandChoice | None = None
    speed_hz: float = math.nan
    speed_sigma_hz: float = math.nan
    told_speed_hz: float = math.nan
    speed_disagrees: float = 0.0
    speed_unconfirmed: float = 0.0
    horizon_s: float = 0.0

    SUMMARY_KEYS = (*(h.label for h in HYPOTHESES),
                    *(f"{h.label}_posterior" for h in (*HYPOTHESES, FaultState.NORMAL)),
                    "band_low_hz", "band_high_hz", "speed_hz", "speed_sigma_hz", *THESIS_SUMMARY_KEYS)

    def speed_warning(self) -> str:
        if self.speed_unconfirmed:
            return (f"shaft speed not confirmed: told {60 * self.speed_hz:.0f} rpm "
                    f"± {200 * self.speed_sigma_hz / self.speed_hz:.0f} %, no shaft line family in the "
                    "vibration; tested over that whole range (a tachometer on shaft_speed, or a smaller "
                    "rpm_tolerance, sharpens the decision)")
        if not self.speed_disagrees:
            return ""
        return (f"measured shaft speed {60 * self.speed_hz:.1f} rpm disagrees with the told "
                f"{60 * self.told_speed_hz:.1f} rpm beyond its tolerance; the measured speed is used")

    def as_dict(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for h, v in self.significance.items():
            out[h.label] = v
            out[f"{h.label}_rho"] = self.rho[h]
            if h in self.long:
                out[f"{h.label}_long"] = self.long[h]
        if self.band is not None:
            out.update(band_low_hz=self.band.low, band_high_hz=self.band.high, band_candidates=self.band.candidates)
        out.update(speed_hz=self.speed_hz, speed_sigma_hz=self.speed_sigma_hz, told_speed_hz=self.told_speed_hz,
                   speed_disagrees=self.speed_disagrees, speed_unconfirmed=self.speed_unconfirmed,
                   horizon_s=self.horizon_s, rms=self.rms)
        out.update(self.thesis_items())
        out.update({f"{h.label}_posterior": p for h, p in self.posterior.items()})
        return out

    def accumulated(self) -> dict:
        return dict(self.long)


class SpectralFrontEnd:
    """The front end (:class:`bearing_diagnoser.decision.front_end.FrontEnd`) of :class:`.settings.SpectralSettings`.

    Parameters
    ----------
    config : DiagnoserConfig
        Its ``front_end`` (SpectralSettings, with the false-alarm budget per hour) and
        ``usable_bandwidth`` (Hz; 0: up to 0.45·fs); ``pfa`` is the fold front end's.
    sample_rate : float
        Hz.
    bearing : Bearing
    """

    envelope_band = None
    reads_blocks = False

    def __init__(self, config: DiagnoserConfig, sample_rate: float, bearing: Bearing):
        self.false_alarm_rate = config.front_end.false_alarm_rate
        self.fs = float(sample_rate)
        self._config, self._bearing = config, bearing
        self.evidence = EvidenceStream(sample_rate, bearing, config.front_end, config.usable_bandwidth)
        self.angle: AngleStream | None = None  # the angle-domain pre-stage, when following a changing speed
        self._checked: int | None = None  # sample index of the last speed-change check
        self.speed_change = 0.0  # relative rate (1/s) of a speed change too fast for one speed; 0: none seen

    def tell_speed(self, hz: float | None, tolerance: float | None = None) -> None:
        if self.angle is None:  # (in the angle domain the speed is the nominal one, its changes are points)
            self.evidence.tell_speed(hz, tolerance)

    def follow_speed(self, nominal_hz: float, top_hz: float) -> None:
        """Decide in the angle domain from now on (module docstring): the measurement is resampled to
        equal shaft-angle increments (:mod:`.angle_domain`) and the core sees a shaft turning at
        ``nominal_hz``, told to a tachometer's tolerance; ``top_hz``: the highest shaft rate expected
        (Hz), which sets the angle signal's usable bandwidth. The speed comes by
        :meth:`tell_speed_points`. Before the first sample only."""
        settings = self._config.front_end
        self.angle = AngleStream(self.fs, nominal_hz)
        usable = self.angle.usable_bandwidth(self._config.usable_bandwidth, top_hz)
        self.evidence = EvidenceStream(self.fs, self._bearing, settings, usable)
        self.evidence.tell_speed(nominal_hz, settings.told_tolerance)

    def tell_speed_points(self, index, rad_s) -> None:
        """Measured shaft speeds (rad/s) at input sample indices ``index`` (the angle domain's)."""
        self.angle.speed.add(index, rad_s)

    def warm_up(self) -> None:
        """Nothing to prepare: the p-value tables are filled by the node's warm-up."""

    def push(self, hypothesis: FaultState, first_index: int, y, streams: dict[FaultState, StreamBlocks],
             expected: set, snapshot: bool = False) -> list[WindowVerdict]:
        if self.angle is None:
            windows = self.evidence.windows(first_index, y, snapshot)
        elif snapshot:
            raise ValueError("a snapshot sensor's chunks are decided at one speed each, not in the angle domain")
        else:
            k, z = self.angle.push(first_index, y)
            windows = self.evidence.windows(k, z) if z.size else ()
        out = [self._verdict(w, streams) for w in windows]  # one at a time (EvidenceStream.windows)
        retained = int(self._input_index(self.evidence.retained_from))
        for st in streams.values():  # blocks before the evidence's buffer are never needed again
            st.trim(retained // st.env.decimation)
        return out

    def _input_index(self, index: int) -> float:
        """The input sample index of the evidence's sample ``index`` (in the angle domain: where the shaft
        reached that angle)."""
        return index if self.angle is None else float(self.angle.input_index(index))

    def flush(self, streams: dict[FaultState, StreamBlocks], expected: set) -> list[WindowVerdict]:
        """Nothing pending: every window is decided when its last sample arrives."""
        return []

    def envelope_view(self) -> EnvelopeView | None:
        """The last tested window's spectrum (:mod:`.envelope_view`); None before the first."""
        return self.evidence.envelope

    def test_level(self, window: int) -> float:
        """α of each test for windows of ``window`` samples (module docstring)."""
        return self.false_alarm_rate * (window / self.fs) / 10800.0

    def _verdict(self, w: WindowEvidence, streams: dict[FaultState, StreamBlocks]) -> WindowVerdict:
        i0, i1 = self._input_index(w.start), self._input_index(w.end)
        t0, t1 = i0 / self.fs, i1 / self.fs
        alpha = self.test_level(i1 - i0)  # the window's duration: more windows an hour above the nominal speed
        real = (w.end - w.start) / (i1 - i0)  # the window's mean shaft rate over the told one (1 at constant speed)
        short = {h: e.log10p for h, e in w.evidence.items()}
        long = {h: e.log10p for h, e in w.long.items() if h in short}
        both = {h: min(lp, long.get(h, 0.0)) for h, lp in short.items()}
        level = significance_level(alpha, len(both)) if both else 1.0  # none: a sensor problem
        unconfirmed = w.speed_source == "told" and w.speed_sigma > UNSURE_SPEED * w.speed_hz
        scores = SpectralScores(rms=w.sensor.rms, significance={h: lp / level for h, lp in both.items()},
                                rho={h: e.rho for h, e in w.evidence.items()},
                                long={h: lp / level for h, lp in long.items()}, band=w.band,
                                speed_hz=w.speed_hz * real, speed_sigma_hz=w.speed_sigma * real,
                                told_speed_hz=math.nan if w.told_hz is None else w.told_hz * real,
                                speed_disagrees=float(w.speed_source == "measured"),
                                speed_unconfirmed=float(unconfirmed),
                                horizon_s=w.horizon_windows * (i1 - i0) / self.fs, untested=w.untested)
        _thesis_blocks(scores, streams, int(round(i0)), int(round(i1)))
        if not w.sensor.ok:
            return WindowVerdict.undiagnosed(t0, t1, scores, SENSOR, w.sensor.problem)
        if not both:
            return WindowVerdict.undiagnosed(t0, t1, scores, RESOLUTION, (
                f"a {t1 - t0:.3g} s snapshot resolves {self.fs / (w.end - w.start):.3g} Hz, too coarse at "
                f"{60 * w.speed_hz:.0f} rpm for every hypothesis: "
                + "; ".join(f"{h.label}: {why}" for h, why in w.untested.items())))
        evidence = sorted(h.label for h, lp in both.items() if lp < level)
        if self.angle is None and self._speed_changing(w):
            return WindowVerdict.undiagnosed(t0, t1, scores, SPEED, (
                f"shaft speed changing: {100 * self.speed_change:.2g} %/s between its last two measurements, too "
                "fast for one speed over a window (the combs smear); a tachometer on shaft_speed lets the decision "
                "follow it"))
        if unconfirmed and evidence:  # evidence at a speed the machine has not confirmed (module docstring)
            return WindowVerdict.undiagnosed(t0, t1, scores, SPEED, (
                f"shaft speed not confirmed: told {60 * w.speed_hz:.0f} rpm ± {200 * w.speed_sigma / w.speed_hz:.0f} "
                f"%, and the {', '.join(evidence)} comb sliding over that range can fit the machine's own lines"))
        if w.speed_source == "provisional" and evidence:  # two lines of a short buffer (module docstring)
            return WindowVerdict.undiagnosed(t0, t1, scores, SPEED, (
                f"shaft speed {60 * w.speed_hz * real:.0f} rpm confirmed provisionally, by two shaft lines of a "
                f"spectrum shorter than {self.evidence.settings.buffer_s:g} s; the {', '.join(evidence)} comb is "
                "called once a full buffer confirms that speed"))
        label, confidence, post = label_window(both, alpha)
        scores.posterior = post
        seen, held = _label(short, alpha), _label(long, alpha)
        since = None
        if label in w.long and seen != label:  # the long horizon's evidence alone: since when it holds
            since = self._input_index(self.evidence.long_onset(label)) / self.fs
        if FaultState.NORMAL not in (seen, held) and FaultState.UNKNOWN not in (seen, held) and held != seen:
            self.evidence.restart_long(w.start)  # the window names another fault than the long horizon
        return WindowVerdict(t0, t1, label, confidence, scores, posterior=post, evidence_since=since)


    def _speed_changing(self, w: WindowEvidence) -> bool:
        """Whether the shaft rate changes too fast for one speed (module docstring), checked once a
        second on the two seconds before the window's end."""
        told = self.evidence.told
        if told is None or (self._checked is not None and w.end - self._checked < self.fs):
            return self.speed_change > 0.0
        self._checked = w.end
        hz, tol = told
        lo, hi = hz * (1.0 - 2.0 * tol), hz * (1.0 + 2.0 * tol)
        lines = self.evidence.settings.speed_lines
        x = self.evidence.recent(w.end, CHECK_SPAN_S)
        n = int(CHECK_PART_S * self.fs)
        if x.size < int(CHECK_SPAN_S * self.fs):
            return self.speed_change > 0.0
        a, b = (estimate_speed(part, self.fs, lo, hi, min_lines=lines) for part in (x[:n], x[-n:]))
        if a is None or b is None:
            return self.speed_change > 0.0
        rate = abs(b.hz - a.hz) / b.hz / (CHECK_SPAN_S - CHECK_PART_S)  # relative change per second
        window = (w.end - w.start) / self.fs
        fast = rate > 1.0 / (self.evidence.f_top * window ** 2)
        significant = abs(b.hz - a.hz) > SPEED_CHANGE_SIGMAS * math.hypot(a.sigma, b.sigma)
        self.speed_change = rate if fast and significant else 0.0
        return self.speed_change > 0.0


def _label(log10p: dict, alpha: float) -> FaultState:
    """The label of one horizon's p-values alone (NORMAL when it has none)."""
    return label_window(log10p, alpha)[0] if log10p else FaultState.NORMAL


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
