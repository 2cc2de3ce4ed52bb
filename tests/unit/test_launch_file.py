"""The launch files, built for real against stand-in launch modules, and the graph's parameters YAML.

``launch`` / ``launch_ros`` are not installable here (no PyPI packages), so minimal stand-ins
with the real call signatures (keyword names checked: a misspelt or unknown argument is a
TypeError, as it would be in launch) are put in ``sys.modules``; they record what the launch
files pass, and the tests check it against ``bearing_bringup.graph.GRAPH`` and, for the
fleet, against the processes ``bearing_bringup.fleet_plan`` plans (what ``bearing-graph --fleet`` runs).
"""

import importlib
import importlib.util
import pathlib
import re
import sys
import types

import pytest
import yaml

from bearing_bringup.fleet_plan import load_fleet, parameters_file, processes
from bearing_bringup.graph import CONFIG_NAME, FLEET_CONFIG_NAME, GRAPH, LIVE_VIEW
from bearing_bringup.restart_policy import MAX_RESTARTS, RESTART_DELAY_S

REPO = pathlib.Path(__file__).resolve().parents[2]
BRINGUP = REPO / "src" / "bearing_bringup"
LAUNCH_FILE = BRINGUP / "launch" / "monitor.launch.py"
FLEET_LAUNCH_FILE = BRINGUP / "launch" / "fleet.launch.py"

#: ExecuteProcess / ExecuteLocal / Action keyword arguments that launch_ros' Node passes on.
EXECUTE_KWARGS = {"shell", "sigterm_timeout", "sigkill_timeout", "emulate_tty", "output", "output_format",
                  "cached_output", "log_cmd", "on_exit", "respawn", "respawn_delay", "respawn_max_retries",
                  "cwd", "env", "additional_env", "prefix", "condition"}


class Recorded:
    def __init__(self, **kwargs):
        self.kwargs = kwargs

    def __eq__(self, other):
        return type(self) is type(other) and self.kwargs == other.kwargs

    def __repr__(self):
        return f"{type(self).__name__}({self.kwargs})"


class LaunchDescription(Recorded):
    def __init__(self, initial_entities=None, *, deprecated_reason=None):
        super().__init__(initial_entities=list(initial_entities or []))


class DeclareLaunchArgument(Recorded):
    def __init__(self, name, *, default_value=None, description=None, choices=None):
        super().__init__(name=name, default_value=default_value, description=description, choices=choices)


class Shutdown(Recorded):
    def __init__(self, *, reason="reason not given"):
        super().__init__(reason=reason)


class OpaqueFunction(Recorded):
    def __init__(self, *, function, args=None, kwargs=None):
        super().__init__(function=function, args=args, kwargs=kwargs)


class IfCondition(Recorded):
    def __init__(self, predicate_expression):
        super().__init__(predicate_expression=predicate_expression)


class LaunchConfiguration(Recorded):
    def __init__(self, variable_name, *, default=None):
        super().__init__(variable_name=variable_name, default=default)


class Node(Recorded):
    def __init__(self, *, executable, package=None, name=None, namespace=None, exec_name=None, parameters=None,
                 remappings=None, ros_arguments=None, arguments=None, **kwargs):
        unknown = set(kwargs) - EXECUTE_KWARGS
        if unknown:
            raise TypeError(f"Node() got unexpected keyword arguments {sorted(unknown)}")
        super().__init__(executable=executable, package=package, name=name, namespace=namespace,
                         parameters=parameters, remappings=remappings, arguments=arguments, **kwargs)


def stand_in_modules(share: pathlib.Path) -> dict:
    def module(name, **attrs):
        mod = types.ModuleType(name)
        mod.__dict__.update(attrs)
        return mod

    def get_package_share_directory(package):
        assert package == "bearing_bringup"
        return str(share)

    return {
        "launch": module("launch", LaunchDescription=LaunchDescription),
        "launch.actions": module("launch.actions", DeclareLaunchArgument=DeclareLaunchArgument, Shutdown=Shutdown,
                                 OpaqueFunction=OpaqueFunction),
        "launch.conditions": module("launch.conditions", IfCondition=IfCondition),
        "launch.substitutions": module("launch.substitutions", LaunchConfiguration=LaunchConfiguration),
        "launch_ros": module("launch_ros"),
        "launch_ros.actions": module("launch_ros.actions", Node=Node),
        "ament_index_python": module("ament_index_python"),
        "ament_index_python.packages": module("ament_index_python.packages",
                                              get_package_share_directory=get_package_share_directory),
    }


def launch_description(monkeypatch, path):
    for name, mod in stand_in_modules(BRINGUP).items():
        monkeypatch.setitem(sys.modules, name, mod)
    spec = importlib.util.spec_from_file_location(path.stem.replace(".", "_"), path)
    launch_file = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(launch_file)
    return launch_file.generate_launch_description()


@pytest.fixture
def description(monkeypatch):
    return launch_description(monkeypatch, LAUNCH_FILE)


def graph_nodes(entities) -> list:
    """The Node actions of the monitoring graph (the live view's aside)."""
    return [e.kwargs for e in entities if isinstance(e, Node) and e.kwargs["executable"] != LIVE_VIEW.executable]


def test_launch_arguments(description):
    args = {e.kwargs["name"]: e.kwargs for e in description.kwargs["initial_entities"]
            if isinstance(e, DeclareLaunchArgument)}
    assert set(args) == {"params_file", "namespace", "foxglove", "foxglove_port", "foxglove_host"}
    assert args["params_file"]["default_value"] == str(BRINGUP / "config" / CONFIG_NAME)
    assert pathlib.Path(args["params_file"]["default_value"]).is_file()
    assert args["namespace"]["default_value"] == ""


def test_one_node_per_graph_entry_with_the_shared_parameters_and_namespace(description):
    nodes = graph_nodes(description.kwargs["initial_entities"])
    assert [(n["package"], n["executable"], n["name"]) for n in nodes] == \
        [(s.package, s.executable, s.name) for s in GRAPH]
    for node in nodes:
        assert node["namespace"] == LaunchConfiguration("namespace")
        assert node["parameters"] == [LaunchConfiguration("params_file")]
        assert node["output"] == "screen"


def test_simulator_ends_the_launch_and_the_others_are_respawned(description):
    nodes = {n["name"]: n for n in graph_nodes(description.kwargs["initial_entities"])}
    sim = nodes.pop("simulator")
    assert isinstance(sim["on_exit"], Shutdown) and not sim.get("respawn")
    assert set(nodes) == {"or_observer", "ir_observer", "diagnoser"}
    for node in nodes.values():
        assert node["respawn"] is True and "on_exit" not in node
        assert node["respawn_delay"] == RESTART_DELAY_S and node["respawn_max_retries"] == MAX_RESTARTS


def test_stand_ins_refuse_unknown_arguments():
    with pytest.raises(TypeError, match="respawn_dealy"):
        Node(executable="observer", respawn_dealy=1.0)


def console_scripts(package: str) -> set:
    setup = (REPO / "src" / package / "setup.py").read_text()
    return set(re.findall(r'["\']([\w-]+)\s*=\s*[\w.]+:\w+["\']', setup))


def test_graph_names_existing_executables():
    for spec in GRAPH:
        assert spec.executable in console_scripts(spec.package), f"{spec.package} has no {spec.executable}"


@pytest.mark.parametrize("name", [CONFIG_NAME, "run_up.yaml"])
def test_yaml_names_only_graph_nodes_and_declared_parameters(name):
    config = yaml.safe_load((BRINGUP / "config" / name).read_text())
    by_name = {spec.name: spec for spec in GRAPH}
    assert set(config) == set(by_name), "YAML sections must be exactly the graph's node names"
    for node_name, section in config.items():
        params = section["ros__parameters"]
        declared = {p.name: p for p in importlib.import_module(by_name[node_name].parameters_module).PARAMETERS}
        for key, value in params.items():
            assert key in declared, f"{node_name}: parameter {key!r} is not declared"
            default = declared[key].default
            assert type(value) is type(default), f"{node_name}.{key}: {value!r} is not a {type(default).__name__}"
            assert declared[key].validate(value) is None, f"{node_name}.{key}: {declared[key].validate(value)}"


def test_every_parameter_has_a_description():
    for spec in GRAPH:
        for param in importlib.import_module(spec.parameters_module).PARAMETERS:
            assert len(param.description) > 10, f"{spec.name}.{param.name} lacks a description"


def test_fleet_launch_starts_the_processes_bearing_graph_runs(monkeypatch, tmp_path):
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    entities = launch_description(monkeypatch, FLEET_LAUNCH_FILE).kwargs["initial_entities"]
    args = {e.kwargs["name"]: e.kwargs for e in entities if isinstance(e, DeclareLaunchArgument)}
    assert set(args) == {"fleet_file", "motors", "foxglove", "foxglove_port", "foxglove_host"}
    assert args["motors"]["default_value"] == ""
    fleet_file = pathlib.Path(args["fleet_file"]["default_value"])
    assert fleet_file == BRINGUP / "config" / FLEET_CONFIG_NAME and fleet_file.is_file()
    (opaque,) = [e for e in entities if isinstance(e, OpaqueFunction)]
    context = types.SimpleNamespace(launch_configurations={"fleet_file": str(fleet_file), "motors": "5"})
    nodes = [n.kwargs for n in opaque.kwargs["function"](context)]

    fleet = load_fleet(fleet_file, 5)
    planned = processes(fleet)
    assert [(n["package"], n["executable"], n["name"], n["namespace"] or "", tuple(n["arguments"]),
             tuple(n["remappings"])) for n in nodes] == [
        (p.package, p.executable, p.node_name, p.namespace, p.arguments, p.remappings) for p in planned]
    (params,) = {n["parameters"][0] for n in nodes}
    assert yaml.safe_load(pathlib.Path(params).read_text()) == parameters_file(fleet)
    for node, proc in zip(nodes, planned):
        if proc.sensor:  # a simulator ends with its scenario; the rest keeps monitoring
            assert not node.get("respawn") and "on_exit" not in node
        else:
            assert node["respawn"] is True and node["respawn_delay"] == RESTART_DELAY_S


@pytest.mark.parametrize("path", [LAUNCH_FILE, FLEET_LAUNCH_FILE], ids=["monitor", "fleet"])
def test_foxglove_true_starts_the_live_view_on_foxglove_port(monkeypatch, path):
    """``foxglove:=true`` (default false) starts one live_view node, respawned like the monitoring nodes,
    with the port and host of ``foxglove_port`` / ``foxglove_host``, whose defaults are the node's own."""
    entities = launch_description(monkeypatch, path).kwargs["initial_entities"]
    args = {e.kwargs["name"]: e.kwargs["default_value"] for e in entities if isinstance(e, DeclareLaunchArgument)}
    declared = {p.name: p.default for p in importlib.import_module(LIVE_VIEW.parameters_module).PARAMETERS}
    assert args["foxglove"] == "false"
    assert yaml.safe_load(args["foxglove_port"]) == declared["port"] == 8765  # launch_ros reads values as YAML
    assert yaml.safe_load(args["foxglove_host"]) == declared["host"]
    (live,) = [e.kwargs for e in entities if isinstance(e, Node) and e.kwargs["executable"] == LIVE_VIEW.executable]
    assert (live["package"], live["name"]) == (LIVE_VIEW.package, LIVE_VIEW.name)
    assert live["condition"] == IfCondition(LaunchConfiguration("foxglove"))
    assert live["parameters"] == [{"port": LaunchConfiguration("foxglove_port"),
                                   "host": LaunchConfiguration("foxglove_host")}]
    assert set(live["parameters"][0]) <= set(declared)
    assert live["respawn"] is True and live["respawn_delay"] == RESTART_DELAY_S
    assert LIVE_VIEW.executable in console_scripts(LIVE_VIEW.package)
