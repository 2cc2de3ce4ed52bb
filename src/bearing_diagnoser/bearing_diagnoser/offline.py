"""Offline diagnosis of a recording: resample, run the observers chunk by chunk as live, decide, segment.

``diagnose_recording`` is what ``bearing-diagnose`` runs.  The pipeline is the live
one: the OR and IR observers (``bearing_observer.observer.FaultObserver``) process
fixed-size chunks and the incremental :class:`.decision.Diagnoser` consumes their
residual / estimate / impulse-train arrays.  ``method="envelope"`` replaces the observers
by the measurement itself and the folding statistic by the squared envelope spectrum
(:mod:`.envelope_method`), the classical reference.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field

import numpy as np

from bearing_common.bearings import CATALOG, fault_frequency

DRIVE_END_6205 = CATALOG["6205"]  # TODO(issue 11): bearing as input
from bearing_common.states import FaultState
from bearing_recordings.recording import InputError, Recording
from bearing_recordings.resampling import resample

from .decision import HYPOTHESES, Decision, Diagnoser, config_for

#: Chunk length (s) fed to the observers, as the simulator node publishes (0.01 s).
CHUNK_S = 0.01


def _log(msg: str, quiet: bool = False):
    if not quiet:
        print(f"bearing-diagnose: {msg}", file=sys.stderr)


def model_set_rate(name: str) -> float | None:
    """Sample rate (Hz) of a model set (bearing_observer.model_sets); None: any (``none``)."""
    from bearing_observer.hw_model import ModelFileError
    from bearing_observer.model_sets import model_set
    try:
        return model_set(name).sample_rate
    except ModelFileError as exc:
        raise InputError(str(exc)) from None


def choose_model_set(rec: Recording, requested: str | None = None) -> str:
    """The model set for ``rec``: ``requested`` if given, else the registry's rule
    (bearing_observer.model_sets.choose_model_set, resampling allowed) for its source,
    rate and bearing (default 6205): simulator → ``sim_48k`` / ``sim_12k``, CWRU →
    ``cwru_de_6205``, anything else → ``none``.
    """
    from bearing_observer.model_sets import choose_model_set as registry_choice
    if requested:
        model_set_rate(requested)  # validates the name
        return requested
    return registry_choice(rec.source, rec.sample_rate, rec.bearing or None, resample=True).name


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


#: Scores summarised per segment (median over the segment's windows).
SEGMENT_SCORE_KEYS = ("outer_race", "inner_race", "outer_race_explained", "inner_race_explained",
                      "outer_race_xcorr", "inner_race_xcorr", "kurtosis")


def segments_from_decisions(decisions: list[Decision], duration: float, model_set: str) -> list[Segment]:
    """Maximal runs of the published state; start = estimated onset, end = next onset."""
    segs: list[Segment] = []
    if not decisions:
        return segs
    first = decisions[0]
    segs.append(Segment(0.0, duration, first.state, 0.0, first.time, {}, model_set))
    members: list[list[Decision]] = [[]]
    for d in decisions:
        if d.changed:
            onset = max(0.0, d.onset)
            while segs and onset <= segs[-1].start + 1e-12 and len(segs) > 1:
                segs.pop()
                members.pop()
            if len(segs) == 1 and onset <= 1e-12:
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
        for k in SEGMENT_SCORE_KEYS:
            v = [d.scores[k] for d in ms if k in d.scores and np.isfinite(d.scores[k])]
            if v:
                s.scores[k] = float(np.median(v))
    return segs


@dataclass
class OfflineResult:
    """Output of :func:`diagnose_recording`."""

    segments: list[Segment]
    decisions: list[Decision]
    model_set: str
    sample_rate: float
    rpm: float
    accel: np.ndarray
    truth: np.ndarray | None
    streams: dict = field(default_factory=dict)  # hypothesis label -> dict of arrays (for plots)
    cpu_s: float = 0.0
    method: str = "model"


def _observers(model_set: str, rpm: float, fs: float):
    try:
        from bearing_observer.observer import FaultObserver
    except ImportError as exc:
        raise InputError(f"the observer core (bearing_observer.observer) is not available ({exc}); "
                         "use --method envelope") from None
    return {h: FaultObserver.from_model_set(model_set, h.label, rpm, fs) for h in HYPOTHESES}


def diagnose_recording(rec: Recording, model_set: str | None = None, method: str = "model",
                       rpm: float | None = None, config=None, quiet: bool = False,
                       keep_streams: bool = False, chunk_s: float = CHUNK_S) -> OfflineResult:
    """Diagnose a whole recording offline, exactly as the live graph would.

    Parameters
    ----------
    rec : Recording
        From :func:`bearing_recordings.load.load_recording`.
    model_set : str, optional
        Override the automatic choice (:func:`choose_model_set`).
    method : ``"model"`` or ``"envelope"``
        Observers + folding/CFAR decision, or the squared-envelope-spectrum reference.
    rpm : float, optional
        Shaft speed (rev/min); default the recording's, else the model set's nominal.
    config : DiagnoserConfig, optional
        Decision parameters (default: the model set's).
    keep_streams : bool
        Keep full residual / estimate / train arrays for figures.

    Stderr says which model set is used and whether the data were resampled.
    """
    if method not in ("model", "envelope"):
        raise InputError(f"unknown method {method!r}; expected model or envelope")
    ms = choose_model_set(rec, model_set)
    _log(f"model set {ms}" + (" (chosen from the input)" if not model_set else ""), quiet)
    fs = model_set_rate(ms) or rec.sample_rate
    x = rec.accel
    if abs(rec.sample_rate - fs) > 1e-9 * fs:
        _log(f"resampling {rec.sample_rate:g} Hz -> {fs:g} Hz (anti-aliased, resample_poly) for model set {ms}",
             quiet)
        x = resample(x, rec.sample_rate, fs)
    truth = rec.truth
    if truth is not None and truth.size != x.size:
        idx = np.minimum((np.arange(x.size) * rec.sample_rate / fs).astype(int), truth.size - 1)
        truth = truth[idx]
    if x.size < 2:
        raise InputError("too few samples to diagnose")
    cfg = config or config_for(ms)
    speed = rpm or rec.rpm or cfg.nominal_rpm
    if rec.rpm is None and rpm is None:
        _log(f"no shaft speed in the input; assuming {speed:g} rpm (give --rpm)", quiet)
    if x.size < cfg.window_s * fs:
        raise InputError(f"recording too short: {x.size / fs:.3f} s < one {cfg.window_s} s window")
    t0 = time.process_time()
    n = x.size
    chunk = max(1, int(round(chunk_s * fs)))
    streams: dict = {}
    if method == "envelope":
        from .envelope_method import EnvelopeDiagnoser
        dg = EnvelopeDiagnoser(cfg, ms)
        decisions = dg.run(x, fs, speed, chunk)
    else:
        dg = Diagnoser(cfg, ms)
        obs = _observers(ms, speed, fs)
        keep = {h: {"residual": [], "estimate": [], "impulse_train": []} for h in HYPOTHESES} if keep_streams else None
        decisions = []
        for i in range(0, n, chunk):
            y = x[i:i + chunk]
            for h, ob in obs.items():
                out = ob.process(y)
                decisions += dg.update(h, i, fs, out.residual, out.estimate, out.impulse_train, ob.fault_frequency)
                if keep is not None:
                    for k in keep[h]:
                        keep[h][k].append(np.asarray(getattr(out, k), float))
        decisions += dg.flush()
        if keep is not None:
            streams = {h.label: {k: np.concatenate(v) for k, v in d.items()} for h, d in keep.items()}
            for h in HYPOTHESES:
                streams[h.label]["fault_frequency"] = obs[h].fault_frequency
    cpu = time.process_time() - t0
    segs = segments_from_decisions(decisions, n / fs, ms)
    return OfflineResult(segs, decisions, ms, fs, speed, x, truth, streams, cpu, method)


def diagnose_measurement(y: np.ndarray, fs: float, rpm: float, model_set: str = "sim_48k", config=None,
                         chunk_s: float = CHUNK_S) -> tuple[list[Segment], list[Decision]]:
    """Decision core on a measurement alone (no observer: y fed as the residual, ŷ = 0).

    This is the "observer without train, L = 0" front end of diagnosis-notes.md; used to
    test the decision core and for data without a model set.
    """
    dg = Diagnoser(config or config_for(model_set), model_set)
    chunk = max(1, int(round(chunk_s * fs)))
    ff = {h: fault_frequency(DRIVE_END_6205, h, rpm) for h in HYPOTHESES}
    out: list[Decision] = []
    for i in range(0, y.size, chunk):
        for h in HYPOTHESES:
            out += dg.update(h, i, fs, y[i:i + chunk], None, None, ff[h])
    out += dg.flush()
    return segments_from_decisions(out, y.size / fs, model_set), out
