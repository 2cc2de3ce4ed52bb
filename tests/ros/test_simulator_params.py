"""Live parameters of the simulator node through its parameter services, as ``ros2 param set`` uses them.

Read-only and invalid values are refused with the reason; ``rpm``, ``noise_density`` and
``realtime`` take effect at the next chunk, on a gap-free stream.
"""

import math
import time

import numpy as np
import pytest
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.parameter import Parameter, parameter_value_to_python

from bearing_common import topics

pytestmark = pytest.mark.ros

FS = 48000.0


def call(ros_graph, srv_type, service: str, request):
    client = ros_graph.node.create_client(srv_type, service)
    try:
        ros_graph.wait_until(client.service_is_ready, 30.0, f"the {service} service")
        future = client.call_async(request)
        ros_graph.wait_until(future.done, 10.0, f"the {service} response")
        return future.result()
    finally:
        ros_graph.node.destroy_client(client)


def set_parameter(ros_graph, name: str, value):
    """One ``ros2 param set /simulator NAME VALUE``: (successful, reason)."""
    request = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
    (result,) = call(ros_graph, SetParameters, "/simulator/set_parameters", request).results
    return result.successful, result.reason


def get_parameter(ros_graph, name: str):
    response = call(ros_graph, GetParameters, "/simulator/get_parameters", GetParameters.Request(names=[name]))
    return parameter_value_to_python(response.values[0])


def noise_level(chunk) -> float:
    """RMS of the first difference (m/s²): the noise-free signal is smooth at 48 kHz."""
    return float(np.std(np.diff(chunk.samples)))


def test_live_parameters(ros_graph):
    vib = ros_graph.subscribe(topics.VIBRATION)
    speed = ros_graph.subscribe(topics.SHAFT_SPEED)
    sim = ros_graph.start("bearing_sim", "simulator", params={
        "scenario": "", "wait_for_subscribers": f"{topics.VIBRATION.name}:1"})
    ros_graph.wait_until(lambda: len(vib) >= 10, 60.0, "the first chunks")

    # refused, with the reason, and nothing changes
    for name, value, reason in [
        ("sample_rate", 12000.0, "read-only"),
        ("scenario", "or", "read-only"),
        ("rpm", -5.0, "rpm: must be in (0, 6000]"),
        ("rpm", 7000.0, "rpm: must be in (0, 6000]"),
        ("rpm", 1500, "Wrong parameter type"),
        ("noise_density", -1.0, "noise_density: must be a finite number >= 0"),
        ("noise_density", math.inf, "noise_density: must be a finite number >= 0"),
    ]:
        ok, why = set_parameter(ros_graph, name, value)
        assert not ok and reason in why, (name, value, why)
    assert get_parameter(ros_graph, "rpm") == 1800.0 and get_parameter(ros_graph, "sample_rate") == FS

    # rpm: shaft_speed reports the new speed from the next chunk on; the stream stays gap-free
    assert set_parameter(ros_graph, "rpm", 1500.0) == (True, "")
    new_omega = 1500.0 * 2.0 * math.pi / 60.0
    ros_graph.wait_until(lambda: speed and speed[-1].angular_velocity == pytest.approx(new_omega), 10.0,
                         "shaft_speed at 1500 rpm")
    assert get_parameter(ros_graph, "rpm") == 1500.0
    omegas = [m.angular_velocity for m in speed]
    first_new = next(i for i, w in enumerate(omegas) if w == pytest.approx(new_omega))
    assert all(w == pytest.approx(1800.0 * math.pi / 30.0) for w in omegas[:first_new])
    assert all(w == pytest.approx(new_omega) for w in omegas[first_new:])

    # noise_density: from the next chunk on
    quiet = max(noise_level(m) for m in vib[-5:])
    assert set_parameter(ros_graph, "noise_density", 4.5e-3) == (True, "")
    n0 = len(vib)
    ros_graph.wait_until(lambda: len(vib) >= n0 + 3, 10.0, "chunks after the noise change")
    assert noise_level(vib[-1]) > 100 * quiet  # 4.5e-3 * sqrt(24 kHz) = 0.7 m/s² RMS, white

    # realtime: off publishes faster than real time, on again returns to real time without a burst
    assert set_parameter(ros_graph, "realtime", False) == (True, "")
    n0, t0 = len(vib), time.monotonic()
    ros_graph.wait_until(lambda: time.monotonic() - t0 >= 2.0, 5.0, "2 s as fast as possible")
    fast = (len(vib) - n0) * 0.01 / (time.monotonic() - t0)
    assert set_parameter(ros_graph, "realtime", True) == (True, "")
    n0, t0 = len(vib), time.monotonic()
    ros_graph.wait_until(lambda: time.monotonic() - t0 >= 2.0, 5.0, "2 s in real time")
    paced = (len(vib) - n0) * 0.01 / (time.monotonic() - t0)
    assert fast > 1.3 and paced < 1.15, (fast, paced)

    index = [m.first_sample_index for m in vib]
    assert index == list(range(0, 480 * len(vib), 480)), "gap or restart of the stream"
    assert all(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 == pytest.approx(i / FS, abs=1e-9)
               for m, i in zip(vib, index))
    assert sim.returncode is None, ros_graph.output()
