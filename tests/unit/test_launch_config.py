"""Static checks of the launch file and the graph's parameters YAML (ros2 launch is not installable here)."""

import ast
import importlib
import pathlib
import re

import yaml

from bearing_bringup.graph import GRAPH

REPO = pathlib.Path(__file__).resolve().parents[2]
BRINGUP = REPO / "src" / "bearing_bringup"


def console_scripts(package: str) -> set:
    setup = (REPO / "src" / package / "setup.py").read_text()
    return set(re.findall(r'["\']([\w-]+)\s*=\s*[\w.]+:\w+["\']', setup))


def test_launch_file_parses_and_uses_the_graph():
    source = (BRINGUP / "launch" / "monitor.launch.py").read_text()
    tree = ast.parse(source)
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    funcs = {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    assert "generate_launch_description" in funcs
    assert "GRAPH" in names  # nodes come from bearing_bringup.graph, like bearing-graph's


def test_graph_names_existing_executables():
    for spec in GRAPH:
        assert spec.executable in console_scripts(spec.package), f"{spec.package} has no {spec.executable}"


def test_yaml_names_only_graph_nodes_and_declared_parameters():
    config = yaml.safe_load((BRINGUP / "config" / "monitor.yaml").read_text())
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
