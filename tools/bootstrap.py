"""Set up everything `make demo` and `make test` need, idempotently.

Steps (each skipped when its inputs are unchanged since it last succeeded):

1. ``.venv/``: a virtual environment of this Python (3.11) for one ROS 2 distribution:
   ``$ROS_DISTRO`` (``jazzy``, the default, or ``kilted``). A venv set up for another
   distribution is removed with ``ros_ws/build``, ``install`` and ``log``, and rebuilt.
2. ``requirements/ros-<distro>.txt`` (which includes ``requirements/base.txt``): ROS 2
   from the PyPI wheels, colcon, numpy, scipy, control, ...
3. the wheels' CMake path fix (``tools/fix_ros_wheel_cmake.py``).
4. the venv as a ROS 2 parent prefix: ``.venv/local_setup.{sh,bash}`` put it on
   AMENT_PREFIX_PATH; colcon chains them from ``ros_ws/install/setup.bash``.
5. ``colcon build`` of ``ros_ws/`` (bearing_msgs and the Python packages).
6. the workspace registered in the venv, so that the venv's tools work without sourcing
   anything: its site-packages directories on sys.path (``bearing_ros_ws.pth``, paths
   only), bearing_msgs' libraries in ``.venv/lib`` (the wheels' bootstrapper puts that
   directory on LD_LIBRARY_PATH), its packages in the venv's ament index
   (``.venv/share/...``, ``.venv/lib/<pkg>``) and the ``bearing-*`` tools in ``.venv/bin``.
   No environment variable is set at interpreter start by this project, so a sourced
   ``ros_ws/install/setup.bash`` is complete too.

Run with the system Python: ``python3 tools/bootstrap.py``. A failing step is
named with its command and the relevant part of its log (``out/setup-logs/``), and the
exit code is non-zero.
"""

from __future__ import annotations

import hashlib
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
VENV = ROOT / ".venv"
VENV_PY = VENV / "bin" / "python"
WS = ROOT / "ros_ws"
WS_INSTALL = WS / "install"
STAMPS = VENV / ".bootstrap-stamps"
LOGS = ROOT / "out" / "setup-logs"
REQUIREMENTS = ROOT / "requirements"
PY_TAG = f"python{sys.version_info.major}.{sys.version_info.minor}"
SOURCE_DIRS = [ROOT / "src", ROOT / "msgs"]
#: The ROS 2 distributions the project installs (``requirements/ros-<name>.txt``); the first is the default.
DISTROS = ("jazzy", "kilted")
#: Console scripts named ``bearing-*`` (the packages' setup.py entry points) are the
#: command-line tools linked into .venv/bin; node executables (simulator, ...) are not.
TOOL_PREFIX = "bearing-"
#: Variables of the caller's shell that must not leak into the build (a sourced full
#: ROS 2 install or workspace would chain its prefixes or shadow the venv's libraries).
BUILD_ENV_DROP = ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH", "PYTHONPATH",
                  "LD_LIBRARY_PATH", "_ROS_WHEELS_BOOTSTRAP_COMPLETE")
#: A line of a failed step's log where the error starts (shown before the log's tail).
ERROR_LINE = re.compile(r"CMake Error|error:|ERROR:|Error:|Traceback \(most recent call last\)")


class StepFailed(RuntimeError):
    """A setup step failed; the message says which and why."""


def say(msg: str) -> None:
    print(f"[setup] {msg}", flush=True)


def digest(*parts: bytes) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(part)
    return h.hexdigest()


def tree_digest(dirs, base: pathlib.Path = ROOT) -> str:
    """Hash of every file (path relative to ``base``, and content) below ``dirs``, caches excluded."""
    h = hashlib.sha256()
    for top in dirs:
        for path in sorted(top.rglob("*")):
            if "__pycache__" in path.parts or path.suffix in {".pyc", ".nbi", ".nbc"}:
                continue
            if path.is_file():
                h.update(str(path.relative_to(base)).encode())
                h.update(path.read_bytes())
    return h.hexdigest()


def done(step: str, key: str) -> bool:
    stamp = STAMPS / step
    return stamp.exists() and stamp.read_text() == key


def mark(step: str, key: str) -> None:
    STAMPS.mkdir(parents=True, exist_ok=True)
    (STAMPS / step).write_text(key)


def log_excerpt(text: str, tail: int = 25, context: int = 30) -> str:
    """The first error of a log (``context`` lines from it) and its last ``tail`` lines."""
    lines = text.splitlines(keepends=True)
    first = next((i for i, line in enumerate(lines) if ERROR_LINE.search(line)), None)
    if first is None or first >= len(lines) - tail:
        return "".join(lines[-tail:])
    head = lines[first:min(first + context, len(lines) - tail)]
    return "".join(head) + "[...]\n" + "".join(lines[-tail:])


def run(step: str, cmd, env=None, cwd=ROOT) -> None:
    """Run ``cmd`` with its whole output in ``out/setup-logs/<step>.log``; raise StepFailed with the error."""
    LOGS.mkdir(parents=True, exist_ok=True)
    log = LOGS / f"{step}.log"
    start = time.monotonic()
    with open(log, "w") as fh:
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
        for line in proc.stdout:
            fh.write(line)
            if line.startswith(("Starting >>>", "Finished <<<", "Failed", "Successfully installed")):
                say(f"  {line.rstrip()[:160]}")
        rc = proc.wait()
    if rc != 0:
        raise StepFailed(f"step '{step}' failed (exit {rc}): {' '.join(map(str, cmd))}\n"
                         f"--- from {log} (the whole output) ---\n{log_excerpt(log.read_text())}")
    say(f"  {step} took {time.monotonic() - start:.0f} s")


def requested_distro() -> str:
    """``$ROS_DISTRO`` (one of :data:`DISTROS`), else the default, Jazzy."""
    distro = os.environ.get("ROS_DISTRO", "").strip().lower() or DISTROS[0]
    if distro not in DISTROS:
        raise StepFailed(f"ROS_DISTRO={distro!r} is not supported: choose one of {', '.join(DISTROS)} "
                         f"(requirements/ros-<distro>.txt; unset means {DISTROS[0]})")
    return distro


def requirements_file(distro: str) -> pathlib.Path:
    return REQUIREMENTS / f"ros-{distro}.txt"


def requirement_files(path: pathlib.Path) -> list:
    """``path`` and every file it includes with ``-r`` (recursively), in order."""
    files = [path]
    for line in path.read_text().splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0] in ("-r", "--requirement"):
            files += requirement_files((path.parent / parts[1]).resolve())
    return files


def built_for() -> str | None:
    """The distribution ``.venv/`` was set up for (None: unknown, e.g. made before the switch existed)."""
    stamp = STAMPS / "distro"
    return stamp.read_text().strip() if stamp.exists() else None


def remove_build_products() -> None:
    for tree in ("build", "install", "log"):
        shutil.rmtree(WS / tree, ignore_errors=True)


def make_venv(distro: str) -> None:
    if VENV.exists() and built_for() != distro:
        say(f"ROS 2 {distro} requested, but .venv/ was set up for {built_for() or 'an unknown distribution'}: "
            f"removing .venv/ and ros_ws/build, install, log to rebuild them for {distro}")
        shutil.rmtree(VENV)
    if VENV_PY.exists():
        say(f"1/6 .venv/ for ROS 2 {distro}: exists")
        return
    if sys.version_info[:2] != (3, 11):
        raise StepFailed(f"step 'venv' needs Python 3.11 (the ROS 2 wheels are cp311), "
                         f"this is {sys.version.split()[0]}")
    say(f"1/6 creating .venv/ for ROS 2 {distro}")
    shutil.rmtree(VENV, ignore_errors=True)
    remove_build_products()  # ros_ws/build and install belong to one venv
    run("venv", [sys.executable, "-m", "venv", str(VENV)])
    run("pip-upgrade", [str(VENV_PY), "-m", "pip", "install", "-q", "--upgrade", "pip"])
    mark("distro", distro)


def install_requirements(distro: str) -> None:
    req = requirements_file(distro)
    key = digest(*(f.read_bytes() for f in requirement_files(req)), sys.version.encode())
    if done("requirements", key):
        say(f"2/6 {req.relative_to(ROOT)}: up to date")
        return
    say(f"2/6 installing {req.relative_to(ROOT)} into .venv (first time: a few minutes)")
    run("requirements", [str(VENV_PY), "-m", "pip", "install", "--disable-pip-version-check", "-r", str(req)])
    mark("requirements", key)
    (STAMPS / "cmake-fix").unlink(missing_ok=True)


def fix_cmake() -> None:
    key = (STAMPS / "requirements").read_text()
    if done("cmake-fix", key):
        say("3/6 wheel CMake path fix: already applied")
        return
    say("3/6 fixing the ROS wheels' CMake paths")
    run("cmake-fix", [str(VENV_PY), str(ROOT / "tools" / "fix_ros_wheel_cmake.py")])
    mark("cmake-fix", key)


def venv_local_setup() -> None:
    """Write ``.venv/local_setup.sh`` and ``.bash``: the venv as a prefix colcon chains.

    colcon (colcon-ros) chains every AMENT_PREFIX_PATH entry holding a ``local_setup.*``
    file into the ``setup.*`` scripts it generates; the build runs with
    AMENT_PREFIX_PATH=.venv, so ``source ros_ws/install/setup.bash`` first sources this
    file, which puts the venv (the wheels' ROS packages, e.g. std_msgs) on AMENT_PREFIX_PATH.
    Nothing else: the venv's Python finds its libraries by itself, and a full ROS 2
    install's tools must not load the venv's libraries.
    """
    say("4/6 .venv/local_setup.sh, .bash (the venv as a parent prefix of ros_ws/install)")
    script = (
        "# Generated by tools/bootstrap.py. This venv is a ROS 2 prefix (the PyPI wheels' packages;\n"
        "# the ros_ws/ packages are registered in its ament index). colcon chains this file from\n"
        "# ros_ws/install/setup.sh and setup.bash: it puts the venv on AMENT_PREFIX_PATH.\n"
        f"_bearing_venv='{VENV}'\n"
        'case ":${AMENT_PREFIX_PATH:-}:" in\n'
        '  *":${_bearing_venv}:"*) ;;\n'
        '  *) AMENT_PREFIX_PATH="${_bearing_venv}${AMENT_PREFIX_PATH:+:${AMENT_PREFIX_PATH}}"\n'
        "     export AMENT_PREFIX_PATH ;;\n"
        "esac\n"
        "unset _bearing_venv\n"
    )
    for name in ("local_setup.sh", "local_setup.bash"):
        (VENV / name).write_text(script)


def colcon_build() -> None:
    local_setup = (VENV / "local_setup.sh").read_bytes()
    key = digest(tree_digest(SOURCE_DIRS).encode(), (STAMPS / "requirements").read_text().encode(), local_setup)
    if done("colcon", key) and (WS_INSTALL / "setup.bash").exists():
        say("5/6 colcon build: sources unchanged")
        return
    say("5/6 colcon build in ros_ws/")
    (STAMPS / "colcon").unlink(missing_ok=True)  # a failed build leaves the install space incomplete
    unlink_workspace()  # the build sees the wheels' prefix only, not an older build of itself
    clear_python_packages()
    env = {k: v for k, v in os.environ.items() if k not in BUILD_ENV_DROP}
    env.update(AMENT_PREFIX_PATH=str(VENV), CMAKE_PREFIX_PATH=str(VENV), VIRTUAL_ENV=str(VENV),
               PATH=f"{VENV / 'bin'}{os.pathsep}{env.get('PATH', '')}")
    # console_direct (on by default) sends every package's output, CMake errors included,
    # to out/setup-logs/colcon.log; the console shows the start and end lines only.
    run("colcon", [str(VENV / "bin" / "colcon"), "build"], env=env, cwd=WS)
    drop_numba_caches()
    mark("colcon", key)


def clear_python_packages() -> None:
    """Remove the build and install trees of the ament_python packages before a rebuild.

    colcon copies Python files into the install space and never deletes one whose source
    was removed or moved, so a stale module could still be imported. They rebuild in
    about a second each; bearing_msgs (CMake, slow) is kept.
    """
    for setup_py in (ROOT / "src").glob("*/setup.py"):
        for tree in ("build", "install"):
            shutil.rmtree(WS / tree / setup_py.parent.name, ignore_errors=True)


def drop_numba_caches() -> None:
    """Delete numba's on-disk caches in the install space after a rebuild.

    numba keys a cached function on its own source file only, so a cached
    integrator would keep calling an old right-hand side from another module.
    """
    for path in WS_INSTALL.rglob("__pycache__/*.nb[ic]"):
        path.unlink()


def workspace_links():
    """Every symbolic link in the venv that points into ``ros_ws/install``."""
    places = [VENV / "bin", VENV / "lib", VENV / "share"]
    places += [p for p in (VENV / "share" / "ament_index" / "resource_index").glob("*") if p.is_dir()]
    for place in places:
        if not place.is_dir():
            continue
        for path in place.iterdir():
            if path.is_symlink() and pathlib.Path(os.readlink(path)).is_relative_to(WS_INSTALL):
                yield path


def unlink_workspace() -> None:
    for link in list(workspace_links()):
        link.unlink()
    (VENV / "lib" / PY_TAG / "site-packages" / "bearing_ros_ws.pth").unlink(missing_ok=True)


def link(path: pathlib.Path, target: pathlib.Path) -> None:
    if path.is_symlink():
        path.unlink()
    elif path.exists():
        raise StepFailed(f"step 'link': {path} exists in the venv and is not ours; not replacing it with "
                         f"a link to {target}")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.symlink_to(target)


def link_workspace() -> None:
    """Register the built workspace in the venv, so that nothing needs sourcing.

    - ``bearing_ros_ws.pth``: each package's site-packages directory on sys.path (paths only);
    - bearing_msgs' shared libraries linked into ``.venv/lib``, which the wheels' own
      bootstrapper puts on LD_LIBRARY_PATH when the venv's Python starts;
    - every package's ament index entries, ``share/<pkg>`` and ``lib/<pkg>`` (the node
      executables) linked into the venv, so that with AMENT_PREFIX_PATH unset or = .venv
      the packages are found in the venv's prefix (``bearing_common.ros_env``);
    - the ``bearing-*`` console scripts linked into ``.venv/bin``.
    """
    say("6/6 registering ros_ws/install in .venv")
    unlink_workspace()
    packages = sorted(p for p in WS_INSTALL.iterdir() if (p / "share" / "ament_index").is_dir())
    site = VENV / "lib" / PY_TAG / "site-packages"
    paths = sorted(str(p) for p in WS_INSTALL.glob(f"*/lib/{PY_TAG}/site-packages"))
    (site / "bearing_ros_ws.pth").write_text(
        "# sys.path entries of the ros_ws/ packages (tools/bootstrap.py); paths only, no code\n"
        + "".join(f"{p}\n" for p in paths))
    libraries = []
    for prefix in packages:
        name = prefix.name
        for lib in sorted((prefix / "lib").glob("*.so*")):
            link(VENV / "lib" / lib.name, lib)
            libraries.append(lib.name)
        for entry in sorted((prefix / "share" / "ament_index" / "resource_index").glob("*/*")):
            link(VENV / "share" / "ament_index" / "resource_index" / entry.parent.name / entry.name, entry)
        if (prefix / "share" / name).is_dir():
            link(VENV / "share" / name, prefix / "share" / name)
        if (prefix / "lib" / name).is_dir():
            link(VENV / "lib" / name, prefix / "lib" / name)
    tools = sorted(WS_INSTALL.glob(f"*/lib/*/{TOOL_PREFIX}*"))
    for target in tools:
        link(VENV / "bin" / target.name, target)
    say(f"  packages: {', '.join(p.name for p in packages)}; {len(libraries)} libraries")
    say(f"  tools: {', '.join(t.name for t in tools)}")


def main() -> int:
    start = time.monotonic()
    try:
        distro = requested_distro()
        make_venv(distro)
        install_requirements(distro)
        fix_cmake()
        venv_local_setup()
        colcon_build()
        link_workspace()
    except StepFailed as exc:
        print(f"[setup] FAILED: {exc}", file=sys.stderr, flush=True)
        return 1
    say(f"ready (ROS 2 {distro}) in {time.monotonic() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
