"""One machine's health, window by window or snapshot by snapshot: what the ``health`` topic carries.

:class:`HealthMonitor` is the one entry point of both the live node and ``bearing-trend``:
per window or snapshot it checks the sensor, computes the condition indicators
(:mod:`.indicators`), the ISO 20816-3 zone (:mod:`.iso20816`) and the trend
(:mod:`.trend`), and returns a :class:`HealthRecord`. The fault-comb evidence per hypothesis
is not computed here: the caller that has it (the spectral decision) passes it in, and the
record carries it (optional; ``None`` when not computed).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..decision.sensor_health import check_window
from .indicators import ConditionIndicators, condition_indicators, default_envelope_band
from .iso20816 import DEFAULT_MACHINE_CLASS, iso_zone, machine_class
from .trend import HealthTrend, TrendConfig, TrendRecord


@dataclass(frozen=True)
class HealthRecord:
    """Health of one window or snapshot.

    Attributes
    ----------
    t : float
        Time of its first sample, s, on the data's clock.
    indicators : ConditionIndicators
    iso_zone : str
        ``A``-``D`` (``""`` when the velocity could not be computed).
    trend : TrendRecord
        State, since when, slope (times relative to the first snapshot).
    evidence : dict or None
        Fault-comb evidence per hypothesis, ``{hypothesis: log10 p}`` (≤ 0; smaller = stronger
        evidence of that fault's impact comb), as the spectral decision computed it for this
        window; None when not computed.
    untested : tuple of str
        Hypotheses this window's length or band could not test (with ``evidence``).
    """

    t: float
    indicators: ConditionIndicators
    iso_zone: str
    trend: TrendRecord
    evidence: dict | None = None
    untested: tuple = ()

    def to_json(self) -> dict:
        """One ``bearing-trend`` line: ``{"t", "state", "indicators", ...}`` (t relative, s)."""
        out = {"t": self.trend.t, "state": self.trend.state.name.lower(),
               "indicators": self.indicators.to_json(), "iso_zone": self.iso_zone or None,
               "trend": self.trend.to_json()}
        if self.evidence is not None:
            out["evidence"] = {k: float(v) for k, v in self.evidence.items()}
            out["untested"] = list(self.untested)
        return out


@dataclass
class HealthMonitor:
    """Indicators, ISO zone and trend of one sensor's windows or snapshots, in time order.

    Parameters
    ----------
    trend : TrendConfig
    machine : str
        ISO 20816-3 machine class (:data:`.iso20816.ZONE_LIMITS_MM_S`).
    f_top : float
        Highest envelope frequency of interest (Hz; e.g. 3 × the highest fault rate), which
        raises the default demodulation band's lower edge (:func:`.indicators.default_envelope_band`).
    """

    trend: TrendConfig = field(default_factory=TrendConfig)
    machine: str = DEFAULT_MACHINE_CLASS
    f_top: float = 0.0

    def __post_init__(self):
        self.machine = machine_class(self.machine)
        self.tracker = HealthTrend(self.trend)
        self.sensor_problems: list = []  # (t, problem) of the windows not scored

    def update(self, t: float, samples, sample_rate: float, envelope_band: tuple | None = None,
               evidence: Mapping[str, float] | None = None, untested: Sequence[str] = ()) -> HealthRecord | None:
        """Score the window starting at ``t`` (s): ``samples`` in m/s² at ``sample_rate`` Hz.

        ``envelope_band`` (Hz) overrides the default demodulation band (the spectral decision's
        choice); ``evidence`` / ``untested`` are passed through to the record. Returns None,
        and records the problem in :attr:`sensor_problems`, when the sensor signal is unfit
        (flat, clipped, coarsely quantised: :func:`bearing_diagnoser.sensor_health.check_window`);
        such a window does not enter the trend.
        """
        x = np.asarray(samples, dtype=float)
        check = check_window(x)
        if not check.ok:
            self.sensor_problems.append((float(t), check.problem))
            return None
        band = envelope_band if envelope_band is not None else default_envelope_band(sample_rate, self.f_top)
        ind = condition_indicators(x, sample_rate, band)
        trend = self.tracker.update(t, ind.trended())
        zone = iso_zone(ind.velocity_rms, self.machine) if math.isfinite(ind.velocity_rms) else ""
        return HealthRecord(float(t), ind, zone, trend, None if evidence is None else dict(evidence), tuple(untested))

    def summary(self) -> dict:
        """The trend's summary (:meth:`.trend.HealthTrend.summary`) and the windows not scored."""
        out = self.tracker.summary()
        out["sensor_problems"] = len(self.sensor_problems)
        out["machine_class"] = self.machine
        return out
