"""The live view's parts without ROS: the JSON made of each message, the vibration blocks, the WebSocket
server (a real client connects), the shipped layouts and ``bearing-graph --foxglove``'s plan."""

from __future__ import annotations

import json
import math
import pathlib
import re

import numpy as np
import pytest
from foxglove_client import PROTOCOLS, FoxgloveClient

from bearing_bringup.graph import LIVE_VIEW
from bearing_bringup.graph_cli import build_parser, plan_run
from bearing_common import topics
from bearing_common.stamps import to_stamp
from bearing_live_view import channels
from bearing_live_view.layout import layouts
from bearing_live_view.server import LiveServer
from bearing_live_view.vibration_blocks import Block, BlockReducer
from bearing_msgs.msg import EnvelopeSpectrum, FaultLines, FaultState, FleetState, HealthIndicators, MotorState

REPO = pathlib.Path(__file__).resolve().parents[2]
FS = 48000.0


def strict(payload: bytes):
    """JSON as a browser parses it: NaN and Infinity are errors."""
    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")
    return json.loads(payload, parse_constant=refuse)


def fault_state(state=1) -> FaultState:
    msg = FaultState(state=state, confidence=0.75, model_set="none", detail="")
    msg.header.stamp, msg.onset = to_stamp(12.5), to_stamp(3.25)
    msg.hypotheses, msg.scores = ["outer_race", "inner_race", "speed_hz"], [4.5, float("nan"), 29.9]
    return msg


def test_a_fault_state_as_json_for_plots_and_state_transitions():
    view = strict(channels.encode(channels.fault_state_view(fault_state())))
    assert view["state"] == 1 and view["state_name"] == "OUTER_RACE" and view["confidence"] == 0.75
    assert view["header"]["stamp"] == {"sec": 12, "nsec": 500_000_000}
    assert view["onset"] == {"sec": 3, "nsec": 250_000_000}
    assert view["scores"] == {"outer_race": 4.5, "inner_race": None, "speed_hz": 29.9}  # NaN: null, JSON has none


def test_a_bad_message_is_refused_with_the_reason():
    with pytest.raises(ValueError, match="unknown fault state 9"):
        channels.fault_state_view(fault_state(state=9))
    bad = fault_state()
    bad.scores = [1.0]
    with pytest.raises(ValueError, match="3 names for 1 values"):
        channels.fault_state_view(bad)


def test_health_as_json_with_the_parallel_arrays_keyed_by_name():
    msg = HealthIndicators(duration=1.0, sample_rate=FS, rms=2.0, peak=8.0, crest_factor=4.0, kurtosis=3.1,
                           velocity_rms=1e-3, envelope_rms=0.5, iso_zone=2, iso_class="group2-rigid", state=1,
                           learning=False, moved="kurtosis", score=1.2, slope=0.05)
    msg.trended, msg.level = ["rms", "kurtosis"], [1.1, float("nan")]
    msg.hypotheses, msg.evidence, msg.evidence_accumulated = ["outer_race"], [2.0], [float("nan")]
    msg.untested, msg.untested_why = ["ball"], ["too short"]
    view = strict(channels.encode(channels.health_view(msg)))
    assert (view["rms"], view["kurtosis"], view["iso_zone"], view["iso_zone_name"]) == (2.0, 3.1, 2, "B")
    assert (view["state"], view["state_name"], view["learning"]) == (1, "WARNING", False)
    assert view["level"] == {"rms": 1.1, "kurtosis": None}
    assert view["evidence"] == {"outer_race": 2.0} and view["evidence_accumulated"] == {"outer_race": None}
    assert view["untested"] == {"ball": "too short"}
    msg.iso_zone = 7
    with pytest.raises(ValueError, match="unknown ISO zone 7"):
        channels.health_view(msg)


def spectrum_message() -> EnvelopeSpectrum:
    msg = EnvelopeSpectrum(window_duration=0.336, bin_width=2.976, bins_per_value=2, frequency_resolution=5.952,
                           band_low=2000.0, band_high=6000.0, told_shaft_rate=float("nan"), shaft_rate=30.1,
                           shaft_rate_source="estimated")
    msg.frequency, msg.magnitude = [7.4, 13.4, 19.3], [1.0, 250.0, 2.0]
    msg.lines = [FaultLines(hypothesis="outer_race", told=[], measured=[107.9, 215.8], carrier=[True, True], rho=0.99)]
    return msg


def test_a_spectrum_as_json_with_markers_the_plot_panel_draws():
    view = strict(channels.encode(channels.spectrum_view(spectrum_message())))
    assert view["frequency"] == pytest.approx([7.4, 13.4, 19.3]) and view["magnitude"] == [1.0, 250.0, 2.0]
    assert view["told_shaft_rate"] is None and view["shaft_rate_source"] == "estimated"
    lines = view["lines"]["outer_race"]
    assert lines["measured"] == pytest.approx([107.9, 215.8]) and lines["told"] == [] and lines["told_level"] == []
    assert lines["measured_level"] == [channels.MARKER_LEVELS["measured"] * 250.0] * 2  # a row above the spectrum
    bad = spectrum_message()
    bad.magnitude = [1.0]
    with pytest.raises(ValueError, match="3 frequencies for 1 values"):
        channels.spectrum_view(bad)


def test_the_fleet_as_json_one_entry_per_motor():
    msg = FleetState(motors=[MotorState(motor="m1", state=2, confidence=0.5, age=1.5, stale=True)])
    (motor,) = strict(channels.encode(channels.fleet_view(msg)))["motors"]
    assert (motor["motor"], motor["state_name"], motor["age"], motor["stale"]) == ("m1", "INNER_RACE", 1.5, True)


@pytest.mark.parametrize("kind, message", [
    (channels.FAULT_STATE, fault_state), (channels.SPECTRUM, spectrum_message),
    (channels.HEALTH, HealthIndicators), (channels.FLEET, FleetState)])
def test_every_json_field_is_in_the_schema_foxglove_completes_paths_from(kind, message):
    view = channels.VIEWS[kind](message())
    assert set(view) == set(kind.json_schema["properties"])
    block = channels.block_view(Block(1.0, 0.01, -1.0, 1.0, 0.5), "drive_end")
    assert set(block) == set(channels.VIBRATION.json_schema["properties"])


def test_the_served_types_subscribe_with_the_contract_qos():
    for msgtype in channels.KINDS:
        assert channels.qos_topic(msgtype).msgtype == msgtype
    assert channels.qos_topic(topics.FAULT_STATE.msgtype).latched  # a client's subscription gets the current state


# -- vibration blocks -----------------------------------------------------------------------------------
def signal(n=9600, seed=0):
    return np.random.default_rng(seed).standard_normal(n)


@pytest.mark.parametrize("chunk", [480, 333, 4800, 1, 9600])
def test_blocks_do_not_depend_on_the_chunking(chunk):
    x = signal()
    whole = BlockReducer("v", 0.01).push(5.0, 0, FS, x)
    parts = []
    reducer = BlockReducer("v", 0.01)
    for i in range(0, x.size, chunk):
        parts += reducer.push(5.0 + i / FS, i, FS, x[i:i + chunk])
    assert len(parts) == len(whole) == 20
    for a, b in zip(parts, whole):
        assert (a.min, a.max, a.duration) == (b.min, b.max, b.duration)
        assert a.stamp == pytest.approx(b.stamp, abs=1e-12) and a.rms == pytest.approx(b.rms, rel=1e-12)


def test_a_block_holds_its_samples_min_max_and_rms():
    x = np.tile([1.0, -1.0, 3.0, -3.0], 120)  # one 480-sample block: rms = sqrt((1 + 1 + 9 + 9) / 4)
    (block,) = BlockReducer("v", 0.01).push(2.0, 0, FS, x)
    assert block == Block(2.0, 0.01, -3.0, 3.0, math.sqrt(5.0))


def test_blocks_follow_the_sample_grid_and_a_gap_drops_the_block_it_breaks():
    reducer = BlockReducer("v", 0.01)
    x = signal()
    first = reducer.push(0.0, 100, FS, x[:1000])  # starts mid-block: the first whole block begins at 480
    assert [round(b.stamp * FS) for b in first] == [380]  # index 480, 380 samples after the chunk's stamp
    after_gap = reducer.push(3000 / FS, 3000, FS, x[:2000])  # index 1100-2999 never came
    assert [round(b.stamp * FS) for b in after_gap] == [3360, 3840, 4320]  # blocks 7-9: 2880-3359 was cut
    assert reducer.stream.counts["gaps"] == 1


def test_a_refused_chunk_says_why_and_is_counted():
    reducer = BlockReducer("accelerometer", 0.01)
    with pytest.raises(ValueError, match="accelerometer: non-finite"):
        reducer.push(0.0, 0, FS, np.array([1.0, np.nan]))
    assert reducer.stream.counts["rejected"] == 1
    with pytest.raises(ValueError, match="block_s must be > 0"):
        BlockReducer("v", 0.0)


# -- the WebSocket server, with a real client -----------------------------------------------------------
def test_a_client_sees_the_channels_subscribes_and_decodes():
    server = LiveServer("127.0.0.1", 0, "test", lambda msgtype: f"# {msgtype}\nint32 x")
    client = None
    try:
        server.advertise("/m1/fault_state", channels.FAULT_STATE)
        server.advertise(topics.DIAGNOSTICS.name, channels.DIAGNOSTICS)
        client = FoxgloveClient(server.port)
        assert client.protocol in PROTOCOLS
        client.wait_for(lambda: len(client.channels) == 2, 10.0, "two channels")
        state, diag = client.channels["/m1/fault_state"], client.channels[topics.DIAGNOSTICS.name]
        assert (state["encoding"], state["schemaEncoding"], state["schemaName"]) == (
            "json", "jsonschema", "bearing_live_view.FaultState")
        assert json.loads(state["schema"]) == channels.FAULT_STATE.json_schema
        assert (diag["encoding"], diag["schemaEncoding"], diag["schema"]) == (
            "cdr", "ros2msg", f"# {topics.DIAGNOSTICS.msgtype}\nint32 x")
        assert not server.watched("/m1/fault_state")  # nobody subscribed yet: the node takes no ROS topic
        client.subscribe(["/m1/fault_state"])
        client.wait_for(lambda: server.watched("/m1/fault_state"), 10.0, "the subscription to reach the server")
        assert not server.watched(topics.DIAGNOSTICS.name)
        server.send("/m1/fault_state", channels.encode(channels.fault_state_view(fault_state())), 123_456)
        client.wait_for(lambda: client.messages.get("/m1/fault_state"), 10.0, "the message")
        ((log_time, _),) = client.messages["/m1/fault_state"]
        assert log_time == 123_456
        assert client.json_messages("/m1/fault_state")[0]["state_name"] == "OUTER_RACE"
    finally:
        if client is not None:
            client.close()
        server.close()


def test_a_port_in_use_is_refused():
    first = LiveServer("127.0.0.1", 0, "first", str)
    try:
        with pytest.raises(RuntimeError, match="Address already in use"):
            LiveServer("127.0.0.1", first.port, "second", str)
    finally:
        first.close()


# -- layouts and bearing-graph --------------------------------------------------------------------------
def test_the_shipped_layouts_are_the_generated_ones():
    """Regenerate with ``python -m bearing_live_view.layout --out src/bearing_bringup/config``."""
    for name, text in layouts().items():
        assert (REPO / "src" / "bearing_bringup" / "config" / name).read_text() == text, name


def test_the_layouts_name_only_channels_the_live_view_serves():
    served = {topics.qualified("", t) for t in (*topics.GRAPH_TOPICS.values(), topics.FLEET_STATE)
              if t.msgtype in channels.KINDS}
    for name, text in layouts().items():
        layout = json.loads(text)
        assert layout["version"] == 1
        named = set(re.findall(r'"(/[\w/]+?)[.\[]', text)) | set(re.findall(r'"topicToRender": "(/[\w/]+)"', text))
        assert named and named <= served, (name, named - served)


def test_bearing_graph_foxglove_adds_one_live_view():
    args = build_parser().parse_args(["--foxglove", "--namespace", "motor_7"])
    live = [p for p in plan_run(args).procs if p.executable == LIVE_VIEW.executable]
    assert [(p.package, p.node_name, p.namespace) for p in live] == [(LIVE_VIEW.package, "live_view", "motor_7")]
    assert live[0].ros_arguments("p.yaml")[-4:] == ["-p", "port:=8765", "-p", "host:=127.0.0.1"]
    args = build_parser().parse_args(["--foxglove", "9000", "--foxglove-host", "0.0.0.0"])
    (live,) = [p for p in plan_run(args).procs if p.executable == LIVE_VIEW.executable]
    assert dict(live.parameters) == {"port": 9000, "host": "0.0.0.0"}
    assert not [p for p in plan_run(build_parser().parse_args([])).procs if p.executable == LIVE_VIEW.executable]
