"""The incremental fault-state decision (thesis section 3.2, taken further): observer chunks in, decisions out.

:class:`Diagnoser` is fed, per observer stream (OUTER_RACE, INNER_RACE), the chunks an
observer publishes — residual r, estimate ŷ, impulse train u — and rebuilds the measurement
as y = r + ŷ. It keeps each stream's blocks (:mod:`.decision.stream_blocks`), hands every
chunk to the front end its configuration names (:func:`.front_ends.build_front_end`, built
at the first chunk, when the sample rate is known), and turns the window verdicts into
published states (:mod:`.decision.state_tracker`: hysteresis, onsets, confidence). Both
front ends report the thesis' own blocks per observer stream and window —
``explained`` and ``xcorr`` (:mod:`.decision.thesis_blocks`) — measured, not decided on.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_common.bearings import CATALOG, DEFAULT_BEARING, Bearing
from bearing_common.model_set_info import NONE
from bearing_common.states import FaultState
from bearing_common.units import sample_rate_problem

from .decision.config import DiagnoserConfig
from .decision.front_end import FrontEnd, WindowVerdict
from .decision.state_tracker import Decision, StateTracker
from .decision.stream_blocks import EnergyEnvelope, StreamBlocks
from .front_ends import build_front_end, config_for

#: The observer streams a diagnoser takes.
STREAMS = (FaultState.OUTER_RACE, FaultState.INNER_RACE)
_STREAM = {int(h): h for h in STREAMS}  # value or FaultState -> FaultState

__all__ = ["STREAMS", "Decision", "Diagnoser"]


class Diagnoser:
    """Incremental diagnoser: feed observer chunks, get decisions as windows become due.

    Parameters
    ----------
    config : DiagnoserConfig, optional
        Decision parameters (default: :func:`.front_ends.config_for` ``(model_set)``).
    model_set : str
        Name reported with decisions and used to pick defaults; ``none``: the streams carry
        no model's estimate.
    bearing : Bearing, optional
        The monitored bearing (default the 6205).
    sample_rate : float, optional
        Hz of the streams, when known in advance (lets :meth:`warm_up` run before the first
        chunk); otherwise taken from the first chunk.
    """

    def __init__(self, config: DiagnoserConfig | None = None, model_set: str = "",
                 bearing: Bearing | None = None, sample_rate: float | None = None):
        self.model_set = model_set
        self.config = config or config_for(model_set)
        self.bearing = bearing or CATALOG[DEFAULT_BEARING]
        self._sample_rate = None if sample_rate is None else float(sample_rate)
        self._streams: dict[FaultState, StreamBlocks] = {}
        self._speed: tuple[float, float | None] | None = None  # told (Hz, relative tolerance)
        self._follow: tuple[float, float] | None = None  # the angle domain's (nominal Hz, top Hz)
        self._speed_points: list = []  # (indices, rad/s) told before the front end was built
        self._front: FrontEnd | None = None
        self._tracker = StateTracker(self.config.k_of_n, self.config.normal_k_of_n, self.config.unknown_rule())
        self.history: list[Decision] = []
        self.keep_history = True
        #: Hypotheses whose streams are deployed though this core has not seen them yet (a restarted
        #: decision's earlier streams): missing, they hold the folding decision like a silent stream.
        self.expected: set = set()

    @property
    def state(self) -> FaultState:
        """The published state."""
        return self._tracker.state

    @property
    def confidence(self) -> float:
        return self._tracker.confidence

    @property
    def onset(self) -> float:
        return self._tracker.onset

    def warm_up(self) -> None:
        """Build the front end now and let it prepare (the fold's thresholds: about 1 s); needs the
        sample rate given at construction."""
        self._front_end(self._sample_rate).warm_up()

    def tell_speed(self, rpm: float | None, tolerance: float | None = None) -> None:
        """The shaft speed (rev/min) from a tachometer, the file or a nameplate, and its relative
        tolerance (default the front end's); None = unknown."""
        if rpm is not None and not (math.isfinite(rpm) and rpm > 0):
            raise ValueError(f"shaft speed must be a positive number of rev/min, got {rpm!r}")
        self._speed = None if rpm is None else (rpm / 60.0, tolerance)
        if self._front is not None:
            self._front.tell_speed(*(self._speed or (None,)))

    @property
    def follows_speed(self) -> bool:
        """Whether this core's front end can decide in the angle domain (:meth:`follow_speed`)."""
        return self.config.front_end.FOLLOWS_SPEED

    def follow_speed(self, nominal_rpm: float, top_rpm: float) -> None:
        """Decide on a changing speed (before the first chunk): every chunk is resampled to equal
        shaft-angle increments and decided as if the shaft turned at ``nominal_rpm``
        (:mod:`.spectral.angle_domain`); ``top_rpm``: the highest speed expected. The speed comes by
        :meth:`tell_speed_points`. ValueError for a front end that cannot (:attr:`follows_speed`)."""
        if not self.follows_speed:
            raise ValueError(f"the {self.config.method} decision cannot follow a changing speed")
        self._follow = (nominal_rpm / 60.0, top_rpm / 60.0)

    def tell_speed_points(self, indices, rad_s) -> None:
        """Measured shaft speeds (rad/s) at sample indices ``indices`` (fractional allowed, increasing),
        for the angle domain (:meth:`follow_speed`)."""
        if self._front is None:
            self._speed_points.append((indices, rad_s))
        else:
            self._front.tell_speed_points(indices, rad_s)

    def _front_end(self, sample_rate: float) -> FrontEnd:
        if self._front is None:
            self._front = build_front_end(self.config, sample_rate, self.bearing)
            if self._follow is not None:
                self._front.follow_speed(*self._follow)
                for points in self._speed_points:
                    self._front.tell_speed_points(*points)
                self._speed_points = []
            elif self._speed is not None:
                self._front.tell_speed(*self._speed)
        return self._front

    # -- feeding -----------------------------------------------------------------------
    def update(self, hypothesis, first_sample_index: int, sample_rate: float, residual,
               estimate=None, impulse_train=None, fault_frequency: float | None = None,
               snapshot: bool = False) -> list[Decision]:
        """Feed one observer chunk; return the decisions that became due (oldest first).

        Parameters
        ----------
        hypothesis : FaultState or int
            The observer stream: OUTER_RACE (1) or INNER_RACE (2).
        first_sample_index : int
            Index of the chunk's first sample since the stream began; time = index / rate.
        sample_rate : float
            Hz; the same for every chunk and stream.
        residual, estimate, impulse_train : array_like, shape (n,)
            r (m/s²), ŷ (m/s², None = 0: y = r, a model-free stream), u (None = no train).
        fault_frequency : float
            Hz at which the observer built its train (the fold front end folds there).
        snapshot : bool
            The chunk is a snapshot sensor's: scored alone for what its length resolves, evidence
            accumulating across the pauses (:meth:`.decision.front_end.FrontEnd.push`).
        """
        h = _STREAM.get(hypothesis)  # FaultState(hypothesis) costs 1 us, twice a chunk
        if h is None:
            raise ValueError(f"unexpected hypothesis {FaultState(hypothesis).label}; "
                             f"expected {[x.label for x in STREAMS]}")
        rate_problem = sample_rate_problem(sample_rate)
        if rate_problem:
            raise ValueError(rate_problem)
        front = self._front_end(self._sample_rate or sample_rate)  # refuses a rate it cannot decide
        if self._sample_rate is None:
            self._sample_rate = float(sample_rate)
        elif abs(sample_rate - self._sample_rate) > 1e-9 * self._sample_rate:
            raise ValueError(f"sample rate changed from {self._sample_rate} to {sample_rate} Hz")
        if fault_frequency is None or not (math.isfinite(fault_frequency) and fault_frequency > 0):
            raise ValueError("fault_frequency (Hz) must be > 0")
        r = np.asarray(residual, dtype=float)
        e = None if estimate is None else np.asarray(estimate, dtype=float)
        u = None if impulse_train is None else np.asarray(impulse_train, dtype=float)
        if r.ndim != 1 or any(a is not None and a.shape != r.shape for a in (e, u)):
            raise ValueError("residual, estimate and impulse_train must be 1-D and of equal length")
        st = self._streams.get(h)
        if st is None:
            st = self._streams[h] = StreamBlocks(EnergyEnvelope(self._sample_rate, front.envelope_band))
        st.fault_hz = float(fault_frequency)
        st.has_model = st.has_model or (estimate is not None and self.model_set != NONE)
        st.has_train = st.has_train or (u is not None and np.any(u != 0.0))
        y = r + (0.0 if e is None else e)  # no estimate: ŷ = 0 (r + 0.0, as r + zeros)
        if front.reads_blocks or st.has_model or st.has_train:  # else the blocks are never read
            st.push(int(first_sample_index), y, r, np.zeros_like(r) if u is None else u)
        return self._decide(front.push(h, int(first_sample_index), y, self._streams, self.expected, snapshot))

    def envelope_view(self):
        """The front end's spectrum of the last window it tested (:meth:`.decision.front_end.FrontEnd.envelope_view`),
        or None (none yet; the fold front end computes none)."""
        return None if self._front is None else self._front.envelope_view()

    def flush(self) -> list[Decision]:
        """Decide every complete window with whatever streams exist (end of data)."""
        if self._front is None:
            return []
        return self._decide(self._front.flush(self._streams, self.expected))

    def _decide(self, verdicts: list[WindowVerdict]) -> list[Decision]:
        """Window verdicts through the hysteresis; a window not diagnosed (a sensor, speed or
        resolution problem) leaves the state as it is."""
        tr = self._tracker
        out = []
        for v in verdicts:
            changed = v.not_diagnosed is None and tr.update(v.label, v.confidence, v.start, v.end, v.posterior,
                                                            v.evidence_since)
            out.append(Decision(v.end, v.start, v.end, v.label, tr.state, tr.confidence, tr.onset, changed, v.scores,
                                v.detail, v.not_diagnosed))
        if self.keep_history:
            self.history.extend(out)
        return out
