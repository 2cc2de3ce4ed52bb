"""What the ``observer`` node does with its inputs, without ROS (``node.py`` only wires topics and parameters).

One :class:`ObserverSession` per node:

* chooses the model set for the chunks' source and sample rate (the ``model_set``
  parameter, else :func:`.model_sets.choose_model_set` for the ``bearing``: a shipped
  set or ``none``) and builds the observer; rebuilds it at the next chunk when source or
  rate change or when ``bearing`` / ``model_set`` are set (:meth:`configure`);
* re-tunes the train to shaft-speed messages that differ by more than
  ``speed_tolerance`` (relative), phase kept continuous; the model itself (its resonances, its
  fault order's measured value) was identified at one speed, so a speed beyond
  :data:`MODEL_SPEED_TOLERANCE` of it is said (a warning, at most once per ``log_period``): the
  observer follows the speed with its train only;
* checks every chunk (:class:`bearing_common.chunk_stream.ChunkStream`): bad chunks are rejected and
  counted; a gap or a restarted producer resets the observer state, and so does each snapshot
  of a snapshot sensor (``input_mode``), without counting or logging a gap;
* never returns a non-finite value;
* without a model (model set ``none``) passes the measurement through as the residual and
  computes nothing else: the estimate is 0 and no train drives a model, so both are left
  out (None; empty arrays on the wire, ``msgs/msg/Residual.msg``).

Messages go to ``log(level, text)`` with ``level`` ``info``, ``warning`` or ``error``;
repeatable per-chunk messages (rejections, bad speeds, no model) at most once per
``log_period`` seconds each.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from bearing_common import topics
from bearing_common.bearings import Bearing, load_bearing
from bearing_common.chunk_stream import ChunkStream
from bearing_common.log_throttle import LogThrottle
from bearing_common.states import FaultState

from .hw_model import ModelFileError
from .model_sets import NONE, choose_model_set
from .observer import BearingMismatchWarning, FaultObserver


@dataclass
class ResidualChunk:
    """The observer's output for one accepted chunk (arrays as long as the chunk; estimate
    and train None when the observer has no model: the residual is the measurement)."""

    residual: np.ndarray     # y - estimate, m/s²
    estimate: np.ndarray | None     # m/s²
    impulse_train: np.ndarray | None  # dimensionless
    model_set: str
    fault_frequency: float   # Hz


#: Relative departure from the speed a model set was identified at beyond which the observer says that its
#: model holds at another speed: a tachometer's tolerance, to which the decision holds one speed.
MODEL_SPEED_TOLERANCE = 0.02


def _quiet(level: str, text: str) -> None:
    """The default log: nothing."""


class ObserverSession:
    """One fault observer on a chunked vibration stream.

    Parameters
    ----------
    fault : FaultState
        OUTER_RACE or INNER_RACE.
    bearing : Bearing
        The watched bearing (a ``bearing`` parameter change is parsed by :meth:`configure`).
    model_set : str
        A set name or directory; ``""`` = chosen from each chunk's source and rate.
    rpm : float
        Shaft speed (rev/min) until shaft-speed messages say otherwise.
    speed_tolerance : float
        Relative speed change that re-tunes the train.
    stream_name : str
        Name of the input stream in reasons.
    input_mode : str
        ``stream``, ``snapshot`` or ``auto`` (:data:`bearing_common.chunk_stream.INPUT_MODES`).
    log : callable
        ``log(level, text)``.
    log_period : float
        Seconds (monotonic clock) between two messages of one repeatable kind.
    """

    def __init__(self, fault: FaultState, bearing: Bearing, model_set: str = "", rpm: float = 1800.0,
                 speed_tolerance: float = 1e-3, stream_name: str = topics.VIBRATION.name, log=_quiet,
                 log_period: float = 5.0, input_mode: str = "stream"):
        self.fault = FaultState(fault)
        self.bearing = bearing
        self.model_set = model_set
        self.rpm = float(rpm)
        self.speed_tolerance = float(speed_tolerance)
        self.stream = ChunkStream(stream_name, input_mode=input_mode)
        self.log = log
        self._log_repeatable = LogThrottle(log, log_period)
        self.observer: FaultObserver | None = None
        self._built_for = None  # (set name, sample rate) of the observer

    @property
    def counts(self):
        """Chunks accepted, rejected (by reason), speeds ignored, chunks without a model."""
        return self.stream.counts

    def configure(self, changes: dict) -> None:
        """Apply changed parameters: ``bearing`` and ``model_set`` rebuild the observer at the
        next chunk; ``rpm`` sets the speed now; ``speed_tolerance`` applies to the next speed."""
        if "bearing" in changes:
            self.bearing = load_bearing(changes["bearing"])
        if "model_set" in changes:
            self.model_set = changes["model_set"]
        rebuild = bool({"bearing", "model_set"} & set(changes))
        if rebuild:
            self._built_for = None
        if "speed_tolerance" in changes:
            self.speed_tolerance = float(changes["speed_tolerance"])
        if "rpm" in changes:
            self._set_rpm(float(changes["rpm"]))
        self.log("info", "set " + ", ".join(f"{k} = {v!r}" for k, v in changes.items())
                 + ("; observer rebuilt at the next chunk" if rebuild else ""))

    def on_speed(self, angular_velocity: float) -> None:
        """A shaft-speed message (rad/s, REP-103)."""
        rpm = angular_velocity * 60.0 / (2.0 * math.pi)
        if not math.isfinite(rpm) or rpm <= 0:
            self.counts["bad shaft speed"] += 1
            self._log_repeatable("bad speed", "warning", f"ignoring shaft speed {angular_velocity!r} rad/s")
        elif abs(rpm - self.rpm) > self.speed_tolerance * self.rpm:
            self._set_rpm(rpm)

    def _set_rpm(self, rpm: float) -> None:
        self.rpm = rpm
        if self.observer is not None:
            self.observer.set_speed(rpm)
            identified = self.observer.model.rpm
            if math.isfinite(identified) and abs(rpm / identified - 1.0) > MODEL_SPEED_TOLERANCE:
                self._log_repeatable("model speed", "warning", self.model_speed_note())

    def model_speed_note(self) -> str:
        """What the observer can follow of a speed its model was not identified at ("" at that speed)."""
        identified = self.observer.model.rpm if self.observer is not None else math.nan
        if not (math.isfinite(identified) and abs(self.rpm / identified - 1.0) > MODEL_SPEED_TOLERANCE):
            return ""
        return (f"model set {self._built_for[0]} was identified at {identified:.0f} rpm; the shaft turns at "
                f"{self.rpm:.0f} rpm: the impulse train follows the speed, the identified model does not")

    def on_chunk(self, stamp: float, first_index: int, sample_rate: float, source: str,
                 samples: np.ndarray) -> ResidualChunk | None:
        """Observe one chunk (first sample at ``stamp`` s, stream index ``first_index``);
        None when it is rejected or no model fits it."""
        verdict = self.stream.check(stamp, first_index, sample_rate, samples)
        if not verdict.accepted:
            self._log_repeatable("rejected", "warning", f"rejected chunk ({dict(self.counts)}): {verdict.reason}")
            return None
        if not self._ensure_observer(source, sample_rate):
            return None
        if verdict.resync:
            self.observer.reset()
            if verdict.reason:  # throttled: an overloaded host drops chunks, and a log line per gap
                # (1-4 ms in rclpy) made it fall further behind
                self._log_repeatable("resync", "info", verdict.reason)
        name, frequency = self._built_for[0], float(self.observer.fault_frequency)
        if name == NONE:
            return ResidualChunk(samples, None, None, name, frequency)
        out = self.observer.process(samples)
        if not (np.all(np.isfinite(out.residual)) and np.all(np.isfinite(out.estimate))):
            self.counts["non-finite output"] += 1
            self.observer.reset()
            self.stream.restart()
            self.log("error", "observer produced non-finite values; state reset, chunk dropped")
            return None
        return ResidualChunk(out.residual, out.estimate, out.impulse_train, name, frequency)

    def _ensure_observer(self, source: str, sample_rate: float) -> bool:
        """Build the observer the chunk needs unless it runs already; False when none can be."""
        try:
            name = self.model_set or choose_model_set(source, sample_rate, self.bearing).name
            if self._built_for == (name, sample_rate):
                return True
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", BearingMismatchWarning)
                self.observer = FaultObserver.from_model_set(name, self.fault.label, self.rpm, sample_rate,
                                                             bearing=self.bearing)
        except (ModelFileError, ValueError) as exc:
            self.observer, self._built_for = None, None
            self.counts["no model"] += 1
            self._log_repeatable("no model", "error", f"cannot observe {sample_rate:g} Hz '{source}' data: {exc}")
            return False
        for w in caught:
            self.log("warning", str(w.message))
        self._built_for = (name, sample_rate)
        self.log("info", f"model set {name} at {sample_rate:g} Hz for {self.bearing.name}, {self.rpm:.1f} rpm: "
                         f"fault frequency {self.observer.fault_frequency:.3f} Hz")
        return True
