"""Fleet files and the processes they give (bearing_bringup.fleet_plan, no ROS graph)."""

import pytest
import yaml

from bearing_bringup import multi_node_process
from bearing_bringup.fleet_plan import FleetError, default_fleet_file, load_fleet, parameters_file, processes
from bearing_bringup.graph import GRAPH, config_path, single_graph
from bearing_common import topics

MONITORS = ["or_observer", "ir_observer", "diagnoser"]


def fleet_yaml(tmp_path, **doc):
    path = tmp_path / "fleet.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def test_the_shipped_fleet_file_runs_three_simulated_motors():
    fleet = load_fleet(default_fleet_file())
    assert [m.name for m in fleet.motors] == ["motor_1", "motor_2", "motor_3"]
    assert all(m.simulated for m in fleet.motors)
    sim = fleet.motors[0].parameters["simulator"]
    base = yaml.safe_load(config_path().read_text())["simulator"]["ros__parameters"]
    assert sim["scenario"] == "or" and sim["wait_for_subscribers"] == base["wait_for_subscribers"]
    assert fleet.motors[1].parameters["simulator"]["scenario"] == "normal-ir"
    for node in MONITORS:  # the motor's rpm reaches every node that uses one, as a float
        assert fleet.motors[0].parameters[node]["rpm"] == 1800.0
    assert fleet.motors[0].parameters["or_observer"]["fault_type"] == "outer_race"  # from monitor.yaml


def test_motors_n_takes_the_first_listed_then_numbers_the_rest(tmp_path):
    path = fleet_yaml(tmp_path, defaults={"scenario": "ir"}, motors={"pump_a": {"scenario": "or"}, "motor_2": {}})
    assert [m.name for m in load_fleet(path, motors=1).motors] == ["pump_a"]
    fleet = load_fleet(path, motors=4)
    assert [m.name for m in fleet.motors] == ["pump_a", "motor_2", "motor_1", "motor_3"]
    assert [m.parameters["simulator"]["scenario"] for m in fleet.motors] == ["or", "ir", "ir", "ir"]


def test_settings_reach_only_the_nodes_that_use_them_and_node_sections_override(tmp_path):
    path = fleet_yaml(tmp_path, motors={"m1": {"bearing": "6203", "sample_rate": 12000, "rpm": 1750,
                                               "diagnoser": {"stale_timeout": 2.5, "rpm": 1700.0}}})
    p = load_fleet(path).motors[0].parameters
    assert p["simulator"]["sample_rate"] == 12000.0 and "bearing" not in p["simulator"]
    assert p["or_observer"]["bearing"] == p["diagnoser"]["bearing"] == "6203"
    assert "sample_rate" not in p["or_observer"]
    assert p["diagnoser"]["stale_timeout"] == 2.5 and p["diagnoser"]["rpm"] == 1700.0
    assert p["ir_observer"]["rpm"] == 1750.0


def test_external_sensors_send_0_1_s_chunks_simulated_ones_the_simulators_and_staleness_follows(tmp_path):
    path = fleet_yaml(tmp_path, motors={"ext": {"sensor": "external"}, "slow": {"sensor": "external",
                                                                              "chunk_duration": 1},
                                        "sim": {}, "sim_big": {"chunk_duration": 0.5}})
    fleet = load_fleet(path)
    ext, slow, sim, sim_big = fleet.motors
    assert (ext.chunk_duration, slow.chunk_duration, sim.chunk_duration, sim_big.chunk_duration) == (0.1, 1.0, 0.01,
                                                                                                   0.5)
    assert sim.parameters["simulator"]["chunk_duration"] == 0.01  # config/monitor.yaml: the thesis' cases
    assert sim_big.parameters["simulator"]["chunk_duration"] == 0.5
    assert "chunk_duration" not in ext.parameters["or_observer"]
    # residuals come one chunk apart: STALE needs 3 chunks without one (monitor.yaml's 1 s otherwise)
    stale = [m.parameters["diagnoser"]["stale_timeout"] for m in fleet.motors]
    assert stale == [1.0, 3.0, 1.0, 1.5]
    assert "stale_timeout" not in fleet.fleet_parameters  # its default, 5 s, is above 3 of the longest chunks
    longest = load_fleet(fleet_yaml(tmp_path, motors={"m": {"sensor": "external", "chunk_duration": 2.0}}))
    assert longest.fleet_parameters["stale_timeout"] == 6.0


@pytest.mark.parametrize("doc, message", [
    ({"motors": {"m": {"sensor": "external", "chunk_duration": 0}}}, "m.chunk_duration: expected a positive number"),
    ({"motors": {"m": {"sensor": "external", "chunk_duration": "1s"}}}, "m.chunk_duration: expected a positive"),
    ({"motors": {"m": {"chunk_duration": -0.1}}}, r"m.simulator.chunk_duration: must be > 0"),
    ({"layout": "threads", "motors": {"m": {}}}, "layout must be one of role, motor, node"),
    ({"motors_per_process": 0, "motors": {"m": {}}}, "motors_per_process must be a positive integer"),
    ({"colour": "red", "motors": {"m": {}}}, "unknown keys colour"),
    ({"motors": {}}, "no motors listed"),
    ({"motors": {"motor 1": {}}}, "is not a namespace"),
    ({"motors": {"m": {"sensor": "radar"}}}, "sensor must be one of simulator, external"),
    ({"motors": {"m": {"torque": 3}}}, "unknown settings torque"),
    ({"motors": {"m": {"rpm": "fast"}}}, r"m.simulator.rpm: expected float"),
    ({"motors": {"m": {"rpm": -5.0}}}, r"m.simulator.rpm: must be in \(0"),
    ({"motors": {"m": {"diagnoser": {"stale_timout": 1.0}}}}, "'stale_timout' is not a parameter of diagnoser"),
    ({"motors": {"m": {"bearing": "6299"}}}, "m.or_observer.bearing"),
    ({"motors": {"m": {"diagnoser": 3}}}, "expected a mapping of parameters"),
    ({"fleet": {"period": -1.0}, "motors": {"m": {}}}, "fleet.period: must be > 0"),
])
def test_bad_fleet_files_are_refused_with_the_reason(tmp_path, doc, message):
    with pytest.raises(FleetError, match=message):
        load_fleet(fleet_yaml(tmp_path, **doc))


def test_the_parameters_file_is_keyed_by_fully_qualified_node_names(tmp_path):
    fleet = load_fleet(fleet_yaml(tmp_path, motors={"a": {}, "plant/b": {"sensor": "external"}},
                                  fleet={"stale_timeout": 3.0}))
    doc = parameters_file(fleet)
    assert set(doc) == {"/a/simulator", *(f"/a/{n}" for n in MONITORS), *(f"/plant/b/{n}" for n in MONITORS),
                        "/fleet"}
    assert doc["/fleet"]["ros__parameters"]["stale_timeout"] == 3.0
    assert doc["/plant/b/ir_observer"]["ros__parameters"]["fault_type"] == "inner_race"


def layout(tmp_path, name, n=3, per_process=2, **motor):
    path = fleet_yaml(tmp_path, layout=name, motors_per_process=per_process,
                      motors={f"motor_{k}": dict(motor) for k in range(1, n + 1)})
    return processes(load_fleet(path))


def test_role_layout_groups_observers_and_diagnosers_by_motors_per_process(tmp_path):
    procs = {p.name: p for p in layout(tmp_path, "role")}
    assert list(procs) == ["motor_1/simulator", "motor_2/simulator", "motor_3/simulator", "observers_1",
                           "diagnosers_1", "observers_2", "diagnosers_2", "fleet"]
    assert procs["observers_1"].arguments == ("/motor_1/or_observer", "/motor_1/ir_observer",
                                              "/motor_2/or_observer", "/motor_2/ir_observer")
    assert procs["diagnosers_2"].arguments == ("/motor_3/diagnoser",)
    assert (procs["observers_1"].package, procs["observers_1"].executable) == ("bearing_bringup", "nodes")
    sims = [p for p in procs.values() if p.sensor]
    assert [(p.executable, p.node_name, p.namespace) for p in sims] == [
        ("simulator", "simulator", f"motor_{k}") for k in (1, 2, 3)]
    fleet = procs["fleet"]
    assert (fleet.package, fleet.node_name, fleet.namespace) == ("bearing_fleet", "fleet", "")


def test_motor_and_node_layouts(tmp_path):
    by_motor = {p.name: p for p in layout(tmp_path, "motor", n=2, sensor="external")}
    assert list(by_motor) == ["motor_1/monitor", "motor_2/monitor", "fleet"]
    assert by_motor["motor_2/monitor"].arguments == tuple(f"/motor_2/{n}" for n in MONITORS)
    by_node = layout(tmp_path, "node", n=1)
    assert [(p.name, p.executable, p.node_name, p.namespace) for p in by_node[:-1]] == [
        (f"motor_1/{s.name}", s.executable, s.name, "motor_1") for s in GRAPH]


def test_a_speed_topic_is_remapped_for_that_motor_only(tmp_path):
    path = fleet_yaml(tmp_path, layout="role", motors={"m1": {"speed_topic": "/drives/d1/speed"}, "m2": {}})
    procs = {p.name: p for p in processes(load_fleet(path))}
    rule = (topics.qualified("m1", topics.SHAFT_SPEED), "/drives/d1/speed")
    assert procs["m1/simulator"].remappings == procs["observers_1"].remappings == (rule,)
    assert procs["m2/simulator"].remappings == () and procs["fleet"].remappings == ()
    args = procs["observers_1"].ros_arguments("p.yaml")
    assert args == ["--ros-args", "--params-file", "p.yaml", "-r", f"{rule[0]}:={rule[1]}"]


def test_single_node_processes_name_and_place_their_node():
    sim = single_graph("motor_7")[0]
    assert sim.ros_arguments("p.yaml") == ["--ros-args", "-r", "__node:=simulator", "-r", "__ns:=/motor_7",
                                           "--params-file", "p.yaml"]
    assert [p.name for p in single_graph()] == [s.name for s in GRAPH]


def test_multi_node_processes_take_only_fully_qualified_names_of_shareable_nodes():
    assert multi_node_process.split_name("/motor_3/diagnoser") == ("/motor_3", "diagnoser")
    assert multi_node_process.split_name("/plant/m/or_observer") == ("/plant/m", "or_observer")
    assert multi_node_process.split_name("/ir_observer") == ("/", "ir_observer")
    for bad in ("motor_3/diagnoser", "/motor_3/simulator", "/motor_3/fleet"):
        with pytest.raises(ValueError, match="not a fully qualified name of one of the nodes"):
            multi_node_process.split_name(bad)
    with pytest.raises(ValueError, match="no nodes named"):
        multi_node_process.make_nodes([])


@pytest.mark.parametrize("layout", ["role", "motor", "node"])
def test_bearing_graph_knows_which_motors_have_a_diagnoser_in_every_layout(tmp_path, layout):
    """bearing-graph starts a motor's simulator once its diagnoser's fault_state reaches it."""
    from bearing_bringup.graph_cli import diagnosed_motors
    path = tmp_path / "f.yaml"
    path.write_text(yaml.safe_dump({"layout": layout, "motors_per_process": 2,
                                    "motors": {"m1": {}, "m2": {}, "m3": {"sensor": "external"}}}))
    procs = processes(load_fleet(path))
    assert diagnosed_motors(procs) == {"m1", "m2", "m3"}
    without = [p for p in procs
               if "/m2/diagnoser" not in p.arguments and (p.namespace, p.node_name) != ("m2", "diagnoser")]
    assert diagnosed_motors(without) == ({"m1", "m2", "m3"} - ({"m1", "m2"} if layout == "role" else {"m2"}))
    assert diagnosed_motors(single_graph()) == {""} and diagnosed_motors(single_graph("motor_7")) == {"motor_7"}


def test_bearing_graph_makes_each_simulator_wait_for_its_watcher_too(tmp_path):
    """A simulator's start gate (its parameters) plus the watcher's sim/truth subscription."""
    from bearing_bringup.graph_cli import watched_gate
    path = tmp_path / "f.yaml"
    path.write_text(yaml.safe_dump({"motors": {"m1": {}, "m2": {"simulator": {"wait_for_subscribers": ""}}}}))
    fleet = load_fleet(path)
    params = parameters_file(fleet)
    sims = {p.namespace: p for p in processes(fleet) if p.sensor}
    base = params["/m1/simulator"]["ros__parameters"]["wait_for_subscribers"]
    assert base and watched_gate(params, sims["m1"]) == ["-p", f"wait_for_subscribers:={base},sim/truth:1"]
    assert watched_gate(params, sims["m2"]) == ["-p", "wait_for_subscribers:=sim/truth:1"]
    single = yaml.safe_load(config_path().read_text())
    assert watched_gate(single, single_graph()[0])[1].endswith(",sim/truth:1")
