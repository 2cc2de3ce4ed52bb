"""Every package.xml: well-formed XML (colcon and rosdep skip a manifest they cannot parse, and
colcon then builds the package as plain Python, without its ament index hook), format 3, the
fields a release needs, and dependencies that rosdep can resolve: workspace packages, released
ROS packages or rosdep keys (``tools/rosdep_keys.py``), or PyPI-only exceptions the manifest
states in a comment. Each package's imports (its modules and launch files) are declared.
"""

import ast
import pathlib
import re
import sys

import pytest

from tools import rosdep_keys as keys
from tools.rosdep_keys import dependencies, read_manifest

ROOT = pathlib.Path(__file__).resolve().parents[2]
MANIFESTS = sorted([*ROOT.glob("src/*/package.xml"), ROOT / "msgs" / "package.xml"])


def package_name(path: pathlib.Path) -> str:
    """The package a manifest must name: its folder's name (msgs/ holds bearing_msgs)."""
    return "bearing_msgs" if path.parent.name == "msgs" else path.parent.name


WORKSPACE = {package_name(path) for path in MANIFESTS}


def imported_modules(package_dir: pathlib.Path) -> set:
    """Top-level modules imported (absolutely) by the package's Python files, setup.py aside."""
    modules = set()
    for path in package_dir.rglob("*.py"):
        if path.name == "setup.py" or "__pycache__" in path.parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                modules |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                modules.add(node.module.split(".")[0])
    return modules - set(sys.stdlib_module_names) - {"__future__"}


@pytest.mark.parametrize("path", MANIFESTS, ids=lambda p: p.parent.name)
def test_manifest_is_format_3_with_the_fields_of_a_release(path):
    root = read_manifest(path)  # raises on malformed XML, e.g. "--" inside a comment
    assert root.tag == "package" and root.get("format") == "3"
    expected = package_name(path)
    assert root.findtext("name") == expected
    assert (ROOT / "ros_ws" / "src" / expected).resolve() == path.parent.resolve()  # colcon finds it
    for field in ("version", "description", "license"):
        assert (root.findtext(field) or "").strip(), f"{path}: no <{field}>"
    assert root.find("maintainer") is not None and root.find("maintainer").get("email")
    build_type = root.findtext("export/build_type")
    setup = (path.parent / "setup.py").exists()
    assert build_type == ("ament_python" if setup else "ament_cmake")


@pytest.mark.parametrize("path", MANIFESTS, ids=lambda p: p.parent.name)
def test_every_dependency_is_a_rosdep_key(path):
    root = read_manifest(path)
    unknown = dependencies(root, keys.DEPEND_TAGS) - WORKSPACE - keys.ROS_PACKAGES - set(keys.SYSTEM_KEYS)
    assert not unknown, (f"{path}: {sorted(unknown)} are neither workspace packages nor known rosdep keys; "
                         "add each to tools/rosdep_keys.py once checked against rosdep's database")
    assert root.findtext("name") not in dependencies(root, keys.DEPEND_TAGS)


@pytest.mark.parametrize("path", [p for p in MANIFESTS if (p.parent / "setup.py").exists()],
                         ids=lambda p: p.parent.name)
def test_every_import_is_declared_or_a_stated_exception(path):
    root = read_manifest(path)
    declared, stated = dependencies(root, keys.RUN_TAGS), keys.comments(root)
    missing = []
    for module in sorted(imported_modules(path.parent) - {root.findtext("name")}):
        if module in WORKSPACE or keys.import_to_key(module):
            key = module if module in WORKSPACE else keys.import_to_key(module)
            if key not in declared:
                missing.append(f"<exec_depend>{key}</exec_depend> (imports {module})")
        elif module in keys.PYPI_ONLY:
            dist, why = keys.PYPI_ONLY[module]
            if not re.search(rf"\b{re.escape(dist)}\b", stated):
                missing.append(f"a comment naming {dist} (PyPI only: {why})")
        else:
            missing.append(f"{module}: no known rosdep key or exception (tools/rosdep_keys.py)")
    assert not missing, f"{path} needs: " + "; ".join(missing)


@pytest.mark.parametrize("path", [p for p in MANIFESTS if (p.parent / "setup.py").exists()],
                         ids=lambda p: p.parent.name)
def test_setup_installs_every_subpackage(path, monkeypatch):
    """colcon installs only the packages setup.py lists: a subpackage left out works from the
    source tree but is missing from a full install's ``install/`` (ImportError at ``ros2 run``)."""
    import runpy

    import setuptools

    captured = {}
    monkeypatch.setattr(setuptools, "setup", lambda **kwargs: captured.update(kwargs))
    monkeypatch.chdir(path.parent)
    runpy.run_path(str(path.parent / "setup.py"), run_name="__main__")
    name = read_manifest(path).findtext("name")
    on_disk = {".".join(init.parent.relative_to(path.parent).parts)
               for init in (path.parent / name).rglob("__init__.py") if "__pycache__" not in init.parts}
    listed = set(captured["packages"])
    assert listed == on_disk, f"{path.parent / 'setup.py'}: not listed {sorted(on_disk - listed)}, " \
                              f"not on disk {sorted(listed - on_disk)}"
