"""The package's node executable, as its console script: light, so that the process handles stop
signals before the node module's imports (foxglove-sdk, numpy, rclpy: seconds under load;
:func:`bearing_common.node_main.run_executable`)."""

from bearing_common.node_main import run_executable


def live_view(args=None) -> int:
    """``ros2 run bearing_live_view live_view``: :func:`bearing_live_view.node.main`."""
    return run_executable("live_view", "bearing_live_view.node:main", args)
