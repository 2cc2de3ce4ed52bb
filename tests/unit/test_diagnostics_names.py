"""The diagnoser's /diagnostics names for a fleet, and the aggregator analyzers YAML that groups them.

``diagnostic_aggregator`` is not on PyPI, so its naming rules are mirrored here from its
``status_item.hpp`` (ros/diagnostics): a GenericAnalyzer takes a status whose name starts
with one of ``startswith``, names it ``<base path>/<path>/<name with "/" as spaces>`` and
strips each ``remove_prefix`` (and the spaces after it) from that last part.
"""

import socket

import yaml

from bearing_bringup.graph import config_path
from bearing_diagnoser.diagnoser_session import motor_name, status_name

AGGREGATOR_YAML = "diagnostic_aggregator.yaml"


def output_name(item_name: str) -> str:
    """The aggregator's ``getOutputName``: "/" becomes " "."""
    return item_name.replace("/", " ")


def remove_leading_chaff(name: str, chaff: str) -> str:
    """The aggregator's ``removeLeadingNameChaff`` for the last path element of ``name``."""
    head, _, last = name.rpartition("/")
    if chaff and last.startswith(chaff):
        last = last[len(chaff):]
    return f"{head}/{last.lstrip(' :')}"


def aggregated(status: str) -> list:
    """Where the shipped analyzers put a status named ``status`` (one entry per matching analyzer)."""
    params = yaml.safe_load(config_path(AGGREGATOR_YAML).read_text())["analyzers"]["ros__parameters"]
    base = "/" + params["path"]
    out = []
    for key, analyzer in params.items():
        if not isinstance(analyzer, dict):
            continue
        assert analyzer["type"] == "diagnostic_aggregator/GenericAnalyzer", key
        if any(status.startswith(prefix) for prefix in analyzer["startswith"]):
            name = f"{base}/{analyzer['path']}/{output_name(status)}"
            for chaff in analyzer.get("remove_prefix", []):
                name = remove_leading_chaff(name, output_name(chaff))
            out.append(name)
    return out


def test_the_motor_is_the_parameter_else_the_namespace_else_the_host():
    assert motor_name("", "/motor_3") == "motor_3"
    assert motor_name("", "/plant/line_2/motor_7") == "plant/line_2/motor_7"
    assert motor_name("pump_a", "/motor_3") == "pump_a"
    assert motor_name("", "/") == socket.gethostname()


def test_status_names_share_one_prefix():
    assert status_name("motor_3") == "bearing_monitor/motor_3/drive_end"


def test_the_shipped_analyzers_group_every_motor_under_one_path():
    assert aggregated(status_name("motor_1")) == ["/Fleet/Bearings/motor_1 drive_end"]
    assert aggregated(status_name("motor_12")) == ["/Fleet/Bearings/motor_12 drive_end"]
    assert aggregated("/motor_1/diagnoser: drive_end bearing") == []  # the old name, not the fleet's
    assert aggregated("cpu_monitor: CPU usage") == []
