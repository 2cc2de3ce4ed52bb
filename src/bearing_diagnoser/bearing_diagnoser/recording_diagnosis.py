"""Offline diagnosis of a recording, exactly as the live graph would: chunks through the nodes' sessions, then segments.

:func:`diagnose_recording` is what ``bearing-diagnose`` runs: it picks the model set and
the decision's configuration, resamples the recording to the set's rate, and feeds it in
chunks through :class:`.pipeline.MonitorPipeline` (the OR and IR observer sessions and the
diagnoser session). ``method="envelope"`` runs the textbook squared-envelope-spectrum
reference on the measurement instead (:func:`.front_ends.envelope_baseline`). With a ``baseline``
(a healthy recording of the same machine, or a saved reference) the decision judges against the
machine's own healthy reference (:mod:`.spectral.machine_reference`), learnt from it by
:func:`learn_recording_reference` exactly as the recording itself is read (model set, rate, speed).
:func:`diagnose_measurement` runs the decision of a model set on a measurement alone.

A recording whose measured speed changes (:attr:`~bearing_recordings.recording.Recording.speed_varies`:
a ``shaft_speed`` series, a speed or tachometer channel) is decided in the shaft-angle domain
(:mod:`.spectral.angle_domain`), its speed told to the observers chunk by chunk; without a
measured speed, ``track_speed`` (a speed range) takes it from the vibration
(:func:`.order_tracking.track_speed`, offline: the whole record first). A tracked speed without
evidence (a stretch longer than one of the tracker's frames between frames that show a shaft line
above what noise gives, :meth:`.order_tracking.SpeedTrack.unsupported`) is not decided on: the record is one window not
diagnosed (kind ``speed``, the tracker's reason), one UNKNOWN segment.

What the run assumed (model set, resampling, speed) is logged (``logging``, logger
``bearing_diagnoser.recording_diagnosis``); ``bearing-diagnose`` prints it on stderr.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field, replace

import numpy as np

from bearing_common.bearings import CATALOG, DEFAULT_BEARING, Bearing
from bearing_common.chunk_stream import MAX_CHUNK_SAMPLES
from bearing_common.states import FaultState
from bearing_recordings.recording import MEASURED_RPM_TOLERANCE, SPEED_VARIATION, InputError, Recording
from bearing_recordings.resampling import resample

from .decision.config import DiagnoserConfig
from .decision.not_diagnosed import SPEED, NotDiagnosed
from .decision.segments import Segment, segments_from_decisions
from .decision.state_tracker import Decision
from .diagnoser import STREAMS
from .diagnoser_node_config import PARAMETERS
from .front_ends import NO_REFERENCE, config_for, envelope_baseline, takes_reference, with_reference
from .pipeline import MonitorPipeline, choose_model_set
from .spectral.machine_reference import MachineReference, MachineReferenceError, learn_reference

LOG = logging.getLogger(__name__)

#: Chunk length (s) the simulator node publishes (0.01 s): what an offline run feeds while it tells the
#: observers a changing speed (chunk by chunk, as the graph's speed topic does).
CHUNK_S = 0.01

#: Chunk length (s) an offline run feeds otherwise. The decision follows sample indices, not chunks:
#: every window, state and score is the same at any chunk (``tests/unit/test_chunk_sizes.py``; every
#: run of ``benchmarks/decision_dump.py``), and a long chunk spares the per-chunk passes through the
#: sessions (checks, states, condition trend: 30-40 % of the CPU at 0.01 s). Capped at the chunk
#: check's limit (:data:`~bearing_common.chunk_stream.MAX_CHUNK_SAMPLES`).
OFFLINE_CHUNK_S = 10.0

METHODS = ("model", "envelope")


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
    not_diagnosed: list = field(default_factory=list)  # (start s, end s, NotDiagnosed) of the windows not diagnosed
    bearing: Bearing | None = None  # the bearing diagnosed
    reference: str = ""  # the machine reference in force (MachineReference.describe()); "": none, blind


def _speed(rec: Recording, rpm: float | None) -> float | None:
    speed = rpm or rec.rpm
    if speed is None:
        LOG.warning("no shaft speed given; estimating it from the vibration (the 1x line) — unreliable "
                    "without a prior, give --rpm")
    return speed


def _decision_config(config: DiagnoserConfig, method: str, set_rate: float, recorded_rate: float) -> DiagnoserConfig:
    """The configuration a run uses: ``method``'s, and nothing above the recording's own band when it
    is upsampled to the model set's rate."""
    if method == "envelope":
        config = envelope_baseline(config)
    if set_rate > recorded_rate:
        usable = min(config.usable_bandwidth or np.inf, 0.45 * recorded_rate)
        config = replace(config, usable_bandwidth=usable)
    return config


def _at_rate(rec: Recording, fs: float, model_set: str) -> tuple[np.ndarray, np.ndarray | None]:
    """The recording's acceleration and truth at ``fs`` Hz."""
    x = rec.accel
    if abs(rec.sample_rate - fs) > 1e-9 * fs:
        LOG.info("resampling %g Hz -> %g Hz (anti-aliased, resample_poly) for model set %s", rec.sample_rate, fs,
                 model_set)
        x = resample(x, rec.sample_rate, fs)
    truth = rec.truth
    if truth is not None and truth.size != x.size:
        truth = truth[np.minimum((np.arange(x.size) * rec.sample_rate / fs).astype(int), truth.size - 1)]
    return x, truth


def _told_tolerance(rec: Recording, rpm: float | None, rpm_tolerance: float | None) -> float | None:
    """The relative tolerance of the speed a run is told: the given one, else the recording's own
    statement for its own speed, else None (the diagnoser's default)."""
    if rpm_tolerance is None and (rpm is None or rpm == rec.rpm):
        return rec.rpm_tolerance
    return rpm_tolerance


def learn_recording_reference(rec: Recording, model_set: str | None = None, rpm: float | None = None,
                              bearing: Bearing | None = None, rpm_tolerance: float | None = None,
                              config: DiagnoserConfig | None = None) -> MachineReference:
    """The machine reference learnt from the healthy recording ``rec`` (its first
    :data:`.spectral.machine_reference.MAX_PERIOD_S`), read as :func:`diagnose_recording` reads a
    recording with the same arguments (model set, rate, speed, tolerance, bearing); InputError (one
    line) when it cannot give one."""
    bearing = bearing or rec.bearing or CATALOG[DEFAULT_BEARING]
    chosen = choose_model_set(rec.source, rec.sample_rate, bearing, model_set)
    fs = chosen.sample_rate or rec.sample_rate
    cfg = _decision_config(config or config_for(chosen.name), "model", fs, rec.sample_rate)
    tolerance = _told_tolerance(rec, rpm, rpm_tolerance)
    if tolerance is None:
        tolerance = next(p.default for p in PARAMETERS if p.name == "rpm_tolerance")
    if not takes_reference(cfg):
        raise InputError(f"baseline {rec.path}: {NO_REFERENCE}")
    x, _ = _at_rate(rec, fs, chosen.name)
    try:
        return learn_reference(x, fs, bearing, rpm or rec.rpm, tolerance, cfg.front_end, cfg.usable_bandwidth,
                               rec.path or "healthy recording")
    except MachineReferenceError as exc:
        raise InputError(f"baseline {rec.path}: {exc}") from None


def run_pipeline(pipeline: MonitorPipeline, x: np.ndarray, fs: float, source: str,
                 chunk_s: float = OFFLINE_CHUNK_S) -> list[Decision]:
    """Feed ``x`` (m/s² at ``fs`` Hz) to ``pipeline`` in chunks of ``chunk_s`` seconds (at most
    :data:`~bearing_common.chunk_stream.MAX_CHUNK_SAMPLES`); every window's decision."""
    chunk = min(max(1, int(round(chunk_s * fs))), MAX_CHUNK_SAMPLES)
    for i in range(0, x.size, chunk):
        pipeline.feed(i, fs, x[i:i + chunk], source)
    return pipeline.finish()


def diagnose_recording(rec: Recording, model_set: str | None = None, method: str = "model",
                       rpm: float | None = None, bearing: Bearing | None = None,
                       config: DiagnoserConfig | None = None, keep_streams: bool = False,
                       chunk_s: float | None = None, rpm_tolerance: float | None = None,
                       baseline: Recording | MachineReference | None = None,
                       track_speed: tuple[float, float, float] | None = None) -> OfflineResult:
    """Diagnose a whole recording offline, exactly as the live graph would.

    Parameters
    ----------
    rec : Recording
        From :func:`bearing_recordings.load.load_recording`.
    model_set : str, optional
        Override the automatic choice (:func:`.pipeline.choose_model_set`).
    method : ``"model"`` or ``"envelope"``
        The decision with the observers (default), or the textbook envelope reference.
    rpm : float, optional
        Shaft speed (rev/min); default the recording's, else estimated from the vibration.
    rpm_tolerance : float, optional
        Relative accuracy of the speed: default the recording's own statement for its speed
        (a rig's measurement), else the diagnoser's default for a told speed (a nameplate's).
    bearing : Bearing, optional
        The monitored bearing (default: the recording's, else the 6205).
    config : DiagnoserConfig, optional
        Decision parameters (default: the model set's).
    keep_streams : bool
        Keep full residual / estimate / train arrays for figures.
    chunk_s : float, optional
        Chunk length fed to the sessions (s): default :data:`OFFLINE_CHUNK_S`, :data:`CHUNK_S` when a
        changing speed is followed (the decisions are the same at any chunk).
    baseline : Recording or MachineReference, optional
        The machine's own healthy reference: a healthy recording of the same machine (learnt by
        :func:`learn_recording_reference` with the same arguments) or a reference learnt before;
        None: the blind decision. The textbook method takes none.
    track_speed : (lo, hi, rate), optional
        For a recording without a measured speed whose speed changes within lo-hi rev/min (narrower
        than an octave) by at most ``rate`` (relative change per second): the speed per sample tracked
        from the vibration
        (:func:`.order_tracking.track_speed`, its accuracy there), then decided as a measured one; a
        track without evidence is not: the whole record is then not diagnosed (module docstring).

    Raises InputError (one line) only when the recording cannot be analysed at all, whatever its
    signal holds: an unknown method or model set, a sample rate too low for the bearing's fault
    lines, a record shorter than one analysis window. A readable recording gets a verdict: where
    no window could be diagnosed (a dead sensor, a speed never confirmed), its one segment says
    so (:func:`.decision.segments.segments_from_decisions`).
    """
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; expected {' or '.join(METHODS)}")
    bearing = bearing or rec.bearing or CATALOG[DEFAULT_BEARING]
    chosen = choose_model_set(rec.source, rec.sample_rate, bearing, model_set)
    ms = chosen.name
    LOG.info("model set %s%s; bearing %s", ms, "" if model_set else " (chosen from the input)", bearing.name)
    fs = chosen.sample_rate or rec.sample_rate
    cfg = _decision_config(config or config_for(ms), method, fs, rec.sample_rate)
    series, tracked_rpm, refused = _changing_speed(rec, fs, track_speed)
    speed = rpm or tracked_rpm or (float(np.mean(series)) * 30.0 / np.pi if series is not None else _speed(rec, rpm))
    if isinstance(baseline, Recording):
        baseline = learn_recording_reference(baseline, model_set, rpm, bearing, rpm_tolerance, config)
    if baseline is not None and method == "envelope":
        LOG.warning("the textbook method judges blind: the machine reference is not used")
        baseline = None
    try:
        cfg = with_reference(cfg, baseline)
        cfg.front_end.check_recording(min(fs, rec.sample_rate), bearing, speed, rec.duration, cfg.usable_bandwidth)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if refused is not None:
        return _not_diagnosed(rec, ms, fs, method, bearing, refused)
    LOG.info("machine reference: %s", baseline.describe() if baseline is not None else "none (the blind decision)")
    x, truth = _at_rate(rec, fs, ms)
    observed = method == "model"
    rpm_tolerance = _told_tolerance(rec, rpm, rpm_tolerance)
    pipeline = MonitorPipeline(bearing, ms, cfg, speed, observed,
                               STREAMS if observed or cfg.front_end.EVERY_STREAM else STREAMS[:1], keep_streams,
                               rpm_tolerance, shaft_speed=series)
    t_cpu = time.process_time()
    if chunk_s is None:
        chunk_s = OFFLINE_CHUNK_S if series is None else CHUNK_S
    decisions = run_pipeline(pipeline, x, fs, rec.source, chunk_s)
    cpu = time.process_time() - t_cpu
    problems = [(d.window_start, d.window_end, d.not_diagnosed) for d in decisions if not d.diagnosed]
    segs = segments_from_decisions(decisions, x.size / fs, ms)
    return OfflineResult(segs, decisions, ms, fs, speed, x, truth, pipeline.kept_streams(), cpu, method, problems,
                         bearing, baseline.describe() if baseline is not None else "")


def _changing_speed(rec: Recording, fs: float, track: tuple[float, float, float] | None
                    ) -> tuple[np.ndarray | None, float | None, NotDiagnosed | None]:
    """(the recording's speed per sample at ``fs`` Hz (rad/s) when it changes (measured, or tracked as
    ``track`` = (lo, hi rev/min, largest change 1/s) says when none is measured), None when it holds one
    speed; the tracked mean speed (rev/min), None when none was tracked; why the tracked speed must not be
    used, None when it may or none was tracked)."""
    w, tracked = rec.shaft_speed, None
    if w is None and track is not None:
        from .order_tracking import track_speed
        lo, hi, rate = track
        found = track_speed(rec.accel, rec.sample_rate, lo, hi, max_rate=rate)
        w = found.speed
        spread, tracked = float((w.max() - w.min()) / w.mean()), float(np.mean(w)) * 30.0 / np.pi
        LOG.info("shaft speed tracked from the vibration within %g-%g rpm, changing by at most %g %%/s: %.0f to "
                 "%.0f rpm, %.0f %% of its frames with a shaft line", lo, hi, 100.0 * rate, w.min() * 30.0 / np.pi,
                 w.max() * 30.0 / np.pi, 100.0 * found.evidenced())
        why = found.unsupported()
        if why is not None:
            LOG.warning("the tracked shaft speed is not used: %s", why)
            return None, tracked, NotDiagnosed(SPEED, why)
    else:
        spread = rec.speed_spread
    if w is None or spread <= SPEED_VARIATION:
        return None, tracked, None
    LOG.info("the shaft speed changes by %.1f %% of its mean: decided in the shaft-angle domain", 100 * spread)
    if abs(rec.sample_rate - fs) > 1e-9 * fs:
        w = np.interp(np.arange(int(round(w.size * fs / rec.sample_rate))) / fs, np.arange(w.size) / rec.sample_rate, w)
    return w, tracked, None


def _not_diagnosed(rec: Recording, model_set: str, fs: float, method: str, bearing: Bearing,
                   why: NotDiagnosed) -> OfflineResult:
    """The result of a recording not decided at all, for ``why``: one window, the whole record, not diagnosed."""
    end = rec.duration
    window = Decision(end, 0.0, end, FaultState.UNKNOWN, FaultState.UNKNOWN, 0.0, 0.0, False, not_diagnosed=why)
    x, truth = _at_rate(rec, fs, model_set)
    return OfflineResult(segments_from_decisions([window], end, model_set), [window], model_set, fs, None, x, truth,
                         method=method, not_diagnosed=[(0.0, end, why)], bearing=bearing)


def diagnose_measurement(y: np.ndarray, fs: float, rpm: float | None, model_set: str = "sim_48k",
                         config: DiagnoserConfig | None = None, bearing: Bearing | None = None,
                         chunk_s: float = OFFLINE_CHUNK_S,
                         rpm_tolerance: float = MEASURED_RPM_TOLERANCE) -> tuple[list[Segment], list[Decision]]:
    """The decision with the defaults of ``model_set`` on a measurement alone (no observer: y fed
    as both streams' residual, ŷ = 0): the "observer without train, L = 0" front end of
    diagnosis-notes.md, for testing the decision core and for data without a model set. ``rpm``
    is known to ``rpm_tolerance`` (default: a measured speed's)."""
    pipeline = MonitorPipeline(bearing or CATALOG[DEFAULT_BEARING], model_set, config or config_for(model_set), rpm,
                               observed=False, rpm_tolerance=rpm_tolerance)
    decisions = run_pipeline(pipeline, np.asarray(y, dtype=float), fs, "measurement", chunk_s)
    return segments_from_decisions(decisions, y.size / fs, model_set), decisions
