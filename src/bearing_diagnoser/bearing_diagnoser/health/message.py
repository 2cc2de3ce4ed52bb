"""A :class:`.monitor.HealthRecord` into a ``bearing_msgs/msg/HealthIndicators`` (no rclpy import here:
the message object is the caller's)."""

from __future__ import annotations

import math

from bearing_common.stamps import to_stamp

from .iso20816 import ZONES

#: Message zone constant of each ISO zone letter (``""``: unknown).
ZONE_CODES = {"": 0, **{z: i + 1 for i, z in enumerate(ZONES)}}


def fill_health_message(msg, record, monitor, frame_id: str = ""):
    """Fill ``msg`` (a ``HealthIndicators``) from ``record`` of ``monitor``; returns ``msg``.

    Stamps: ``header.stamp`` = the window's first sample, ``state_since`` = when the state
    began, both on the data's clock. The evidence arrays stay empty when the record has none
    (``evidence_problem`` says why).
    """
    ind, trend = record.indicators, record.trend
    msg.header.stamp = to_stamp(record.t)
    msg.header.frame_id = frame_id
    msg.duration = float(ind.duration)
    msg.sample_rate = float(ind.sample_rate)
    msg.rms, msg.peak, msg.crest_factor, msg.kurtosis = (float(v) for v in (ind.rms, ind.peak, ind.crest_factor,
                                                                            ind.kurtosis))
    msg.velocity_rms = float(ind.velocity_rms)
    msg.velocity_band_low, msg.velocity_band_high = (float(v) for v in ind.velocity_band)
    msg.envelope_rms = float(ind.envelope_rms)
    band = ind.envelope_band or (math.nan, math.nan)
    msg.envelope_band_low, msg.envelope_band_high = float(band[0]), float(band[1])
    msg.iso_zone = ZONE_CODES[record.iso_zone]
    msg.iso_class = monitor.machine
    msg.state = int(trend.state)
    msg.state_since = to_stamp((monitor.tracker.t0 or 0.0) + trend.since)
    msg.learning = bool(trend.learning)
    msg.speed_changing = bool(record.speed_changing)
    msg.moved = trend.moved
    msg.score = float(trend.score.get(trend.moved, math.nan)) if trend.moved else math.nan
    msg.slope = float(trend.slope.get(trend.moved, math.nan)) if trend.moved else math.nan
    msg.trended = list(monitor.tracker.names)
    msg.level = [float(trend.level.get(n, math.nan)) for n in monitor.tracker.names]
    ev = record.evidence
    if ev is None:
        msg.evidence_problem = "not computed"
        return msg
    msg.hypotheses = list(ev.significance)
    msg.evidence = [float(v) for v in ev.significance.values()]
    msg.evidence_accumulated = [float(ev.accumulated.get(h, math.nan)) for h in ev.significance]
    msg.untested = list(ev.untested)
    msg.untested_why = list(ev.untested.values())
    msg.evidence_problem = ev.problem
    return msg

