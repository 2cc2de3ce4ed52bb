"""Trend and early warning over a machine's life: a baseline learned online, departures with a
stated false-alarm rate per day, states HEALTHY / WARNING / ALARM, the trend's slope.

:class:`HealthTrend` is called once per window or snapshot, by the live node and by
``bearing-trend`` alike, with the condition indicators of :data:`TRENDED` (any positive
quantity works). Per indicator, on y = ln(indicator):

1. **Baseline.** The machine's own first :attr:`TrendConfig.baseline_snapshots` snapshots
   (and at least :attr:`TrendConfig.baseline_duration` s), or a stated healthy period
   (:attr:`TrendConfig.healthy_until`), are taken as healthy: the median μ̂, a robust AR(1)
   fit (φ̂, σ̂; :func:`.null_model.fit_ar1`) and the snapshot interval Δt (their median).
   Nothing about the life's length enters: it is unknown online.
2. **Statistics.** m_t = median of the last three y (one outlying snapshot — a knock, a
   glitch — never moves it) and z_t = EWMA of m (weight λ). Two charts per indicator test
   the level against the baseline's, in log units (ln 2: doubled): the EWMA chart
   D_t = z_t − μ̂ for slow, small changes, and the median chart D'_t = m_t − μ̂ for sudden
   large ones (the combined Shewhart-EWMA scheme of Lucas & Saccucci 1990: an EWMA alone
   takes several snapshots to follow a jump, and many bearings fail abruptly). Each is
   standardised, s = D / sd(D), with sd(D) from the null model (:mod:`.null_model`), which
   includes the autocorrelation φ̂ and the error of μ̂.
3. **Limits.** For each chart, u_W and u_A are set so that s crosses them upwards at most
   ``false_warnings_per_day`` and ``false_alarms_per_day`` times a day over all charts of all
   indicators (:func:`.null_model.limit_for_rate` with p = rate·Δt / (86 400 s · charts)).
4. **Relevance.** Real healthy indicators drift beyond what a baseline of tens of
   snapshots shows (temperature, load, running-in); a significant change is reported only
   when it is also relevant: a WARNING needs D ≥ ln(:attr:`TrendConfig.warning_change`)
   (+25 %, the change ISO 20816-3 calls significant), an ALARM D ≥
   ln(:attr:`TrendConfig.alarm_change`) (2×, +6 dB), on the chart that is significant. The
   stated rates hold whatever the drift as long as it stays inside these bands; beyond
   them a drift *is* reported.
5. **States.** A level (WARNING, ALARM) begins when some chart is significant and relevant
   for it, and ends when every chart's s is back below that level's limit; so each false
   onset needs an upward crossing, and the rates of 3. bound the false onsets per day. The
   state is the highest level in force, with the time it began.
6. **Slope** of each indicator: least squares of y over the last
   :attr:`TrendConfig.baseline_snapshots` snapshots, per hour, as a relative rate
   (0.1 = +10 %/h); reported for the indicator that moved most (largest s relative to its
   warning limit).
"""

from __future__ import annotations

import enum
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .null_model import Ar1Fit, d_moments, fit_ar1, limit_for_rate, median_of_3_rows

#: The indicators trended by default (keys of :meth:`.indicators.ConditionIndicators.trended`).
TRENDED = ("rms", "kurtosis", "envelope_rms", "velocity_rms")

SECONDS_PER_DAY = 86400.0

#: Fewest snapshots a baseline can be fitted from.
MIN_BASELINE = 6

#: EWMA weight of the median chart: no smoothing.
MEDIAN_CHART = 1.0


class HealthState(enum.IntEnum):
    """Trend states (the integers of ``bearing_msgs/msg/HealthIndicators``)."""

    HEALTHY = 0
    WARNING = 1
    ALARM = 2


@dataclass(frozen=True)
class TrendConfig:
    """Parameters of :class:`HealthTrend` (defaults are the shipped design, not fitted to any data).

    Attributes
    ----------
    baseline_snapshots : int
        Snapshots the baseline takes at least (≥ 6).
    baseline_duration : float
        s the baseline spans at least (0: by count only).
    healthy_until : float or None
        A stated healthy period instead: the baseline is every snapshot up to this many s
        after the first (at least 6 of them).
    false_warnings_per_day, false_alarms_per_day : float
        Design rates of false onsets per day (a healthy machine within the relevance bands).
    warning_change, alarm_change : float
        Smallest relevant change of a smoothed indicator, as a factor of its baseline level.
    smoothing : float
        EWMA weight λ (0 < λ ≤ 1).
    indicators : tuple of str
        The indicators trended.
    """

    baseline_snapshots: int = 30
    baseline_duration: float = 0.0
    healthy_until: float | None = None
    false_warnings_per_day: float = 0.1
    false_alarms_per_day: float = 0.01
    warning_change: float = 1.25
    alarm_change: float = 2.0
    smoothing: float = 0.2
    indicators: tuple = TRENDED

    def __post_init__(self):
        if not (isinstance(self.baseline_snapshots, int) and self.baseline_snapshots >= MIN_BASELINE):
            raise ValueError(f"baseline_snapshots must be an integer of at least {MIN_BASELINE}, "
                             f"got {self.baseline_snapshots!r}")
        if not self.baseline_duration >= 0.0:
            raise ValueError(f"baseline_duration must be ≥ 0 s, got {self.baseline_duration!r}")
        if self.healthy_until is not None and not self.healthy_until > 0.0:
            raise ValueError(f"healthy_until must be > 0 s, got {self.healthy_until!r}")
        if not 0.0 < self.false_alarms_per_day <= self.false_warnings_per_day:
            raise ValueError("need 0 < false_alarms_per_day <= false_warnings_per_day, got "
                             f"{self.false_alarms_per_day!r} and {self.false_warnings_per_day!r}")
        if not 1.0 <= self.warning_change <= self.alarm_change:
            raise ValueError("need 1 <= warning_change <= alarm_change, got "
                             f"{self.warning_change!r} and {self.alarm_change!r}")
        if not 0.0 < self.smoothing <= 1.0:
            raise ValueError(f"smoothing must be in (0, 1], got {self.smoothing!r}")
        if not self.indicators:
            raise ValueError("no indicators to trend")

    @property
    def slope_window(self) -> int:
        """Snapshots the slope is fitted over: as many as the baseline takes (30 by default: a
        slope's standard error is about 0.2/h for 8 % snapshot noise at one a minute)."""
        return self.baseline_snapshots


@dataclass(frozen=True)
class IndicatorBaseline:
    """Baseline of one indicator: the fit, and per chart (EWMA, median) the sd of D (log units)
    and both limits (in units of that sd)."""

    fit: Ar1Fit
    sd: tuple  # (EWMA chart, median chart)
    warning_limit: tuple
    alarm_limit: tuple

    def level(self, chart: int, limit: float, change: float) -> float:
        """The chart's value (indicator units) at which ``limit`` and ``change`` are both met."""
        return math.exp(self.fit.centre + max(math.log(change), limit * self.sd[chart]))


@dataclass(frozen=True)
class Baseline:
    """What the baseline period gave: per-indicator fits, the snapshot interval, its extent."""

    indicators: dict  # name -> IndicatorBaseline
    interval: float  # s, median snapshot interval
    snapshots: int
    end: float  # s (relative), time of its last snapshot


@dataclass(frozen=True)
class TrendRecord:
    """The trend after one snapshot; times relative to the first snapshot (s)."""

    t: float
    state: HealthState
    since: float
    learning: bool  # still inside the baseline period
    level: dict  # name -> smoothed (EWMA) indicator / baseline level, exp(D); empty while learning
    score: dict  # name -> largest s / warning limit over its charts (≥ 1: significant); empty while learning
    slope: dict  # name -> relative rate per hour, d ln(indicator)/dt
    moved: str  # the indicator with the largest score ("" while learning)

    def to_json(self) -> dict:
        out = {"state": self.state.name.lower(), "since": self.since, "learning": self.learning,
               "slope_per_h": _clean(self.slope)}
        if not self.learning:
            out.update(moved=self.moved, level=_clean(self.level), score=_clean(self.score))
        return out


def _finite(v: float) -> float | None:
    """``v``, or None where JSON has no number (inf: a limit a too short baseline cannot set)."""
    return float(v) if math.isfinite(v) else None


def _clean(d: dict) -> dict:
    return {k: _finite(v) for k, v in d.items()}


@dataclass
class _Level:
    state: HealthState
    rate: float  # design false onsets per day
    change: float  # smallest relevant factor
    on: bool = False

    @property
    def log_change(self) -> float:
        return math.log(self.change)


@dataclass
class HealthTrend:
    """The trend of one machine (one sensor): call :meth:`update` per window or snapshot, in time order."""

    config: TrendConfig = field(default_factory=TrendConfig)

    def __post_init__(self):
        c = self.config
        self.names = tuple(c.indicators)
        p, w = len(self.names), c.slope_window
        self.t0: float | None = None
        self.baseline: Baseline | None = None
        self._learn_t: list = []
        self._learn_y: list = []
        self._t = np.zeros(w)  # ring of the last w times (s, relative) ...
        self._y = np.full((w, p), np.nan)  # ... and log-indicators (slope; the last 3 for the median)
        self._z = np.full(p, np.nan)
        self._levels = [_Level(HealthState.WARNING, c.false_warnings_per_day, c.warning_change),
                        _Level(HealthState.ALARM, c.false_alarms_per_day, c.alarm_change)]
        self._u = None  # (2, p) limits; inf for an indicator not trended
        self._centre = self._sd = None
        self._last = -math.inf
        self.state = HealthState.HEALTHY
        self.since = 0.0
        self.first = {HealthState.WARNING: None, HealthState.ALARM: None}
        self.snapshots = 0

    # ------------------------------------------------------------------------------------
    def update(self, t: float, indicators: Mapping[str, float]) -> TrendRecord:
        """Take the indicators of the snapshot starting at ``t`` (s, the data's clock)."""
        rel = self._place(t)
        y = np.array([_log(indicators.get(n)) for n in self.names])
        k = self.snapshots % self._t.size
        self._t[k], self._y[k] = rel, y
        self.snapshots += 1
        med = self._median()
        lam = self.config.smoothing
        self._z = np.where(np.isnan(self._z), med, np.where(np.isnan(med), self._z, (1 - lam) * self._z + lam * med))
        slope = self._slopes()
        if self.baseline is None:
            self._learn_t.append(rel)
            self._learn_y.append(y)
            if self._baseline_complete(rel):
                self._fit_baseline()
            return TrendRecord(rel, self.state, self.since, True, {}, {}, slope, "")
        d = np.concatenate([self._z, med]) - self._centre  # (EWMA charts, median charts)
        s = d / self._sd
        for level, u in zip(self._levels, self._u):
            above = s >= u
            if not level.on and (above & (d >= level.log_change)).any():
                level.on = True
            elif level.on and not above.any():
                level.on = False
        state = max((lv.state for lv in self._levels if lv.on), default=HealthState.HEALTHY)
        if state != self.state:
            self.state, self.since = state, rel
            for st in self.first:
                if state >= st and self.first[st] is None:
                    self.first[st] = rel
        p = len(self.names)
        with np.errstate(invalid="ignore"):
            ratio = s / self._u[0]
        score = np.fmax(ratio[:p], ratio[p:])
        ranked = np.where(np.isnan(score), -np.inf, score)
        moved = self.names[int(np.argmax(ranked))] if np.isfinite(ranked).any() else ""
        return TrendRecord(rel, self.state, self.since, False, dict(zip(self.names, np.exp(d[:p]).tolist())),
                           dict(zip(self.names, score.tolist())), slope, moved)

    def _place(self, t: float) -> float:
        """``t`` (s) relative to the first window or snapshot; ValueError when it goes back in time."""
        if self.t0 is None:
            self.t0 = float(t)
        rel = float(t) - self.t0
        if rel < self._last:
            raise ValueError(f"snapshots must come in time order: {rel:.6g} s after {self._last:.6g} s")
        self._last = rel
        return rel

    def hold(self, t: float) -> TrendRecord:
        """A window or snapshot starting at ``t`` (s, the data's clock) held out of the trend (its shaft
        speed changing: the indicators follow the speed, not the machine's condition): not learnt from,
        not charted; the record says the state in force, with the slopes of the windows taken."""
        rel = self._place(t)
        return TrendRecord(rel, self.state, self.since, self.baseline is None, {}, {}, self._slopes(), "")

    def _median(self) -> np.ndarray:
        """Median of the last three log values per indicator (of fewer at the start; NaN ignored)."""
        w = self._t.size
        rows = self._y[[(self.snapshots - i) % w for i in range(1, min(self.snapshots, 3) + 1)]]
        if rows.shape[0] == 3 and not np.isnan(rows).any():
            return median_of_3_rows(rows[0], rows[1], rows[2])
        out = np.full(rows.shape[1], np.nan)
        cols = ~np.isnan(rows).all(axis=0)
        out[cols] = np.nanmedian(rows[:, cols], axis=0)
        return out

    # ------------------------------------------------------------------------------------
    def _baseline_complete(self, rel: float) -> bool:
        c = self.config
        if c.healthy_until is not None:
            return rel >= c.healthy_until and len(self._learn_t) >= MIN_BASELINE
        return len(self._learn_t) >= c.baseline_snapshots and rel >= c.baseline_duration

    def _fit_baseline(self) -> None:
        c = self.config
        t = np.asarray(self._learn_t)
        y = np.asarray(self._learn_y)
        steps = np.diff(t)
        interval = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 1.0
        fits = {}
        for j, name in enumerate(self.names):
            col = y[:, j][np.isfinite(y[:, j])]
            if col.size >= MIN_BASELINE:
                fits[name] = fit_ar1(col)
        charts = (c.smoothing, MEDIAN_CHART)
        per_step = interval / SECONDS_PER_DAY / max(len(charts) * len(fits), 1)
        p = len(self.names)
        out, u = {}, np.full((2, len(charts) * p), np.inf)
        centre, sd = np.zeros(len(charts) * p), np.ones(len(charts) * p)
        for j, name in enumerate(self.names):
            fit = fits.get(name)
            if fit is None:
                continue
            sds, lims = [], []
            for lam in charts:
                g, _rho = d_moments(fit.phi, lam, fit.n)
                sds.append(fit.sigma_e * math.sqrt(float(g)))
                lims.append([limit_for_rate(level.rate * per_step, fit, lam) for level in self._levels])
            out[name] = IndicatorBaseline(fit, tuple(sds), tuple(x[0] for x in lims), tuple(x[1] for x in lims))
            for k in range(len(charts)):
                u[:, k * p + j] = lims[k]
                centre[k * p + j], sd[k * p + j] = fit.centre, sds[k]
        self._u, self._centre, self._sd = u, centre, sd
        self.baseline = Baseline(out, interval, len(self._learn_t), float(t[-1]))
        self._learn_t, self._learn_y = [], []

    def _slopes(self) -> dict:
        """Least-squares slope of each log-indicator over the slope window, per hour (NaN-aware;
        the ring's order does not matter to least squares)."""
        m = min(self.snapshots, self._t.size)
        t, y = self._t[:m], self._y[:m]
        if m < 3:
            return dict.fromkeys(self.names, math.nan)
        if not np.isnan(y).any():
            tc = t - t.mean()
            var = float(tc @ tc)
            slope = (tc @ y) / var * 3600.0 if var > 0 else np.full(y.shape[1], np.nan)
            return dict(zip(self.names, slope.tolist()))
        ok = ~np.isnan(y)
        n = ok.sum(axis=0)
        with np.errstate(all="ignore"):
            tm = np.where(ok, t[:, None], 0.0).sum(axis=0) / n
            dt = np.where(ok, t[:, None] - tm, 0.0)
            var = (dt * dt).sum(axis=0)
            slope = (dt * np.where(ok, y, 0.0)).sum(axis=0) / var * 3600.0
        slope[(n < 3) | ~(var > 0)] = np.nan
        return dict(zip(self.names, slope.tolist()))

    # ------------------------------------------------------------------------------------
    def limits(self) -> dict:
        """Per trended indicator: (baseline level, (warning, alarm) of the EWMA chart, (warning, alarm)
        of the median chart), in its own units: the chart values at which each state begins; {}
        while learning."""
        if self.baseline is None:
            return {}
        c = self.config
        return {n: (math.exp(b.fit.centre),
                    *((b.level(k, b.warning_limit[k], c.warning_change), b.level(k, b.alarm_limit[k], c.alarm_change))
                      for k in range(2)))
                for n, b in self.baseline.indicators.items()}

    def summary(self) -> dict:
        """First warning and alarm (s after the first snapshot, or None), the baseline and its design."""
        b = self.baseline
        out = {"first_warning": self.first[HealthState.WARNING], "first_alarm": self.first[HealthState.ALARM],
               "state": self.state.name.lower(), "since": self.since, "snapshots": self.snapshots,
               "false_warnings_per_day": self.config.false_warnings_per_day,
               "false_alarms_per_day": self.config.false_alarms_per_day}
        if b is None:
            out["baseline"] = None
            return out
        lim = self.limits()
        out["baseline"] = {"snapshots": b.snapshots, "end": b.end, "interval": b.interval,
                           "indicators": {n: {"level": lim[n][0], "sigma": ib.fit.sigma, "phi": ib.fit.phi,
                                              "ewma_limits": [_finite(v) for v in lim[n][1]],
                                              "median_limits": [_finite(v) for v in lim[n][2]]}
                                          for n, ib in b.indicators.items()}}
        return out


_DURATION = re.compile(r"\s*([0-9]*\.?[0-9]+)\s*(s|min|h|d)\s*", re.IGNORECASE)
_SECONDS = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}


def parse_baseline(text: str, min_duration: float = 0.0) -> TrendConfig:
    """The :class:`TrendConfig` of a baseline given as text: a count N (the first N windows or snapshots,
    spanning at least ``min_duration`` s) or a duration such as ``2h``, ``45min``, ``600s`` (a stated
    healthy period after the first); ValueError when unreadable."""
    text = str(text).strip()
    if text.isdigit():
        return TrendConfig(baseline_snapshots=int(text), baseline_duration=float(min_duration))
    m = _DURATION.fullmatch(text)
    if not m:
        raise ValueError(f"baseline {text!r}: give a number of snapshots (e.g. 30) or a duration "
                         "(e.g. 2h, 45min, 600s)")
    return TrendConfig(healthy_until=float(m.group(1)) * _SECONDS[m.group(2).lower()])


def _log(v) -> float:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return math.nan
    return math.log(v) if v > 0 and math.isfinite(v) else math.nan
