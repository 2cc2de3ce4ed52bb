"""The package's node executable, as its console script: light, so that the process handles stop
signals before the node module's imports (numpy, numba, rclpy: seconds under load;
:func:`bearing_common.node_main.run_executable`)."""

from bearing_common.node_main import run_executable


def observer(args=None) -> int:
    """``ros2 run bearing_observer observer``: :func:`bearing_observer.node.main`."""
    return run_executable("observer", "bearing_observer.node:main", args)
