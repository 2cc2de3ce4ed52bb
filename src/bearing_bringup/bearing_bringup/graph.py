"""The monitoring graph: which node executables run, under which names.

One definition used by the launch file (``launch/monitor.launch.py``), the
``bearing-graph`` starter of ``make demo``, the multi-node processes (:mod:`.nodes_main`)
and the launch/YAML checks in tests.
"""

import pathlib
from dataclasses import dataclass

from bearing_common import ros_env


@dataclass(frozen=True)
class NodeSpec:
    """A node of the graph: ``ros2 run <package> <executable>`` named ``name``.

    ``parameters_module`` holds the node's declared ``PARAMETERS`` (rclpy-free). ``node_class``
    (``module:Class``, constructed as ``Class(name=..., namespace=...)``) lets a multi-node
    process run the node; empty for a node with a run loop of its own (the simulator paces
    itself), which runs only as its own executable.
    """

    package: str
    executable: str
    name: str
    parameters_module: str
    node_class: str = ""


#: Simulator -> OR and IR observers -> diagnoser (sim/truth is for evaluation only).
GRAPH = (
    NodeSpec("bearing_sim", "simulator", "simulator", "bearing_sim.sim_node_config"),
    NodeSpec("bearing_observer", "observer", "or_observer", "bearing_observer.observer_node_config",
             "bearing_observer.node:ObserverNode"),
    NodeSpec("bearing_observer", "observer", "ir_observer", "bearing_observer.observer_node_config",
             "bearing_observer.node:ObserverNode"),
    NodeSpec("bearing_diagnoser", "diagnoser", "diagnoser", "bearing_diagnoser.diagnoser_node_config",
             "bearing_diagnoser.node:DiagnoserNode"),
)

CONFIG_NAME = "monitor.yaml"


def config_path() -> pathlib.Path:
    """The parameters YAML: the installed ``share/bearing_bringup/config`` copy, else the source tree's."""
    share = ros_env.package_share_directory("bearing_bringup")
    if share is not None and (share / "config" / CONFIG_NAME).is_file():
        return share / "config" / CONFIG_NAME
    return pathlib.Path(__file__).resolve().parent.parent / "config" / CONFIG_NAME
