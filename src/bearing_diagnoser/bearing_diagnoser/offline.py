"""Offline diagnosis of a recording, exactly as the live graph would: observers chunk by chunk, decide, segment.

:func:`diagnose_recording` is what ``bearing-diagnose`` runs. The OR and IR observers
(:class:`bearing_observer.observer.FaultObserver`) process fixed-size chunks and the
incremental :class:`.decision.Diagnoser` consumes their residual / estimate / train arrays.
Without an identified model set (model set ``none``) the measurement goes straight to the
decision (the observers would pass it through). ``method="envelope"`` runs the textbook
squared-envelope-spectrum reference on the measurement instead
(:func:`.decision_config.envelope_baseline`).

What the run assumed (model set, resampling, speed) is logged (``logging``, logger
``bearing_diagnoser.offline``); ``bearing-diagnose`` prints it on stderr.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field, replace

import numpy as np

from bearing_common.bearings import Bearing, fault_frequency, load_bearing
from bearing_observer.hw_model import ModelFileError
from bearing_observer.model_sets import ModelSet, model_set
from bearing_observer.model_sets import choose_model_set as registry_choice
from bearing_recordings.recording import InputError, Recording
from bearing_recordings.resampling import resample

from .decision import STREAMS, Diagnoser
from .decision_config import DiagnoserConfig, config_for, envelope_baseline
from .segments import Segment, is_sensor_problem, segments_from_decisions
from .spectral_engine import check_resolvable
from .state_tracker import Decision

LOG = logging.getLogger(__name__)

#: Chunk length (s) fed to the observers, as the simulator node publishes (0.01 s).
CHUNK_S = 0.01

METHODS = ("model", "envelope")


def choose_model_set(rec: Recording, bearing: Bearing, requested: str | None = None) -> ModelSet:
    """The model set for ``rec``: ``requested`` if given, else the registry's rule for its source,
    rate and bearing with resampling allowed (:func:`bearing_observer.model_sets.choose_model_set`):
    simulator output → ``sim_48k`` / ``sim_12k``, CWRU drive-end 6205 → ``cwru_de_6205``,
    anything else (another rig, another bearing, a user's sensor) → ``none``.
    """
    if requested:
        try:
            return model_set(requested)
        except ModelFileError as exc:
            raise InputError(str(exc)) from None
    return registry_choice(rec.source, rec.sample_rate, bearing, resample=True)


@dataclass
class OfflineResult:
    """Output of :func:`diagnose_recording`."""

    segments: list[Segment]
    decisions: list[Decision]
    model_set: str
    sample_rate: float
    rpm: float | None
    accel: np.ndarray
    truth: np.ndarray | None
    streams: dict = field(default_factory=dict)  # hypothesis label -> dict of arrays (for plots)
    cpu_s: float = 0.0
    method: str = "model"
    sensor_problems: list = field(default_factory=list)  # (start s, end s, problem)


def _observers(model_set: str, rpm: float, fs: float, bearing: Bearing):
    try:
        from bearing_observer.observer import FaultObserver
    except ImportError as exc:
        raise InputError(f"the observer core (bearing_observer.observer) is not available ({exc}); "
                         "use --method envelope or --model-set none") from None
    return {h: FaultObserver.from_model_set(model_set, h.label, rpm, fs, bearing=bearing) for h in STREAMS}


def _speed(rec: Recording, rpm: float | None) -> float | None:
    speed = rpm or rec.rpm
    if speed is None:
        LOG.warning("no shaft speed given; estimating it from the vibration (the 1x line) — unreliable "
                    "without a prior, give --rpm")
    return speed


def diagnose_recording(rec: Recording, model_set: str | None = None, method: str = "model",
                       rpm: float | None = None, bearing: Bearing | str | None = None,
                       config: DiagnoserConfig | None = None, keep_streams: bool = False,
                       chunk_s: float = CHUNK_S) -> OfflineResult:
    """Diagnose a whole recording offline, exactly as the live graph would.

    Parameters
    ----------
    rec : Recording
        From :func:`bearing_recordings.load.load_recording`.
    model_set : str, optional
        Override the automatic choice (:func:`choose_model_set`).
    method : ``"model"`` or ``"envelope"``
        The decision with the observers (default), or the textbook envelope reference.
    rpm : float, optional
        Shaft speed (rev/min); default the recording's, else estimated from the vibration.
    bearing : Bearing or str, optional
        The monitored bearing (default: the one stored with the recording, else the 6205).
    config : DiagnoserConfig, optional
        Decision parameters (default: the model set's).
    keep_streams : bool
        Keep full residual / estimate / train arrays for figures.

    Raises InputError (one line) when the recording cannot be diagnosed: a sample rate too
    low for the bearing's fault lines, a record shorter than one analysis window, a signal
    that is a sensor problem throughout.
    """
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; expected {' or '.join(METHODS)}")
    bearing = load_bearing(bearing or rec.bearing or None)
    chosen = choose_model_set(rec, bearing, model_set)
    ms = chosen.name
    LOG.info("model set %s%s; bearing %s", ms, "" if model_set else " (chosen from the input)", bearing.name)
    fs = chosen.sample_rate or rec.sample_rate
    cfg = config or config_for(ms)
    if method == "envelope":
        cfg = envelope_baseline(cfg)
    if fs > rec.sample_rate:  # upsampled: nothing above the input's own band is measurement
        usable = min(cfg.spectral.usable_bandwidth or np.inf, 0.45 * rec.sample_rate)
        cfg = replace(cfg, spectral=replace(cfg.spectral, usable_bandwidth=usable))
    speed = _speed(rec, rpm)
    _check(cfg, min(fs, rec.sample_rate), bearing, speed, rec.duration)
    x = rec.accel
    if abs(rec.sample_rate - fs) > 1e-9 * fs:
        LOG.info("resampling %g Hz -> %g Hz (anti-aliased, resample_poly) for model set %s", rec.sample_rate, fs, ms)
        x = resample(x, rec.sample_rate, fs)
    truth = rec.truth
    if truth is not None and truth.size != x.size:
        truth = truth[np.minimum((np.arange(x.size) * rec.sample_rate / fs).astype(int), truth.size - 1)]
    dg = Diagnoser(cfg, ms, bearing, fs)
    dg.tell_speed(speed)
    nominal = speed or cfg.fold.nominal_rpm
    observed = method == "model"
    feeds = STREAMS if observed or cfg.method == "fold" else STREAMS[:1]  # one measurement suffices
    fault_hz = {h: fault_frequency(bearing, h, nominal) for h in STREAMS}
    obs = _observers(ms, nominal, fs, bearing) if observed else {}
    keep = {h: {"residual": [], "estimate": [], "impulse_train": []} for h in obs} if keep_streams else {}
    chunk = max(1, int(round(chunk_s * fs)))
    t_cpu = time.process_time()
    decisions: list[Decision] = []
    try:
        for i in range(0, x.size, chunk):
            y = x[i:i + chunk]
            for h in feeds:
                if h in obs:
                    out = obs[h].process(y)
                    decisions += dg.update(h, i, fs, out.residual, out.estimate, out.impulse_train,
                                           obs[h].fault_frequency)
                    for k, parts in keep.get(h, {}).items():
                        parts.append(np.asarray(getattr(out, k), float))
                else:
                    decisions += dg.update(h, i, fs, y, None, None, fault_hz[h])
        decisions += dg.flush()
    except ValueError as exc:
        raise InputError(str(exc)) from None
    cpu = time.process_time() - t_cpu
    streams = {h.label: {k: np.concatenate(v) for k, v in d.items()} | {"fault_frequency": obs[h].fault_frequency}
               for h, d in keep.items()}
    problems = [(d.window_start, d.window_end, d.detail[len("sensor: "):]) for d in decisions if is_sensor_problem(d)]
    segs = segments_from_decisions(decisions, x.size / fs, ms)
    if decisions and not segs:
        raise InputError(f"no window could be diagnosed: {problems[0][2]}")
    return OfflineResult(segs, decisions, ms, fs, speed, x, truth, streams, cpu, method, problems)


def _check(cfg: DiagnoserConfig, fs: float, bearing: Bearing, rpm: float | None, duration: float) -> None:
    """One InputError line for a recording that cannot be diagnosed (before any work)."""
    try:
        if cfg.method == "spectral":
            check_resolvable(fs, bearing, rpm or 60.0 * cfg.spectral.blind_range_hz[1], cfg.spectral, duration)
            return
        fold = cfg.fold
        if fold.band[0] >= min(0.45 * fs, cfg.spectral.usable_bandwidth or np.inf):
            raise ValueError(f"sample rate {fs:g} Hz too low for the {fold.band[0]:g}-{fold.band[1]:g} Hz band")
        if duration < fold.window_s:
            raise ValueError(f"recording too short: {duration:.3f} s < one {fold.window_s} s window")
    except ValueError as exc:
        raise InputError(str(exc)) from None


def diagnose_measurement(y: np.ndarray, fs: float, rpm: float | None, model_set: str = "sim_48k",
                         config: DiagnoserConfig | None = None, bearing: Bearing | str | None = None,
                         chunk_s: float = CHUNK_S) -> tuple[list[Segment], list[Decision]]:
    """The decision with the defaults of ``model_set`` on a measurement alone (no observer: y fed
    as both streams' residual, ŷ = 0): the "observer without train, L = 0" front end of
    diagnosis-notes.md, for testing the decision core and for data without a model set."""
    bearing = load_bearing(bearing)
    cfg = config or config_for(model_set)
    dg = Diagnoser(cfg, model_set, bearing, fs)
    dg.tell_speed(rpm)
    fault_hz = {h: fault_frequency(bearing, h, rpm or cfg.fold.nominal_rpm) for h in STREAMS}
    chunk = max(1, int(round(chunk_s * fs)))
    out: list[Decision] = []
    for i in range(0, y.size, chunk):
        for h in STREAMS:
            out += dg.update(h, i, fs, y[i:i + chunk], None, None, fault_hz[h])
    out += dg.flush()
    return segments_from_decisions(out, y.size / fs, model_set), out
