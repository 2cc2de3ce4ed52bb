"""Rewrite the build-machine paths hard-coded in the ROS 2 PyPI wheels' CMake files.

The ROS 2 wheels (Jazzy and Kilted alike) export CMake targets whose include
directories point at the wheel builder's interpreter (``/opt/python/cp311-cp311/...``).
Building an interface package then fails with "Imported target ... includes non-existent
path". This step rewrites those two paths to this interpreter's Python include
directory and numpy's include directory (see ../shared/ros2-from-pypi.md).
Idempotent: files already rewritten are left alone. Run with the venv's python.
"""

import pathlib
import sys
import sysconfig

import numpy

BUILDER_PY_INCLUDE = "/opt/python/cp311-cp311/include/python3.11"
BUILDER_NUMPY_INCLUDE = "/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"


def main() -> int:
    replacements = {
        BUILDER_NUMPY_INCLUDE: numpy.get_include(),
        BUILDER_PY_INCLUDE: sysconfig.get_paths()["include"],
    }
    share = pathlib.Path(sys.prefix) / "share"
    changed = 0
    for path in share.rglob("*.cmake"):
        text = path.read_text(errors="surrogateescape")
        new = text
        for old, repl in replacements.items():  # numpy path first: it contains no py-include prefix clash
            new = new.replace(old, repl)
        if new != text:
            path.write_text(new, errors="surrogateescape")
            changed += 1
    print(f"rewrote builder paths in {changed} CMake files under {share}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
