"""The observer node through real DDS: residuals match the offline observer, bad chunks are rejected,
parameters are set as ``ros2 param set`` does."""

import numpy as np
import pytest
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter

from bearing_common import topics
from bearing_common.bearings import CATALOG
from bearing_common.states import parse_fault
from bearing_msgs.msg import VibrationChunk
from bearing_observer.model_sets import load_model_set
from bearing_observer.observer import FaultObserver

pytestmark = pytest.mark.ros

FS = 48000.0
N = 480


def chunk_msg(i, samples, fs=FS):
    msg = VibrationChunk(sample_rate=fs, first_sample_index=i * N, source="simulator")
    t = i * N / FS
    msg.header.stamp.sec = int(t)
    msg.header.stamp.nanosec = int(round((t - int(t)) * 1e9))
    msg.header.frame_id = "drive_end"
    msg.samples = [float(x) for x in samples]
    return msg


def synthetic_vibration(n_chunks):
    """Decaying 3 kHz bursts every BPFO period (1800 rpm) plus white noise, m/s^2."""
    rng = np.random.default_rng(1)
    t = np.arange(n_chunks * N) / FS
    phase = (t * 107.544) % 1.0 / 107.544
    return 50.0 * np.exp(-phase * 2000.0) * np.sin(2 * np.pi * 3000.0 * phase) + rng.normal(0, 0.3, t.size)


@pytest.mark.parametrize("fault_type, node_name", [("outer_race", "or_observer"), ("inner_race", "ir_observer")])
def test_residuals_match_offline_observer_and_bad_chunks_are_rejected(ros_graph, fault_type, node_name):
    received = ros_graph.subscribe(topics.residual_topic(parse_fault(fault_type)))
    pub = ros_graph.publisher(topics.VIBRATION)
    node = ros_graph.start("bearing_observer", "observer", params={"fault_type": fault_type})
    ros_graph.wait_until(lambda: pub.get_subscription_count() > 0, 30.0, "the observer to subscribe")
    y = synthetic_vibration(20)
    chunks = [y[i * N:(i + 1) * N] for i in range(20)]
    for i, c in enumerate(chunks):
        if i == 5:  # a NaN sample
            pub.publish(chunk_msg(i, np.where(np.arange(N) == 7, np.nan, c)))
        elif i == 9:  # a sample rate no model set has: no model, the measurement passes through
            pub.publish(chunk_msg(i, c, fs=12345.0))
        else:
            pub.publish(chunk_msg(i, c))
    ros_graph.wait_until(lambda: len(received) >= 19, 30.0, "19 residual chunks")
    assert node_name in ros_graph.node.get_node_names()  # default node name follows fault_type
    indices = [m.first_sample_index // N for m in received]
    assert indices == [i for i in range(20) if i != 5]
    assert [m.model_set for m in received] == ["none" if i == 9 else "sim_48k" for i in indices]
    for m in received:
        assert m.fault_hypothesis == (1 if fault_type == "outer_race" else 2)
        assert m.sample_rate == (12345.0 if m.model_set == "none" else FS)
        y = chunks[m.first_sample_index // N]
        r, e = np.asarray(m.residual), np.asarray(m.estimate)
        assert r.dtype == np.float32 and len(r) == N and np.all(np.isfinite(r))
        if m.model_set == "none":  # no model: the measurement itself in float32, no estimate, no train
            assert len(m.estimate) == len(m.impulse_train) == 0
            np.testing.assert_array_equal(r, y.astype(np.float32))
        else:  # residual + estimate reproduce the measurement to float32's rounding (2^-24 relative, each)
            assert len(m.estimate) == len(m.impulse_train) == N
            np.testing.assert_allclose(r.astype(float) + e, y, rtol=0, atol=2.0**-23 * np.max(np.abs(r) + np.abs(e)))
    # The first run of chunks (0-4) is what the offline observer computes, rounded to float32.
    offline = FaultObserver.from_model_set(received[0].model_set, fault_type, 1800.0, FS)
    out = offline.process(np.concatenate(chunks[:5]))
    live = np.concatenate([np.asarray(m.residual) for m in received[:5]])
    np.testing.assert_array_equal(live, out.residual.astype(np.float32))
    log = "\n".join(node.lines)
    assert "non-finite samples: 1 NaN/inf of 480" in log
    assert "model set none at 12345 Hz" in log


def set_parameters(ros_graph, node_name, **values):
    """``ros2 param set``: one SetParameters request to ``/<node_name>/set_parameters``; the results."""
    client = ros_graph.node.create_client(SetParameters, f"/{node_name}/set_parameters")
    ros_graph.wait_until(lambda: client.service_is_ready(), 30.0, f"/{node_name}/set_parameters")
    request = SetParameters.Request(parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()])
    future = client.call_async(request)
    ros_graph.wait_until(future.done, 10.0, "the set_parameters response")
    return future.result().results


def test_parameters_set_live_through_the_parameter_service(ros_graph):
    """Read-only fault_type refused with rclpy's reason, an unknown bearing refused with ours, and
    a valid bearing applied: the following residuals carry the new bearing's BPFO (no simulator
    set for a 6203: model set none)."""
    received = ros_graph.subscribe(topics.RESIDUAL_OUTER_RACE)
    pub = ros_graph.publisher(topics.VIBRATION)
    ros_graph.start("bearing_observer", "observer", params={"fault_type": "outer_race"})
    ros_graph.wait_until(lambda: pub.get_subscription_count() > 0, 30.0, "the observer to subscribe")
    [result] = set_parameters(ros_graph, "or_observer", fault_type="inner_race")
    assert not result.successful and result.reason == "Trying to set a read-only parameter: fault_type."
    [result] = set_parameters(ros_graph, "or_observer", bearing="nope")
    assert not result.successful and result.reason.startswith("bearing: unknown bearing 'nope': give a catalog name")
    y = synthetic_vibration(10)
    for i in range(5):
        pub.publish(chunk_msg(i, y[i * N:(i + 1) * N]))
    ros_graph.wait_until(lambda: len(received) >= 5, 30.0, "5 residual chunks")
    [result] = set_parameters(ros_graph, "or_observer", bearing="6203")
    assert result.successful, result.reason
    for i in range(5, 10):
        pub.publish(chunk_msg(i, y[i * N:(i + 1) * N]))
    ros_graph.wait_until(lambda: len(received) >= 10, 30.0, "10 residual chunks")
    sim_bpfo = load_model_set("sim_48k")["outer_race"].fault_order * 30.0
    assert [m.model_set for m in received] == ["sim_48k"] * 5 + ["none"] * 5
    assert [m.fault_frequency for m in received] == pytest.approx(
        [sim_bpfo] * 5 + [CATALOG["6203"].frequencies(1800.0).bpfo] * 5, rel=1e-12)
