"""Start a fleet of monitored motors from one fleet YAML (full ROS 2 installs).

    ros2 launch bearing_bringup fleet.launch.py [fleet_file:=FILE] [motors:=N]
        [foxglove:=true [foxglove_port:=8765] [foxglove_host:=127.0.0.1]]

The processes are bearing_bringup.fleet_plan.processes(), the ones `bearing-graph --fleet` runs:
every motor's graph in its own namespace, laid out as the fleet file says, and the fleet
node. The parameters of every node are written to one file keyed by fully qualified node
names (a temporary directory). Every process but a simulator is respawned when it dies
(same delay as bearing-graph; launch caps the respawns per process in total); a simulator
that ends its scenario just exits, and the rest keeps monitoring until Ctrl-C. With ``foxglove:=true``
one live_view node (root namespace) serves every motor to Foxglove (docs/live-view.md).
"""

import os
import tempfile

import yaml
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from bearing_bringup.fleet_plan import load_fleet, parameters_file, processes
from bearing_bringup.graph import FLEET_CONFIG_NAME, LIVE_VIEW, LIVE_VIEW_ARGUMENTS, LIVE_VIEW_PARAMETERS
from bearing_bringup.launch_ctrl_c import hear_ctrl_c
from bearing_bringup.restart_policy import MAX_RESTARTS, RESTART_DELAY_S


def fleet_nodes(context):
    """The fleet's processes as Node actions (run at launch time, when the arguments are known)."""
    config = context.launch_configurations
    motors = config["motors"]
    fleet = load_fleet(config["fleet_file"], int(motors) if motors else None)
    params = os.path.join(tempfile.mkdtemp(prefix="bearing_fleet_"), "fleet_params.yaml")
    with open(params, "w") as f:
        yaml.safe_dump(parameters_file(fleet), f)
    respawn = {"respawn": True, "respawn_delay": RESTART_DELAY_S, "respawn_max_retries": MAX_RESTARTS}
    return [
        Node(
            package=proc.package,
            executable=proc.executable,
            name=proc.node_name,
            namespace=proc.namespace or None,
            arguments=list(proc.arguments),
            parameters=[params],
            remappings=list(proc.remappings),
            output="screen",
            **({} if proc.sensor else respawn),
        )
        for proc in processes(fleet)
    ]


def generate_launch_description():
    hear_ctrl_c()  # also when started with SIGINT ignored (a script's background job)
    default_fleet = os.path.join(get_package_share_directory("bearing_bringup"), "config", FLEET_CONFIG_NAME)
    return LaunchDescription([
        DeclareLaunchArgument("fleet_file", default_value=default_fleet,
                              description="fleet YAML: motors, their settings, the process layout"),
        DeclareLaunchArgument("motors", default_value="",
                              description="run N motors (the file's first N, then motor_<k> on its defaults); "
                                          "empty = the motors listed"),
        *(DeclareLaunchArgument(name, default_value=default, description=text)
          for name, default, text in LIVE_VIEW_ARGUMENTS),
        OpaqueFunction(function=fleet_nodes),
        Node(package=LIVE_VIEW.package, executable=LIVE_VIEW.executable, name=LIVE_VIEW.name,
             parameters=[{p: LaunchConfiguration(a) for p, a in LIVE_VIEW_PARAMETERS.items()}], output="screen",
             condition=IfCondition(LaunchConfiguration("foxglove")), respawn=True, respawn_delay=RESTART_DELAY_S,
             respawn_max_retries=MAX_RESTARTS),
    ])
