"""The fleet summary, without rclpy: each motor's latest fault state, its age, and a text table.

A motor is the namespace its graph runs in: ``/motor_7/fault_state`` belongs to ``motor_7``
(the root namespace gives ``""``). A motor whose last decision arrived longer ago than the
stale timeout is marked stale (its diagnoser stopped deciding: no input, a dead node).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bearing_common import topics
from bearing_common.states import FaultState


def motor_of(topic_name: str) -> str | None:
    """The motor (namespace) of a fully qualified ``fault_state`` topic name, None for another topic."""
    suffix = "/" + topics.FAULT_STATE.name
    if not topic_name.endswith(suffix):
        return None
    return topic_name[: -len(suffix)].strip("/")


@dataclass
class MotorRow:
    """A motor's latest state: times in seconds (``onset``/``stamp`` signal time, ``received`` node time)."""

    motor: str
    state: FaultState
    confidence: float
    onset: float
    stamp: float
    received: float

    def age(self, now: float) -> float:
        return max(0.0, now - self.received)


class FleetTable:
    """Latest state per motor; ``stale_timeout`` in seconds."""

    def __init__(self, stale_timeout: float = 5.0):
        self.stale_timeout = float(stale_timeout)
        self._rows: dict[str, MotorRow] = {}

    def add_motor(self, motor: str) -> None:
        """A motor seen in the graph before its first decision: listed as stale until one arrives."""
        self._rows.setdefault(motor, MotorRow(motor, FaultState.NORMAL, 0.0, 0.0, 0.0, float("-inf")))

    def update(self, motor: str, state: int, confidence: float, onset: float, stamp: float, now: float) -> bool:
        """A decision of ``motor``; True when its state changed.

        Raises ValueError (one line, the table unchanged) for a state that is not a
        :class:`FaultState`, a confidence outside [0, 1] or non-finite times.
        """
        if state not in FaultState._value2member_map_:
            raise ValueError(f"{motor or '/'}: unknown state {state!r}")
        if not 0.0 <= confidence <= 1.0:
            raise ValueError(f"{motor or '/'}: confidence {confidence!r} outside [0, 1]")
        if not all(math.isfinite(t) for t in (onset, stamp)):
            raise ValueError(f"{motor or '/'}: non-finite onset or stamp ({onset!r}, {stamp!r})")
        old = self._rows.get(motor)
        self._rows[motor] = MotorRow(motor, FaultState(state), float(confidence), onset, stamp, now)
        return old is None or old.state != FaultState(state) or old.received == float("-inf")

    def rows(self) -> list[MotorRow]:
        """Motors in name order."""
        return [self._rows[m] for m in sorted(self._rows)]

    def is_stale(self, row: MotorRow, now: float) -> bool:
        return row.age(now) > self.stale_timeout

    def render(self, now: float) -> str:
        """A fixed-width text table, worst first (faults, then unknown, then stale, then normal)."""
        def rank(row):
            if self.is_stale(row, now):
                return 2
            return {FaultState.NORMAL: 3, FaultState.UNKNOWN: 1}.get(row.state, 0)

        rows = sorted(self.rows(), key=lambda r: (rank(r), r.motor))
        lines = [f"{'motor':<16} {'state':<11} {'conf':>5} {'onset (s)':>10} {'last (s)':>10} {'age (s)':>8}"]
        for r in rows:
            stale = self.is_stale(r, now)
            age = "never" if r.received == float("-inf") else f"{r.age(now):8.1f}"
            state = "STALE" if stale else r.state.name
            lines.append(f"{r.motor or '/':<16} {state:<11} {r.confidence:5.2f} {r.onset:10.3f} {r.stamp:10.3f} "
                         f"{age:>8}")
        faults = sum(1 for r in rows if not self.is_stale(r, now) and r.state != FaultState.NORMAL)
        stale = sum(1 for r in rows if self.is_stale(r, now))
        lines.append(f"{len(rows)} motors, {faults} not normal, {stale} stale")
        return "\n".join(lines)
