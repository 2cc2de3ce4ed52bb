"""The dependency keys the packages' ``package.xml`` files may name, and the stated exceptions.

``rosdep install --from-paths src`` on a full ROS 2 install resolves every ``*depend`` of a
package.xml: a package of the workspace, a released ROS package (``ros-jazzy-<name>``) or a
key of rosdep's database (``rosdistro/rosdep/*.yaml``). The tests have no network, so the keys
our manifests use are listed here, each checked by hand against that database (rosdistro,
``rosdep/python.yaml``) and the Jazzy distribution; ``tests/unit/test_package_manifests.py``
holds every package.xml to them and to its package's imports. A new dependency means a new
entry here, with the same check.

``tools/full_ros_install.py`` installs what rosdep would install for the run-time keys (the
PyPI distributions named here, at the pins of ``requirements/base.txt``) into the environment
that stands for ``/opt/ros/jazzy``.
"""

from __future__ import annotations

import pathlib
import xml.etree.ElementTree as ET

#: Released ROS 2 Jazzy packages the manifests name; import name = package name (Python
#: packages, message packages). rosdep installs ``ros-jazzy-<name with - for _>``.
ROS_PACKAGES = frozenset({
    "ament_cmake", "ament_index_python", "builtin_interfaces", "diagnostic_msgs", "launch", "launch_ros",
    "rcl_interfaces", "rclpy", "rosgraph_msgs", "rosidl_default_generators", "rosidl_default_runtime", "std_msgs",
})

#: Keys of rosdep's python.yaml: key -> (top-level import name, PyPI distribution). Each resolves
#: to the Debian/Ubuntu package of the same name on Debian and on Ubuntu 24.04 (Jazzy's platform).
SYSTEM_KEYS = {
    "python3-matplotlib": ("matplotlib", "matplotlib"),
    "python3-numpy": ("numpy", "numpy"),
    "python3-pytest": ("pytest", "pytest"),
    "python3-scipy": ("scipy", "scipy"),
    "python3-yaml": ("yaml", "PyYAML"),
}

#: Imported at run time but not installable through rosdep on Jazzy's platform: import name ->
#: (PyPI distribution, why). A package.xml that needs one says so in a comment naming the
#: distribution; users install it with pip (docs/install.md "With a full ROS 2 install").
PYPI_ONLY = {
    "numba": ("numba", "rosdep's python3-numba resolves on Debian and on Ubuntu 18.04/20.04 only, not on "
                       "24.04 (Jazzy); it also pulls llvmlite, pinned with it"),
    "control": ("control", "no rosdep key for python-control"),
    "rosbags": ("rosbags", "no rosdep key; reads and writes rosbag2 without a ROS 2 install"),
    "foxglove": ("foxglove-sdk", "no rosdep key for Foxglove's Python SDK (ROS releases its C++ foxglove_bridge "
                                 "only); the live view's WebSocket server"),
}

#: Distributions installed with a PyPI_ONLY one because its pin needs theirs (numba -> llvmlite).
PINNED_WITH = {"numba": ("llvmlite",)}


def import_to_key(module: str) -> str | None:
    """The rosdep key that provides top-level module ``module`` (a ROS package or a system key), or None."""
    if module in ROS_PACKAGES:
        return module
    return next((key for key, (name, _dist) in SYSTEM_KEYS.items() if name == module), None)


DEPEND_TAGS = ("depend", "build_depend", "buildtool_depend", "build_export_depend", "exec_depend",
               "test_depend", "doc_depend")
RUN_TAGS = ("depend", "exec_depend")  #: what a package needs at run time


def read_manifest(path: pathlib.Path) -> ET.Element:
    """A package.xml's root element, comments kept as elements; ParseError on malformed XML
    (expat is strict: e.g. ``--`` inside a comment)."""
    return ET.parse(path, parser=ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))).getroot()


def dependencies(root: ET.Element, tags=DEPEND_TAGS) -> set:
    """The names a manifest lists under ``tags``."""
    return {el.text.strip() for tag in tags for el in root.iter(tag)}


def comments(root: ET.Element) -> str:
    """The text of a manifest's comments, where it states its PyPI-only dependencies."""
    return " ".join(el.text for el in root.iter() if el.tag is ET.Comment)
