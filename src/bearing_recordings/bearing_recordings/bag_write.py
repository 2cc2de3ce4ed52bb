"""Writing rosbag2 recordings with ``rosbags`` (no rclpy): the writer used by
``bearing-bag record`` and the recording → bag conversion of ``bearing-bag from-mat``.

Bags are rosbag2 version 9 directories, MCAP by default (sqlite3 on request), with the
complete ros2msg definition of every type embedded (dependencies such as
``std_msgs/Header`` and ``builtin_interfaces/Time`` included) and the type hashes ROS 2
computes, so ``ros2 bag``, Foxglove and ``mcap-ros2-support`` decode them without this
project's packages.  The QoS each topic was offered with is stored too, so
``ros2 bag play`` re-offers ``fault_state`` and ``sim/truth`` as transient local.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bearing_common import topics
from bearing_common.topics import Topic

from .bag_types import CUSTOM_BEARING, CUSTOM_NAMESPACE, BagError, project_typestore
from .recording import Recording, check_rpm

STORAGES = ("mcap", "sqlite3")

#: Default chunk length (s) of from-mat, as the simulator publishes.
DEFAULT_CHUNK_DURATION = 0.01


def topic_qos(latched: bool, depth: int):
    """The rosbags ``Qos`` a topic is offered with (reliable; transient local if latched),
    as :func:`bearing_common.topics.qos` offers it live."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
    zero = QosTime(0, 0)
    return Qos(QosHistory.KEEP_LAST, depth, QosReliability.RELIABLE,
               QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE,
               zero, zero, QosLiveliness.AUTOMATIC, zero, False)


class BagWriter:
    """A rosbag2 directory being written; use as a context manager or call :meth:`close`.

    Parameters
    ----------
    out : path
        The bag directory to create (must not exist).
    storage : ``"mcap"`` or ``"sqlite3"``
    namespace : str
        Namespace of the graph being recorded; stored in the bag's custom_data.
    """

    def __init__(self, out, storage: str = "mcap", namespace: str = "", bearing: str = ""):
        from rosbags.rosbag2 import StoragePlugin, Writer, WriterError
        if storage not in STORAGES:
            raise BagError(f"unknown storage {storage!r}; expected one of {', '.join(STORAGES)}")
        self.path = Path(out)
        if self.path.exists():
            raise BagError(f"{out} exists already; choose a new bag directory")
        self.typestore = project_typestore()
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        self.storage = storage
        self._writer = Writer(self.path, version=9, storage_plugin=plugin)
        self._writer.set_custom_data(CUSTOM_NAMESPACE, (namespace or "").strip("/"))
        self._writer.set_custom_data("bearing_bag.writer", "bearing-bag (rosbags)")
        if bearing:
            self._writer.set_custom_data(CUSTOM_BEARING, bearing)
        try:
            self._writer.open()
        except (WriterError, OSError) as exc:
            raise BagError(f"cannot create bag {out}: {exc}") from None
        self.connections: dict = {}
        self.counts: dict = {}
        self._closed = False

    def add_graph_topic(self, topic: Topic, namespace: str = ""):
        """Register one of the graph's topics under ``namespace`` with its contract QoS."""
        return self.add_topic(topics.qualified(namespace, topic), topic.msgtype, topic.latched, topic.depth)

    def add_topic(self, name: str, msgtype: str, latched: bool = False, depth: int = 10):
        """Register fully qualified topic ``name`` of ``msgtype``; returns the connection."""
        if name in self.connections:
            return self.connections[name]
        if msgtype not in self.typestore.fielddefs:
            raise BagError(f"cannot record {name}: type {msgtype} is not known to the bag writer "
                           "(only ROS 2 standard messages and bearing_msgs)")
        conn = self._writer.add_connection(name, msgtype, typestore=self.typestore,
                                           offered_qos_profiles=[topic_qos(latched, depth)])
        self.connections[name] = conn
        self.counts[name] = 0
        return conn

    def write(self, name: str, log_time_ns: int, raw) -> None:
        """Append one serialized (CDR) message of topic ``name`` logged at ``log_time_ns``."""
        self._writer.write(self.connections[name], int(log_time_ns), raw)
        self.counts[name] += 1

    def serialize(self, msg, msgtype: str):
        """CDR bytes of a rosbags message object (``self.typestore.types[msgtype](...)``)."""
        return self.typestore.serialize_cdr(msg, msgtype)

    def close(self) -> None:
        """Write the index and metadata.yaml; afterwards the bag is complete and readable."""
        if not self._closed:
            self._closed = True
            self._writer.close()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def time_msg(store, seconds: float):
    """builtin_interfaces/Time of ``seconds`` (≥ 0), nanosecond-rounded."""
    ns = int(round(seconds * 1e9))
    return store.types["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


@dataclass
class Conversion:
    """Summary of :func:`recording_to_bag`."""

    path: str
    chunks: int
    samples: int
    sample_rate: float
    rpm: float
    duration: float


def recording_to_bag(rec: Recording, out, chunk_duration: float = DEFAULT_CHUNK_DURATION,
                     start_time: float = 0.0, storage: str = "mcap", namespace: str = "",
                     max_duration: float | None = None, resample_to: float | None = None,
                     bearing: str = "") -> Conversion:
    """Write a recording into a bag as a sensor driver would have published it.

    ``vibration/drive_end`` in chunks of ``chunk_duration`` s, ``shaft_speed`` at the
    recording's speed (see :func:`write_signal_bag`; the measured speed at each chunk's start
    when the recording carries one per sample); source = the recording's (``cwru``,
    ``mfpt``, ...). ``max_duration`` (s) keeps only the start; ``resample_to`` (Hz)
    resamples (anti-aliased) first, as a driver configured for that rate would deliver;
    ``bearing`` (catalog name or description) is stored in the bag's custom data.
    """
    if rec.rpm is None:
        raise BagError(f"{rec.path}: the recording states no shaft speed; give --rpm")
    rpm = check_rpm(rec.rpm)
    x, fs, speed = rec.accel, rec.sample_rate, rec.shaft_speed
    if resample_to is not None:
        if not (np.isfinite(resample_to) and resample_to > 0):
            raise BagError(f"resample rate must be positive, got {resample_to:g} Hz")
        from .resampling import resample  # scipy.signal: only when resampling (not for bearing-bag --help)

        x, fs_in, fs = resample(x, fs, resample_to), fs, float(resample_to)
        if speed is not None:
            speed = np.interp(np.arange(x.size) / fs, np.arange(speed.size) / fs_in, speed)
    if max_duration is not None:
        if not (np.isfinite(max_duration) and max_duration > 0):
            raise BagError(f"duration must be positive, got {max_duration:g} s")
        x = x[: max(1, int(round(max_duration * fs)))]
    count = write_signal_bag(out, x, fs, rpm, source=rec.source, chunk_duration=chunk_duration,
                             start_time=start_time, storage=storage, namespace=namespace, bearing=bearing,
                             shaft_speed=None if speed is None else speed[:x.size])
    return Conversion(str(out), count, int(x.size), fs, rpm, x.size / fs)


def write_signal_bag(out, samples, sample_rate: float, rpm: float, source: str, speed_source: str = "",
                     chunk_duration: float = DEFAULT_CHUNK_DURATION, start_time: float = 0.0,
                     storage: str = "mcap", namespace: str = "", frame_id: str = "drive_end",
                     bearing: str = "", shaft_speed=None) -> int:
    """Write a uniformly sampled acceleration signal (m/s²) as the graph's topics; return the chunk count.

    ``vibration/drive_end``: VibrationChunk of ``chunk_duration`` s (the last may be
    shorter), consecutive ``first_sample_index``, stamp = ``start_time`` + index /
    ``sample_rate``; ``shaft_speed``: one ShaftSpeed (rad/s) per chunk, same stamp: ``rpm``,
    or the value of ``shaft_speed`` (rad/s per sample) at the chunk's first sample.
    Log time = stamp.
    """
    return write_signals_bag(out, {namespace: samples}, sample_rate, rpm, source, speed_source, chunk_duration,
                             start_time, storage, frame_id, bearing, bag_namespace=namespace,
                             shaft_speeds=None if shaft_speed is None else {namespace: shaft_speed})


def write_signals_bag(out, signals: dict, sample_rate: float, rpm: float, source: str, speed_source: str = "",
                      chunk_duration: float = DEFAULT_CHUNK_DURATION, start_time: float = 0.0,
                      storage: str = "mcap", frame_id: str = "drive_end", bearing: str = "",
                      bag_namespace: str = "", shaft_speeds: dict | None = None) -> int:
    """:func:`write_signal_bag` for several motors in one bag: ``signals`` maps a namespace to its
    acceleration (m/s², all at ``sample_rate`` Hz and ``rpm``, or at the speed per sample
    ``shaft_speeds[namespace]`` in rad/s where given); chunks of equal stamps follow each
    other in namespace order. ``bag_namespace`` is stored as the recorded namespace. Returns the
    chunk count of the longest signal.
    """
    if not (np.isfinite(chunk_duration) and chunk_duration > 0):
        raise BagError(f"chunk duration must be positive, got {chunk_duration:g} s")
    if not (np.isfinite(start_time) and start_time >= 0):
        raise BagError(f"start time must be >= 0 s, got {start_time:g}")
    if not (np.isfinite(rpm) and rpm > 0):
        raise BagError(f"shaft speed must be positive, got {rpm:g} rpm")
    xs = {ns: np.asarray(x, dtype=np.float64) for ns, x in signals.items()}
    fs = float(sample_rate)
    n_chunk = max(1, int(round(chunk_duration * fs)))
    omega = float(rpm) * 2.0 * np.pi / 60.0
    vib_type, spd_type = topics.VIBRATION.msgtype, topics.SHAFT_SPEED.msgtype
    count = 0
    with BagWriter(out, storage, bag_namespace, bearing) as bag:
        ts = bag.typestore
        Header, Chunk, Speed = (ts.types["std_msgs/msg/Header"], ts.types[vib_type], ts.types[spd_type])
        names = {}
        for ns in xs:
            bag.add_graph_topic(topics.VIBRATION, ns)
            bag.add_graph_topic(topics.SHAFT_SPEED, ns)
            names[ns] = topics.qualified(ns, topics.VIBRATION), topics.qualified(ns, topics.SHAFT_SPEED)
        for i0 in range(0, max(x.size for x in xs.values()), n_chunk):
            stamp = time_msg(ts, start_time + i0 / fs)
            log_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
            for ns, x in xs.items():
                if i0 >= x.size:
                    continue
                vib, spd = names[ns]
                chunk = Chunk(header=Header(stamp=stamp, frame_id=frame_id), sample_rate=fs,
                              first_sample_index=i0, source=source,
                              samples=np.ascontiguousarray(x[i0:i0 + n_chunk]))
                bag.write(vib, log_ns, bag.serialize(chunk, vib_type))
                w = omega if not shaft_speeds or ns not in shaft_speeds else float(shaft_speeds[ns][i0])
                speed = Speed(header=Header(stamp=stamp, frame_id=""), angular_velocity=w,
                              source=speed_source or source)
                bag.write(spd, log_ns, bag.serialize(speed, spd_type))
            count += 1
    return count
