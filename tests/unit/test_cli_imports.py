"""The command-line tools start like a plain numpy script: rclpy, numba and matplotlib are imported only
where they are used (issue 20). Checked on the import graph (``python -X importtime``), not by timing."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest
from data_paths import REPO_ROOT

HEAVY = ("rclpy", "numba", "matplotlib")


def _cli_modules() -> dict[str, str]:
    """Every ``bearing-*`` console script of the packages: name -> module (the nodes are not CLIs)."""
    found = {}
    for setup in sorted((REPO_ROOT / "src").glob("*/setup.py")):
        for name, module in re.findall(r"""["'](bearing-[\w-]+)\s*=\s*([\w.]+):main["']""", setup.read_text()):
            found[name] = module
    return found


def _imported(*argv: str) -> set[str]:
    """Top-level packages a fresh interpreter imports running ``python -X importtime argv``."""
    done = subprocess.run([sys.executable, "-X", "importtime", *argv], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    names = re.findall(r"^import time:\s+\d+ \|\s+\d+ \|\s*([\w.]+)$", done.stderr, re.M)
    assert names, "no import timings read"
    return {n.split(".")[0] for n in names}


def test_every_cli_is_listed():
    assert {"bearing-diagnose", "bearing-sim", "bearing-identify", "bearing-accuracy", "bearing-bag"} <= set(
        _cli_modules())


@pytest.mark.parametrize("name, module", sorted(_cli_modules().items()))
def test_cli_start_up_imports_no_ros_numba_or_matplotlib(name, module):
    imported = _imported("-m", module, "--help")
    assert "argparse" in imported  # the graph was read
    assert not imported & set(HEAVY), f"{name} --help imports {sorted(imported & set(HEAVY))}"


def test_offline_diagnosis_imports_no_ros_or_matplotlib():
    """What a ``bearing-diagnose`` run imports: the observers' numba kernels, but no ROS and no plotting
    (matplotlib only with --plot)."""
    imported = _imported("-c", "import bearing_diagnoser.batch_diagnosis, bearing_diagnoser.recording_diagnosis, "
                               "bearing_recordings.load, bearing_recordings.mat_files, bearing_recordings.npz_files")
    assert "numba" in imported and "scipy" in imported
    assert not imported & {"rclpy", "matplotlib"}, sorted(imported & {"rclpy", "matplotlib"})


def _node_entry_modules() -> dict[str, str]:
    """Every node executable's console script (the names without ``bearing-``): name -> module."""
    found = {}
    for setup in sorted((REPO_ROOT / "src").glob("*/setup.py")):
        for name, module in re.findall(r"""["']([a-z_]+)\s*=\s*([\w.]+):\w+["']""", setup.read_text()):
            found[name] = module
    return found


@pytest.mark.parametrize("name, module", sorted(_node_entry_modules().items()))
def test_a_node_executable_handles_stop_signals_before_its_heavy_imports(name, module):
    """Its console script's module imports nothing heavy (not even numpy): the process's stop
    signals are in place (node_main.run_executable) before the node module's imports, seconds
    under load, so that Ctrl-C meanwhile is a stop, not a KeyboardInterrupt traceback."""
    imported = _imported("-c", f"import {module}")
    assert not imported & {*HEAVY, "numpy", "scipy"}, f"{name}: {sorted(imported & {*HEAVY, 'numpy', 'scipy'})}"


def test_every_node_executable_is_listed():
    assert set(_node_entry_modules()) == {"simulator", "observer", "diagnoser", "fleet", "nodes", "live_view"}
