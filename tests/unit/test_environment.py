"""The set-up environment works both ways (tools/bootstrap.py).

* Without sourcing anything: the venv's tools and Python find rclpy, bearing_msgs and the
  workspace packages, and no project hook sets AMENT_PREFIX_PATH or LD_LIBRARY_PATH at
  interpreter start (colcon's setup scripts skip any variable the Python running them
  already has, so such a hook would break the next point).
* ``source ros_ws/install/setup.bash`` in a fresh shell (what ros2 CLI users do) gives a
  complete environment: the workspace and the venv's ROS packages on AMENT_PREFIX_PATH,
  bearing_msgs' libraries on LD_LIBRARY_PATH, working node executables.

The shells start from ``env -i`` (nothing inherited); the rclpy parts use an isolated
domain with localhost-only discovery and talk to no other node.
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

import pytest

from bearing_common import ros_env

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
VENV = REPO_ROOT / ".venv"
VENV_PY = VENV / "bin" / "python"
INSTALL = REPO_ROOT / "ros_ws" / "install"

pytestmark = pytest.mark.skipif(not (INSTALL / "setup.bash").is_file() or not VENV_PY.exists(),
                                reason="needs the set-up .venv/ and ros_ws/install (make setup)")

#: Invalid parameters per node executable: each must exit 2 with its parameter error.
BAD_PARAMETERS = {
    ("bearing_sim", "simulator"): ("scenario:=no_such_scenario", "no_such_scenario"),
    ("bearing_observer", "observer"): ("fault_type:=no_such_fault", "no_such_fault"),
    ("bearing_diagnoser", "diagnoser"): ("stale_timeout:=-1.0", "stale_timeout"),
}

PYTHON_CHECK = """
import json, os
import rclpy
import bearing_msgs.msg as m
from ament_index_python.packages import get_package_share_directory
out = {}
out["bearing_bringup"] = get_package_share_directory("bearing_bringup")
out["std_msgs"] = get_package_share_directory("std_msgs")
rclpy.init()
node = rclpy.create_node("environment_check")
pub = node.create_publisher(m.VibrationChunk, "environment_check", 10)
pub.publish(m.VibrationChunk(sample_rate=48000.0, samples=[1.0, 2.0]))
out["published"] = True
node.destroy_node()
rclpy.try_shutdown()
print(json.dumps(out))
"""


def fresh_shell(script: str, timeout: float = 120.0) -> subprocess.CompletedProcess:
    """Run ``script`` in bash started by ``env -i`` (HOME, a minimal PATH and an isolated domain only)."""
    env = {"HOME": os.environ.get("HOME", "/tmp"), "PATH": "/usr/bin:/bin",
           "ROS_DOMAIN_ID": str(100 + os.getpid() % 100), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    cmd = ["env", "-i", *(f"{k}={v}" for k, v in env.items()), "bash", "--noprofile", "--norc", "-c", script]
    return subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True, timeout=timeout)


def test_no_project_hook_sets_environment_variables_at_interpreter_start():
    """Our .pth holds paths only (a line starting with ``import`` would run at start-up), and
    the venv's Python has no AMENT_PREFIX_PATH; its LD_LIBRARY_PATH holds only what the
    wheels' own bootstrapper adds (the venv's lib directories, nothing of ros_ws/)."""
    site = VENV / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    lines = (site / "bearing_ros_ws.pth").read_text().splitlines()
    assert not [line for line in lines if line.startswith("import")]
    proc = fresh_shell(f"{VENV_PY} -c 'import json, os; print(json.dumps(dict(os.environ)))'")
    assert proc.returncode == 0, proc.stderr
    env = json.loads(proc.stdout)
    assert "AMENT_PREFIX_PATH" not in env
    assert "ros_ws" not in env.get("LD_LIBRARY_PATH", "")


def test_venv_tools_work_without_sourcing_anything():
    proc = fresh_shell(f"{VENV}/bin/bearing-diagnose --help && "
                       f"{VENV_PY} -c 'import rclpy, bearing_msgs.msg; print(bearing_msgs.msg.VibrationChunk)'")
    assert proc.returncode == 0, proc.stderr
    assert "usage: bearing-diagnose" in proc.stdout
    assert "VibrationChunk" in proc.stdout


def test_workspace_packages_are_in_the_venvs_ament_index():
    """With AMENT_PREFIX_PATH unset (our lookups) or = the venv (ament_index_python)."""
    ours = ("from bearing_common import ros_env as r; "
            "print(r.package_share_directory('bearing_bringup')); print(r.executable('bearing_sim', 'simulator'))")
    ament = ("from ament_index_python.packages import get_package_share_directory as g; "
             "print(g('bearing_bringup')); print(g('bearing_msgs'))")
    proc = fresh_shell(f'{VENV_PY} -c "{ours}" && AMENT_PREFIX_PATH={VENV} {VENV_PY} -c "{ament}"')
    assert proc.returncode == 0, proc.stderr
    share, exe, share2, msgs = proc.stdout.split()
    assert share == share2 == str(VENV / "share" / "bearing_bringup")
    assert exe == str(VENV / "lib" / "bearing_sim" / "simulator")
    assert (VENV / "share" / "bearing_bringup" / "config" / "monitor.yaml").is_file()
    assert msgs == str(VENV / "share" / "bearing_msgs")


def test_sourced_setup_bash_gives_a_complete_environment():
    """The shell's own variables (what the ros2 CLI and any process started from it get),
    then the venv's Python in that shell."""
    check = PYTHON_CHECK.replace("'", "'\\''")
    proc = fresh_shell('source ros_ws/install/setup.bash && printf "%s\\n" "$AMENT_PREFIX_PATH" "$LD_LIBRARY_PATH" && '
                       f"{VENV_PY} -c '{check}'")
    assert proc.returncode == 0, proc.stderr
    ament_prefix_path, ld_library_path, *_, last = proc.stdout.strip().splitlines()
    prefixes = ament_prefix_path.split(os.pathsep)
    assert str(INSTALL / "bearing_msgs") in prefixes and str(INSTALL / "bearing_bringup") in prefixes
    assert str(VENV) in prefixes
    assert str(INSTALL / "bearing_msgs" / "lib") in ld_library_path.split(os.pathsep)
    out = json.loads(last)
    assert out["bearing_bringup"] == str(INSTALL / "bearing_bringup" / "share" / "bearing_bringup")
    assert out["std_msgs"] == str(VENV / "share" / "std_msgs")
    assert out["published"]


@pytest.mark.parametrize(("package", "executable"), sorted(BAD_PARAMETERS))
def test_installed_node_executables_start_in_a_sourced_shell(package, executable):
    """A node started as ``ros2 run`` would (the installed executable) gets as far as its
    parameters: an invalid one gives the parameter error and exit 2, not an import error."""
    param, expected = BAD_PARAMETERS[package, executable]
    path = INSTALL / package / "lib" / package / executable
    proc = fresh_shell(f"source ros_ws/install/setup.bash && {path} --ros-args -p {param}")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert expected in proc.stderr and proc.stderr.startswith(f"{executable}: "), proc.stderr
    assert "Traceback" not in proc.stderr


def test_ros_distro_matches_the_installed_rclpy():
    from importlib import metadata
    distro = ros_env.ros_distro()
    assert distro in ("jazzy", "kilted")
    assert int(metadata.version("ros-rclpy").split(".")[0]) == {"jazzy": 7, "kilted": 9}[distro]
