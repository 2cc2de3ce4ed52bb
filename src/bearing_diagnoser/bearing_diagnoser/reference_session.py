"""The diagnoser node's machine reference, without rclpy: loaded from a file, or learnt over the healthy period.

The ``reference_file`` parameter names a saved reference (:mod:`.spectral.machine_reference`). When
the file exists it is loaded and in force from the start. Otherwise the node learns one over the
condition trend's own healthy period (the ``baseline`` parameter: its duration, or its counted
windows' span), at most :data:`.spectral.machine_reference.MAX_PERIOD_S` of a stream's signal from
the start, and saves it to ``reference_file`` (when one is named) so that a restart does not learn
again. While it learns, the decision runs blind. A gap in the stream starts the learning again
(the period must be one stretch of signal); snapshots are not learnt from (a period of pauses is no
stretch). :meth:`ReferenceSession.status` is the /diagnostics value of "machine reference".
"""

from __future__ import annotations

import os

import numpy as np

from bearing_common.bearings import Bearing

from .diagnoser_node_config import health_settings
from .spectral.machine_reference import (
    MAX_PERIOD_S,
    MachineReference,
    MachineReferenceError,
    learn_reference,
    load_reference,
)


def learning_period(values: dict) -> float:
    """Seconds of signal learnt from: the trend's healthy period (a stated duration, or the counted
    windows' span, at least ``baseline_min_duration``), at most :data:`MAX_PERIOD_S`."""
    trend = health_settings(values).trend
    period = trend.healthy_until or max(trend.baseline_snapshots * float(values["health_period"]),
                                        trend.baseline_duration)
    return min(float(period), MAX_PERIOD_S)


class ReferenceSession:
    """The machine reference of one diagnoser (module docstring).

    Parameters
    ----------
    values : dict
        The node's parameter values (``reference_file``, the trend's ``baseline`` parameters).
    log : callable(level, text)
    """

    def __init__(self, values: dict, log):
        self.values = values
        self._log = log
        self.path = str(values["reference_file"])
        self.reference: MachineReference | None = None
        self.file_problem = ""  # why reference_file cannot be read: no learning then (it is not overwritten)
        self.problem = ""  # why the last learning attempt gave no reference
        self.period = learning_period(values)
        self._held: list[np.ndarray] = []
        self._next: int | None = None  # index of the sample that continues the stretch held
        self._rate = 0.0
        if self.path and os.path.exists(self.path):
            try:
                self.reference = load_reference(self.path)
                log("info", f"machine reference from {self.path}: {self.reference.describe()}")
            except MachineReferenceError as exc:  # kept, not overwritten: the user must see and fix it
                self.file_problem = str(exc)
                log("warning", f"{exc}; deciding blind")

    @property
    def learning(self) -> bool:
        return self.reference is None and not self.file_problem

    def status(self) -> str:
        """The /diagnostics value of "machine reference"."""
        if self.reference is not None:
            saved = f" (file {self.path})" if self.path else " (not saved: no reference_file)"
            return self.reference.describe() + saved
        if self.file_problem:
            return f"none, deciding blind: {self.file_problem}"
        held = sum(x.size for x in self._held) / self._rate if self._rate else 0.0
        last = f"; last attempt: {self.problem}" if self.problem else ""
        return f"learning: {held:.1f} of {self.period:.1f} s of healthy signal (deciding blind meanwhile){last}"

    def push(self, first_index: int, sample_rate: float, y: np.ndarray, snapshot: bool, bearing: Bearing,
             told_rpm: float | None, tolerance: float, settings) -> MachineReference | None:
        """A stretch of the measurement (m/s²) from sample ``first_index``; the reference when it has just
        been learnt (and saved), else None. ``bearing``, the told speed (rev/min, None: unknown) and its
        relative ``tolerance``, and the decision's ``settings`` (:class:`.spectral.settings.SpectralSettings`)
        are those the decision runs with."""
        if not self.learning or snapshot:
            return None
        if self._next != first_index or sample_rate != self._rate:  # a gap or a new stream: begin again
            self._held, self._rate = [], float(sample_rate)
        self._held.append(np.asarray(y, float))
        self._next = first_index + len(y)
        if sum(x.size for x in self._held) < self.period * sample_rate:
            return None
        x = np.concatenate(self._held)
        self._held, self._next = [], None
        try:
            reference = learn_reference(x, sample_rate, bearing, told_rpm, tolerance, settings,
                                        source=f"learnt by the node over its first {x.size / sample_rate:.1f} s")
        except MachineReferenceError as exc:
            self.problem = str(exc)
            self._log("warning", f"machine reference not learnt: {exc}; learning again")
            return None
        self.reference, self.problem = reference, ""
        if self.path:
            try:
                reference.save(self.path)
            except OSError as exc:
                self._log("warning", f"cannot save the machine reference to {self.path}: {exc.strerror}")
        self._log("info", f"machine reference learnt: {reference.describe()}")
        return reference
