"""Start a fleet of monitored motors from one fleet YAML (full ROS 2 installs).

    ros2 launch bearing_bringup fleet.launch.py [fleet_file:=FILE] [motors:=N]

The processes are bearing_bringup.fleet_plan.processes(), the ones `bearing-graph --fleet` runs:
every motor's graph in its own namespace, laid out as the fleet file says, and the fleet
node. The parameters of every node are written to one file keyed by fully qualified node
names (a temporary directory). Every process but a simulator is respawned when it dies
(same delay as bearing-graph; launch caps the respawns per process in total); a simulator
that ends its scenario just exits, and the rest keeps monitoring until Ctrl-C.
"""

import os
import tempfile

import yaml
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch_ros.actions import Node

from bearing_bringup.fleet_plan import load_fleet, parameters_file, processes
from bearing_bringup.graph import FLEET_CONFIG_NAME
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
        OpaqueFunction(function=fleet_nodes),
    ])
