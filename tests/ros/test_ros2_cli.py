"""The project used as a user of a full ROS 2 Jazzy install uses it: the real ``ros2`` command line
(launch, run, topic, node, param, interface, pkg) on ``ros_ws/`` built by ``colcon build`` in a
stand-in for ``/opt/ros/jazzy`` (``tools/full_ros_install.py``: ``../shared/ros2-cli`` over the
PyPI wheels, the system packages rosdep would install, nothing of the project's venv).

Every command line here is one of docs/install.md's "With a full ROS 2 install", run in a fresh
bash that sourced the install and ``ros_ws/install/setup.bash``. Skipped, with the reason,
where ``../shared/ros2-cli`` is absent. Stops are Ctrl-C as a terminal sends it: SIGINT to the
launch's process group (launch then sends its own SIGINT to every node), several of them with
the graph starved of CPU and behind real time (``cpu_load``); ``make stops`` repeats that 20 times.
Commands that need no graph share one shell, and the executables start together: the suite's time
goes into the two launches (about 5 minutes on 2 shared cores, besides the one-time build).
"""

from __future__ import annotations

import configparser
import os
import pathlib
import re
import signal
import subprocess
import time

import pytest
import yaml
from cpu_load import group_pids, native_stacks, one_core, starved
from foxglove_client import FoxgloveClient
from mcap_ros2._dynamic import generate_dynamic
from ros_harness import REPO_ROOT, session_domain_id
from test_bag_record_play import write_play_bag

from bearing_bringup.process_group import ProcessGroup
from bearing_common import topics
from tools import full_ros_install

pytestmark = pytest.mark.ros

SATURATE_S = 1.0  # s of starvation after the simulator fell behind real time, before Ctrl-C
FLEET_STOPS = 10  # Ctrl-C to the fleet launch, half of them with SIGINT inherited ignored
STALL_PROBE_S = 3.0  # s after Ctrl-C, and every 3 s on: whatever still runs has its native stacks printed
STOP_TIMEOUT_S = 30.0  # s from Ctrl-C to the launch's exit, at most
STOPS = int(os.environ.get("BEARING_STOPS", "0"))  # more saturated stops than the monitor test's (`make stops`: 20)
TOOL_PREFIX = "bearing-"  # console scripts named bearing-* are command-line tools, the others nodes
#: How `ros2 run` starts each node executable here, and the nodes it must then show in `ros2 node list`.
NODE_RUNS = {
    ("bearing_sim", "simulator"): ("", ["/simulator"]),  # default scenario: normal operation, no end
    ("bearing_observer", "observer"): ("--ros-args -p fault_type:=inner_race", ["/ir_observer"]),
    ("bearing_diagnoser", "diagnoser"): ("", ["/diagnoser"]),
    ("bearing_fleet", "fleet"): ("", ["/fleet"]),
    ("bearing_live_view", "live_view"): ("--ros-args -p port:=0", ["/live_view"]),  # any free port
    ("bearing_bringup", "nodes"): ("/cell_9/or_observer /cell_9/diagnoser",
                                   ["/cell_9/or_observer", "/cell_9/diagnoser"]),
}
NEXT = "=== next command ==="  # between the outputs of commands run in one shell (Shell.ok_each)
FAULT_SEEN = "state OUTER_RACE"  # the diagnoser's log line when it decides an outer-race fault


@pytest.fixture(scope="module")
def install():
    """The full install, built if out of date; the ros2 daemon its commands started is stopped at the end."""
    if not os.environ.get("BEARING_REAL_CLI"):
        pytest.skip("the real-CLI tests run with `make cli-test` (they build the full install first: 8 min)")
    reason = full_ros_install.cli_missing()
    if reason:
        pytest.skip(reason)
    try:
        built = full_ros_install.ensure()
    except full_ros_install.bootstrap.StepFailed as exc:
        pytest.fail(str(exc))
    yield built
    Shell(built).run("ros2 daemon stop", timeout=30.0)


class Shell:
    """Fresh shells of the full install in one isolated DDS domain; everything started is stopped."""

    def __init__(self, install: full_ros_install.FullInstall):
        self.install = install
        self.env = full_ros_install.fresh_env({"ROS_DOMAIN_ID": str(session_domain_id()),
                                               "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
        self.processes = ProcessGroup(env=self.env, echo=False)

    def run(self, command: str, timeout: float = 60.0) -> tuple[int, str]:
        """Run ``command`` to its end: (exit code, output). Past ``timeout`` it gets Ctrl-C and fails."""
        proc = subprocess.Popen(self.install.shell(command), cwd=self.install.root, env=self.env, text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                process_group=0)
        try:
            out, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGINT)  # rclpy tools ignore SIGTERM
            try:
                out, _ = proc.communicate(timeout=5.0)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                out, _ = proc.communicate()
            raise AssertionError(f"`{command}` still running after {timeout} s:\n{out}") from None
        return proc.returncode, out

    def ok(self, command: str, timeout: float = 60.0) -> str:
        code, out = self.run(command, timeout)
        assert code == 0, f"`{command}` exited with {code}:\n{out}"
        return out

    def ok_each(self, commands: list, timeout: float = 120.0) -> list:
        """Run ``commands`` one after the other in one fresh shell, each of them required to succeed:
        their outputs."""
        return self.ok(f" && echo '{NEXT}' && ".join(commands), timeout).split(NEXT + "\n")

    def echo_once(self, topic: str, timeout: float = 60.0) -> dict:
        """``ros2 topic echo --once TOPIC``'s message; run again while the ros2 daemon (started by the
        first command, discovering the graph since) does not know the topic yet, as a user would."""
        deadline = time.monotonic() + timeout
        while True:
            code, out = self.run(f"ros2 topic echo --once {topic}", timeout)
            if code == 0:  # the message, without echo's "A message was lost!!!" notes (tab-indented)
                lines = [line for line in out.split("\n---")[0].splitlines()
                         if not line.startswith(("A message was lost", "\t"))]
                return yaml.safe_load("\n".join(lines))
            assert "does not appear to be published yet" in out and time.monotonic() < deadline, out
            time.sleep(0.5)

    def start(self, name: str, command: str, sigint_ignored: bool = False):
        """Start a long-running ``command`` (``exec``: the shell becomes it) in a process group of its own;
        with ``sigint_ignored`` as a script's background job starts it: SIGINT ignored (inherited)."""
        return self.processes.start(name, self.install.shell(("trap '' INT; " if sigint_ignored else "")
                                                             + f"exec {command}"))

    def wait_for_line(self, member, text: str, timeout: float, after: int = 0) -> None:
        deadline = time.monotonic() + timeout
        while not any(text in line for line in member.lines[after:]):
            assert member.returncode is None, f"{member.name} ended (exit {member.returncode}):\n{tail(member)}"
            assert time.monotonic() < deadline, f"no '{text}' from {member.name} in {timeout} s:\n{tail(member)}"
            time.sleep(0.1)

    def close(self) -> None:
        self.processes.stop()


@pytest.fixture
def shell(install):
    sh = Shell(install)
    try:
        yield sh
    finally:
        sh.close()


def tail(member, n: int = 80) -> str:
    return "\n".join(member.lines[-n:])


def share(install, package: str) -> pathlib.Path:
    return install.root / "ros_ws" / "install" / package / "share" / package


def monitor_params(install, tmp_path, schedule: str, model_set: str = "") -> pathlib.Path:
    """config/monitor.yaml as installed, the simulator on ``schedule`` (e.g. an outer-race fault for 10 min);
    ``model_set``: the observers' and the diagnoser's (default: as installed)."""
    params = yaml.safe_load((share(install, "bearing_bringup") / "config" / "monitor.yaml").read_text())
    params["simulator"]["ros__parameters"].update(schedule=schedule, scenario="")
    for node in ("or_observer", "ir_observer", "diagnoser"):
        if model_set:
            params[node]["ros__parameters"]["model_set"] = model_set
    path = tmp_path / "monitor.yaml"
    path.write_text(yaml.safe_dump(params))
    return path


def saturated_ctrl_c(launch) -> tuple:
    """Starve the launch and its nodes (one core, busy processes: as many as it takes) until the
    simulator is behind real time, then Ctrl-C; return (the seconds until launch exited, the number
    of busy loops). The native stacks of whatever still runs are printed every ``STALL_PROBE_S``
    after Ctrl-C (a stop that stalls says where, in C too)."""
    core, seen = one_core(), len(launch.lines)
    pgid = os.getpgid(launch.process.pid)
    behind = lambda: any("falling behind real time" in line for line in launch.lines[seen:])  # noqa: E731
    with starved(core, lambda: group_pids(pgid), behind) as loops:
        time.sleep(SATURATE_S)
        os.killpg(pgid, signal.SIGINT)
        sent = time.monotonic()
        while launch.process.poll() is None and time.monotonic() - sent < STOP_TIMEOUT_S:
            try:
                launch.process.wait(timeout=STALL_PROBE_S)
            except subprocess.TimeoutExpired:
                print(f"still running {time.monotonic() - sent:.1f} s after Ctrl-C:\n"  # noqa: T201
                      f"{native_stacks(group_pids(pgid))}")
        wait_for_exit(launch)
        took = time.monotonic() - sent
        busy = len(loops)
    assert_finished_cleanly(launch)
    return took, busy


def ctrl_c(launch) -> None:
    os.killpg(os.getpgid(launch.process.pid), signal.SIGINT)
    wait_for_exit(launch)
    assert_finished_cleanly(launch)


def wait_for_exit(launch, timeout: float = STOP_TIMEOUT_S) -> None:
    try:
        launch.process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        raise AssertionError(f"launch still running {timeout} s after Ctrl-C:\n{tail(launch, 200)}") from None


def assert_finished_cleanly(launch) -> None:
    """launch exited 0 and says of every process it started that it finished cleanly."""
    launch.reader.join(timeout=5.0)
    text = "\n".join(launch.lines)
    started = re.findall(r"\[INFO\] \[([\w.-]+)\]: process started with pid", text)
    cleanly = re.findall(r"\[INFO\] \[([\w.-]+)\]: process has finished cleanly", text)
    assert started, text
    assert sorted(cleanly) == sorted(started), f"started {started}, finished cleanly {cleanly}:\n{text}"
    for bad in ("process has died", "Timeout (", "Traceback"):
        assert bad not in text, f"launch output has '{bad}':\n{text}"
    assert launch.returncode == 0, text


def test_colcon_build_registers_every_package_and_message(install, shell):
    """Every package is a ROS package of the install (a manifest colcon cannot parse makes it plain
    Python: no ament index hook, and `ros2 run` and the launch files cannot find it), and `ros2
    interface show` shows every field of every message."""
    log = (full_ros_install.LOGS / "full-install-colcon.log").read_text()
    assert "Failed to parse potential ROS package manifest" not in log
    packages = sorted(p.name for p in (install.root / "ros_ws" / "src").iterdir())
    messages = sorted((REPO_ROOT / "msgs" / "msg").glob("*.msg"))
    listed, prefixes, diagnoser, env, *shown = shell.ok_each(
        ["ros2 pkg list", "echo $AMENT_PREFIX_PATH", "ros2 pkg prefix bearing_diagnoser", "env",
         *(f"ros2 interface show bearing_msgs/msg/{msg.stem}" for msg in messages)])
    assert set(packages) <= set(listed.split())
    for package in packages:
        assert str(install.root / "ros_ws" / "install" / package) in prefixes.strip().split(":"), package
    assert diagnoser.strip() == str(install.root / "ros_ws" / "install" / "bearing_diagnoser")
    assert str(REPO_ROOT / ".venv") not in env
    for msg, out in zip(messages, shown, strict=True):
        fields = [" ".join(line.split("#")[0].split()) for line in msg.open()]
        seen = {" ".join(line.split("#")[0].split()) for line in out.splitlines()}
        assert [f for f in fields if f and f not in seen] == [], f"{msg.name}:\n{out}"


def console_scripts(install) -> set:
    """(package, executable) of every console script of every package, as installed."""
    scripts = set()
    for entry_points in (install.root / "ros_ws" / "install").glob("*/lib/python3*/site-packages/*.egg-info/"
                                                                  "entry_points.txt"):
        package = entry_points.parents[4].name
        parser = configparser.ConfigParser()
        parser.read(entry_points)
        if parser.has_section("console_scripts"):
            scripts |= {(package, name) for name in parser["console_scripts"]}
    return scripts


def test_ros2_run_of_every_executable(install, shell):
    """Each command-line tool prints its help; each node executable starts and its nodes appear in
    `ros2 node list`; Ctrl-C ends every one with exit code 0. All of them start at once."""
    scripts = console_scripts(install)
    listed = {tuple(line.split()) for line in shell.ok("ros2 pkg executables").splitlines()}
    assert scripts and scripts <= listed
    nodes = {s for s in scripts if not s[1].startswith(TOOL_PREFIX)}
    assert nodes == set(NODE_RUNS), "a node executable without a way to start it here (NODE_RUNS), or gone"
    runs = {s: shell.start(s[1], f"ros2 run {s[0]} {s[1]} {NODE_RUNS[s][0]}") for s in sorted(nodes)}
    helps = {s: shell.start(s[1], f"ros2 run {s[0]} {s[1]} --help") for s in sorted(scripts - nodes)}
    for (_package, tool), member in helps.items():
        assert member.process.wait(timeout=120.0) == 0, tail(member)
        member.reader.join(timeout=5.0)
        assert member.lines and member.lines[0].startswith(f"usage: {tool}"), tail(member)
    want = {name for _args, names in NODE_RUNS.values() for name in names}
    deadline, seen = time.monotonic() + 120.0, set()
    while not want <= seen:
        assert all(m.returncode is None for m in runs.values()), "\n".join(tail(m) for m in runs.values())
        assert time.monotonic() < deadline, f"`ros2 node list` shows {sorted(seen)}, not {sorted(want - seen)}"
        seen = set(shell.ok("ros2 node list").split())
    # running, not starting: the simulator's and the observer's first chunks compiled (numba, lazily)
    assert shell.echo_once(topics.RESIDUAL_INNER_RACE.name)["sample_rate"] > 0.0
    for member in runs.values():
        os.killpg(member.process.pid, signal.SIGINT)
    for script, member in runs.items():
        assert member.process.wait(timeout=15.0) == 0, f"ros2 run {' '.join(script)}:\n{tail(member)}"


def test_monitor_launch_echo_node_param_and_ctrl_c_under_load(install, shell, tmp_path):
    """`ros2 launch bearing_bringup monitor.launch.py` on an outer-race fault: `ros2 topic echo --once
    fault_state` shows it, `ros2 node list` the four nodes, `ros2 param` sets a live parameter and is
    refused a read-only one; then Ctrl-C with the graph starved of CPU ends every node cleanly."""
    params = monitor_params(install, tmp_path, "outer_race:600")
    launch = shell.start("launch", f"ros2 launch bearing_bringup monitor.launch.py params_file:={params}")
    shell.wait_for_line(launch, FAULT_SEEN, 180.0)
    time.sleep(2.0)  # the diagnoser's transient-local history (10 decisions) holds outer-race states only
    echoed = shell.echo_once(topics.FAULT_STATE.name)
    assert echoed["state"] == 1 and echoed["confidence"] > 0.5 and "outer_race" in echoed["hypotheses"], echoed

    assert {"/simulator", "/or_observer", "/ir_observer", "/diagnoser"} <= set(shell.ok("ros2 node list").split())

    assert "Double value is: 0.0" in shell.ok("ros2 param get /diagnoser window")  # 0: four cage periods
    assert "Set parameter successful" in shell.ok("ros2 param set /diagnoser window 0.4")
    assert "Double value is: 0.4" in shell.ok("ros2 param get /diagnoser window")
    refused = shell.run("ros2 param set /diagnoser diagnostics_period 2.0")[1]
    assert "Setting parameter failed" in refused and "read-only" in refused, refused
    assert "Double value is: 1.0" in shell.ok("ros2 param get /diagnoser diagnostics_period")

    saturated_ctrl_c(launch)


def test_monitor_launch_with_foxglove_serves_the_graph_on_port_8765(install, shell, tmp_path):
    """`ros2 launch bearing_bringup monitor.launch.py foxglove:=true` on an outer-race fault, deciding with
    the spectral front end (model set none: the simulator sets' fold draws no spectrum): a WebSocket
    client on port 8765 subscribes to the fault state, health, /diagnostics and the envelope spectrum
    and decodes them; Ctrl-C ends every process, the live view too, cleanly."""
    params = monitor_params(install, tmp_path, "outer_race:600", model_set="none")
    launch = shell.start("launch", f"ros2 launch bearing_bringup monitor.launch.py params_file:={params} "
                                   "foxglove:=true")
    shell.wait_for_line(launch, "serving the graph to Foxglove on ws://127.0.0.1:8765", 180.0)
    shell.wait_for_line(launch, FAULT_SEEN, 300.0)  # the graph runs: every node started (numba: first run)
    wanted = [topics.qualified("", t) for t in (topics.FAULT_STATE, topics.HEALTH, topics.DIAGNOSTICS,
                                                topics.ENVELOPE_SPECTRUM)]
    state, health, diagnostics, spectrum = wanted
    client = FoxgloveClient(8765, on_timeout=lambda: tail(launch))
    try:
        client.wait_for(lambda: set(wanted) <= set(client.channels), 120.0, "the channels advertised")
        client.subscribe(wanted)
        client.wait_for(lambda: all(client.messages.get(t) for t in wanted) and any(
            s["state_name"] == "OUTER_RACE" for s in client.json_messages(state)), 180.0, "an outer-race fault")
    finally:
        client.close()
    assert client.json_messages(state)[-1]["state_name"] == "OUTER_RACE"
    assert client.json_messages(health)[-1]["rms"] > 0.0
    last = client.json_messages(spectrum)[-1]
    assert 0 < len(last["frequency"]) == len(last["magnitude"]) <= 100 and "outer_race" in last["lines"]
    schema = client.channels[diagnostics]
    decode = generate_dynamic(schema["schemaName"], schema["schema"])[schema["schemaName"]]
    statuses = [s for _, data in client.messages[diagnostics] for s in decode(data).status]
    assert any(s.name.startswith("bearing_monitor/") for s in statuses), statuses
    ctrl_c(launch)


def test_fleet_launch_echo_fleet_state_and_ctrl_c(install, shell, tmp_path):
    """`ros2 launch bearing_bringup fleet.launch.py` of one motor with an outer-race fault:
    `ros2 topic echo --once fleet_state` names it; Ctrl-C ends every process cleanly."""
    fleet = yaml.safe_load((share(install, "bearing_bringup") / "config" / "fleet.yaml").read_text())
    fleet["motors"] = {"motor_1": {"scenario": "or"}}
    fleet["defaults"]["segment_duration"] = 600.0
    path = tmp_path / "fleet.yaml"
    path.write_text(yaml.safe_dump(fleet))
    launch = shell.start("launch", f"ros2 launch bearing_bringup fleet.launch.py fleet_file:={path}")
    shell.wait_for_line(launch, FAULT_SEEN, 180.0)
    deadline = time.monotonic() + 60.0
    while True:
        summary = shell.echo_once(topics.FLEET_STATE.name)
        motors = {m["motor"]: m for m in summary["motors"]}
        if motors.get("motor_1", {}).get("state") == 1 or time.monotonic() > deadline:
            break
    assert motors["motor_1"]["state"] == 1 and not motors["motor_1"]["stale"], summary
    ctrl_c(launch)


@pytest.mark.parametrize("stop", range(FLEET_STOPS))
def test_ctrl_c_to_the_fleet_launch_is_never_lost(install, shell, tmp_path, stop):
    """Ctrl-C to `ros2 launch fleet.launch.py` (one motor) once its diagnoser decides: launch exits
    and every process finished cleanly. Every other launch starts with SIGINT ignored, as the
    background job of a script (a CI runner) inherits it: launch, which installs no SIGINT handler
    of its own, never heard Ctrl-C, while the nodes stopped and were respawned, and it ran on
    (bearing_bringup.launch_ctrl_c; fails without it on those runs)."""
    path = tmp_path / "fleet.yaml"
    fleet = yaml.safe_load((share(install, "bearing_bringup") / "config" / "fleet.yaml").read_text())
    fleet["motors"] = {"motor_1": {"scenario": "normal"}}
    fleet["defaults"]["segment_duration"] = 600.0
    path.write_text(yaml.safe_dump(fleet))
    launch = shell.start("launch", f"ros2 launch bearing_bringup fleet.launch.py fleet_file:={path}",
                         sigint_ignored=stop % 2 == 1)
    shell.wait_for_line(launch, "state NORMAL", 180.0)
    ctrl_c(launch)


def test_topic_echo_of_a_bag_played_by_bearing_bag(shell, tmp_path):
    write_play_bag(tmp_path / "bag")
    player = shell.start("play", f"ros2 run bearing_recordings bearing-bag play {tmp_path / 'bag'} --loop")
    shell.wait_for_line(player, "bearing-bag: playing", 60.0)  # its publishers exist: echo finds the types
    state = shell.echo_once(topics.FAULT_STATE.name)
    assert state["state"] == 1 and state["confidence"] == 0.9 and state["model_set"] == "sim_48k", state
    chunk = shell.echo_once(topics.VIBRATION.name)
    assert chunk["header"]["frame_id"] == "drive_end" and chunk["sample_rate"] == 1000.0, chunk
    assert chunk["source"] == "simulator" and chunk["first_sample_index"] % 50 == 0, chunk
    os.killpg(player.process.pid, signal.SIGINT)
    assert player.process.wait(timeout=15.0) == 0, tail(player)


@pytest.mark.parametrize("stop", range(max(STOPS, 1)))
def test_ctrl_c_of_the_starved_monitor_launch_ends_every_node_cleanly(install, shell, tmp_path, stop):
    """Repeated Ctrl-C under load, beyond the monitor test's one (``BEARING_STOPS``, `make stops`: 20)."""
    if not STOPS:
        pytest.skip("the repeated stops under load are `make stops` (BEARING_STOPS); the monitor launch "
                    "test stops once under load")
    params = monitor_params(install, tmp_path, "normal:600")
    launch = shell.start("launch", f"ros2 launch bearing_bringup monitor.launch.py params_file:={params}")
    shell.wait_for_line(launch, "state NORMAL", 180.0)
    took, busy = saturated_ctrl_c(launch)
    print(f"stop {stop + 1}/{STOPS}: every node finished cleanly, launch exited {took:.2f} s after Ctrl-C "  # noqa: T201
          f"beside {busy} busy loops")
