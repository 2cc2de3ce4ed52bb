"""The monitoring graph: which node executables run, under which names.

One definition used by the launch files (``launch/monitor.launch.py``, ``launch/fleet.launch.py``),
the ``bearing-graph`` starter of ``make demo``, the multi-node processes of a fleet
(:mod:`.multi_node_process`) and the launch/YAML checks in tests.
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

#: The fleet's summary node (one per machine, root namespace): every motor's fault_state -> fleet_state.
FLEET_NODE = NodeSpec("bearing_fleet", "fleet", "fleet", "bearing_fleet.fleet_node_config")


@dataclass(frozen=True)
class Process:
    """One process of a graph (``bearing-graph`` and the launch files start these).

    A single node (``node_name`` in ``namespace``, the package's own executable) or several
    (``bearing_bringup nodes`` with ``arguments`` = their fully qualified names); ``remappings``
    are global ``(from, to)`` rules with absolute ``from`` names, so each hits one motor only.
    ``sensor``: a simulator, whose exit 0 means its scenario ended.
    """

    name: str
    package: str
    executable: str
    node_name: str | None = None
    namespace: str = ""
    arguments: tuple = ()
    remappings: tuple = ()
    sensor: bool = False

    def ros_arguments(self, params_file) -> list:
        """The ``--ros-args`` part of its command line."""
        args = ["--ros-args"]
        if self.node_name:
            args += ["-r", f"__node:={self.node_name}"]
        if self.namespace:
            args += ["-r", f"__ns:=/{self.namespace}"]
        args += ["--params-file", str(params_file)]
        for source, target in self.remappings:
            args += ["-r", f"{source}:={target}"]
        return args


def single_graph(namespace: str = "") -> list:
    """The processes of one motor's graph in ``namespace``: one per node of :data:`GRAPH`, named as the node."""
    ns = namespace.strip("/")
    return [Process(spec.name, spec.package, spec.executable, spec.name, ns, sensor=spec.name == "simulator")
            for spec in GRAPH]


CONFIG_NAME = "monitor.yaml"
FLEET_CONFIG_NAME = "fleet.yaml"


def config_path(name: str = CONFIG_NAME) -> pathlib.Path:
    """A YAML of ``config/`` (default: the graph's parameters): the installed
    ``share/bearing_bringup/config`` copy, else the source tree's."""
    share = ros_env.package_share_directory("bearing_bringup")
    if share is not None and (share / "config" / name).is_file():
        return share / "config" / name
    return pathlib.Path(__file__).resolve().parent.parent / "config" / name
