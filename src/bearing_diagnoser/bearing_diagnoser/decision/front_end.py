"""The one interface between the decision core and a front end: observer chunks in, window verdicts out.

A front end (:mod:`bearing_diagnoser.spectral`, :mod:`bearing_diagnoser.fold`) is built by
:class:`bearing_diagnoser.diagnoser.Diagnoser` from its settings (the one place that picks
it). The core keeps, per observer stream, the stream's blocks (:mod:`.stream_blocks`: the
raw sums every window's RMS and thesis blocks need, and the energy envelope of
``envelope_band`` when the front end reads one), hands each chunk's measurement
y = r + ŷ to the front end, and turns the verdicts it returns into published states
(:mod:`.state_tracker`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from bearing_common.states import FaultState

from .not_diagnosed import NotDiagnosed
from .scores import WindowScores
from .stream_blocks import StreamBlocks


@dataclass(frozen=True)
class WindowVerdict:
    """What a front end concludes from one window [start, end) (s of signal time).

    ``posterior``: {state: probability} when the front end has one (the tracker then reports
    the mean posterior of the published state as its confidence); ``detail``: what was special
    about the window (a missing stream); ``not_diagnosed``: why the window was not diagnosed at
    all (:mod:`.not_diagnosed`: the sensor, the speed or the resolution; None when it was);
    ``evidence_since``: when the evidence for the label began (s), when the front end knows it
    better than the window (accumulated evidence).
    """

    start: float
    end: float
    label: FaultState
    confidence: float
    scores: WindowScores
    posterior: dict | None = None
    detail: str = ""
    not_diagnosed: NotDiagnosed | None = None
    evidence_since: float | None = None

    @classmethod
    def undiagnosed(cls, start: float, end: float, scores: WindowScores, kind: str, reason: str) -> WindowVerdict:
        """A window not diagnosed, for a reason of ``kind`` (:data:`.not_diagnosed.KINDS`): UNKNOWN, confidence 0."""
        return cls(start, end, FaultState.UNKNOWN, 0.0, scores, not_diagnosed=NotDiagnosed(kind, reason))


class FrontEnd(Protocol):
    """What the core asks of a front end.

    Attributes
    ----------
    envelope_band : (lo, hi) or None
        Band (Hz) of the energy envelope the front end reads from every stream's blocks;
        None: the blocks hold the raw sums only.
    reads_blocks : bool
        Whether the front end decides from the streams' blocks (their sums are then kept for
        every stream, not only for streams with a model or a train).
    """

    envelope_band: tuple[float, float] | None
    reads_blocks: bool

    def tell_speed(self, hz: float | None, tolerance: float | None = None) -> None:
        """The shaft rate (Hz) and its relative tolerance (None: the front end's default); None = unknown."""

    def follow_speed(self, nominal_hz: float, top_hz: float) -> None:
        """Decide on a changing speed, told by :meth:`tell_speed_points` (only the front ends whose
        settings say ``FOLLOWS_SPEED``)."""

    def tell_speed_points(self, index, rad_s) -> None:
        """Measured shaft speeds (rad/s) at sample indices ``index``, while following the speed."""

    def warm_up(self) -> None:
        """Compute now what the first windows would otherwise wait for (thresholds)."""

    def push(self, hypothesis: FaultState, first_index: int, y, streams: dict[FaultState, StreamBlocks],
             expected: set, snapshot: bool = False) -> list[WindowVerdict]:
        """One stream's chunk: its measurement ``y`` from sample ``first_index`` (its blocks are already in
        ``streams``); ``expected``: hypotheses whose streams are deployed but not seen yet; ``snapshot``:
        the chunk is a snapshot sensor's (scored alone; evidence may accumulate across the pause
        before it). Returns the windows that became due."""

    def flush(self, streams: dict[FaultState, StreamBlocks], expected: set) -> list[WindowVerdict]:
        """End of data: decide what can still be decided."""

    def envelope_view(self):
        """The spectrum the last window was decided on, for plotting
        (:class:`bearing_diagnoser.spectral.envelope_view.EnvelopeView`), or None: none yet, or the
        front end computes none."""
