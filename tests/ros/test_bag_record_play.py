"""bearing-bag record / play through real DDS (separate processes, isolated domain)."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time

import numpy as np
import pytest
from graph_helpers import BAG_CLI
from publish_probe import known_chunk
from ros_harness import REPO_ROOT

from bearing_common import topics
from bearing_msgs.msg import FaultState
from bearing_recordings.bag_read import read_bag
from bearing_recordings.bag_write import BagWriter

pytestmark = pytest.mark.ros


def stop_member(member, signals, timeout=15.0) -> int:
    """Send ``signals`` (10 ms apart) to a member's process group and wait for it to exit."""
    for i, sig in enumerate(signals):
        if i:
            time.sleep(0.01)
        os.killpg(member.process.pid, sig)
    return member.process.wait(timeout=timeout)


@pytest.mark.parametrize("signals", [(signal.SIGINT,), (signal.SIGTERM,), (signal.SIGINT, signal.SIGINT)],
                         ids=["SIGINT", "SIGTERM", "SIGINT-twice"])
def test_record_a_publisher_and_stop_by_signal(ros_graph, tmp_path, signals):
    """A recording stopped by Ctrl-C / SIGTERM (or a terminal's Ctrl-C under ros2 launch: SIGINT
    twice) is a complete bag with the messages intact, including a transient-local fault_state
    published before the recorder started."""
    latched = FaultState()
    latched.header.stamp.sec = 7
    latched.state = FaultState.INNER_RACE
    latched.onset.sec = 6
    latched.hypotheses, latched.scores = ["inner_race"], [3.5]
    latched_pub = ros_graph.publisher(topics.FAULT_STATE, depth=10)  # kept alive: it holds the sample
    latched_pub.publish(latched)

    seen = ros_graph.subscribe(topics.VIBRATION)
    probe = REPO_ROOT / "tests" / "ros" / "publish_probe.py"
    ros_graph.start("", "", name="publish_probe", argv=[sys.executable, str(probe)])
    ros_graph.wait_until(lambda: len(seen) >= 2, timeout=30.0, what="the probe publishing")

    bag = tmp_path / "rec"
    t_start = time.time_ns()
    recorder = ros_graph.start("", "", name="bag_record", argv=BAG_CLI + ["record", "--out", str(bag)])
    for topic in (topics.qualified("", topics.VIBRATION), topics.qualified("", topics.FAULT_STATE)):
        ros_graph.wait_until(lambda t=topic: any(f"first message on {t}" in line for line in recorder.lines),
                             timeout=30.0, what=f"the recorder to receive {topic}")
    n0 = len(seen)
    ros_graph.wait_until(lambda: len(seen) >= n0 + 20, timeout=30.0, what="20 more probe messages (1 s)")
    assert stop_member(recorder, signals) == 0, ros_graph.output()
    assert "Traceback" not in "\n".join(recorder.lines), ros_graph.output()
    t_end = time.time_ns()
    assert any(signals[0].name in line for line in recorder.lines), recorder.lines

    contents = read_bag(bag)
    assert len(contents.chunks) >= 10, ros_graph.output()
    want = known_chunk()
    for c in contents.chunks:
        assert c.stamp == pytest.approx(12.345, abs=1e-12)  # header stamp kept, not the receive time
        assert c.frame_id == "drive_end" and c.source == "probe" and c.first_sample_index == 480
        assert list(c.samples) == list(want.samples)
    log_ns = [round(c.log_time * 1e9) for c in contents.chunks]
    assert log_ns == sorted(log_ns)
    assert t_start - 10**9 <= log_ns[0] and log_ns[-1] <= t_end + 10**9  # log time = receive time
    (state,) = contents.fault_states
    assert state.state == FaultState.INNER_RACE and state.stamp == 7.0 and state.scores == {"inner_race": 3.5}


#: s of recording: the publisher sees the recorder matched before the recorder's reader may know the
#: publisher (DDS discovery on this machine: up to 3.1 s); 3 s once recorded nothing on a cold start
DURATION_S = 8.0


def test_record_duration_and_namespace(ros_graph, tmp_path):
    pub = ros_graph.publisher(topics.VIBRATION, namespace="rig_a", depth=50)
    bag = tmp_path / "ns"
    recorder = ros_graph.start("", "", name="bag_record", argv=BAG_CLI + [
        "record", "--namespace", "rig_a", "--topics", topics.VIBRATION.name, "--duration", str(DURATION_S),
        "--storage", "sqlite3", "--out", str(bag)])
    ros_graph.wait_until(lambda: pub.get_subscription_count() >= 1, timeout=30.0,
                         what="the recorder to subscribe")
    msg = known_chunk()
    while recorder.returncode is None:
        pub.publish(msg)
        msg.first_sample_index += 5
        time.sleep(0.05)
    assert recorder.returncode == 0, ros_graph.output()
    contents = read_bag(bag)
    assert contents.storage == "sqlite3" and contents.namespace == "rig_a"
    assert len(contents.chunks) >= 5
    idx = [c.first_sample_index for c in contents.chunks]
    assert idx == sorted(idx) and np.all(np.diff(idx) % 5 == 0)


def write_play_bag(path, n=21, dt=0.05):
    """Synthetic bag: n chunks every dt s of log time (stamps 5 s later) + a latched fault_state."""
    with BagWriter(path) as bag:
        store = bag.typestore
        T = store.types
        vib, state_topic = bag.add_graph_topic(topics.VIBRATION).topic, bag.add_graph_topic(topics.FAULT_STATE).topic
        t0 = 1_000_000_000_000
        for k in range(n):
            t = t0 + round(k * dt * 1e9)
            sec, nsec = divmod(t + 5 * 10**9, 10**9)
            msg = T["bearing_msgs/msg/VibrationChunk"](
                header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec),
                                                frame_id="drive_end"),
                sample_rate=1000.0, first_sample_index=50 * k, source="simulator",
                samples=np.full(50, float(k)))
            bag.write(vib, t, bag.serialize(msg, topics.VIBRATION.msgtype))
        state = T["bearing_msgs/msg/FaultState"](
            header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id=""),
            state=1, confidence=0.9, onset=T["builtin_interfaces/msg/Time"](sec=0, nanosec=500), hypotheses=[],
            scores=np.zeros(0), model_set="sim_48k", detail="")
        bag.write(state_topic, t0 + round((n - 1) * dt * 1e9), bag.serialize(state, topics.FAULT_STATE.msgtype))
    return t0, n, dt


def test_play_publishes_in_order_at_rate_with_clock(ros_graph, tmp_path):
    from rosgraph_msgs.msg import Clock

    t0, n, dt = write_play_bag(tmp_path / "play")
    chunks, clocks, lock = [], [], threading.Lock()

    def on_chunk(msg):
        with lock:
            stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
            chunks.append((time.monotonic(), msg.first_sample_index, stamp))

    def on_clock(msg):
        with lock:
            clocks.append((time.monotonic(), msg.clock.sec * 10**9 + msg.clock.nanosec))

    ros_graph.node.create_subscription(topics.message_class(topics.VIBRATION.msgtype), topics.VIBRATION.name,
                                       on_chunk, topics.qos(topics.VIBRATION, depth=1000))
    ros_graph.node.create_subscription(Clock, topics.CLOCK.name, on_clock, topics.qos(topics.CLOCK, depth=1000))
    states = ros_graph.subscribe(topics.FAULT_STATE)
    rate = 2.0
    player = ros_graph.start("", "", name="bag_play", argv=BAG_CLI + [
        "play", str(tmp_path / "play"), "--rate", str(rate), "--clock", "--wait-for-subscribers"])
    ros_graph.wait_until(lambda: len(chunks) >= n and len(states) >= 1, timeout=30.0,
                         what=f"{n} chunks and the fault_state (got {len(chunks)} and {len(states)})")
    ros_graph.wait_until(lambda: player.returncode is not None, timeout=15.0, what="the player to finish")
    assert player.returncode == 0, ros_graph.output()
    with lock:
        got, clk = list(chunks), list(clocks)
    assert [i for _t, i, _s in got] == [50 * k for k in range(n)]  # all, in order
    assert [s for _t, _i, s in got] == [t0 + 5 * 10**9 + round(k * dt * 1e9) for k in range(n)]  # stamps intact
    span = got[-1][0] - got[0][0]
    expected = (n - 1) * dt / rate  # 0.5 s
    assert expected * 0.8 < span < expected + 0.3, span
    assert states[0].state == 1 and states[0].confidence == 0.9
    # /clock: recording time, non-decreasing, covering the recording
    values = [v for _t, v in clk]
    last = t0 + round((n - 1) * dt * 1e9)
    assert len(values) >= 10 and values == sorted(values)
    assert t0 <= values[0] < t0 + 10**8 and values[-1] == last


def test_play_of_a_bad_bag_fails_with_one_line(ros_graph, tmp_path):
    (tmp_path / "nobag").mkdir()
    player = ros_graph.start("", "", name="bag_play", argv=BAG_CLI + ["play", str(tmp_path / "nobag")])
    ros_graph.wait_until(lambda: player.returncode is not None, timeout=30.0, what="the player to fail")
    assert player.returncode == 2
    errors = [line for line in player.lines if line.strip()]
    assert len(errors) == 1 and errors[0].startswith("bearing-bag: error:") and "no metadata.yaml" in errors[0]


def test_play_recuts_the_vibration_into_chunks_of_the_duration_asked(ros_graph, tmp_path):
    """--chunk-duration 0.12 s on 0.05 s chunks of 1 kHz: every sample arrives once, in chunks of
    120 samples (the last one shorter), each stamped with its first sample's time."""
    t0, n, dt = write_play_bag(tmp_path / "play")  # 21 chunks of 50 samples, sample values = chunk number
    chunks = ros_graph.subscribe(topics.VIBRATION, depth=1000)
    player = ros_graph.start("", "", name="bag_play", argv=BAG_CLI + [
        "play", str(tmp_path / "play"), "--rate", "4", "--chunk-duration", "0.12", "--topics", topics.VIBRATION.name,
        "--wait-for-subscribers"])
    ros_graph.wait_until(lambda: player.returncode is not None, timeout=90.0, what="the player to finish")
    assert player.returncode == 0, ros_graph.output()
    ros_graph.wait_until(lambda: sum(len(c.samples) for c in chunks) >= 50 * n, timeout=10.0, what="every sample")
    assert [len(c.samples) for c in chunks] == [120] * 8 + [90]
    assert [c.first_sample_index for c in chunks] == [120 * k for k in range(9)]
    stamp0 = t0 + 5 * 10**9  # stamp of sample 0; sample i at stamp0 + i ms
    assert [c.header.stamp.sec * 10**9 + c.header.stamp.nanosec for c in chunks] == \
        [stamp0 + 120 * k * 10**6 for k in range(9)]
    np.testing.assert_array_equal(np.concatenate([np.asarray(c.samples) for c in chunks]),
                                  np.repeat(np.arange(n, dtype=float), 50))


#: Residual.msg before its arrays became float32 (a bag recorded then embeds this definition).
RESIDUAL_FLOAT64 = """std_msgs/Header header
float64 sample_rate
uint64 first_sample_index
uint8 fault_hypothesis
string model_set
float64 fault_frequency
float64[] residual
float64[] estimate
float64[] impulse_train
"""


def test_play_reencodes_messages_recorded_with_an_older_definition(ros_graph, tmp_path):
    """A bag whose Residual messages carry float64 arrays (the recorded definition and type hash)
    plays as today's Residual: the same values in float32, every other field kept."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg(RESIDUAL_FLOAT64, topics.RESIDUAL_OUTER_RACE.msgtype))
    T = store.types
    values = np.array([0.1, -2.5, 1e-3, 123.456789])
    with Writer(tmp_path / "old", version=9) as writer:
        conn = writer.add_connection(topics.qualified("", topics.RESIDUAL_OUTER_RACE),
                                     topics.RESIDUAL_OUTER_RACE.msgtype, typestore=store)
        for k in range(3):
            msg = T[topics.RESIDUAL_OUTER_RACE.msgtype](
                header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=k, nanosec=7),
                                                frame_id="drive_end"),
                sample_rate=48000.0, first_sample_index=4 * k, fault_hypothesis=1, model_set="sim_48k",
                fault_frequency=107.5, residual=values + k, estimate=-values, impulse_train=np.zeros(4))
            writer.write(conn, 10**9 + k * 10**7, store.serialize_cdr(msg, topics.RESIDUAL_OUTER_RACE.msgtype))
    received = ros_graph.subscribe(topics.RESIDUAL_OUTER_RACE, depth=100)
    player = ros_graph.start("", "", name="bag_play", argv=BAG_CLI + ["play", str(tmp_path / "old"),
                                                                      "--wait-for-subscribers"])
    ros_graph.wait_until(lambda: player.returncode is not None, timeout=90.0, what="the player to finish")
    assert player.returncode == 0, ros_graph.output()
    ros_graph.wait_until(lambda: len(received) >= 3, timeout=10.0, what="3 residuals")
    for k, m in enumerate(received):
        assert (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id) == (k, 7, "drive_end")
        assert (m.first_sample_index, m.fault_hypothesis, m.model_set, m.fault_frequency) == (4 * k, 1, "sim_48k",
                                                                                              107.5)
        np.testing.assert_array_equal(np.asarray(m.residual), (values + k).astype(np.float32))
        np.testing.assert_array_equal(np.asarray(m.estimate), (-values).astype(np.float32))
        assert len(m.impulse_train) == 4
