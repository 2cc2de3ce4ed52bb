"""Segments: maximal runs of one published state, the unit ``bearing-diagnose`` prints (CONTRACT.md)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bearing_common.states import FaultState

from .state_tracker import Decision


@dataclass
class Segment:
    """A maximal run of one state (times in s from the data start)."""

    start: float
    end: float
    state: FaultState
    confidence: float
    detected_at: float
    scores: dict = field(default_factory=dict)
    model_set: str = ""

    def to_json(self) -> dict:
        """The contract's JSON object."""
        return {"start": round(self.start, 6), "end": round(self.end, 6), "state": self.state.label,
                "confidence": round(float(np.clip(self.confidence, 0, 1)), 4),
                "detected_at": round(self.detected_at, 6),
                "scores": {k: round(float(v), 4) for k, v in self.scores.items() if np.isfinite(v)},
                "model_set": self.model_set}


def segments_from_decisions(decisions: list[Decision], duration: float, model_set: str) -> list[Segment]:
    """Maximal runs of the published state; start = estimated onset, end = next onset.

    Windows not diagnosed (a sensor or speed problem) take no part. A segment's scores are
    the medians over its windows of the names its front end summarises
    (:attr:`.scores.WindowScores.SUMMARY_KEYS`).
    """
    segs: list[Segment] = []
    members: list[list[Decision]] = []
    for d in (d for d in decisions if d.diagnosed):
        if not segs:
            segs.append(Segment(0.0, duration, d.state, 0.0, d.time, {}, model_set))
            members.append([])
        elif d.changed:
            onset = max(0.0, d.onset)
            while len(segs) > 1 and onset <= segs[-1].start + 1e-12:  # the new state began before the last one
                segs.pop()
                members.pop()
            if segs[-1].state == d.state:  # back to the state the popped segments interrupted
                segs[-1].end = duration
            elif len(segs) == 1 and onset <= 1e-12:
                segs[0] = Segment(0.0, duration, d.state, 0.0, d.time, {}, model_set)
                members[0] = []
            else:
                segs[-1].end = onset
                segs.append(Segment(onset, duration, d.state, 0.0, d.time, {}, model_set))
                members.append([])
        members[-1].append(d)
    for s, ms in zip(segs, members):
        conf = [d.confidence for d in ms]
        s.confidence = float(np.mean(conf)) if conf else 0.0
        named = [d.scores.as_dict() for d in ms]
        for k in type(ms[0].scores).SUMMARY_KEYS if ms else ():
            v = [n[k] for n in named if k in n and np.isfinite(n[k])]
            if v:
                s.scores[k] = float(np.median(v))
    return segs
