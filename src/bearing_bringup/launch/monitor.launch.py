"""Start the whole monitoring graph from one parameters YAML (full ROS 2 installs).

    ros2 launch bearing_bringup monitor.launch.py [params_file:=FILE] [namespace:=NS]
        [foxglove:=true [foxglove_port:=8765] [foxglove_host:=127.0.0.1]]

The node list is bearing_bringup.graph.GRAPH, the same one `make demo` runs. When the
simulator exits (its scenario ended, repeat: false) the whole launch shuts down; the
observers and the diagnoser are respawned when they die, as bearing-graph restarts them
(same delay; launch caps the respawns per node in total, not per minute). With ``foxglove:=true``
the live_view node serves the graph to Foxglove (docs/live-view.md), respawned likewise.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, Shutdown
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from bearing_bringup.graph import CONFIG_NAME, GRAPH, LIVE_VIEW, LIVE_VIEW_ARGUMENTS, LIVE_VIEW_PARAMETERS
from bearing_bringup.launch_ctrl_c import hear_ctrl_c
from bearing_bringup.restart_policy import MAX_RESTARTS, RESTART_DELAY_S


def lifecycle(spec) -> dict:
    """What happens when the node's process ends."""
    if spec.executable == "simulator":
        return {"on_exit": Shutdown(reason="the simulator ended")}
    return {"respawn": True, "respawn_delay": RESTART_DELAY_S, "respawn_max_retries": MAX_RESTARTS}


def generate_launch_description():
    hear_ctrl_c()  # also when started with SIGINT ignored (a script's background job)
    default_params = os.path.join(get_package_share_directory("bearing_bringup"), "config", CONFIG_NAME)
    params_file = LaunchConfiguration("params_file")
    namespace = LaunchConfiguration("namespace")
    nodes = [
        Node(
            package=spec.package,
            executable=spec.executable,
            name=spec.name,
            namespace=namespace,
            parameters=[params_file],
            output="screen",
            **lifecycle(spec),
        )
        for spec in GRAPH
    ]
    return LaunchDescription([
        DeclareLaunchArgument("params_file", default_value=default_params,
                              description="parameters YAML for all nodes"),
        DeclareLaunchArgument("namespace", default_value="",
                              description="namespace of this machine's topics, e.g. motor_7"),
        *(DeclareLaunchArgument(name, default_value=default, description=text)
          for name, default, text in LIVE_VIEW_ARGUMENTS),
        *nodes,
        Node(package=LIVE_VIEW.package, executable=LIVE_VIEW.executable, name=LIVE_VIEW.name, namespace=namespace,
             parameters=[{p: LaunchConfiguration(a) for p, a in LIVE_VIEW_PARAMETERS.items()}], output="screen",
             condition=IfCondition(LaunchConfiguration("foxglove")), **lifecycle(LIVE_VIEW)),
    ])
