"""What the live view serves for each message type of the graph, and the JSON it makes of each (no rclpy).

Every topic of a type in :data:`KINDS` becomes one Foxglove channel of the same name (``/motor_3/health``),
in the form Foxglove's panels read:

* ``FaultState`` (``fault_state``, ``sim/truth``), ``HealthIndicators`` (``health``), ``EnvelopeSpectrum``
  (``envelope_spectrum``) and ``FleetState`` (``fleet_state``): JSON with a JSON schema, numbers as
  numbers (the Plot panel plots any numeric field), names as strings (State Transitions), the
  parallel arrays of the ROS messages as objects keyed by name (``.scores.outer_race``,
  ``.level.kurtosis``, ``.lines.outer_race.measured[:]``), stamps as ``{sec, nsec}`` (the Plot
  panel's ``headerStamp`` time); non-finite numbers become ``null`` (JSON has no NaN);
* ``VibrationChunk`` (``vibration/drive_end``, ``unbalance``): min, max and RMS per block of samples
  (:mod:`.vibration_blocks`), one JSON message per block;
* ``DiagnosticArray`` (``/diagnostics``): the ROS 2 message itself, CDR with its ``ros2msg`` schema, as
  Foxglove's Diagnostics panels read it.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from bearing_common import topics
from bearing_common.states import FaultState
from bearing_diagnoser.health.iso20816 import ZONES
from bearing_diagnoser.health.trend import HealthState

#: Schema names of the JSON channels (the live view's own: no ROS type has these fields).
SCHEMA_PREFIX = "bearing_live_view."

#: Offset of the spectrum markers above the spectrum's largest value (module docstring of :func:`spectrum_view`).
MARKER_LEVELS = {"measured": 1.05, "told": 1.15}


@dataclass(frozen=True, eq=False)  # compared and hashed by identity: one object per kind
class Kind:
    """How one ROS message type is served: its Foxglove schema name and the JSON schema of its view
    (None: the ROS message passes as CDR with its ros2msg schema)."""

    msgtype: str
    schema_name: str
    json_schema: dict | None


def _number(description: str) -> dict:
    return {"type": ["number", "null"], "description": description}


def _numbers(description: str) -> dict:
    return {"type": "array", "items": {"type": ["number", "null"]}, "description": description}


def _keyed(description: str, item: dict | None = None) -> dict:
    return {"type": "object", "additionalProperties": item or {"type": ["number", "null"]}, "description": description}


_TIME = {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}
_HEADER = {"type": "object", "properties": {"stamp": _TIME, "frame_id": {"type": "string"}}}


def _object(title: str, properties: dict) -> dict:
    return {"title": title, "type": "object", "properties": {"header": _HEADER, **properties}}


FAULT_STATE = Kind(topics.FAULT_STATE.msgtype, SCHEMA_PREFIX + "FaultState", _object("fault state", {
    "state": {"type": "integer", "description": "0 NORMAL, 1 OUTER_RACE, 2 INNER_RACE, 3 BALL, 4 UNKNOWN"},
    "state_name": {"type": "string"},
    "confidence": _number("0..1"),
    "onset": _TIME,
    "scores": _keyed("per hypothesis: significance (>= 1 significant), posterior, band, speed (FaultState.msg)"),
    "model_set": {"type": "string"},
    "detail": {"type": "string"},
}))

HEALTH = Kind(topics.HEALTH.msgtype, SCHEMA_PREFIX + "HealthIndicators", _object("condition indicators and trend", {
    **{k: _number(d) for k, d in (
        ("duration", "s"), ("sample_rate", "Hz"), ("rms", "m/s^2"), ("peak", "m/s^2"), ("crest_factor", ""),
        ("kurtosis", ""), ("velocity_rms", "m/s"), ("envelope_rms", "m/s^2"), ("score", "trend statistic / limit"),
        ("slope", "d ln(indicator)/dt, 1/h"))},
    "iso_zone": {"type": "integer", "description": "ISO 20816-3 zone: 0 unknown, 1-4 = A-D"},
    "iso_zone_name": {"type": "string"},
    "iso_class": {"type": "string"},
    "state": {"type": "integer", "description": "0 HEALTHY, 1 WARNING, 2 ALARM"},
    "state_name": {"type": "string"},
    "state_since": _TIME,
    "learning": {"type": "boolean"},
    "moved": {"type": "string"},
    "level": _keyed("per trended indicator: level / baseline"),
    "evidence": _keyed("per hypothesis: fault-comb statistic / threshold"),
    "evidence_accumulated": _keyed("per hypothesis: the accumulated evidence alone"),
    "untested": _keyed("per hypothesis: why it was not tested", {"type": "string"}),
    "evidence_problem": {"type": "string"},
}))

_LINES = {"type": "object", "properties": {
    "told": _numbers("Hz, at the told shaft rate"), "measured": _numbers("Hz, at the rate used"),
    "carrier": {"type": "array", "items": {"type": "boolean"}}, "rho": _number("best comb scale"),
    "told_level": _numbers("marker heights for told (Plot: x = told)"),
    "measured_level": _numbers("marker heights for measured (Plot: x = measured)")}}

SPECTRUM = Kind(topics.ENVELOPE_SPECTRUM.msgtype, SCHEMA_PREFIX + "EnvelopeSpectrum", _object("envelope spectrum", {
    **{k: _number(d) for k, d in (
        ("window_duration", "s"), ("bin_width", "Hz"), ("frequency_resolution", "Hz"), ("band_low", "Hz"),
        ("band_high", "Hz"), ("told_shaft_rate", "Hz"), ("shaft_rate", "Hz"))},
    "bins_per_value": {"type": "integer"},
    "shaft_rate_source": {"type": "string"},
    "frequency": _numbers("Hz"),
    "magnitude": _numbers("normalised squared envelope spectrum (noise median 1)"),
    "lines": _keyed("per hypothesis: its comb lines", _LINES),
}))

FLEET = Kind(topics.FLEET_STATE.msgtype, SCHEMA_PREFIX + "FleetState", _object("fleet", {
    "motors": {"type": "array", "items": {"type": "object", "properties": {
        "motor": {"type": "string"}, "state": {"type": "integer"}, "state_name": {"type": "string"},
        "confidence": _number("0..1"), "onset": _TIME, "last_update": _TIME, "age": _number("s"),
        "stale": {"type": "boolean"}}}},
}))

VIBRATION = Kind(topics.VIBRATION.msgtype, SCHEMA_PREFIX + "VibrationBlock", _object("vibration block", {
    "duration": _number("s of signal in the block"),
    "min": _number("m/s^2"), "max": _number("m/s^2"), "rms": _number("m/s^2, mean not removed"),
}))

DIAGNOSTICS = Kind(topics.DIAGNOSTICS.msgtype, topics.DIAGNOSTICS.msgtype, None)

#: The message types the live view serves, by ROS type name.
KINDS = {k.msgtype: k for k in (FAULT_STATE, HEALTH, SPECTRUM, FLEET, VIBRATION, DIAGNOSTICS)}


def qos_topic(msgtype: str) -> topics.Topic:
    """The graph's topic whose QoS a subscription to any topic of ``msgtype`` takes (the contract's table)."""
    by_type = {t.msgtype: t for t in (*topics.GRAPH_TOPICS.values(), topics.FLEET_STATE)}
    return by_type[msgtype]


# -- messages into JSON ------------------------------------------------------------------------------
def encode(view: dict) -> bytes:
    """``view`` as strict JSON (non-finite numbers as null: JSON has no NaN)."""
    return json.dumps(_finite(view), allow_nan=False, separators=(",", ":")).encode()


def _finite(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def time_view(stamp) -> dict:
    """A builtin_interfaces/Time as Foxglove's ``{sec, nsec}``."""
    return {"sec": int(stamp.sec), "nsec": int(stamp.nanosec)}


def seconds_view(seconds: float) -> dict:
    """Seconds (>= 0) as Foxglove's ``{sec, nsec}``, rounded to the nanosecond."""
    sec, nsec = divmod(round(seconds * 1e9), 1_000_000_000)
    return {"sec": int(sec), "nsec": int(nsec)}


def header_view(header) -> dict:
    return {"stamp": time_view(header.stamp), "frame_id": header.frame_id}


def _pairs(names, values) -> dict:
    """Parallel arrays as {name: value}; ValueError when their lengths differ."""
    names, values = list(names), list(values)
    if len(names) != len(values):
        raise ValueError(f"{len(names)} names for {len(values)} values")
    return {n: (float(v) if isinstance(v, float) else v) for n, v in zip(names, values)}


def state_name(state: int) -> str:
    """The name of a FaultState integer; ValueError for another."""
    try:
        return FaultState(state).name
    except ValueError:
        raise ValueError(f"unknown fault state {state!r}") from None


def fault_state_view(msg) -> dict:
    """A ``FaultState`` message as JSON (:data:`FAULT_STATE`)."""
    return {"header": header_view(msg.header), "state": int(msg.state), "state_name": state_name(msg.state),
            "confidence": float(msg.confidence), "onset": time_view(msg.onset),
            "scores": _pairs(msg.hypotheses, msg.scores), "model_set": msg.model_set, "detail": msg.detail}


def health_view(msg) -> dict:
    """A ``HealthIndicators`` message as JSON (:data:`HEALTH`)."""
    zone = int(msg.iso_zone)
    if not 0 <= zone <= len(ZONES):
        raise ValueError(f"unknown ISO zone {zone}")
    try:
        trend = HealthState(msg.state).name
    except ValueError:
        raise ValueError(f"unknown condition state {msg.state!r}") from None
    out = {"header": header_view(msg.header)}
    out.update({k: float(getattr(msg, k)) for k in (
        "duration", "sample_rate", "rms", "peak", "crest_factor", "kurtosis", "velocity_rms", "envelope_rms", "score",
        "slope")})
    out.update(iso_zone=zone, iso_zone_name=ZONES[zone - 1] if zone else "", iso_class=msg.iso_class,
               state=int(msg.state), state_name=trend, state_since=time_view(msg.state_since),
               learning=bool(msg.learning), moved=msg.moved, level=_pairs(msg.trended, msg.level),
               evidence=_pairs(msg.hypotheses, msg.evidence),
               evidence_accumulated=_pairs(msg.hypotheses, msg.evidence_accumulated),
               untested=_pairs(msg.untested, msg.untested_why), evidence_problem=msg.evidence_problem)
    return out


def spectrum_view(msg) -> dict:
    """An ``EnvelopeSpectrum`` message as JSON (:data:`SPECTRUM`).

    Each hypothesis' lines come with marker heights for the Plot panel (x = the line frequencies,
    y = ``*_level``, points without a line): a row at :data:`MARKER_LEVELS` × the spectrum's largest
    value, the measured-speed row under the told-speed row, so that both show where they coincide.
    """
    freq, mag = [float(f) for f in msg.frequency], [float(v) for v in msg.magnitude]
    if len(freq) != len(mag):
        raise ValueError(f"{len(freq)} frequencies for {len(mag)} values")
    top = max((v for v in mag if math.isfinite(v)), default=1.0)
    lines = {}
    for entry in msg.lines:
        told, measured = [float(f) for f in entry.told], [float(f) for f in entry.measured]
        lines[entry.hypothesis] = {"told": told, "measured": measured, "carrier": [bool(c) for c in entry.carrier],
                                   "rho": float(entry.rho),
                                   "told_level": [MARKER_LEVELS["told"] * top] * len(told),
                                   "measured_level": [MARKER_LEVELS["measured"] * top] * len(measured)}
    out = {"header": header_view(msg.header)}
    out.update({k: float(getattr(msg, k)) for k in (
        "window_duration", "bin_width", "frequency_resolution", "band_low", "band_high", "told_shaft_rate",
        "shaft_rate")})
    out.update(bins_per_value=int(msg.bins_per_value), shaft_rate_source=msg.shaft_rate_source, frequency=freq,
               magnitude=mag, lines=lines)
    return out


def fleet_view(msg) -> dict:
    """A ``FleetState`` message as JSON (:data:`FLEET`)."""
    return {"header": header_view(msg.header), "motors": [
        {"motor": m.motor, "state": int(m.state), "state_name": state_name(m.state), "confidence": float(m.confidence),
         "onset": time_view(m.onset), "last_update": time_view(m.last_update), "age": float(m.age),
         "stale": bool(m.stale)} for m in msg.motors]}


def block_view(block, frame_id: str) -> dict:
    """A :class:`.vibration_blocks.Block` of a sample stream as JSON (:data:`VIBRATION`)."""
    return {"header": {"stamp": seconds_view(block.stamp), "frame_id": frame_id}, "duration": block.duration,
            "min": block.min, "max": block.max, "rms": block.rms}


#: The JSON view of each JSON kind's messages.
VIEWS = {FAULT_STATE: fault_state_view, HEALTH: health_view, SPECTRUM: spectrum_view, FLEET: fleet_view}
