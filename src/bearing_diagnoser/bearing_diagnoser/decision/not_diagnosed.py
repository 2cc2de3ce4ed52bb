"""Why a window was not diagnosed: one outcome, a kind and a one-line reason, from the front end to every output.

A window is diagnosed (labelled, and taken into the hysteresis) or not diagnosed, for one
reason of one kind:

* ``sensor`` — the sensor signal is unfit: dead, clipped, quantised, non-finite
  (:mod:`.sensor_health`);
* ``speed`` — the shaft speed is not known well enough to tell the parts' combs apart
  (a nameplate speed the vibration has not confirmed; a speed tracked from the vibration that
  no shaft comb carries, :meth:`..order_tracking.SpeedTrack.unsupported`);
* ``resolution`` — the window (a short snapshot) is too short to resolve any hypothesis' lines.

The front end names it (:class:`.front_end.WindowVerdict`), the core passes it on
(:class:`.state_tracker.Decision`), and the outputs carry it as they are: the node's
``/diagnostics``, the health records' evidence, ``bearing-diagnose``'s segments and
``bearing-trend``'s lines (JSON ``{"kind": ..., "reason": ...}``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass

SENSOR = "sensor"
SPEED = "speed"
RESOLUTION = "resolution"

#: The kinds of "not diagnosed", in the order a run's summary prefers them on a tie.
KINDS = (SENSOR, SPEED, RESOLUTION)


@dataclass(frozen=True)
class NotDiagnosed:
    """Why one window was not diagnosed: ``kind`` (one of :data:`KINDS`) and ``reason`` (one line, for people)."""

    kind: str
    reason: str

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"unknown kind {self.kind!r} of 'not diagnosed'; expected one of {', '.join(KINDS)}")
        if "\n" in self.reason:
            raise ValueError("the reason a window was not diagnosed is one line")

    def __str__(self) -> str:
        return f"{self.kind}: {self.reason}"

    def to_json(self) -> dict:
        return {"kind": self.kind, "reason": self.reason}


def prevailing(outcomes: Iterable[NotDiagnosed | None]) -> NotDiagnosed | None:
    """The reason that stands for many windows' outcomes: the most frequent kind among those not
    diagnosed (ties in the order of :data:`KINDS`), with the first reason of that kind; None when
    every window was diagnosed."""
    seen = [o for o in outcomes if o is not None]
    if not seen:
        return None
    counts = Counter(o.kind for o in seen)
    kind = max(KINDS, key=lambda k: (counts[k], -KINDS.index(k)))
    return next(o for o in seen if o.kind == kind)
