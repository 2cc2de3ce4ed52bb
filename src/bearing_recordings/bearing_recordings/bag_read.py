"""Reading rosbag2 recordings of the monitoring graph without rclpy (via ``rosbags``).

A bag is a rosbag2 directory (``metadata.yaml`` plus MCAP or sqlite3 storage) as written
by ``ros2 bag record`` or ``bearing-bag record`` / ``bearing-bag from-mat``.  Messages are
decoded with the definitions embedded in the bag itself (ros2msg / ros2idl text, checked
against the recorded RIHS01 type hashes); bags without embedded definitions fall back to
:func:`.bag_types.project_typestore`.

The graph's topics are relative names; in a bag they appear fully qualified, e.g.
``/vibration/drive_end`` or ``/machine_3/vibration/drive_end``.  :func:`read_bag` finds a
topic by its relative name under one namespace (``namespace=None``: the only one present).

Errors are :class:`BagError` (an :class:`~.recording.InputError`) with one line meant
for the user.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bearing_common import topics
from bearing_common.bearings import Bearing, BearingError, load_bearing
from bearing_common.shaft_angle import angle_from_pulses
from bearing_common.stamps import to_seconds
from bearing_common.units import sample_rate_problem

from .bag_types import CUSTOM_BEARING, CUSTOM_NAMESPACE, BagError, project_typestore
from .recording import MAX_SAMPLES, MEASURED_RPM_TOLERANCE, Recording

LOG = logging.getLogger(__name__)

#: What the readers raise on a damaged file (a damaged length field makes them try to
#: allocate gigabytes: MemoryError).
_DAMAGED = (OSError, ValueError, KeyError, TypeError, EOFError, AssertionError, MemoryError, OverflowError)


# ----------------------------------------------------------------------------------------
# Opening and validating bags


def _reader_errors():
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag2 import ReaderError
    from rosbags.typesys import TypesysError
    return (AnyReaderError, ReaderError, TypesysError)


def check_bag_dir(path) -> Path:
    """Raise :class:`BagError` unless ``path`` looks like a complete rosbag2 directory."""
    p = Path(path)
    if not p.exists():
        raise BagError(f"{path}: no such file or directory")
    if not p.is_dir():
        raise BagError(f"{path}: not a rosbag2 recording (a rosbag2 recording is a directory with metadata.yaml)")
    if not (p / "metadata.yaml").is_file():
        storage = sorted(x.name for x in p.iterdir() if x.suffix in (".mcap", ".db3"))
        if storage:
            raise BagError(f"{path}: truncated bag: metadata.yaml is missing beside {', '.join(storage)} "
                           "(the recorder was killed before it could close the bag)")
        raise BagError(f"{path}: not a rosbag2 recording (no metadata.yaml)")
    return p


@contextmanager
def open_bag(path, fallback_typestore: bool = True):
    """Open a rosbag2 directory with ``rosbags.highlevel.AnyReader``; errors → :class:`BagError`.

    The reader's type store holds the definitions embedded in the bag (checked against
    their type hashes); a bag without embedded definitions is decoded with
    :func:`project_typestore` when ``fallback_typestore``.
    """
    from rosbags.highlevel import AnyReader
    p = check_bag_dir(path)
    errors = _reader_errors()
    try:
        reader = AnyReader([p], default_typestore=project_typestore() if fallback_typestore else None)
        reader.open()
    except errors as exc:
        raise BagError(f"{path}: not a readable rosbag2 recording: {_one_line(exc)}") from None
    except _DAMAGED as exc:
        raise BagError(f"{path}: not a readable rosbag2 recording ({exc.__class__.__name__}: "
                       f"{_one_line(exc)})") from None
    try:
        yield reader
    finally:
        try:
            reader.close()
        except Exception:  # closing a half-read broken file must not hide the real error
            pass


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(a) for a in exc.args) if exc.args else exc.__class__.__name__
    return " ".join(text.split()).rstrip(".")


def iter_raw(reader, connections) -> Iterator[tuple]:
    """``(connection, log_time_ns, raw_cdr)`` in log-time order; storage errors → :class:`BagError`.

    A storage file cut short (a crashed recorder, a partial copy) raises here, naming
    how far it got.
    """
    count = 0
    try:
        for conn, t, raw in reader.messages(connections=connections):
            yield conn, t, raw
            count += 1
    except _reader_errors() + _DAMAGED as exc:
        raise BagError(f"{reader.paths[0]}: bag storage is damaged after {count} messages: "
                       f"{_one_line(exc)}") from None
    except Exception as exc:  # mcap / sqlite3 raise their own error types on truncated files
        raise BagError(f"{reader.paths[0]}: bag storage is damaged after {count} messages "
                       f"({exc.__class__.__name__}: {_one_line(exc)})") from None


def find_topic(recorded, relative: str, namespace: str | None = None) -> str | None:
    """The recorded name of graph topic ``relative`` among ``recorded`` names (None if absent).

    With ``namespace`` (e.g. ``"machine_3"`` or ``""`` for the root) the name must be
    exactly ``/namespace/relative``; without, any namespace is accepted as long as only one
    recorded topic matches.
    """
    names = list(recorded)
    if namespace is not None:
        want = topics.qualified(namespace, relative)
        return want if want in names else None
    rel = relative.strip("/")
    matches = [n for n in names if n.strip("/") == rel or n.endswith("/" + rel)]
    if relative.startswith("/"):
        matches = [n for n in matches if n == relative]
    if len(matches) > 1:
        raise BagError(f"topic {relative!r} is recorded under several namespaces ({', '.join(sorted(matches))}); "
                       "choose one with --namespace")
    return matches[0] if matches else None


# ----------------------------------------------------------------------------------------
# Decoded contents


@dataclass
class Chunk:
    """One ``VibrationChunk`` (stamp = time of its first sample, s)."""

    stamp: float
    first_sample_index: int
    sample_rate: float
    source: str
    frame_id: str
    samples: np.ndarray  # shape (n,), SI units (m/s²)
    log_time: float  # s, when it was recorded (receive time)


@dataclass
class SpeedSample:
    """One ``ShaftSpeed``."""

    stamp: float
    angular_velocity: float  # rad/s
    source: str
    log_time: float


@dataclass
class PulseBatch:
    """One ``Tachometer`` message: the pulses in [stamp, stamp + duration) s."""

    stamp: float
    duration: float
    pulse_times: np.ndarray  # s, absolute (stamp + offsets)
    first_pulse_index: int
    pulses_per_revolution: int
    source: str
    log_time: float


@dataclass
class StateSample:
    """One ``FaultState`` (from ``fault_state`` or ``sim/truth``)."""

    stamp: float  # decision time (signal time)
    state: int  # FaultState integer
    confidence: float
    onset: float  # s, estimated start of the state
    scores: dict
    model_set: str
    detail: str
    log_time: float


@dataclass
class BagContents:
    """What :func:`read_bag` decoded; every list is in recording (log-time) order."""

    path: str
    storage: str
    namespace: str  # namespace the topics were found under ("" = root)
    topics: dict  # recorded name -> (type, message count)
    chunks: list = field(default_factory=list)
    speeds: list = field(default_factory=list)
    pulses: list = field(default_factory=list)
    fault_states: list = field(default_factory=list)
    truth: list = field(default_factory=list)

    @property
    def rpm(self) -> float | None:
        """Median recorded shaft speed (rev/min), or None."""
        if not self.speeds:
            return None
        return float(np.median([s.angular_velocity for s in self.speeds])) * 60.0 / (2.0 * np.pi)

    def speed_at(self, t: np.ndarray) -> np.ndarray | None:
        """Shaft speed (rad/s) at times ``t`` (s, stamps' clock): from the tachometer pulses when at least
        three were recorded (:func:`bearing_common.shaft_angle.angle_from_pulses`), else ``shaft_speed``
        interpolated linearly between its stamps and held beyond them; None without either."""
        times = np.concatenate([b.pulse_times for b in self.pulses]) if self.pulses else np.empty(0)
        if times.size >= 3:
            return angle_from_pulses(np.unique(times), t, self.pulses[0].pulses_per_revolution)[1]
        if not self.speeds:
            return None
        order = np.argsort([s.stamp for s in self.speeds], kind="stable")
        stamps = np.array([self.speeds[i].stamp for i in order])
        values = np.array([self.speeds[i].angular_velocity for i in order])
        return np.interp(t, stamps, values)


def _state_sample(msg, log_time: float) -> StateSample:
    scores = {str(k): float(v) for k, v in zip(msg.hypotheses, np.asarray(msg.scores).tolist())}
    return StateSample(to_seconds(msg.header.stamp), int(msg.state), float(msg.confidence),
                       to_seconds(msg.onset), scores, str(msg.model_set), str(msg.detail), log_time)


def _bag_info(path) -> dict:
    """``rosbag2_bagfile_information`` of ``metadata.yaml`` ({} when unreadable)."""
    import yaml
    try:
        meta = yaml.safe_load((Path(path) / "metadata.yaml").read_text())
        info = meta.get("rosbag2_bagfile_information") if isinstance(meta, dict) else None
        return info if isinstance(info, dict) else {}
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return {}


def bag_storage(path) -> str:
    """The storage identifier in ``metadata.yaml`` (``mcap``, ``sqlite3``), or ``""``."""
    return str(_bag_info(path).get("storage_identifier", ""))


def _custom(path, key: str) -> str | None:
    custom = _bag_info(path).get("custom_data") or {}
    value = custom.get(key) if isinstance(custom, dict) else None
    return None if value is None else str(value)


def bag_namespace_hint(path) -> str | None:
    """The namespace ``bearing-bag`` stored in the bag's custom_data, if any."""
    return _custom(path, CUSTOM_NAMESPACE)


def bag_bearing_spec(path) -> str:
    """The bearing description ``bearing-bag from-mat`` stored in the bag's custom_data, else ""."""
    return _custom(path, CUSTOM_BEARING) or ""


def bag_bearing(path) -> Bearing | None:
    """The bearing ``bearing-bag from-mat`` stored in the bag (:func:`bag_bearing_spec`), else None;
    BagError when what is stored is not a bearing."""
    spec = bag_bearing_spec(path)
    if not spec:
        return None
    try:
        return load_bearing(spec)
    except BearingError as exc:
        raise BagError(f"{path}: the bearing stored in the bag is not usable: {exc}") from None


def read_bag(path, namespace: str | None = None, vibration_topic: str = topics.VIBRATION.name) -> BagContents:
    """Decode the graph's recorded vibration, shaft speed and fault states.

    Parameters
    ----------
    path : str or Path
        rosbag2 directory.
    namespace : str, optional
        Namespace of the machine's topics (``""`` = root); default: the only one present.
    vibration_topic : str
        Relative name of the VibrationChunk topic to read.

    Returns
    -------
    BagContents
        ``chunks`` (VibrationChunk of ``vibration_topic``), ``speeds`` (``shaft_speed``),
        ``pulses`` (``shaft_pulses``), ``fault_states`` (the diagnoser's ``fault_state``) and
        ``truth`` (``sim/truth``).

    Raises
    ------
    BagError
        Not a bag, truncated or damaged, no vibration topic, or a topic of the wrong type.
    """
    wanted = {vibration_topic: topics.VIBRATION.msgtype, topics.SHAFT_SPEED.name: topics.SHAFT_SPEED.msgtype,
              topics.TACHOMETER.name: topics.TACHOMETER.msgtype,
              topics.FAULT_STATE.name: topics.FAULT_STATE.msgtype, topics.TRUTH.name: topics.TRUTH.msgtype}
    with open_bag(path) as reader:
        recorded = {c.topic: c.msgtype for c in reader.connections}
        counts: dict = {}
        for c in reader.connections:
            counts[c.topic] = (c.msgtype, counts.get(c.topic, (None, 0))[1] + c.msgcount)
        if namespace is None and find_topic(recorded, vibration_topic) is None:
            namespace = bag_namespace_hint(path)
        names = {}
        for rel, typ in wanted.items():
            name = find_topic(recorded, rel, namespace)
            if name is None:
                continue
            if recorded[name] != typ:
                raise BagError(f"{path}: topic {name} has type {recorded[name]}, expected {typ}")
            names[name] = rel
        vib_name = next((n for n, r in names.items() if r == vibration_topic), None)
        if vib_name is None:
            have = ", ".join(f"{t} ({recorded[t]})" for t in sorted(recorded)) or "no topics"
            raise BagError(f"{path}: no {vibration_topic} topic"
                           + (f" under namespace /{namespace.strip('/')}" if namespace else "")
                           + f" in the bag (it has {have})")
        ns = vib_name[: -len(vibration_topic)].strip("/") if not vibration_topic.startswith("/") else ""
        out = BagContents(str(path), bag_storage(path), ns, counts)
        conns = [c for c in reader.connections if c.topic in names]
        for conn, t, raw in iter_raw(reader, conns):
            rel = names[conn.topic]
            try:
                msg = reader.deserialize(raw, conn.msgtype)
            except Exception as exc:
                raise BagError(f"{path}: cannot decode a {conn.msgtype} message on {conn.topic}: "
                               f"{_one_line(exc)}") from None
            log_time = t * 1e-9
            if rel == vibration_topic:
                out.chunks.append(Chunk(to_seconds(msg.header.stamp), int(msg.first_sample_index),
                                        float(msg.sample_rate), str(msg.source), str(msg.header.frame_id),
                                        np.asarray(msg.samples, dtype=float), log_time))
            elif rel == topics.SHAFT_SPEED.name:
                out.speeds.append(SpeedSample(to_seconds(msg.header.stamp), float(msg.angular_velocity),
                                              str(msg.source), log_time))
            elif rel == topics.TACHOMETER.name:
                stamp = to_seconds(msg.header.stamp)
                out.pulses.append(PulseBatch(stamp, float(msg.duration),
                                             stamp + np.asarray(msg.pulse_offsets, dtype=float),
                                             int(msg.first_pulse_index), max(1, int(msg.pulses_per_revolution)),
                                             str(msg.source), log_time))
            elif rel == topics.FAULT_STATE.name:
                out.fault_states.append(_state_sample(msg, log_time))
            else:
                out.truth.append(_state_sample(msg, log_time))
    return out


# ----------------------------------------------------------------------------------------
# Bag → Recording (for bearing-diagnose)


@dataclass
class Stream:
    """The vibration chunks joined into one uniformly sampled signal."""

    samples: np.ndarray  # (n,), m/s²
    sample_rate: float  # Hz
    start_time: float  # s, stamp of the first sample
    first_sample_index: int
    source: str
    gaps: list  # (first missing sample index, number of missing samples), filled with zeros
    duplicates: int  # chunks dropped because their samples were already present


def join_chunks(chunks: list) -> Stream:
    """Join chunks by ``first_sample_index`` (sorted; duplicates dropped; gaps zero-filled).

    Raises :class:`BagError` when the chunks disagree on sample rate or source (several
    streams mixed on one topic).
    """
    if not chunks:
        raise BagError("no vibration chunks in the bag")
    rates = {c.sample_rate for c in chunks}
    if len(rates) > 1:
        listed = ", ".join(f"{r:g}" for r in sorted(rates))
        raise BagError(f"vibration chunks have different sample rates ({listed} Hz)")
    rate = rates.pop()
    if sample_rate_problem(rate):
        raise BagError(f"vibration chunks: {sample_rate_problem(rate)}")
    sources = {c.source for c in chunks}
    if len(sources) > 1:
        raise BagError(f"vibration chunks come from several sources ({', '.join(sorted(sources))})")
    ordered = sorted(chunks, key=lambda c: c.first_sample_index)
    first = ordered[0]
    span = max(c.first_sample_index + c.samples.size for c in ordered) - first.first_sample_index
    if span > MAX_SAMPLES:
        raise BagError(f"vibration chunks span {span} samples ({span / rate:.0f} s at {rate:g} Hz), more than the "
                       f"{MAX_SAMPLES} this tool reads at once: a damaged index or several recordings in one bag")
    parts, gaps, dups = [], [], 0
    nxt = first.first_sample_index
    for c in ordered:
        n = c.samples.size
        if c.first_sample_index + n <= nxt:
            dups += 1
            continue
        if c.first_sample_index > nxt:
            missing = c.first_sample_index - nxt
            gaps.append((nxt, missing))
            parts.append(np.zeros(missing))
            nxt = c.first_sample_index
        parts.append(c.samples[nxt - c.first_sample_index:])
        nxt = c.first_sample_index + n
    return Stream(np.concatenate(parts), rate, first.stamp, first.first_sample_index, first.source, gaps, dups)


def truth_per_sample(truth: list, start_time: float, n: int, rate: float) -> np.ndarray | None:
    """Per-sample true state from the recorded ``sim/truth`` changes (state from its onset on)."""
    if not truth:
        return None
    t = start_time + np.arange(n) / rate
    out = np.zeros(n, dtype=int)
    for s in sorted(truth, key=lambda s: s.onset):
        out[t >= s.onset - 0.5 / rate] = s.state
    return out


def load_bag(path, channel: str | None = None, namespace: str | None = None) -> Recording:
    """A rosbag2 recording of the graph as a :class:`~.recording.Recording` (``bearing-diagnose BAG_DIR``).

    ``channel`` is the relative VibrationChunk topic (default ``vibration/drive_end``).
    The chunks are joined by ``first_sample_index`` (gaps zero-filled, logged as a
    warning); ``source`` is the chunks' source field (picks the model set), ``rpm`` the
    median of ``shaft_speed``, ``truth`` per sample from ``sim/truth`` when recorded. When the
    recorded speed changes (``shaft_speed``, or ``shaft_pulses`` tachometer pulses, which take precedence),
    ``shaft_speed`` holds it per sample and ``rpm`` its mean.
    The stamp of the first sample is kept as ``recording.start_time`` (s), the bearing
    stored by ``bearing-bag from-mat`` as ``recording.bearing``.
    """
    contents = read_bag(path, namespace=namespace, vibration_topic=channel or topics.VIBRATION.name)
    try:
        stream = join_chunks(contents.chunks)
    except BagError as exc:
        raise BagError(f"{path}: {exc}") from None
    if stream.gaps:
        missing = sum(n for _i, n in stream.gaps)
        LOG.warning("%s: %d gaps in %s (%d samples, %.3f s) filled with zeros", path, len(stream.gaps),
                    channel or topics.VIBRATION.name, missing, missing / stream.sample_rate)
    truth = truth_per_sample(contents.truth, stream.start_time, stream.samples.size, stream.sample_rate)
    rec = Recording(stream.samples, stream.sample_rate, contents.rpm, stream.source, truth,
                    channel or topics.VIBRATION.name, str(path), start_time=stream.start_time,
                    bearing=bag_bearing(path), rpm_tolerance=None if contents.rpm is None else MEASURED_RPM_TOLERANCE)
    try:
        speed = contents.speed_at(stream.start_time + np.arange(stream.samples.size) / stream.sample_rate)
    except ValueError as exc:  # pulses that do not increase
        raise BagError(f"{path}: tachometer: {exc}") from None
    if speed is not None and np.ptp(speed) > 0.0:  # a changing speed: the series, its mean as rpm
        rec.set_shaft_speed(speed, f"{path}: shaft speed")
    return rec
