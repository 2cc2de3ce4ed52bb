"""The message types a bag of the graph holds: a ``rosbags`` type store with ``bearing_msgs``.

Also the bag-level names every bag tool shares (the custom-data keys ``bearing-bag``
writes) and :class:`BagError`.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from bearing_common import ros_env

from .recording import InputError

#: Interface package of the project; its .msg files give the definitions.
MSG_PACKAGE = "bearing_msgs"

#: Keys in a bag's ``custom_data``: the namespace the graph ran in, the bearing monitored.
CUSTOM_NAMESPACE = "bearing_bag.namespace"
CUSTOM_BEARING = "bearing_bag.bearing"


class BagError(InputError):
    """The path is not a readable rosbag2 recording of the graph (one-line message)."""


def msg_definition_dirs() -> list:
    """Directories holding ``bearing_msgs/msg/*.msg``: the installed package's share
    directory (found beside the importable ``bearing_msgs`` Python package), else the
    repository's ``msgs/msg``."""
    dirs = []
    try:
        import bearing_msgs  # the generated Python package: .../install/bearing_msgs/lib/python3.11/site-packages
        pkg = Path(bearing_msgs.__file__).resolve().parent
        for up in pkg.parents:
            share = up / "share" / MSG_PACKAGE / "msg"
            if share.is_dir():
                dirs.append(share)
                break
    except ImportError:
        pass
    source = Path(__file__).resolve().parents[3] / "msgs" / "msg"
    if source.is_dir():
        dirs.append(source)
    return dirs


@lru_cache(maxsize=1)
def _project_typedefs() -> dict:
    from rosbags.typesys import get_types_from_msg
    for d in msg_definition_dirs():
        files = sorted(d.glob("*.msg"))
        if files:
            typs = {}
            for f in files:
                typs.update(get_types_from_msg(f.read_text(), f"{MSG_PACKAGE}/msg/{f.stem}"))
            return typs
    raise BagError(f"cannot find the {MSG_PACKAGE} .msg definitions (looked in: "
                   f"{', '.join(map(str, msg_definition_dirs())) or 'nowhere'}); build ros_ws first")


def project_typestore():
    """A fresh ``rosbags`` type store: the ROS 2 standard types + ``bearing_msgs``.

    The standard types are those of the installed distribution (:func:`store_name`).
    ``store.generate_msgdef(t, ros_version=2)`` gives the full ros2msg definition text
    (with dependencies such as std_msgs/Header) and ``store.hash_rihs01(t)`` the same type
    hash ROS 2 computes, so bags written with it decode in other tools.
    """
    from rosbags.typesys import Stores, get_typestore
    store = get_typestore(Stores[store_name()])
    store.register(_project_typedefs())
    return store


def store_name() -> str:
    """The ``rosbags`` type store of the installed ROS 2 distribution (``ROS2_JAZZY``,
    ``ROS2_KILTED``, ...); ``LATEST`` for one rosbags does not know. (rosbags 0.11.9: the
    Jazzy and Kilted stores give the same type hashes for every type both have.)"""
    from rosbags.typesys import Stores
    distro = ros_env.ros_distro()
    name = f"ROS2_{distro.upper()}" if distro else "LATEST"
    return name if name in Stores.__members__ else "LATEST"
