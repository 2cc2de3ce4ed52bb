"""The live view over DDS and a WebSocket: the graph on a simulated outer-race fault, watched like Foxglove does.

Simulator (outer race at 1800 rpm) -> observers -> diagnoser on the spectral front end (model set
``none``: the decision that publishes ``envelope_spectrum``), and the ``live_view`` node. A plain
WebSocket client (:mod:`foxglove_client`) connects, sees the channels advertised with their schemas,
subscribes, and decodes what it receives: the fault state is OUTER_RACE, the spectrum's strongest
value lies on an outer-race line at the measured speed, ``/diagnostics`` decodes from its ros2msg
schema with an independent CDR decoder (mcap_ros2) and says OUTER_RACE, health and vibration blocks
arrive with consistent numbers.
"""

from __future__ import annotations

import json
import socket

import pytest
from foxglove_client import PROTOCOLS, FoxgloveClient
from graph_helpers import wait_spec
from mcap_ros2._dynamic import generate_dynamic

from bearing_common import topics
from bearing_common.bearings import CATALOG, DEFAULT_BEARING
from bearing_common.states import FaultState

pytestmark = pytest.mark.ros

RPM = 1800.0
SIGNAL_S = 6.0  # of outer-race fault: a health record per second, a spectrum per 0.17 s
MOTOR = "test_motor"
SERVED = (topics.FAULT_STATE, topics.TRUTH, topics.HEALTH, topics.ENVELOPE_SPECTRUM, topics.VIBRATION,
          topics.DIAGNOSTICS)
STATE, TRUTH, HEALTH, SPECTRUM, VIBRATION, DIAGNOSTICS = (topics.qualified("", t) for t in SERVED)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_websocket_client_sees_the_graph_of_an_outer_race_fault(ros_graph):
    port = free_port()
    ros_graph.start("bearing_live_view", "live_view", name="live_view", params={"port": port,
                                                                                "discovery_period": 0.5})
    for name, fault in (("or_observer", "outer_race"), ("ir_observer", "inner_race")):
        ros_graph.start("bearing_observer", "observer", name=name, params={"fault_type": fault, "model_set": "none"})
    ros_graph.start("bearing_diagnoser", "diagnoser", name="diagnoser", params={"model_set": "none", "motor": MOTOR})

    client = None
    ros_graph.wait_until(lambda: _listening(port), 60.0, "the live view's server")
    try:
        client = FoxgloveClient(port, on_timeout=ros_graph.output)
        assert client.protocol in PROTOCOLS
        expected = {topics.qualified("", t) for t in SERVED if t is not topics.TRUTH}  # no simulator yet
        client.wait_for(lambda: expected <= set(client.channels), 120.0, "the diagnoser's topics advertised")
        ros_graph.start("bearing_sim", "simulator", name="simulator", params={
            "schedule": f"outer_race:{SIGNAL_S}", "rpm": RPM, "realtime": True,
            "wait_for_subscribers": wait_spec({topics.VIBRATION: 2, topics.RESIDUAL_OUTER_RACE: 1,
                                               topics.RESIDUAL_INNER_RACE: 1})})
        client.wait_for(lambda: TRUTH in client.channels, 30.0, "sim/truth advertised")
        _check_channels(client.channels)
        client.subscribe([topics.qualified("", t) for t in SERVED])
        client.wait_for(lambda: _decided(client), 90.0, "OUTER_RACE, a spectrum after it, health, diagnostics")
    finally:
        if client is not None:
            client.close()
    _check_fault_states(client)
    _check_spectrum(client)
    _check_diagnostics(client)
    _check_health(client)
    _check_vibration(client)


def _listening(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
        return True
    except OSError:
        return False


def _decided(client) -> bool:
    states = client.json_messages(STATE)
    spectra = client.json_messages(SPECTRUM)
    return (any(s["state_name"] == "OUTER_RACE" for s in states) and len(spectra) >= 3
            and len(client.messages.get(HEALTH, [])) >= 2 and len(client.messages.get(DIAGNOSTICS, [])) >= 2
            and len(client.messages.get(VIBRATION, [])) >= 50)


def _check_channels(channels: dict) -> None:
    for topic in SERVED:
        channel = channels[topics.qualified("", topic)]
        if topic is topics.DIAGNOSTICS:
            assert (channel["encoding"], channel["schemaEncoding"]) == ("cdr", "ros2msg")
            assert channel["schemaName"] == topics.DIAGNOSTICS.msgtype
            assert channel["schema"].startswith("std_msgs/Header header\ndiagnostic_msgs/DiagnosticStatus[] status")
        else:
            assert (channel["encoding"], channel["schemaEncoding"]) == ("json", "jsonschema")
            assert "properties" in json.loads(channel["schema"])


def _check_fault_states(client) -> None:
    states = client.json_messages(STATE)
    assert states[-1]["state"] == int(FaultState.OUTER_RACE) and states[-1]["state_name"] == "OUTER_RACE", states[-1]
    last = states[-1]
    assert 0.0 <= last["confidence"] <= 1.0
    assert last["scores"]["outer_race"] >= 1.0  # significant
    assert last["model_set"] == "none"
    truth = client.json_messages(TRUTH)
    assert truth and truth[-1]["state_name"] == "OUTER_RACE"


def _check_spectrum(client) -> None:
    fr = RPM / 60.0
    bpfo = CATALOG[DEFAULT_BEARING].orders().bpfo * fr
    for spectrum in client.json_messages(SPECTRUM):
        freq, mag = spectrum["frequency"], spectrum["magnitude"]
        assert len(freq) == len(mag) <= 100
        assert spectrum["frequency_resolution"] == pytest.approx(spectrum["bins_per_value"] * spectrum["bin_width"])
        assert spectrum["told_shaft_rate"] == pytest.approx(fr, rel=1e-12)  # the simulator's shaft_speed
        assert spectrum["shaft_rate"] == pytest.approx(fr, rel=0.02)  # within the told tolerance
        lines = spectrum["lines"]["outer_race"]
        assert lines["told"][0] == pytest.approx(bpfo, rel=1e-9)
        assert lines["measured"][0] == pytest.approx(bpfo * spectrum["shaft_rate"] / fr, rel=1e-9)
        # the strongest value lies on a harmonic of the outer-race line at the measured speed, and the
        # value holding that line stands far above the noise median (1); "on": within half a value's
        # width (max-hold) plus one bin (a line's energy may peak in the bin next to it)
        tolerance = spectrum["frequency_resolution"] / 2 + spectrum["bin_width"]
        fundamental = lines["measured"][0]
        peak = freq[max(range(len(mag)), key=mag.__getitem__)]
        harmonic = max(1, round(peak / fundamental))
        assert abs(peak - harmonic * fundamental) <= tolerance, (peak, fundamental, tolerance)
        holding = min(range(len(freq)), key=lambda i: abs(freq[i] - fundamental))
        assert abs(freq[holding] - fundamental) <= spectrum["frequency_resolution"] / 2
        assert mag[holding] > 20.0, (freq[holding], mag[holding])


def _check_diagnostics(client) -> None:
    channel = client.channels[DIAGNOSTICS]
    decode = generate_dynamic(channel["schemaName"], channel["schema"])[channel["schemaName"]]
    arrays = [decode(payload) for _, payload in client.messages[DIAGNOSTICS]]
    ours = [s for a in arrays for s in a.status if s.hardware_id == MOTOR]
    assert ours and ours[-1].name == f"bearing_monitor/{MOTOR}/drive_end"
    assert "OUTER_RACE" in ours[-1].message and ours[-1].level == 2, ours[-1]  # ERROR: a fault
    assert {"state": "OUTER_RACE"}.items() <= {kv.key: kv.value for kv in ours[-1].values}.items()


def _check_health(client) -> None:
    health = client.json_messages(HEALTH)
    for h in health:
        assert h["duration"] == pytest.approx(1.0) and h["sample_rate"] == pytest.approx(48000.0)
        assert 0.0 < h["rms"] <= h["peak"] and h["crest_factor"] == pytest.approx(h["peak"] / h["rms"])
        assert h["state_name"] == "HEALTHY" and h["learning"] is True  # the baseline takes 10 min to learn
        assert set(h["level"]) == {"rms", "kurtosis", "envelope_rms", "velocity_rms"}


def _check_vibration(client) -> None:
    blocks = client.json_messages(VIBRATION)
    stamps = [b["header"]["stamp"]["sec"] + 1e-9 * b["header"]["stamp"]["nsec"] for b in blocks]
    for b in blocks:
        assert b["duration"] == pytest.approx(0.01) and b["min"] <= b["max"] and 0.0 <= b["rms"]
        assert b["rms"] <= max(abs(b["min"]), abs(b["max"]))
    steps = [round((b - a) / 0.01, 6) for a, b in zip(stamps, stamps[1:])]
    assert all(s >= 1 and s == int(s) for s in steps), steps  # block starts on the 0.01 s grid, in order
    times = [t for t, _ in client.messages[VIBRATION]]
    assert times == sorted(times)
