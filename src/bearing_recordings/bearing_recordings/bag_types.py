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


#: numpy element types of the ros2msg numeric base types (rosbags holds such sequences as arrays).
_NUMPY_TYPES = {"float32": "float32", "float64": "float64", "int8": "int8", "uint8": "uint8", "int16": "int16",
                "uint16": "uint16", "int32": "int32", "uint32": "uint32", "int64": "int64", "uint64": "uint64",
                "byte": "uint8", "char": "uint8", "octet": "uint8"}


def convert_message(msg, msgtype: str, store):
    """A message decoded with another definition of ``msgtype`` (an older bag's) as ``store``'s
    ``msgtype``: fields of the same name are copied (nested messages converted, numeric
    arrays cast to the new element type, e.g. float64 -> float32), fields the old
    definition lacks take their defaults (0, "", empty)."""
    _consts, fields = store.fielddefs[msgtype]
    values = {name: _convert_field(getattr(msg, name, None), kind, detail, store) for name, (kind, detail) in fields}
    return store.types[msgtype](**values)


def _convert_field(value, kind, detail, store):
    import numpy as np
    from rosbags.interfaces import Nodetype
    if kind == Nodetype.NAME:
        return convert_message(value if value is not None else _Absent(), detail, store)
    if kind == Nodetype.BASE:
        name = detail[0]
        if value is not None:
            return value
        return "" if name in ("string", "wstring") else (False if name == "bool" else 0)
    (elem_kind, elem), size = detail  # ARRAY (fixed size) or SEQUENCE
    length = size if kind == Nodetype.ARRAY else 0  # of an absent field
    if elem_kind == Nodetype.BASE and elem[0] in _NUMPY_TYPES:
        dtype = _NUMPY_TYPES[elem[0]]
        return np.zeros(length, dtype) if value is None else np.asarray(value, dtype=dtype)
    return [_convert_field(v, elem_kind, elem, store) for v in ([None] * length if value is None else value)]


class _Absent:
    """A nested message the old definition did not have: every field missing."""
