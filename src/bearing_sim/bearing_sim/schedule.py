"""Schedules: faults (the thesis' scenarios and ``fault:seconds`` SPEC strings) and speed.

A fault schedule is a list of ``(FaultState, seconds)`` segments played in order; a
fault starts at the start of its segment. A speed schedule is a
:class:`~bearing_common.shaft_angle.SpeedProfile` from ``T0:RPM0,T1:RPM1,...`` and an
optional wobble ``FRACTION:PERIOD`` (:func:`speed_profile`).
"""

import math

from bearing_common.shaft_angle import SpeedProfile
from bearing_common.states import FaultState, parse_fault

DEFAULT_SEGMENT_DURATION = 0.2  #: s, per scenario segment (CONTRACT.md)

#: The thesis cases: name -> sequence of states.
SCENARIOS = {
    name: tuple(parse_fault(part) for part in name.split("-"))
    for name in ("normal", "or", "ir", "or-ir", "ir-or", "or-normal", "normal-or", "ir-normal", "normal-ir")
}


def _check_duration(seconds, what):
    try:
        value = float(seconds)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: duration {seconds!r} is not a number") from None
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{what}: duration must be a positive number of seconds, got {seconds!r}")
    return value


def scenario(name, segment_duration=DEFAULT_SEGMENT_DURATION):
    """Schedule of a named scenario (``normal``, ``or``, ``or-ir``, ...), each
    segment lasting ``segment_duration`` s."""
    key = str(name).strip().lower()
    if key not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; expected one of: {', '.join(SCENARIOS)}")
    d = _check_duration(segment_duration, "segment_duration")
    return [(state, d) for state in SCENARIOS[key]]


def parse_schedule(spec):
    """Parse ``"normal:0.1,outer_race:0.2,inner_race:0.2"`` (short forms ``or``/``ir``
    accepted) into ``[(FaultState, seconds), ...]``."""
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError("empty schedule; expected e.g. 'normal:0.1,outer_race:0.2'")
    out = []
    for item in spec.split(","):
        item = item.strip()
        if ":" not in item:
            raise ValueError(f"schedule item {item!r} is not of the form fault:seconds")
        name, _, secs = item.partition(":")
        state = parse_fault(name)
        if state in (FaultState.BALL, FaultState.UNKNOWN):
            raise ValueError(f"schedule item {item!r}: the simulator has no model for {state.label!r}")
        out.append((state, _check_duration(secs.strip(), f"schedule item {item!r}")))
    return out


def validate_schedule(schedule):
    """Check a list of (state, seconds); returns it as [(FaultState, float)]."""
    out = []
    if len(schedule) == 0:
        raise ValueError("empty schedule")
    for entry in schedule:
        try:
            state, secs = entry
        except (TypeError, ValueError):
            raise ValueError(f"schedule entry {entry!r} is not a (state, seconds) pair") from None
        state = parse_fault(state) if isinstance(state, str) else FaultState(int(state))
        if state in (FaultState.BALL, FaultState.UNKNOWN):
            raise ValueError(f"the simulator has no model for {state.label!r}")
        out.append((state, _check_duration(secs, f"schedule entry {entry!r}")))
    return out


def speed_profile(rpm, spec, wobble, duration):
    """The speed schedule of a run of ``duration`` s: ``spec`` ``"T0:RPM0,T1:RPM1,..."``
    (seconds:rev/min, piecewise linear) or else the constant ``rpm``, times the wobble
    ``"FRACTION:PERIOD"`` (1 + FRACTION·sin(2π t / PERIOD s)) when given. None when neither
    is given (empty strings count as not given): the constant-speed simulator. ValueError
    with the reason otherwise."""
    if not spec and not wobble:
        return None
    profile = SpeedProfile.parse(spec) if spec else SpeedProfile.constant(rpm)
    if wobble:
        fraction, sep, period = wobble.partition(":")
        try:
            if not sep:
                raise ValueError
            fraction, period = float(fraction), float(period)
        except ValueError:
            raise ValueError(f"speed wobble {wobble!r} is not of the form FRACTION:PERIOD, e.g. 0.02:1.5") from None
        profile = profile.with_wobble(fraction, period, duration)
    return profile
