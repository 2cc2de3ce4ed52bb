"""Compare published fault states with the simulator's ground truth (no rclpy).

Used by ``bearing-graph`` (the ``make demo`` summary) and by the live tests.
Times are signal (simulation) times in seconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from bearing_common.states import FaultState


@dataclass(frozen=True)
class StateChange:
    """A published state: ``state`` began at ``onset`` and was decided at ``detected_at``."""

    state: int
    onset: float
    detected_at: float
    confidence: float = 1.0


@dataclass(frozen=True)
class SegmentResult:
    """One true segment and what the diagnoser made of it."""

    true_state: int
    start: float
    end: float
    detected_state: int | None  # the state in force at the segment's end (None: nothing published)
    detected_at: float | None  # when that state was first decided within the segment
    onset: float | None

    @property
    def correct(self) -> bool:
        return self.detected_state == self.true_state

    @property
    def delay(self) -> float | None:
        """Decision time after the true change (s), None when not detected in the segment."""
        if not self.correct or self.detected_at is None:
            return None
        return max(0.0, self.detected_at - self.start)


def truth_segments(truth: Sequence[StateChange], end: float) -> list:
    """(state, start, end) runs from the truth changes, the last one ending at ``end``."""
    changes = sorted(truth, key=lambda c: c.onset)
    runs = []
    for i, change in enumerate(changes):
        stop = changes[i + 1].onset if i + 1 < len(changes) else end
        if runs and runs[-1][0] == change.state:
            runs[-1] = (change.state, runs[-1][1], stop)
        elif stop > change.onset:
            runs.append((change.state, change.onset, stop))
    return runs


def evaluate(truth: Sequence[StateChange], decided: Sequence[StateChange], end: float) -> list:
    """Score each true segment by the state in force at its end.

    A decision counts for a segment when it was made before the segment's end
    (decisions arrive in order of ``detected_at``). ``detected_at`` is the first
    decision of the segment's final state inside the segment.
    """
    decided = sorted(decided, key=lambda c: c.detected_at)
    results = []
    for state, start, stop in truth_segments(truth, end):
        in_force = [d for d in decided if d.detected_at <= stop + 1e-9]
        final = in_force[-1] if in_force else None
        first = None
        if final is not None:
            for d in reversed(in_force):
                if d.state != final.state or d.detected_at < start:
                    break
                first = d
        results.append(SegmentResult(state, start, stop, final.state if final else None,
                                     first.detected_at if first else None,
                                     first.onset if first else None))
    return results


def format_table(results: Sequence[SegmentResult]) -> str:
    """A Markdown table of the results, one row per true segment."""
    rows = ["| segment | true state | published state | decided at (s) | delay (s) | estimated onset (s) | ok |",
            "|---|---|---|---|---|---|---|"]
    for r in results:
        detected = FaultState(r.detected_state).name if r.detected_state is not None else "-"
        rows.append(
            f"| {r.start:.3f}-{r.end:.3f} s | {FaultState(r.true_state).name} | {detected} | "
            f"{_fmt(r.detected_at)} | {_fmt(r.delay)} | {_fmt(r.onset)} | {'yes' if r.correct else 'NO'} |")
    return "\n".join(rows)


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"
