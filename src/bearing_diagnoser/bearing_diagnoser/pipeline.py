"""The monitoring graph in one process: the nodes' own sessions, wired as the nodes are, fed with recorded chunks.

Live, a vibration chunk reaches the OR and the IR observer node
(:class:`bearing_observer.observer_session.ObserverSession`), each publishes a residual
chunk, and the diagnoser node (:class:`.diagnoser_session.DiagnoserSession`) decides.
:class:`MonitorPipeline` runs exactly those sessions on chunks of a recording, so that
``bearing-diagnose``, ``bearing-accuracy`` and the figures give the decisions the graph
gives by construction, not by a second wiring. Without observers (the textbook baseline,
``--method envelope``; a measurement alone) the measurement goes to the diagnoser session
as the residual of a model-free stream, as an observer of model set ``none`` would pass it.

A recording is whole: a chunk that a session refuses (or a decision that cannot be made)
is an :class:`~bearing_recordings.recording.InputError`, not a logged rejection — unless the
pipeline is not ``strict`` (``bearing-trend``: a life of snapshots whose condition is scored
whether or not the decision can be made; the sessions count and say what they refused).
The diagnoser session's condition records (:meth:`.diagnoser_session.DiagnoserSession.take_health`)
are what the node publishes on ``health``; snapshots are fed with their own stamps
(:meth:`MonitorPipeline.feed`, ``input_mode`` among ``parameters``).

This module and :mod:`.recording_diagnosis` are the diagnoser's only users of the observer
package (its sessions and its model-set registry).
"""

from __future__ import annotations

import logging

import numpy as np

from bearing_common.bearings import Bearing, bearing_spec, fault_frequency
from bearing_common.states import FaultState
from bearing_observer.model_sets import ModelSet, model_set
from bearing_observer.model_sets import choose_model_set as registry_choice
from bearing_observer.observer_session import ObserverSession
from bearing_recordings.recording import InputError

from .decision.config import DiagnoserConfig
from .decision.state_tracker import Decision
from .diagnoser import STREAMS
from .diagnoser_node_config import PARAMETERS
from .diagnoser_session import DiagnoserSession

LOG = logging.getLogger(__name__)

#: Shaft speed (rev/min) the observers assume while none is known: the observer node's default.
NOMINAL_RPM = 1800.0

#: Longest stretch (s) of one stream handed to a decision that reads every stream (the folding
#: decision) before the other streams' same samples: half its largest lag
#: (:attr:`.fold.settings.FoldSettings.max_lag_s`, 1 s). Live, each observer's chunk arrives within
#: a chunk of the other's; offline a chunk is 10 s, and handed whole, stream after stream, the
#: first ran 10 s ahead: the decision took the second for absent and decided without it (an
#: inner-race simulation called OUTER_RACE for its first 9 s).
INTERLEAVE_S = 0.5


def choose_model_set(source: str, sample_rate: float, bearing: Bearing, requested: str | None = None) -> ModelSet:
    """The model set for a recording: ``requested`` if given, else the registry's rule for its source,
    rate and bearing with resampling allowed (:func:`bearing_observer.model_sets.choose_model_set`):
    simulator output → ``sim_48k`` / ``sim_12k``, CWRU drive-end 6205 → ``cwru_de_6205``,
    anything else (another rig, another bearing, a user's sensor) → ``none``.
    """
    if requested:
        try:
            return model_set(requested)
        except ValueError as exc:
            raise InputError(str(exc)) from None
    return registry_choice(source, sample_rate, bearing, resample=True)


def _log(level: str, text: str) -> None:
    """A session's message: warnings are the user's (a model for another bearing), the rest the
    pipeline's own (what goes wrong becomes an InputError)."""
    LOG.log(logging.WARNING if level == "warning" else logging.DEBUG, text)


class MonitorPipeline:
    """Observer and diagnoser sessions on one recording's chunks.

    Parameters
    ----------
    bearing : Bearing
    model_set : str
        The observers' model set (a name or directory), also the decision's.
    config : DiagnoserConfig
        The decision's configuration, as it is.
    rpm : float or None
        The recording's shaft speed (rev/min): a label (the ``rpm`` parameter, within
        ``rpm_tolerance``), refined from the vibration; None: the decision estimates it, the
        observers assume :data:`NOMINAL_RPM`.
    rpm_tolerance : float
        Relative tolerance of ``rpm`` (default: the diagnoser node's, a nameplate's).
    observed : bool
        Run the observers; else the measurement is a model-free stream.
    streams : tuple of FaultState
        The observer streams fed (one suffices for a front end that takes one measurement).
    keep_streams : bool
        Keep every residual, estimate and impulse train, for figures.
    parameters : dict
        More diagnoser parameters (:data:`.diagnoser_node_config.PARAMETERS`: ``input_mode``, the
        condition trend's), as the node would be given them.
    strict : bool
        A refused chunk or a decision that cannot be made raises InputError (module docstring).
    shaft_speed : ndarray (n,), optional
        The measured speed per sample (rad/s) of a recording whose speed changes: the observers
        are told it per chunk (as the ``shaft_speed`` topic would), and the decision follows it in
        the shaft-angle domain at the nominal ``rpm`` (:meth:`.diagnoser_session.DiagnoserSession.follow_speed`).
    """

    def __init__(self, bearing: Bearing, model_set: str, config: DiagnoserConfig, rpm: float | None = None,
                 observed: bool = True, streams: tuple = STREAMS, keep_streams: bool = False,
                 rpm_tolerance: float | None = None, parameters: dict | None = None, strict: bool = True,
                 shaft_speed: np.ndarray | None = None):
        self.model_set = model_set
        self.streams = streams
        self.strict = strict
        nominal = rpm or NOMINAL_RPM
        values = {p.name: p.default for p in PARAMETERS} | {"model_set": model_set, "bearing": bearing_spec(bearing),
                                                             "rpm": float(rpm or 0.0)} | (parameters or {})
        self.observers = {h: ObserverSession(h, bearing, model_set, nominal, log=_log, input_mode=values["input_mode"])
                          for h in streams} if observed else {}
        self.fault_hz = {h: fault_frequency(bearing, h, nominal) for h in streams}
        if rpm_tolerance is not None:
            values["rpm_tolerance"] = float(rpm_tolerance)
        self.diagnoser = DiagnoserSession(values, _log, bearing=bearing, config=config, keep_history=True)
        #: s of one stream per hand-over (:data:`INTERLEAVE_S`) for a decision that reads every stream and
        #: chunks that are a stream; None: whole chunks (a snapshot sensor's chunk is a waveform of its own)
        self._interleave = INTERLEAVE_S if config.front_end.EVERY_STREAM and values["input_mode"] != "snapshot" \
            else None
        self.kept = {h: {"residual": [], "estimate": [], "impulse_train": []} for h in self.observers} \
            if keep_streams else {}
        self.shaft_speed = None if shaft_speed is None else np.asarray(shaft_speed, dtype=float)
        if self.shaft_speed is not None:
            self.diagnoser.follow_speed(nominal, float(self.shaft_speed.max()) * 30.0 / np.pi)

    @property
    def decisions(self) -> list[Decision]:
        """Every window's decision so far (signal time: s from the recording's first sample)."""
        return self.diagnoser.history

    def feed(self, first_index: int, sample_rate: float, samples: np.ndarray, source: str,
             stamp: float | None = None) -> None:
        """One vibration chunk (m/s²) whose first sample has index ``first_index``, as a sensor driver
        publishes it: stamped ``stamp`` (s; default index / rate: the recording's clock)."""
        stamp = first_index / sample_rate if stamp is None else float(stamp)
        if self.shaft_speed is not None:
            w = self.shaft_speed[first_index:first_index + len(samples)]
            self.diagnoser.speed_samples(stamp, sample_rate, w)
            for observer in self.observers.values():
                observer.on_speed(float(w[0]))
        outputs = {}
        for h in self.streams:
            if h in self.observers:
                out = self.observers[h].on_chunk(stamp, first_index, sample_rate, source, samples)
                if out is None and not self.strict:
                    continue
                if out is None:
                    raise InputError(f"the {h.label} observer cannot process this recording: "
                                     f"{dict(self.observers[h].counts)}")
                for key, parts in self.kept.get(h, {}).items():
                    part = getattr(out, key)  # None without a model: no estimate (0), no train
                    parts.append(np.zeros_like(out.residual) if part is None else part)
                outputs[h] = (out.residual, out.estimate, out.impulse_train, out.fault_frequency, out.model_set)
            else:
                outputs[h] = (samples, None, None, self.fault_hz[h], self.model_set)
        piece = max(1, int(self._interleave * sample_rate)) if self._interleave and len(outputs) > 1 \
            else max(1, len(samples))
        for i0 in range(0, len(samples), piece):
            i1 = i0 + piece
            for h, (y, estimate, train, fault_hz, name) in outputs.items():
                self._decide(h, stamp + i0 / sample_rate, first_index + i0, sample_rate, y[i0:i1],
                             None if estimate is None else estimate[i0:i1], None if train is None else train[i0:i1],
                             fault_hz, name)

    def _decide(self, h: FaultState, stamp: float, first_index: int, sample_rate: float, residual, estimate, train,
                fault_hz: float, model_set: str) -> None:
        self.diagnoser.on_residual(h, stamp, first_index, sample_rate, residual, estimate, train, fault_hz,
                                   model_set, now=0.0)
        if self.strict and (self.diagnoser.decision_problem or self.diagnoser.last_refusal):
            raise InputError(self.diagnoser.decision_problem or self.diagnoser.last_refusal)

    def finish(self) -> list[Decision]:
        """End of the recording: decide what can still be decided; every window's decision."""
        self.diagnoser.flush()
        if self.strict and self.diagnoser.decision_problem:
            raise InputError(self.diagnoser.decision_problem)
        return self.decisions

    def kept_streams(self) -> dict:
        """{hypothesis label: {residual, estimate, impulse_train: whole arrays; fault_frequency: Hz}}."""
        return {h.label: {k: np.concatenate(v) for k, v in d.items()}
                | {"fault_frequency": self.observers[h].observer.fault_frequency} for h, d in self.kept.items()}
