"""One machine's health, window by window or snapshot by snapshot: what the ``health`` topic carries.

:class:`HealthMonitor` is the one entry point of both the live node and ``bearing-trend``:
per window or snapshot it checks the sensor, computes the condition indicators
(:mod:`.indicators`), the ISO 20816-3 zone (:mod:`.iso20816`) and the trend
(:mod:`.trend`), and returns a :class:`HealthRecord`. The fault-comb evidence per hypothesis
is not computed here: the caller that has it (the fault decision, :mod:`.health_session`)
passes it in as :class:`FaultEvidence`, and the record carries it (``None`` when not
computed at all).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..decision.not_diagnosed import NotDiagnosed
from ..decision.sensor_health import check_window
from .indicators import ConditionIndicators, condition_indicators, default_envelope_band
from .iso20816 import DEFAULT_MACHINE_CLASS, iso_zone, machine_class
from .trend import HealthTrend, TrendConfig, TrendRecord


@dataclass(frozen=True)
class FaultEvidence:
    """The fault decision's comb evidence for one window or snapshot, hypotheses by name.

    Attributes
    ----------
    significance : dict
        {hypothesis: the comb test's statistic ÷ its threshold} of the decided window that
        ended last in this one, as the decision weighs it (the stronger of the window alone and
        ``accumulated``; ≥ 1: significant at the decision's false-alarm rate; the numbers
        ``fault_state`` publishes as its scores).
    accumulated : dict
        {hypothesis: the same of the evidence accumulated over recent windows or snapshots}
        (the spectral decision's long horizon; empty when it holds none).
    untested : dict
        {hypothesis: why this window or snapshot could not test it} (too short to resolve its lines).
    problem : str
        Why there is no evidence ("" when there is): not diagnosed (sensor, speed, resolution),
        no decision yet, the decision impossible.
    not_diagnosed : NotDiagnosed or None
        The decided window's own outcome when it was not diagnosed
        (:mod:`bearing_diagnoser.decision.not_diagnosed`; ``problem`` then says it too).
    """

    significance: dict = field(default_factory=dict)
    accumulated: dict = field(default_factory=dict)
    untested: dict = field(default_factory=dict)
    problem: str = ""
    not_diagnosed: NotDiagnosed | None = None

    def to_json(self) -> dict:
        out = {"significance": dict(self.significance), "accumulated": dict(self.accumulated),
               "untested": dict(self.untested)}
        if self.not_diagnosed is not None:
            out["not_diagnosed"] = self.not_diagnosed.to_json()
        return out | ({"problem": self.problem} if self.problem else {})


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
    evidence : FaultEvidence or None
        The fault decision's comb evidence for it; None when not computed at all.
    speed_changing : bool
        Its measured shaft speed spread beyond 2 % of its mean (:mod:`.health_session`): its indicators were
        held out of the trend (``trend`` is the state in force, untouched).
    """

    t: float
    indicators: ConditionIndicators
    iso_zone: str
    trend: TrendRecord
    evidence: FaultEvidence | None = None
    speed_changing: bool = False

    def to_json(self) -> dict:
        """One ``bearing-trend`` line: ``{"t", "state", "indicators", ...}`` (t relative, s)."""
        out = {"t": self.trend.t, "state": self.trend.state.name.lower(),
               "indicators": self.indicators.to_json(), "iso_zone": self.iso_zone or None,
               "trend": self.trend.to_json(), "speed_changing": self.speed_changing}
        if self.evidence is not None:
            out["evidence"] = self.evidence.to_json()
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
               evidence: FaultEvidence | None = None, speed_changing: bool = False) -> HealthRecord | None:
        """Score the window starting at ``t`` (s): ``samples`` in m/s² at ``sample_rate`` Hz.

        ``envelope_band`` (Hz) overrides the default demodulation band (which stays put, so that
        the envelope RMS trends one band over a life); ``evidence`` is passed through to the
        record; ``speed_changing``: the window's shaft speed changed, its indicators are computed but
        held out of the trend (:meth:`.trend.HealthTrend.hold`). Returns None,
        and records the problem in :attr:`sensor_problems`, when the sensor signal is unfit
        (flat, clipped, coarsely quantised: :func:`bearing_diagnoser.decision.sensor_health.check_window`);
        such a window does not enter the trend.
        """
        x = np.asarray(samples, dtype=float)
        check = check_window(x)
        if not check.ok:
            self.sensor_problems.append((float(t), check.problem))
            return None
        band = envelope_band if envelope_band is not None else default_envelope_band(sample_rate, self.f_top)
        ind = condition_indicators(x, sample_rate, band)
        trend = self.tracker.hold(t) if speed_changing else self.tracker.update(t, ind.trended())
        zone = iso_zone(ind.velocity_rms, self.machine) if math.isfinite(ind.velocity_rms) else ""
        return HealthRecord(float(t), ind, zone, trend, evidence, speed_changing)

    def summary(self) -> dict:
        """The trend's summary (:meth:`.trend.HealthTrend.summary`) and the windows not scored."""
        out = self.tracker.summary()
        out["sensor_problems"] = len(self.sensor_problems)
        out["machine_class"] = self.machine
        return out
