"""The fault states: one set of integers for messages, npz ``truth`` and code.

The values are the project's contract (``../shared/CONTRACT.md``) and are
mirrored as constants in ``bearing_msgs/msg/FaultState.msg``.
"""

from enum import IntEnum


class FaultState(IntEnum):
    """Condition of the drive-end bearing."""

    NORMAL = 0
    OUTER_RACE = 1
    INNER_RACE = 2
    BALL = 3  # rolling-element defect (decided by the spectral method only)
    UNKNOWN = 4  # abnormal, but no fault model explains it

    @property
    def label(self) -> str:
        """Lower-case name used in JSON and schedules, e.g. ``outer_race``."""
        return self.name.lower()


_ALIASES = {"or": FaultState.OUTER_RACE, "ir": FaultState.INNER_RACE}


def parse_fault(name: str) -> FaultState:
    """Parse a fault name: ``normal``, ``outer_race``/``or``, ``inner_race``/``ir``, ...

    Raises ValueError naming the accepted names.
    """
    key = name.strip().lower()
    if key in _ALIASES:
        return _ALIASES[key]
    for state in FaultState:
        if state.label == key:
            return state
    accepted = ", ".join([s.label for s in FaultState] + sorted(_ALIASES))
    raise ValueError(f"unknown fault name {name!r}; expected one of: {accepted}")
