"""The monitoring graph: which node executables run, under which names.

One definition used by the launch files (``launch/monitor.launch.py``, ``launch/fleet.launch.py``),
the ``bearing-graph`` starter of ``make demo``, the multi-node processes of a fleet
(:mod:`.multi_node_process`) and the launch/YAML checks in tests.
"""

import pathlib
from dataclasses import dataclass

from bearing_common import ros_env
from bearing_live_view.live_view_node_config import DEFAULT_HOST, DEFAULT_PORT


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

#: The live view (``foxglove:=true``, ``bearing-graph --foxglove``): every topic it discovers, served to Foxglove.
LIVE_VIEW = NodeSpec("bearing_live_view", "live_view", "live_view", "bearing_live_view.live_view_node_config")

#: The launch files' live-view arguments: (name, default, description); ``foxglove`` starts it.
LIVE_VIEW_ARGUMENTS = (
    ("foxglove", "false", "true: also serve the graph to Foxglove (the live_view node, docs/live-view.md)"),
    ("foxglove_port", str(DEFAULT_PORT), "TCP port of the Foxglove WebSocket server"),
    ("foxglove_host", DEFAULT_HOST, "address it listens on: 127.0.0.1 this machine only, 0.0.0.0 every interface "
                                   "(no authentication)"),
)

#: The live view's parameters from those arguments: {parameter: launch argument}.
LIVE_VIEW_PARAMETERS = {"port": "foxglove_port", "host": "foxglove_host"}


@dataclass(frozen=True)
class Process:
    """One process of a graph (``bearing-graph`` and the launch files start these).

    A single node (``node_name`` in ``namespace``, the package's own executable) or several
    (``bearing_bringup nodes`` with ``arguments`` = their fully qualified names); ``remappings``
    are global ``(from, to)`` rules with absolute ``from`` names, so each hits one motor only.
    ``sensor``: a simulator, whose exit 0 means its scenario ended. ``parameters``: ``(name, value)``
    set on its command line, after the parameters file.
    """

    name: str
    package: str
    executable: str
    node_name: str | None = None
    namespace: str = ""
    arguments: tuple = ()
    remappings: tuple = ()
    sensor: bool = False
    parameters: tuple = ()

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
        for name, value in self.parameters:
            args += ["-p", f"{name}:={value}"]
        return args


def single_graph(namespace: str = "") -> list:
    """The processes of one motor's graph in ``namespace``: one per node of :data:`GRAPH`, named as the node."""
    ns = namespace.strip("/")
    return [Process(spec.name, spec.package, spec.executable, spec.name, ns, sensor=spec.name == "simulator")
            for spec in GRAPH]


def live_view(namespace: str, port: int, host: str) -> Process:
    """The live view's process for ``bearing-graph --foxglove``: serving on ``host``:``port``."""
    return Process(LIVE_VIEW.name, LIVE_VIEW.package, LIVE_VIEW.executable, LIVE_VIEW.name, namespace.strip("/"),
                   parameters=(("port", int(port)), ("host", host)))


CONFIG_NAME = "monitor.yaml"
FLEET_CONFIG_NAME = "fleet.yaml"


def config_path(name: str = CONFIG_NAME) -> pathlib.Path:
    """A YAML of ``config/`` (default: the graph's parameters): the installed
    ``share/bearing_bringup/config`` copy, else the source tree's."""
    share = ros_env.package_share_directory("bearing_bringup")
    if share is not None and (share / "config" / name).is_file():
        return share / "config" / name
    return pathlib.Path(__file__).resolve().parent.parent / "config" / name
