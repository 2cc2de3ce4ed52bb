"""A stand-in for a full ROS 2 Jazzy install, and ``ros_ws/`` built in it as its users build it.

A user of a full install has ``/opt/ros/jazzy`` (the ROS 2 packages and the real ``ros2``
command line), installs with rosdep the system packages our package.xml files name, and runs
``colcon build`` in ``ros_ws/``. The real-CLI tests (``tests/ros/test_ros2_cli.py``) do the same:

1. ``out/ros2-cli/``: the real Jazzy command line that ``../shared/ros2-cli/build.sh`` builds over
   the PyPI wheels; its ``bin/ros2-env`` stands for ``/opt/ros/jazzy/setup.bash``. Its Python gets
   what rosdep would install for the manifests' run-time keys, plus the PyPI-only exceptions they
   state (``tools/rosdep_keys.py``), at the pins of ``requirements/base.txt``. Nothing of the
   project's ``.venv/`` takes part: not its Python, its ``.pth`` files nor its ament index.
2. ``out/full-install/``: a copy of ``src/``, ``msgs/`` and ``ros_ws/src/`` (its links), built in a
   fresh shell with docs/install.md's commands, ``source <ros2-env>`` then ``cd ros_ws && colcon build``.

Each step is redone only when its inputs changed (stamps hold their hash): the ros2-cli sources,
``build.sh`` and its pins, the pins and keys of step 1's packages and this file (1); those and
the workspace's sources (2). Measured on 2 shared cores: 3.5-5.5 min for step 1, 3.4 min for
step 2 (bearing_msgs' C/C++ type support: 2.6 min). Logs: ``out/setup-logs/full-install-*.log``.

    python3 tools/full_ros_install.py      # prints the prefix and the workspace; exit 3 without ros2-cli
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
import shlex
import shutil
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import bootstrap  # noqa: E402 (tools/ is no package: the set-up helpers beside this file)
import rosdep_keys  # noqa: E402

ROOT = bootstrap.ROOT
CLI_SOURCES = ROOT.parent / "shared" / "ros2-cli"
PREFIX = ROOT / "out" / "ros2-cli"
WORKSPACE = ROOT / "out" / "full-install"
LOGS = bootstrap.LOGS
STAMP_NAME = ".bearing-full-install"
#: What a fresh login shell must not inherit from this process: a sourced workspace or ROS
#: install, the project venv (its Python re-executes with the wheels' LD_LIBRARY_PATH).
DROP_PREFIXES = ("AMENT_", "COLCON_", "ROS_", "RMW_", "RCUTILS_", "CMAKE_PREFIX_PATH")
DROP = (*bootstrap.BUILD_ENV_DROP, "VIRTUAL_ENV", "PYTHONHOME", "PYTHONUNBUFFERED")


@dataclasses.dataclass(frozen=True)
class FullInstall:
    """Where the stand-in lives: ``prefix`` (for /opt/ros/jazzy) and ``root`` (holds ros_ws/)."""

    prefix: pathlib.Path
    root: pathlib.Path

    @property
    def setup(self) -> pathlib.Path:
        """The script that stands for ``/opt/ros/jazzy/setup.bash``."""
        return self.prefix / "bin" / "ros2-env"

    def shell(self, command: str) -> list:
        """argv of a fresh bash in ``root`` that sources the install and the workspace, then runs ``command``."""
        return ["bash", "--noprofile", "--norc", "-c", f"cd {shlex.quote(str(self.root))} && "
                f"source {shlex.quote(str(self.setup))} && source ros_ws/install/setup.bash && {command}"]


def fresh_env(extra: dict | None = None) -> dict:
    """This process's environment as a new login shell has it: no ROS, workspace or venv variables,
    no ``.venv/bin`` on PATH; then ``extra``."""
    env = {k: v for k, v in os.environ.items() if k not in DROP and not k.startswith(DROP_PREFIXES)}
    venv = str(bootstrap.VENV)
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if p and not p.startswith(venv))
    env.update(extra or {})
    return env


def cli_missing() -> str | None:
    """Why the real command line cannot be built here, or None."""
    if not (CLI_SOURCES / "build.sh").is_file():
        return (f"the real ros2 command line's sources are not at {CLI_SOURCES} "
                "(../shared/ros2-cli beside the repository)")
    return None


def base_pins() -> dict:
    """requirements/base.txt's ``name==version`` lines by lower-case distribution name."""
    pins = {}
    for line in (bootstrap.REQUIREMENTS / "base.txt").read_text().splitlines():
        spec = line.split("#")[0].strip()
        if "==" in spec:
            pins[spec.split("==")[0].strip().lower()] = spec
    return pins


def system_distributions() -> list:
    """PyPI distributions standing for what rosdep installs for the manifests' run-time system keys,
    and the stated PyPI-only exceptions (with what their pins need)."""
    manifests = [*ROOT.glob("src/*/package.xml"), ROOT / "msgs" / "package.xml"]
    keys = set().union(*(rosdep_keys.dependencies(rosdep_keys.read_manifest(p), rosdep_keys.RUN_TAGS)
                         for p in manifests))
    dists = {dist for key, (_module, dist) in rosdep_keys.SYSTEM_KEYS.items() if key in keys}
    for module, (dist, _why) in rosdep_keys.PYPI_ONLY.items():
        dists |= {dist, *rosdep_keys.PINNED_WITH.get(module, ())}
    return sorted(dists, key=str.lower)


def pinned(dists: list) -> list:
    pins = base_pins()
    missing = [d for d in dists if d.lower() not in pins]
    if missing:
        raise bootstrap.StepFailed(f"step 'full-install': {missing} have no pin in requirements/base.txt")
    return [pins[d.lower()] for d in dists]


def cli_key() -> str:
    parts = [bootstrap.tree_digest([CLI_SOURCES], base=CLI_SOURCES).encode()]
    parts += [line.encode() for line in pinned(system_distributions())]
    parts += [pathlib.Path(__file__).read_bytes(), pathlib.Path(rosdep_keys.__file__).read_bytes()]
    return bootstrap.digest(*parts)


def workspace_key(cli: str) -> str:
    links = sorted(f"{p.name}->{os.readlink(p)}" for p in (ROOT / "ros_ws" / "src").iterdir())
    return bootstrap.digest(cli.encode(), bootstrap.tree_digest([ROOT / "src", ROOT / "msgs"]).encode(),
                            "\n".join(links).encode())


def stamped(directory: pathlib.Path, key: str) -> bool:
    stamp = directory / STAMP_NAME
    return stamp.is_file() and stamp.read_text() == key


def build_cli(key: str) -> None:
    """Step 1: build.sh into a new PREFIX, then the system packages into its Python."""
    bootstrap.say(f"full install 1/2: the real ros2 command line into {PREFIX.relative_to(ROOT)} (a few minutes)")
    shutil.rmtree(PREFIX, ignore_errors=True)
    env = fresh_env({"PYTHON": sys._base_executable})
    bootstrap.run("full-install-ros2-cli", ["bash", str(CLI_SOURCES / "build.sh"), str(PREFIX)], env=env)
    specs = pinned(system_distributions())
    python = PREFIX / "venv" / "bin" / "python"
    have = subprocess.run([str(python), "-c", "import importlib.metadata as m; "
                           "print('\\n'.join(d.metadata['Name'].lower() for d in m.distributions()))"],
                          capture_output=True, text=True, check=True, env=env).stdout.split()
    wanted = [s for s in specs if s.split("==")[0].lower() not in have]  # the system has the others already
    bootstrap.say(f"  system packages (rosdep's part): {', '.join(wanted)}")
    bootstrap.run("full-install-system-packages", [str(python), "-m", "pip", "install", *wanted], env=env)
    (PREFIX / STAMP_NAME).write_text(key)


def build_workspace(install: FullInstall, key: str) -> None:
    """Step 2: a copy of the workspace, built by colcon in a fresh shell of the stand-in."""
    bootstrap.say(f"full install 2/2: colcon build in {WORKSPACE.relative_to(ROOT)}/ros_ws (a few minutes)")
    shutil.rmtree(WORKSPACE, ignore_errors=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")
    for tree in ("src", "msgs", "ros_ws/src"):
        shutil.copytree(ROOT / tree, WORKSPACE / tree, symlinks=True, ignore=ignore)
    command = ["bash", "--noprofile", "--norc", "-c",
               f"source {shlex.quote(str(install.setup))} && cd ros_ws && colcon build"]
    bootstrap.run("full-install-colcon", command, env=fresh_env(), cwd=WORKSPACE)
    (WORKSPACE / STAMP_NAME).write_text(key)


def ensure() -> FullInstall:
    """Build what is out of date; return where the stand-in is (StepFailed on a failed step)."""
    install = FullInstall(PREFIX, WORKSPACE)
    key = cli_key()
    if stamped(PREFIX, key) and (PREFIX / "bin" / "ros2").exists():
        bootstrap.say("full install 1/2: the real ros2 command line is up to date")
    else:
        (WORKSPACE / STAMP_NAME).unlink(missing_ok=True)
        build_cli(key)
    ws_key = workspace_key(key)
    if stamped(WORKSPACE, ws_key):
        bootstrap.say("full install 2/2: the workspace build is up to date")
    else:
        build_workspace(install, ws_key)
    return install


def main() -> int:
    reason = cli_missing()
    if reason:
        print(f"[setup] full install skipped: {reason}", flush=True)
        return 3
    start = time.monotonic()
    try:
        install = ensure()
    except bootstrap.StepFailed as exc:
        print(f"[setup] FAILED: {exc}", file=sys.stderr, flush=True)
        return 1
    bootstrap.say(f"full install ready in {time.monotonic() - start:.0f} s: source {install.setup}, "
                  f"then {install.root / 'ros_ws' / 'install' / 'setup.bash'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
