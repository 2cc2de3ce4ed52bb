"""The package's node executable, as its console script: light, so that the process handles stop
signals before the node module's imports (numpy, numba, rclpy: seconds under load;
:func:`bearing_common.node_main.run_executable`)."""

from bearing_common.node_main import run_executable


def nodes(args=None) -> int:
    """``ros2 run bearing_bringup nodes``: :func:`bearing_bringup.multi_node_process.main`."""
    return run_executable("nodes", "bearing_bringup.multi_node_process:main", args)
