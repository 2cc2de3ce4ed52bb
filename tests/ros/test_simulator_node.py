"""The simulator node through real DDS: gap-free, correctly stamped chunks; truth; clean exit; bad parameters."""

import math

import numpy as np
import pytest

from bearing_common import topics
from bearing_msgs.msg import FaultState

pytestmark = pytest.mark.ros

FS = 48000.0


def stamp(msg):
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def test_publishes_gap_free_stamped_chunks_and_exits_at_the_end(ros_graph):
    vib = ros_graph.subscribe(topics.VIBRATION)
    unb = ros_graph.subscribe(topics.UNBALANCE)
    speed = ros_graph.subscribe(topics.SHAFT_SPEED)
    truth = ros_graph.subscribe(topics.TRUTH)
    sim = ros_graph.start("bearing_sim", "simulator", params={
        "schedule": "outer_race:0.05,normal:0.05", "realtime": False,
        "wait_for_subscribers": f"{topics.VIBRATION.name}:1"})
    ros_graph.wait_until(lambda: sim.returncode is not None, timeout=120.0, what="the simulator to exit")
    assert sim.returncode == 0, ros_graph.output()
    assert len(vib) == 10 and len(unb) == 10, f"{len(vib)} chunks\n{ros_graph.output()}"
    for i, msg in enumerate(vib):
        assert msg.first_sample_index == 480 * i
        assert len(msg.samples) == 480 and msg.sample_rate == FS
        assert stamp(msg) == pytest.approx(msg.first_sample_index / FS, abs=1e-9)
        assert msg.source == "simulator" and msg.header.frame_id == "drive_end"
        assert all(math.isfinite(x) for x in msg.samples)
    assert [stamp(m) for m in unb] == [stamp(m) for m in vib]
    assert speed and speed[0].angular_velocity == pytest.approx(1800 * 2 * math.pi / 60)
    assert [(m.state, round(stamp(m), 6)) for m in truth] == [(FaultState.OUTER_RACE, 0.0), (FaultState.NORMAL, 0.05)]


def test_a_speed_profile_goes_out_as_shaft_speed_and_tachometer_pulses(ros_graph):
    """rpm_profile 1500 -> 1800 rpm over 0.1 s: shaft_speed at speed_rate = 200 per second of signal with
    the speed at each stamp; one Tachometer message per chunk, gap-free, whose pulses mark whole turns."""
    from bearing_common.shaft_angle import SpeedProfile
    profile = SpeedProfile.parse("0:1500,0.1:1800")
    vib = ros_graph.subscribe(topics.VIBRATION)
    speed = ros_graph.subscribe(topics.SHAFT_SPEED)
    tacho = ros_graph.subscribe(topics.TACHOMETER)
    sim = ros_graph.start("bearing_sim", "simulator", params={
        "schedule": "normal:0.1", "realtime": False, "rpm_profile": "0:1500,0.1:1800", "speed_rate": 200.0,
        "tachometer": True, "tachometer_jitter": 0.0, "wait_for_subscribers": f"{topics.TACHOMETER.name}:1"})
    ros_graph.wait_until(lambda: sim.returncode is not None, timeout=120.0, what="the simulator to exit")
    assert sim.returncode == 0, ros_graph.output()
    assert len(vib) == 10 and len(tacho) == 10
    stamps = np.array([stamp(m) for m in speed])
    np.testing.assert_allclose(stamps, np.arange(20) * 0.005, atol=1e-9)
    np.testing.assert_allclose([m.angular_velocity for m in speed], profile.omega(stamps), rtol=1e-9)
    assert [m.first_pulse_index for m in tacho] == list(np.cumsum([0] + [len(m.pulse_offsets) for m in tacho[:-1]]))
    pulses = np.concatenate([stamp(m) + np.asarray(m.pulse_offsets) for m in tacho])
    np.testing.assert_allclose(profile.angle(pulses), 2 * np.pi * np.arange(pulses.size), atol=1e-6)
    assert all(m.duration == pytest.approx(0.01) and m.pulses_per_revolution == 1 for m in tacho)


def test_realtime_pacing_keeps_wall_clock(ros_graph):
    vib = ros_graph.subscribe(topics.VIBRATION)
    import time
    start = time.monotonic()
    sim = ros_graph.start("bearing_sim", "simulator", params={"scenario": "normal", "segment_duration": 0.5,
                                                              "wait_for_subscribers": f"{topics.VIBRATION.name}:1"})
    ros_graph.wait_until(lambda: sim.returncode is not None, timeout=120.0, what="the simulator to exit")
    assert sim.returncode == 0, ros_graph.output()
    assert len(vib) == 50
    assert time.monotonic() - start >= 0.5  # not faster than real time


@pytest.mark.parametrize("param, value, reason", [
    ("rpm", -100.0, "rpm: must be in (0, 6000]"),
    ("scenario", "bogus", "unknown scenario"),
    ("rpm", 1800, "wrong type"),
])
def test_invalid_parameters_are_refused_with_a_reason(ros_graph, param, value, reason):
    proc = ros_graph.start("bearing_sim", "simulator", params={param: value})
    ros_graph.wait_until(lambda: proc.returncode is not None, timeout=60.0, what="the simulator to refuse")
    proc.reader.join(timeout=2.0)
    assert proc.returncode == 2
    assert len(proc.lines) == 1 and proc.lines[0].startswith("simulator: ") and reason in proc.lines[0], proc.lines
