"""Where the ROS 2 packages are, with or without a sourced ``setup.bash`` (pure Python).

The ament prefixes are ``AMENT_PREFIX_PATH`` when it is set (a sourced setup script,
``ros2 run``, ``ros2 launch``), else this interpreter's prefix: the project's venv, whose
ament index also lists the ``ros_ws/`` packages (``tools/bootstrap.py`` registers them
there), so the venv's tools work without sourcing anything and without any start-up hook
that sets environment variables. ``ament_index_python`` itself refuses to look anywhere
when AMENT_PREFIX_PATH is unset; use these functions instead.
"""

from __future__ import annotations

import os
import pathlib
import sys

RESOURCE_INDEX = pathlib.Path("share", "ament_index", "resource_index")

#: rclpy's major version -> the ROS 2 distribution it belongs to (the PyPI wheels are
#: named ``ros-rclpy`` whatever the distribution).
RCLPY_MAJOR_DISTRO = {3: "humble", 5: "iron", 7: "jazzy", 9: "kilted"}


def ament_prefixes() -> list:
    """The ament prefixes to search, highest priority first (paths)."""
    value = os.environ.get("AMENT_PREFIX_PATH", "")
    if value:
        return [pathlib.Path(p) for p in value.split(os.pathsep) if p]
    return [pathlib.Path(sys.prefix)]


def package_prefix(package: str) -> pathlib.Path | None:
    """The prefix whose ament index lists ``package`` (as ``ros2 pkg prefix``), or None."""
    for prefix in ament_prefixes():
        if (prefix / RESOURCE_INDEX / "packages" / package).is_file():
            return prefix
    return None


def package_share_directory(package: str) -> pathlib.Path | None:
    """``<prefix>/share/<package>`` of an installed package, or None."""
    prefix = package_prefix(package)
    return None if prefix is None else prefix / "share" / package


def executable(package: str, name: str) -> pathlib.Path | None:
    """The node executable ``ros2 run package name`` would start (``<prefix>/lib/<package>/<name>``), or None."""
    for prefix in ament_prefixes():
        path = prefix / "lib" / package / name
        if path.is_file():
            return path
    return None


def ros_distro() -> str | None:
    """The ROS 2 distribution of the rclpy this interpreter imports (e.g. ``jazzy``), or None.

    From the installed ``ros-rclpy`` wheel's version; without one (a full ROS 2 install,
    whose rclpy is no pip distribution) from ``ROS_DISTRO``, which its setup script sets.
    """
    from importlib import metadata
    try:
        major = int(metadata.version("ros-rclpy").split(".")[0])
    except (metadata.PackageNotFoundError, ValueError):
        return os.environ.get("ROS_DISTRO") or None
    return RCLPY_MAJOR_DISTRO.get(major)
