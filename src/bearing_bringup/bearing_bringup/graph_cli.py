"""``bearing-graph``: run the monitoring graph without ``ros2 launch`` (the ``make demo`` starter).

Starts the node executables of ``bearing_bringup.graph.GRAPH`` as separate
processes with one parameters YAML (the launch file's), prefixes and interleaves
their output, prints every fault-state change as it is published, and stops
everything cleanly on Ctrl-C / SIGTERM or when the simulator's scenario ends. A node
that dies meanwhile is restarted after a delay (:mod:`.restart_policy`; a crash loop
stops the graph). It then writes a summary against the simulator's ground truth and
plots to ``--out``.

Exit 0 only when every node of the graph ran and the scenario completed; when
parts are missing it runs what exists, names what is missing and exits 3.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import pathlib
import signal
import sys
import time

from bearing_common import ros_env
from bearing_common.stop_signals import StopSignals

from .graph import CONFIG_NAME, GRAPH, config_path
from .process_group import ProcessGroup
from .restart_policy import MAX_RESTARTS, RESTART_DELAY_S, RestartPolicy
from .state_report import evaluate, format_table

SIMULATOR = "simulator"  # the node whose exit 0 ends the scenario
EXIT_MISSING = 3
EXIT_FAILED = 1
MISSING_SIMULATOR_RUN_S = 5.0


def installed_executable(package: str, executable: str) -> pathlib.Path | None:
    """The executable ``ros2 run`` would start (AMENT_PREFIX_PATH, else the venv's prefix), or None."""
    return ros_env.executable(package, executable)


def missing_parts() -> list:
    """Names of graph nodes whose executable or node module is not there."""
    missing = []
    for spec in GRAPH:
        if installed_executable(spec.package, spec.executable) is None:
            missing.append(f"{spec.name} ({spec.package}/{spec.executable}: executable not built)")
        elif importlib.util.find_spec(f"{spec.package}.node") is None:
            missing.append(f"{spec.name} ({spec.package}.node: module missing)")
    return missing


def node_argv(spec, params_file: pathlib.Path, namespace: str) -> list:
    argv = [str(installed_executable(spec.package, spec.executable)), "--ros-args",
            "-r", f"__node:={spec.name}", "--params-file", str(params_file)]
    if namespace:
        argv += ["-r", f"__ns:=/{namespace.strip('/')}"]
    return argv


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="bearing-graph", description=__doc__.split("\n\n")[0])
    parser.add_argument("--params", type=pathlib.Path, help=f"parameters YAML (default: the installed {CONFIG_NAME})")
    parser.add_argument("--namespace", default="", help="namespace for all nodes, e.g. motor_7")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/demo"),
                        help="summary and plots directory")
    parser.add_argument("--timeout", type=float, default=600.0, help="stop after this many wall seconds")
    parser.add_argument("--settle", type=float, default=30.0,
                        help="at most this many wall seconds for the diagnoser to decide the last window "
                             "after the simulator ends")
    parser.add_argument("--restart-delay", type=float, default=RESTART_DELAY_S,
                        help="seconds before a dead node is restarted")
    parser.add_argument("--max-restarts", type=int, default=MAX_RESTARTS,
                        help="restarts of one node per minute before the graph stops (crash loop)")
    args = parser.parse_args(argv)

    params_file = args.params or config_path()
    if not params_file.is_file():
        print(f"bearing-graph: parameters file {params_file} not found", file=sys.stderr)
        return EXIT_FAILED
    missing = missing_parts()
    runnable = [s for s in GRAPH if not any(m.startswith(f"{s.name} ") for m in missing)]

    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")  # a demo stays on this machine
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # nodes solve small systems: BLAS threads only contend
    from .graph_watcher import GraphWatcher  # rclpy: imported only when the graph runs

    policy = RestartPolicy(args.restart_delay, args.max_restarts)
    sim = failure = None
    with StopSignals() as stop:
        watcher = GraphWatcher(args.namespace)
        group = ProcessGroup(on_line=None)
        watcher.on_change = lambda text: group.echo(text, "state")
        for part in missing:
            group.echo(f"MISSING: {part}")
        try:
            for spec in runnable:
                group.start(spec.name, node_argv(spec, params_file, args.namespace))
            for member in group.members:
                group.echo(f"started {member.name} (pid {member.process.pid})")
            sim = next((m for m in group.members if m.name == SIMULATOR), None)
            # Without a simulator nothing ends the scenario: show that the rest starts, then stop.
            deadline = time.monotonic() + (args.timeout if sim is not None else MISSING_SIMULATOR_RUN_S)
            failure = supervise(group, policy, deadline, stop)
            if failure:
                group.echo(failure)
            elif sim is not None and sim.returncode == 0:
                group.echo("scenario ended; waiting for the diagnoser to decide the last window")
                if not watcher.wait_decided_to_end(args.settle, stop):
                    group.echo(f"the diagnoser did not reach the end of the data within {args.settle:g} s")
        finally:
            codes = group.stop()
            watcher.close()

    group.echo("exit codes: " + ", ".join(f"{name} {code}" for name, code in codes.items()))
    completed = sim is not None and sim.returncode == 0 and not stop and failure is None
    report = write_report(watcher, args.out, completed)
    if report:
        print(report, flush=True)
    if missing:
        print("bearing-graph: not runnable yet: " + "; ".join(missing), file=sys.stderr)
        return EXIT_MISSING
    others_ok = all(code in (0, -signal.SIGINT) for name, code in codes.items())
    return 0 if completed and others_ok else EXIT_FAILED


def supervise(group: ProcessGroup, policy: RestartPolicy, deadline: float, stop) -> str | None:
    """Run until the simulator ends its scenario (exit 0), ``stop``, or ``deadline`` (monotonic
    s), restarting nodes that die as ``policy`` says; return why the graph must stop otherwise."""
    due = {}  # name -> monotonic time of its restart
    while time.monotonic() < deadline and not stop:
        now = time.monotonic()
        for member in group.members:
            code = member.returncode
            if code is None or member.name in due:
                continue
            if member.name == SIMULATOR and code == 0:
                return None
            verdict = policy.after_exit(member.name, code, now)
            if not verdict.restart:
                return verdict.message
            group.echo(verdict.message)
            due[member.name] = now + policy.delay
        for member in group.members:
            if member.name in due and now >= due[member.name]:
                del due[member.name]
                group.restart(member)
                group.echo(f"restarted {member.name} (pid {member.process.pid})")
        time.sleep(0.1)
    return None


def write_report(watcher, out: pathlib.Path, completed: bool) -> str:
    """Summary table against sim/truth and plots; returns the table text."""
    out.mkdir(parents=True, exist_ok=True)
    truth = watcher.truth_changes()
    decided = watcher.state_changes(all_decisions=True)
    end = watcher.signal_end()
    if not truth or end is None:
        return "no ground truth received: nothing to summarise"
    results = evaluate(truth, decided, end)
    table = format_table(results)
    (out / "summary.md").write_text(
        f"# Monitoring run\n\nscenario completed: {completed}\n\n{table}\n")
    (out / "summary.json").write_text(json.dumps({
        "completed": completed,
        "segments": [dict(true_state=r.true_state, start=r.start, end=r.end, detected_state=r.detected_state,
                          detected_at=r.detected_at, delay=r.delay, onset=r.onset, correct=r.correct)
                     for r in results],
        "state_changes": [c.__dict__ for c in watcher.state_changes()],
    }, indent=2))
    watcher.plot(out / "states.png", truth, decided, end)
    return f"summary against ground truth (also in {out}/summary.md):\n{table}"


if __name__ == "__main__":
    sys.exit(main())
