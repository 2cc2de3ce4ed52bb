"""The package's node executable, as its console script: light, so that the process handles stop
signals before the node module's imports (numpy, numba, rclpy: seconds under load;
:func:`bearing_common.node_main.run_executable`)."""

from bearing_common.node_main import run_executable


def simulator(args=None) -> int:
    """``ros2 run bearing_sim simulator``: :func:`bearing_sim.node.main`."""
    return run_executable("simulator", "bearing_sim.node:main", args)
