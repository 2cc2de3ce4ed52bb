"""Bags written by bearing-bag: independent decoding, CWRU conversion, reading back, bad bags.

No DDS here: messages are serialized with rclpy.serialization (no graph needed) or with the
rosbags type store; every bag written is checked with the independent ``mcap_ros2``
decoder (mcap-ros2-support) or with ``bearing_recordings.bag_read``.
"""

from __future__ import annotations

import json
import pathlib
import shutil

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from bearing_common import topics
from bearing_common.units import STANDARD_GRAVITY as G
from bearing_recordings import bag_cli
from bearing_recordings.bag_read import Chunk, StateSample, join_chunks, load_bag, read_bag, truth_per_sample
from bearing_recordings.bag_types import BagError, project_typestore
from bearing_recordings.bag_write import BagWriter, recording_to_bag, write_signals_bag
from bearing_recordings.load import load_recording
from bearing_recordings.mat_files import load_mat

RECORD_105 = "105_IR007_0hp_DE12k.mat"
VIB, SPEED, RES_IR, STATE = (topics.qualified("", t) for t in (topics.VIBRATION, topics.SHAFT_SPEED,
                                                                topics.RESIDUAL_INNER_RACE, topics.FAULT_STATE))


# ----------------------------------------------------------------------------------------
# helpers


def mat_to_bag(path, out, sample_rate, rpm=None, **kwargs):
    """``bearing-bag from-mat`` without the command line."""
    return recording_to_bag(load_mat(path, sample_rate, rpm), out, **kwargs)


def rclpy_messages():
    """One message of each bearing_msgs type with awkward values (rclpy classes)."""
    from bearing_msgs.msg import FaultState, Residual, ShaftSpeed, VibrationChunk
    chunk = VibrationChunk()
    chunk.header.stamp.sec, chunk.header.stamp.nanosec = 12, 345_000_000
    chunk.header.frame_id = "drive_end"
    chunk.sample_rate = 48000.0
    chunk.first_sample_index = 2**40 + 7
    chunk.source = "simulator"
    chunk.samples = [0.0, -1.5, 2.25, 1e-300, 3.0e4, -0.0]
    speed = ShaftSpeed()
    speed.header.stamp.sec = 3
    speed.angular_velocity = 188.49555921538757
    speed.source = "tachometer"
    res = Residual()
    res.header.stamp.sec, res.header.stamp.nanosec = 1, 5
    res.header.frame_id = "drive_end"
    res.sample_rate = 12000.0
    res.first_sample_index = 120
    res.fault_hypothesis = Residual.INNER_RACE
    res.model_set = "cwru_de_6205"
    res.fault_frequency = 162.1857
    res.residual = [1.0, -2.0, 3.5]
    res.estimate = [0.5, 0.25, -0.125]
    res.impulse_train = [0.0, 1.0, 0.0]
    state = FaultState()
    state.header.stamp.sec, state.header.stamp.nanosec = 0, 410_000_000
    state.state = FaultState.OUTER_RACE
    state.confidence = 0.875
    state.onset.sec, state.onset.nanosec = 0, 200_000_000
    state.hypotheses = ["outer_race", "inner_race"]
    state.scores = [7.5, 0.25]
    state.model_set = "sim_48k"
    state.detail = "ünïcode ok"
    return {VIB: chunk, SPEED: speed, RES_IR: res,
            STATE: state}


TYPES = {topics.qualified("", t): t.msgtype
         for t in (topics.VIBRATION, topics.SHAFT_SPEED, topics.RESIDUAL_INNER_RACE, topics.FAULT_STATE)}


def fields_of(msg):
    """Plain comparable values of a message from rclpy or mcap_ros2 (recursive)."""
    if isinstance(msg, (str, bytes, bool, int, float)):
        return msg
    if isinstance(msg, (list, tuple, np.ndarray)) or type(msg).__name__ == "array":
        return [fields_of(x) for x in (msg.tolist() if hasattr(msg, "tolist") else msg)]
    if hasattr(msg, "get_fields_and_field_types"):  # rclpy
        names = list(msg.get_fields_and_field_types())
    else:  # mcap_ros2: a SimpleNamespace subclass listing its fields in __slots__
        names = list(type(msg).__slots__)
    return {k: fields_of(getattr(msg, k)) for k in names}


def write_rclpy_bag(out: pathlib.Path, storage: str = "mcap"):
    from rclpy.serialization import serialize_message
    msgs = rclpy_messages()
    with BagWriter(out, storage) as bag:
        for i, (topic, msg) in enumerate(msgs.items()):
            bag.add_topic(topic, TYPES[topic], latched=topic == STATE, depth=50)
            bag.write(topic, 1_000_000_000 + i, serialize_message(msg))
    return msgs


def synthetic_chunks(n_chunks=5, n=4, rate=1000.0, t0=2.0, skip=(), dup=()):
    chunks = []
    for k in range(n_chunks):
        if k in skip:
            continue
        i0 = k * n
        chunks.append(Chunk(t0 + i0 / rate, i0, rate, "simulator", "drive_end", np.arange(i0, i0 + n, dtype=float),
                            float(k)))
        if k in dup:
            chunks.append(chunks[-1])
    return chunks


# ----------------------------------------------------------------------------------------
# independent decoding


def read_ros2_messages(path):
    """Every message of an MCAP file decoded by mcap_ros2, as objects with ``channel``,
    ``schema``, ``ros_msg`` and ``log_time_ns`` (mcap's reader, mcap_ros2's decoder)."""
    from types import SimpleNamespace

    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [SimpleNamespace(schema=schema, channel=channel, ros_msg=ros_msg, log_time_ns=message.log_time)
                for schema, channel, message, ros_msg in reader.iter_decoded_messages()]


def test_written_bag_decodes_with_mcap_ros2_field_for_field(tmp_path):
    bag = tmp_path / "bag"
    sent = write_rclpy_bag(bag)
    files = list(bag.glob("*.mcap"))
    assert len(files) == 1 and (bag / "metadata.yaml").is_file()
    got = {m.channel.topic: m for m in read_ros2_messages(str(files[0]))}
    assert set(got) == set(sent)
    for topic, msg in sent.items():
        decoded = got[topic]
        assert decoded.schema.name == TYPES[topic]
        assert decoded.schema.encoding == "ros2msg"
        text = decoded.schema.data.decode()
        assert "MSG: std_msgs/Header" in text and "MSG: builtin_interfaces/Time" in text
        assert fields_of(decoded.ros_msg) == fields_of(msg), topic
    assert got[VIB].log_time_ns == 1_000_000_000


def test_embedded_type_hashes_are_the_ones_ros_computes():
    import bearing_msgs
    store = project_typestore()
    checked = 0
    for up in pathlib.Path(bearing_msgs.__file__).resolve().parents:
        share = up / "share" / "bearing_msgs" / "msg"
        if share.is_dir():
            for js in share.glob("*.json"):
                data = json.loads(js.read_text())
                want = data["type_hashes"][0]["hash_string"]
                assert store.hash_rihs01(f"bearing_msgs/msg/{js.stem}") == want
                checked += 1
            break
    n_msgs = len(list((pathlib.Path(__file__).resolve().parents[2] / "msgs" / "msg").glob("*.msg")))
    assert checked == n_msgs, "bearing_msgs type description .json files not found in the installed share/"


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_bag_files_reads_back_what_was_written(tmp_path, storage):
    sent = write_rclpy_bag(tmp_path / "bag", storage)
    contents = read_bag(tmp_path / "bag")
    assert contents.storage == storage and contents.namespace == ""
    (chunk,) = contents.chunks
    want = sent[VIB]
    assert chunk.stamp == pytest.approx(12.345) and chunk.first_sample_index == 2**40 + 7
    assert chunk.sample_rate == 48000.0 and chunk.source == "simulator" and chunk.frame_id == "drive_end"
    assert_array_equal(chunk.samples, np.asarray(want.samples))
    (speed,) = contents.speeds
    assert speed.angular_velocity == 188.49555921538757 and speed.source == "tachometer"
    assert contents.rpm == pytest.approx(1800.0)
    (state,) = contents.fault_states
    assert state.state == 1 and state.confidence == 0.875 and state.onset == pytest.approx(0.2)
    assert state.scores == {"outer_race": 7.5, "inner_race": 0.25} and state.detail == "ünïcode ok"
    assert contents.truth == []


def test_namespaced_topics_are_found_and_ambiguity_is_an_error(tmp_path):
    from rclpy.serialization import serialize_message
    msg = rclpy_messages()[VIB]
    with BagWriter(tmp_path / "bag", namespace="m1") as bag:
        for ns in ("m1", "m2"):
            bag.add_graph_topic(topics.VIBRATION, ns)
            bag.write(topics.qualified(ns, topics.VIBRATION), 1, serialize_message(msg))
    with pytest.raises(BagError, match="several namespaces"):
        read_bag(tmp_path / "bag")
    assert read_bag(tmp_path / "bag", namespace="m2").namespace == "m2"
    assert len(read_bag(tmp_path / "bag", namespace="/m1").chunks) == 1


def test_one_bag_holds_several_motors_each_in_its_namespace(tmp_path):
    fs = 1000.0
    signals = {"motor_1": np.arange(25.0), "motor_2": -np.arange(12.0)}
    assert write_signals_bag(tmp_path / "bag", signals, fs, 1800.0, "simulator", chunk_duration=0.01) == 3
    for motor, x in signals.items():
        contents = read_bag(tmp_path / "bag", namespace=motor)
        assert [c.first_sample_index for c in contents.chunks] == list(range(0, x.size, 10))
        assert_array_equal(np.concatenate([c.samples for c in contents.chunks]), x)
        assert len(contents.speeds) == len(contents.chunks)


# ----------------------------------------------------------------------------------------
# joining chunks into a Recording


def test_join_chunks_fills_gaps_and_drops_duplicates():
    stream = join_chunks(list(reversed(synthetic_chunks(skip=(2,), dup=(1,)))))
    assert stream.start_time == 2.0 and stream.sample_rate == 1000.0 and stream.source == "simulator"
    assert stream.gaps == [(8, 4)] and stream.duplicates == 1
    expected = np.arange(20, dtype=float)
    expected[8:12] = 0.0
    assert_array_equal(stream.samples, expected)


def test_join_chunks_rejects_mixed_streams():
    chunks = synthetic_chunks()
    chunks[1].sample_rate = 2000.0
    with pytest.raises(BagError, match="different sample rates"):
        join_chunks(chunks)
    chunks = synthetic_chunks()
    chunks[3].source = "cwru"
    with pytest.raises(BagError, match="several sources"):
        join_chunks(chunks)
    with pytest.raises(BagError, match="no vibration chunks"):
        join_chunks([])


def test_truth_per_sample_follows_onsets():
    truth = [StateSample(0.0, 0, 1.0, 0.0, {}, "", "", 0.0), StateSample(0.3, 1, 1.0, 0.25, {}, "", "", 0.3)]
    per = truth_per_sample(truth, 0.0, 10, 20.0)  # samples at 0, 0.05, ..., 0.45
    assert_array_equal(per, [0, 0, 0, 0, 0, 1, 1, 1, 1, 1])
    assert truth_per_sample([], 0.0, 10, 20.0) is None


# ----------------------------------------------------------------------------------------
# CWRU .mat → bag


@pytest.fixture
def record_105(cwru_record):
    return cwru_record(RECORD_105)


def test_from_mat_chunks_units_and_speed(tmp_path, record_105):
    from scipy.io import loadmat
    raw_g = np.asarray(loadmat(record_105)["X105_DE_time"], dtype=float).ravel()
    out = tmp_path / "cwru"
    rc = bag_cli.main(["from-mat", str(record_105), "--channel", "X105_DE_time", "--sample-rate", "12000",
                       "--duration", "0.255", "--out", str(out)])
    assert rc == 0
    msgs = list(read_ros2_messages(str(next(out.glob("*.mcap")))))
    chunks = [m for m in msgs if m.channel.topic == VIB]
    speeds = [m for m in msgs if m.channel.topic == SPEED]
    # 0.255 s at 12 kHz = 3060 samples = 25 chunks of 120 + one of 60
    assert len(chunks) == 26 and len(speeds) == 26
    assert [len(m.ros_msg.samples) for m in chunks] == [120] * 25 + [60]
    for k, m in enumerate(chunks):
        c = m.ros_msg
        assert c.first_sample_index == 120 * k
        assert c.source == "cwru" and c.header.frame_id == "drive_end" and c.sample_rate == 12000.0
        t_ns = round(k * 0.01 * 1e9)
        assert c.header.stamp.sec * 10**9 + c.header.stamp.nanosec == t_ns
        assert m.log_time_ns == t_ns
        assert_allclose(c.samples, raw_g[120 * k:120 * k + len(c.samples)] * G, rtol=1e-15, atol=0)
    for m in speeds:
        assert m.ros_msg.angular_velocity == pytest.approx(1797 * 2 * np.pi / 60, rel=1e-12)
        assert m.ros_msg.source == "cwru"
    rec = load_bag(out)
    assert rec.source == "cwru" and rec.sample_rate == 12000.0 and rec.rpm == pytest.approx(1797.0)
    assert_allclose(rec.accel, raw_g[:3060] * G, rtol=1e-15)


def test_from_mat_rpm_start_time_and_sqlite3(tmp_path, record_105):
    out = tmp_path / "cwru"
    res = mat_to_bag(record_105, out, 12000.0, rpm=1750.0, chunk_duration=0.02, start_time=100.5,
                     storage="sqlite3", namespace="rig", max_duration=0.1)
    assert res.chunks == 5 and res.rpm == 1750.0
    contents = read_bag(out)
    assert contents.storage == "sqlite3" and contents.namespace == "rig"
    assert [c.stamp for c in contents.chunks] == pytest.approx([100.5, 100.52, 100.54, 100.56, 100.58])
    assert [c.first_sample_index for c in contents.chunks] == [0, 240, 480, 720, 960]
    assert contents.rpm == pytest.approx(1750.0)
    assert {s.source for s in contents.speeds} == {"cwru"}
    assert load_bag(out).start_time == pytest.approx(100.5)


def test_from_mat_errors(tmp_path, record_105, capsys):
    assert bag_cli.main(["from-mat", str(record_105), "--channel", "X999_DE_time", "--sample-rate", "12000",
                         "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no channel 'X999_DE_time'" in err[0]
    (tmp_path / "exists").mkdir()
    assert bag_cli.main(["from-mat", str(record_105), "--sample-rate", "12000", "--out", str(tmp_path / "exists")]) == 2
    assert "exists already" in capsys.readouterr().err


# ----------------------------------------------------------------------------------------
# truncated and foreign bags


def _one_error_line(capsys, argv) -> str:
    rc = bag_cli.main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2, err
    assert len(err) == 1, err
    assert err[0].startswith("bearing-bag: error: ")
    return err[0]


def test_bad_bags_give_one_error_line(tmp_path, capsys):
    write_rclpy_bag(tmp_path / "good")
    # not a bag at all
    (tmp_path / "file.txt").write_text("hello")
    assert "not a rosbag2 recording" in _one_error_line(capsys, ["info", str(tmp_path / "file.txt")])
    (tmp_path / "empty").mkdir()
    assert "no metadata.yaml" in _one_error_line(capsys, ["info", str(tmp_path / "empty")])
    assert "no such file" in _one_error_line(capsys, ["info", str(tmp_path / "missing")])
    # recorder killed before closing: storage file without metadata.yaml
    shutil.copytree(tmp_path / "good", tmp_path / "killed")
    (tmp_path / "killed" / "metadata.yaml").unlink()
    assert "truncated bag" in _one_error_line(capsys, ["info", str(tmp_path / "killed")])
    # foreign metadata.yaml
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign" / "metadata.yaml").write_text("name: something else\n")
    assert "not a readable rosbag2" in _one_error_line(capsys, ["info", str(tmp_path / "foreign")])
    # metadata fine, storage file cut short
    shutil.copytree(tmp_path / "good", tmp_path / "cut")
    mcap = next((tmp_path / "cut").glob("*.mcap"))
    mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    with pytest.raises(BagError):
        read_bag(tmp_path / "cut")
    # storage file replaced by garbage
    shutil.copytree(tmp_path / "good", tmp_path / "garbage")
    next((tmp_path / "garbage").glob("*.mcap")).write_bytes(b"\x00" * 1000)
    with pytest.raises(BagError):
        read_bag(tmp_path / "garbage")
    assert bag_cli.main(["info", str(tmp_path / "good")]) == 0
    out = capsys.readouterr().out
    assert VIB in out and "bearing_msgs/msg/VibrationChunk" in out and "mcap" in out


def test_wrong_types_and_missing_topics_are_reported(tmp_path):
    store = project_typestore()
    with BagWriter(tmp_path / "wrong") as bag:
        bag.add_topic(VIB, "std_msgs/msg/String")
        msg = store.types["std_msgs/msg/String"](data="not a chunk")
        bag.write(VIB, 1, bag.serialize(msg, "std_msgs/msg/String"))
    with pytest.raises(BagError, match="has type std_msgs/msg/String, expected bearing_msgs/msg/VibrationChunk"):
        read_bag(tmp_path / "wrong")
    with BagWriter(tmp_path / "other") as bag:
        bag.add_topic("/chatter", "std_msgs/msg/String")
        bag.write("/chatter", 1, bag.serialize(store.types["std_msgs/msg/String"](data="x"), "std_msgs/msg/String"))
    with pytest.raises(BagError, match=r"no vibration/drive_end topic in the bag \(it has /chatter"):
        read_bag(tmp_path / "other")


def test_bag_error_is_an_input_error_for_bearing_diagnose():
    from bearing_recordings.recording import InputError
    assert issubclass(BagError, InputError)


def test_bearing_diagnose_reads_a_bag(tmp_path, record_105, capsys):
    """``bearing-diagnose BAG_DIR`` on a CWRU bag (load_recording → bag_read.load_bag)."""
    mat_to_bag(record_105, tmp_path / "bag", 12000.0, max_duration=0.5)
    rec = load_recording(tmp_path / "bag")
    assert rec.source == "cwru" and rec.accel.size == 6000 and rec.rpm == pytest.approx(1797.0)
    from bearing_diagnoser.diagnose_cli import main as diagnose
    assert diagnose([str(tmp_path / "bag")]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines() if x.strip()]
    assert lines and lines[0]["model_set"] == "cwru_de_6205"
