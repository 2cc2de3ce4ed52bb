"""``nodes``: several of the graph's nodes in one process (a fleet's multi-node processes).

    ros2 run bearing_bringup nodes /motor_1/or_observer /motor_1/ir_observer /motor_2/or_observer ... \\
        --ros-args --params-file fleet_params.yaml

Each argument is the fully qualified name of a node to run: a namespace (the motor) and
one of the graph's node names that can share a process (``or_observer``, ``ir_observer``,
``diagnoser``: :data:`bearing_bringup.graph.GRAPH` entries with a ``node_class``). The
nodes are the single-node executables' classes, unchanged, in one single-threaded
executor (:func:`bearing_common.node_main.run_nodes_main`: same clean stop, same exit
codes); each finds its parameters in the parameters file under its fully qualified name
(``/motor_3/diagnoser: ros__parameters: ...``). A name that is not such a node gives one
line on stderr and exit code 2, as invalid parameters do.
"""

from __future__ import annotations

import importlib
import sys

from bearing_common.node_main import run_nodes_main

from .graph import GRAPH

SHAREABLE = {spec.name: spec for spec in GRAPH if spec.node_class}


def split_name(fqn: str) -> tuple[str, str]:
    """``/motor_3/diagnoser`` -> (``/motor_3``, ``diagnoser``); ValueError for other names."""
    namespace, _, name = fqn.rpartition("/")
    if not fqn.startswith("/") or name not in SHAREABLE:
        raise ValueError(f"{fqn!r} is not a fully qualified name of one of the nodes "
                         f"{', '.join(sorted(SHAREABLE))} (e.g. /motor_1/{next(iter(SHAREABLE))})")
    return namespace or "/", name


def make_nodes(names: list) -> list:
    """The nodes of ``names`` (fully qualified), built in order."""
    if not names:
        raise ValueError("no nodes named: give fully qualified node names before --ros-args")
    places = [split_name(fqn) for fqn in names]  # every name checked before any node is built
    nodes = []
    for namespace, name in places:
        module, _, cls = SHAREABLE[name].node_class.partition(":")
        nodes.append(getattr(importlib.import_module(module), cls)(name=name, namespace=namespace))
    return nodes


def main(args=None) -> int:
    from rclpy.utilities import remove_ros_args

    argv = sys.argv if args is None else args
    names = remove_ros_args(argv)[1:]
    return run_nodes_main("nodes", lambda: make_nodes(names), None, argv)


if __name__ == "__main__":
    sys.exit(main())
