"""The package's node executable, as its console script: light, so that the process handles stop
signals before the node module's imports (numpy, numba, rclpy: seconds under load;
:func:`bearing_common.node_main.run_executable`)."""

from bearing_common.node_main import run_executable


def fleet(args=None) -> int:
    """``ros2 run bearing_fleet fleet``: :func:`bearing_fleet.node.main`."""
    return run_executable("fleet", "bearing_fleet.node:main", args)
