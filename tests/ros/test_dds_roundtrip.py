"""A bearing_msgs message published by one process arrives intact in another, over DDS."""

import os
import sys

import pytest
from publish_probe import known_chunk
from ros_harness import REPO_ROOT

from bearing_common import topics

pytestmark = pytest.mark.ros


def test_vibration_chunk_crosses_processes_intact(ros_graph):
    received = ros_graph.subscribe(topics.VIBRATION)
    probe = REPO_ROOT / "tests" / "ros" / "publish_probe.py"
    ros_graph.start("", "", name="publish_probe", argv=[sys.executable, str(probe)])
    ros_graph.wait_until(lambda: len(received) >= 3, timeout=30.0, what="3 VibrationChunk messages")
    expected = known_chunk()
    got = received[0]
    assert got.header.stamp.sec == 12 and got.header.stamp.nanosec == 345_000_000
    assert got.header.frame_id == "drive_end"
    assert got.sample_rate == 48000.0
    assert got.first_sample_index == 480
    assert got.source == "probe"
    assert list(got.samples) == list(expected.samples)


def test_stop_leaves_no_process_behind(ros_graph):
    received = ros_graph.subscribe(topics.VIBRATION)
    probe = REPO_ROOT / "tests" / "ros" / "publish_probe.py"
    member = ros_graph.start("", "", name="publish_probe", argv=[sys.executable, str(probe)])
    ros_graph.wait_until(lambda: len(received) >= 1, timeout=30.0, what="the probe publishing")
    codes = ros_graph.processes.stop()
    assert codes["publish_probe"] == 0, ros_graph.output()  # clean exit on SIGINT
    with pytest.raises(ProcessLookupError):
        os.killpg(member.process.pid, 0)  # its whole process group is gone
