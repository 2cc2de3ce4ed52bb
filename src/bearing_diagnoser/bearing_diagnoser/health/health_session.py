"""The diagnoser's view of the machine's condition: its measurement in, a record per window or snapshot out.

No rclpy.

:class:`HealthSession` is fed by the diagnoser session
(:class:`bearing_diagnoser.diagnoser_session.DiagnoserSession`) with the measurement
y = r + ŷ each residual chunk carries, its stamp (s, the data's clock) and whether the chunk
is a snapshot sensor's (:mod:`bearing_common.chunk_stream`). Both observer streams carry
the same measurement: the first to bring a sample wins, the other's copy is skipped.

* A stream is cut into windows of ``period`` s (1 s: the health topic's rate), back to back
  from the stream's start; a gap drops the window it breaks, and the windows start afresh
  after it.
* Each snapshot is one record, whole (in ``auto`` input mode the first snapshot is
  recognised only at the second: it is scored then).

Each window or snapshot goes to :class:`.monitor.HealthMonitor` — indicators, ISO zone,
trend, the code ``bearing-trend`` runs — with the fault decision's comb evidence for it
(:class:`.monitor.FaultEvidence`): the scores of the decided window that ended last inside
it, or why there is none.

A changing shaft speed. The measured speed (:meth:`HealthSession.speed`: ``shaft_speed``'s stamped
values, a recording's speed per sample) is kept alongside; a window or snapshot over which it spreads
by more than :data:`bearing_recordings.recording.SPEED_VARIATION` (2 % of its mean: what a measured
speed is trusted to, and beyond which the fault decision follows the speed in the shaft-angle domain)
is scored, but held out of the trend (:meth:`.trend.HealthTrend.hold`): the indicators follow the
speed through a run-up, not the machine's condition, and would neither make a baseline nor a
departure from one. Its record says so (``speed_changing``).

The trend is the machine's life: it outlives restarts of the fault decision (a parameter
change, another model set). It begins again, with a new baseline, when the measurement does
(time going back: a replay started over) or changes its sample rate.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bearing_recordings.recording import SPEED_VARIATION

from ..decision.not_diagnosed import NotDiagnosed
from .iso20816 import DEFAULT_MACHINE_CLASS
from .monitor import FaultEvidence, HealthMonitor, HealthRecord
from .trend import TrendConfig

#: Health window of a stream (s): about one message a second.
DEFAULT_PERIOD = 1.0

#: Seconds of measured shaft speed kept ahead of the last window scored (a snapshot's length at most).
SPEED_KEPT_S = 60.0

#: Speed batches gathered before they are joined and trimmed (``shaft_speed`` brings one value each).
SPEED_BATCHES = 256


@dataclass(frozen=True)
class HealthSettings:
    """What the health of one machine needs: the trend's design, the ISO 20816-3 machine class, the
    window of a stream (s)."""

    trend: TrendConfig = field(default_factory=TrendConfig)
    machine: str = DEFAULT_MACHINE_CLASS
    period: float = DEFAULT_PERIOD


@dataclass(frozen=True)
class DecidedWindow:
    """A fault decision's window as the health needs it: its end (s, the data's clock), its scores,
    why it was not diagnosed (None when it was)."""

    end: float
    scores: object  # bearing_diagnoser.decision.scores.WindowScores
    not_diagnosed: NotDiagnosed | None = None

    def evidence(self) -> FaultEvidence:
        if self.not_diagnosed is not None:
            return FaultEvidence(problem=f"not diagnosed: {self.not_diagnosed}", not_diagnosed=self.not_diagnosed)
        s = self.scores
        return FaultEvidence({h.label: float(v) for h, v in s.significance.items()},
                             {h.label: float(v) for h, v in s.accumulated().items()},
                             {h.label: why for h, why in s.untested.items()})


class HealthSession:
    """Windows and snapshots of one machine's measurement, scored by one :class:`.monitor.HealthMonitor`.

    Parameters
    ----------
    settings : HealthSettings
    log : callable(level, text)
    keep_history : bool
        Keep every record in :attr:`history` (offline runs).
    """

    def __init__(self, settings: HealthSettings, log, keep_history: bool = False):
        self.settings = settings
        self._log = log
        self.monitor: HealthMonitor | None = None
        self.history: list[HealthRecord] | None = [] if keep_history else None
        self._rate: float | None = None
        self._seen_until: float | None = None  # stamp (s) one past the last sample taken
        self._parts: list[np.ndarray] = []  # samples of the window being filled
        self._held = 0  # how many samples they hold (counted, not summed per chunk)
        self._window_t: float | None = None  # its first sample's stamp (s)
        self._pending_snapshot = False  # the window being filled is one chunk that may prove a snapshot
        self._decided: list[DecidedWindow] = []  # decided windows not yet matched to a record
        self._speeds: list = []  # batches (stamps s, rad/s) of the measured shaft speed, in time order
        self.counts = {"records": 0, "broken windows": 0, "unfit": 0, "speed changing": 0}

    def configure(self, settings: HealthSettings) -> None:
        """New settings: a new machine class applies to the next record; anything else begins the trend again."""
        old, self.settings = self.settings, settings
        if self.monitor is not None and (settings.trend, settings.period) != (old.trend, old.period):
            self._begin_again("the health parameters changed")
        elif self.monitor is not None:
            self.monitor.machine = settings.machine

    def decided(self, windows: list[DecidedWindow]) -> None:
        """The fault decision's windows decided since the last call (ends in time order)."""
        self._decided.extend(windows)

    def speed(self, stamps, rad_s) -> None:
        """Measured shaft speeds (rad/s) at ``stamps`` (s, the data's clock, increasing)."""
        self._speeds.append((np.asarray(stamps, dtype=float).ravel(), np.asarray(rad_s, dtype=float).ravel()))
        if len(self._speeds) > SPEED_BATCHES:
            t, _ = self._joined_speeds()
            self._keep_speeds_from(t[-1] - SPEED_KEPT_S)

    def _joined_speeds(self) -> tuple:
        """(stamps, rad/s) of the speeds kept, as one batch; only the newest run when time went back."""
        t = np.concatenate([b[0] for b in self._speeds])
        w = np.concatenate([b[1] for b in self._speeds])
        back = np.flatnonzero(np.diff(t) < 0)
        if back.size:  # a replay started over: its new speeds only
            t, w = t[back[-1] + 1:], w[back[-1] + 1:]
        self._speeds = [(t, w)]
        return t, w

    def _keep_speeds_from(self, t0: float) -> None:
        """Forget the speeds before the last one at or before ``t0`` (s)."""
        t, w = self._speeds[0]
        k = max(0, int(np.searchsorted(t, t0, side="right")) - 1)
        self._speeds = [(t[k:], w[k:])]

    def speed_changing(self, t: float, end: float) -> bool:
        """Whether the measured speed spreads by more than :data:`SPEED_VARIATION` of its mean from
        ``t`` to ``end`` (s): its values inside, and at both ends interpolated (held beyond the
        measured ones); False without a measured speed."""
        if not self._speeds:
            return False
        ts, ws = self._joined_speeds()
        if not ts.size:
            return False
        inside = (ts > t) & (ts < end)
        w = np.concatenate([np.interp([t, end], ts, ws), ws[inside]])
        return bool((w.max() - w.min()) / w.mean() > SPEED_VARIATION)

    def push(self, stamp: float, sample_rate: float, y: np.ndarray, snapshot: bool, f_top: float,
             restart: bool = False, no_evidence: str = "") -> list[HealthRecord]:
        """One chunk of the measurement (m/s², first sample at ``stamp`` s); the records it completes.

        ``snapshot``: a snapshot sensor's chunk; ``restart``: its stream restarted (a chunk of it far
        back in time then begins the trend again; without it, it is a lagging copy); ``f_top`` (Hz):
        the fault and shaft lines' top (:func:`.indicators.fault_lines_top`), for a monitor begun
        now; ``no_evidence``: why the decision holds none (told to records without a decided window).
        """
        y = np.asarray(y, dtype=float)
        end = stamp + y.size / sample_rate
        tol = 0.5 / sample_rate
        if self._rate is not None and sample_rate != self._rate:
            self._begin_again(f"the sample rate changed to {sample_rate:g} Hz")
        if self._seen_until is not None and end <= self._seen_until + tol:
            if restart and end < self._seen_until - max(1.0, y.size / sample_rate):  # far back: time restarted
                self._begin_again("the measurement's time went back (a replay started over)")
            else:
                return []  # the other observer stream's copy of samples taken already
        if self._seen_until is not None and stamp < self._seen_until - tol:  # partly seen: the new part only
            skip = int(round((self._seen_until - stamp) * sample_rate))
            y, stamp = y[skip:], stamp + skip / sample_rate
        gap = self._seen_until is None or stamp > self._seen_until + tol
        self._rate, self._seen_until = sample_rate, end
        if self.monitor is None:
            s = self.settings
            self.monitor = HealthMonitor(s.trend, s.machine, f_top)
        out = []
        if snapshot:
            if self._pending_snapshot and self._parts:  # auto mode saw the first snapshot as a stream's chunk
                out += self._score(self._window_t, np.concatenate(self._parts), no_evidence)
            self._parts, self._held, self._window_t, self._pending_snapshot = [], 0, None, False
            out += self._score(stamp, y, no_evidence)
        else:
            out += self._stream(stamp, y, gap, no_evidence)
        return out

    def _stream(self, stamp: float, y: np.ndarray, gap: bool, no_evidence: str) -> list[HealthRecord]:
        """Fill and cut the stream's windows."""
        if gap or self._window_t is None:  # a pause, or the stream goes on after a snapshot scored whole
            if gap and self._parts:
                self.counts["broken windows"] += 1
            self._parts, self._held, self._window_t = [], 0, stamp
            self._pending_snapshot = gap  # a chunk alone after a pause, until another continues it
        else:
            self._pending_snapshot = False
        self._parts.append(y)
        self._held += y.size
        held = self._held
        n = int(round(self.settings.period * self._rate))
        out = []
        if held < n:
            return out
        x = np.concatenate(self._parts)
        k = 0
        while held - k >= n:
            out += self._score(self._window_t, x[k:k + n], no_evidence)
            self._window_t += n / self._rate
            k += n
        self._parts = [x[k:]] if k < x.size else []
        self._held = x.size - k
        self._pending_snapshot = False
        return out

    def _score(self, t: float, x: np.ndarray, no_evidence: str) -> list[HealthRecord]:
        end = t + x.size / self._rate
        tol = 1.0 / self._rate  # a snapshot's decided window ends at its last sample, to the sample
        inside = [d for d in self._decided if t < d.end <= end + tol]
        self._decided = [d for d in self._decided if d.end > end + tol]
        if inside:
            evidence = inside[-1].evidence()
        else:
            evidence = FaultEvidence(problem=no_evidence or "no fault decision ended in this window")
        changing = self.speed_changing(t, end)
        if self._speeds:
            self._keep_speeds_from(end)
        record = self.monitor.update(t, x, self._rate, evidence=evidence, speed_changing=changing)
        if record is None:
            self.counts["unfit"] += 1
            return []
        self.counts["records"] += 1
        self.counts["speed changing"] += changing
        if self.history is not None:
            self.history.append(record)
        return [record]

    def _begin_again(self, why: str) -> None:
        self._log("info", f"{why}; the condition trend begins again (a new baseline)")
        self.monitor = None
        self._seen_until = None
        self._parts, self._held, self._window_t, self._pending_snapshot = [], 0, None, False
        self._decided = []
