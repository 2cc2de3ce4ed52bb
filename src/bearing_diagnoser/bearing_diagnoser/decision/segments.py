"""Segments: maximal runs of one published state, the unit ``bearing-diagnose`` prints (CONTRACT.md).

A run none of whose windows was diagnosed (a dead sensor throughout, a speed never
confirmed) is one segment over the whole data, UNKNOWN with confidence 0 and the reason
(``not_diagnosed``: :func:`.not_diagnosed.prevailing` of its windows): a verdict, not an error.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bearing_common.states import FaultState

from .not_diagnosed import NotDiagnosed, prevailing
from .state_tracker import Decision


@dataclass
class Segment:
    """A maximal run of one state (times in s from the data start); ``not_diagnosed``: why none of
    its windows was diagnosed (None: they were)."""

    start: float
    end: float
    state: FaultState
    confidence: float
    detected_at: float
    scores: dict = field(default_factory=dict)
    model_set: str = ""
    not_diagnosed: NotDiagnosed | None = None

    def to_json(self) -> dict:
        """The contract's JSON object, with ``"not_diagnosed": {"kind", "reason"}`` when not diagnosed."""
        out = {"start": round(self.start, 6), "end": round(self.end, 6), "state": self.state.label,
               "confidence": round(float(np.clip(self.confidence, 0, 1)), 4),
               "detected_at": round(self.detected_at, 6),
               "scores": {k: round(float(v), 4) for k, v in self.scores.items() if np.isfinite(v)},
               "model_set": self.model_set}
        if self.not_diagnosed is not None:
            out["not_diagnosed"] = self.not_diagnosed.to_json()
        return out


def segments_from_decisions(decisions: list[Decision], duration: float, model_set: str) -> list[Segment]:
    """Maximal runs of the published state; start = estimated onset, end = next onset.

    Windows not diagnosed (a sensor, speed or resolution problem) take no part, unless none was
    diagnosed (module docstring). A segment's scores are the medians over its windows of the
    names its front end summarises (:attr:`.scores.WindowScores.SUMMARY_KEYS`).
    """
    if decisions and not any(d.diagnosed for d in decisions):
        seg = Segment(0.0, duration, FaultState.UNKNOWN, 0.0, decisions[0].time, {}, model_set,
                      prevailing(d.not_diagnosed for d in decisions))
        _summarise(seg, decisions)
        return [seg]
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
        _summarise(s, ms)
    return segs


def _summarise(seg: Segment, members: list[Decision]) -> None:
    """The medians of the members' summarised scores into ``seg.scores``."""
    named = [d.scores.as_dict() for d in members]
    for k in type(members[0].scores).SUMMARY_KEYS if members else ():
        v = [n[k] for n in named if k in n and np.isfinite(n[k])]
        if v:
            seg.scores[k] = float(np.median(v))
