"""Set up everything `make demo` and `make test` need, idempotently.

Steps (each skipped when its inputs are unchanged since it last succeeded):

1. ``.venv/``: a virtual environment of this Python (3.11).
2. ``requirements.txt``: ROS 2 Kilted from the PyPI wheels, numpy, scipy, control, ...
3. the wheels' CMake path fix (``tools/fix_ros_wheel_cmake.py``).
4. ``colcon build`` of ``ros_ws/`` (bearing_msgs and the Python packages).
5. the workspace made importable from the venv without sourcing anything
   (``bearing_ros_ws.pth``) and the command-line tools linked into ``.venv/bin/``.

Run with the system Python: ``python3 tools/bootstrap.py``. A failing step is
named with its command and the tail of its log, and the exit code is non-zero.
"""

import hashlib
import os
import pathlib
import shutil
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
VENV = ROOT / ".venv"
VENV_PY = VENV / "bin" / "python"
WS = ROOT / "ros_ws"
STAMPS = VENV / ".bootstrap-stamps"
LOGS = ROOT / "out" / "setup-logs"
PY_TAG = f"python{sys.version_info.major}.{sys.version_info.minor}"
SOURCE_DIRS = [ROOT / "src", ROOT / "msgs"]
#: Console scripts named ``bearing-*`` (the packages' setup.py entry points) are the
#: command-line tools linked into .venv/bin; node executables (simulator, ...) are not.
TOOL_PREFIX = "bearing-"


class StepFailed(RuntimeError):
    """A setup step failed; the message says which and why."""


def say(msg: str) -> None:
    print(f"[setup] {msg}", flush=True)


def digest(*parts: bytes) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(part)
    return h.hexdigest()


def tree_digest(dirs) -> str:
    """Hash of every file (path and content) below ``dirs``, caches excluded."""
    h = hashlib.sha256()
    for top in dirs:
        for path in sorted(top.rglob("*")):
            if "__pycache__" in path.parts or path.suffix in {".pyc", ".nbi", ".nbc"}:
                continue
            if path.is_file():
                h.update(str(path.relative_to(ROOT)).encode())
                h.update(path.read_bytes())
    return h.hexdigest()


def done(step: str, key: str) -> bool:
    stamp = STAMPS / step
    return stamp.exists() and stamp.read_text() == key


def mark(step: str, key: str) -> None:
    STAMPS.mkdir(parents=True, exist_ok=True)
    (STAMPS / step).write_text(key)


def run(step: str, cmd, env=None, cwd=ROOT) -> None:
    """Run ``cmd`` with output teed to a log; raise StepFailed with the log tail."""
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
        tail = "".join(log.read_text().splitlines(keepends=True)[-25:])
        raise StepFailed(f"step '{step}' failed (exit {rc}): {' '.join(map(str, cmd))}\n"
                         f"--- last lines of {log} ---\n{tail}")
    say(f"  {step} took {time.monotonic() - start:.0f} s")


def make_venv() -> None:
    if VENV_PY.exists():
        return
    if sys.version_info[:2] != (3, 11):
        raise StepFailed(f"step 'venv' needs Python 3.11 (the ROS 2 Kilted wheels are cp311), "
                         f"this is {sys.version.split()[0]}")
    say("1/5 creating .venv")
    run("venv", [sys.executable, "-m", "venv", str(VENV)])
    run("pip-upgrade", [str(VENV_PY), "-m", "pip", "install", "-q", "--upgrade", "pip"])


def install_requirements() -> None:
    req = ROOT / "requirements.txt"
    key = digest(req.read_bytes(), sys.version.encode())
    if done("requirements", key):
        say("2/5 requirements: up to date")
        return
    say("2/5 installing requirements.txt into .venv (first time: a few minutes)")
    run("requirements", [str(VENV_PY), "-m", "pip", "install", "--disable-pip-version-check",
                         "-r", str(req)])
    mark("requirements", key)
    (STAMPS / "cmake-fix").unlink(missing_ok=True)


def fix_cmake() -> None:
    key = (STAMPS / "requirements").read_text()
    if done("cmake-fix", key):
        say("3/5 wheel CMake path fix: already applied")
        return
    say("3/5 fixing the ROS wheels' CMake paths")
    run("cmake-fix", [str(VENV_PY), str(ROOT / "tools" / "fix_ros_wheel_cmake.py")])
    mark("cmake-fix", key)


def colcon_build() -> None:
    key = digest(tree_digest(SOURCE_DIRS).encode(), (STAMPS / "requirements").read_text().encode())
    if done("colcon", key) and (WS / "install" / "setup.bash").exists():
        say("4/5 colcon build: sources unchanged")
        return
    say("4/5 colcon build in ros_ws/")
    clear_python_packages()
    env = dict(os.environ)
    env.update(AMENT_PREFIX_PATH=str(VENV), CMAKE_PREFIX_PATH=str(VENV), VIRTUAL_ENV=str(VENV),
               PATH=f"{VENV / 'bin'}{os.pathsep}{env.get('PATH', '')}")
    run("colcon", [str(VENV / "bin" / "colcon"), "build", "--event-handlers", "console_direct-"],
        env=env, cwd=WS)
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
    for path in (WS / "install").rglob("__pycache__/*.nb[ic]"):
        path.unlink()


def link_workspace() -> None:
    """Make the built workspace usable from the venv without sourcing setup.bash.

    ``bearing_ros_ws.pth`` (processed before the wheels' bootstrapper .pth, which
    re-executes Python with LD_LIBRARY_PATH extended) puts each package's
    site-packages on sys.path and bearing_msgs' shared libraries on
    LD_LIBRARY_PATH; the console scripts colcon installed are linked into .venv/bin.
    """
    say("5/5 linking ros_ws/install into .venv")
    install = WS / "install"
    site = VENV / "lib" / PY_TAG / "site-packages"
    lines = sorted(str(p) for p in install.glob(f"*/lib/{PY_TAG}/site-packages"))
    libs = os.pathsep.join(sorted(str(p) for p in install.glob("*/lib") if any(p.glob("*.so"))))
    prefixes = os.pathsep.join([str(p) for p in sorted(install.iterdir()) if p.is_dir()] + [str(VENV)])
    env_line = (
        "import os; "
        f"_l = {libs!r}; _c = os.environ.get('LD_LIBRARY_PATH', ''); "
        "os.environ['LD_LIBRARY_PATH'] = _c if _l in _c else os.pathsep.join(p for p in (_l, _c) if p); "
        f"os.environ.setdefault('AMENT_PREFIX_PATH', {prefixes!r})"
    )
    (site / "bearing_ros_ws.pth").write_text("\n".join(lines + [env_line]) + "\n")
    tools = sorted(install.glob(f"*/lib/*/{TOOL_PREFIX}*"))
    for target in tools:
        link = VENV / "bin" / target.name
        if link.is_symlink() or link.exists():
            link.unlink()
        link.symlink_to(target)
    say(f"  tools: {', '.join(t.name for t in tools)}")


def main() -> int:
    start = time.monotonic()
    try:
        make_venv()
        install_requirements()
        fix_cmake()
        colcon_build()
        link_workspace()
    except StepFailed as exc:
        print(f"[setup] FAILED: {exc}", file=sys.stderr, flush=True)
        return 1
    say(f"ready in {time.monotonic() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
