"""bearing-graph names missing parts, runs what exists and exits non-zero."""

import pathlib

from bearing_bringup import graph_cli
from bearing_bringup.graph import GRAPH


def test_missing_parts_are_named(tmp_path, monkeypatch):
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path))
    missing = graph_cli.missing_parts()
    assert [m.split()[0] for m in missing] == [spec.name for spec in GRAPH]
    assert "executable not built" in missing[0]


def test_installed_graph_is_complete():
    assert graph_cli.missing_parts() == []


def test_demo_with_nothing_built_exits_3_and_says_what_is_missing(tmp_path, monkeypatch, capsys):
    config = pathlib.Path(graph_cli.__file__).resolve()  # any existing file works as params here
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path))
    monkeypatch.setattr(graph_cli, "MISSING_SIMULATOR_RUN_S", 0.5)
    code = graph_cli.main(["--params", str(config), "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code == graph_cli.EXIT_MISSING
    assert "not runnable yet: simulator" in captured.err
    assert "MISSING: diagnoser" in captured.out
