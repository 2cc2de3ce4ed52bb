"""``bearing-graph``: run the monitoring graph without ``ros2 launch`` (the ``make demo`` starter).

Starts the node executables of ``bearing_bringup.graph.GRAPH`` as separate
processes with one parameters YAML (the launch file's), prefixes and interleaves
their output, prints every fault-state change as it is published, and stops
everything cleanly on Ctrl-C / SIGTERM or when the simulator's scenario ends. A node
that dies meanwhile is restarted after a delay (:mod:`.restart_policy`; a crash loop
stops the graph). It then writes a summary against the simulator's ground truth and
plots to ``--out``.

With ``--fleet FILE`` or ``--motors N`` it runs a fleet instead (:mod:`.fleet`): every
motor's graph in its own namespace, its processes laid out as the fleet file says, plus
the ``fleet`` node; the parameters every node got are written to ``--out``/fleet_params.yaml,
the restart policy applies per process, the run ends when every simulator has ended its
scenario (without simulators: on Ctrl-C or ``--timeout``), and the summary has one table
per simulated motor (``--out``/<motor>/ holds its summary and plot).

With ``--foxglove [PORT]`` it also runs the live view (the ``live_view`` node, one for a fleet too),
serving the graph to Foxglove on PORT (default 8765), as the launch files' ``foxglove:=true`` does.

Exit 0 only when every node of the graph ran and the scenario completed; when
parts are missing it runs what exists, names what is missing and exits 3; an
unusable fleet file gives one line on stderr and exit 2.
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
from dataclasses import dataclass

import yaml

from bearing_common import ros_env, topics
from bearing_common.stop_signals import StopSignals

from .fleet_plan import FleetError, default_fleet_file, load_fleet, parameters_file, processes
from .graph import CONFIG_NAME, DEFAULT_HOST, DEFAULT_PORT, config_path, live_view, single_graph
from .process_group import ProcessGroup
from .restart_policy import MAX_RESTARTS, RESTART_DELAY_S, RestartPolicy
from .state_report import evaluate, format_table

SIMULATOR = "simulator"  # the node whose exit 0 ends the scenario
EXIT_MISSING = 3
EXIT_FAILED = 1
EXIT_BAD_FLEET = 2
MISSING_SIMULATOR_RUN_S = 5.0
DIAGNOSER_WAIT_S = 30.0  # longest wait for the diagnosers' fault_state before the simulators start anyway
FLEET_PARAMS = "fleet_params.yaml"


def installed_executable(package: str, executable: str) -> pathlib.Path | None:
    """The executable ``ros2 run`` would start (AMENT_PREFIX_PATH, else the venv's prefix), or None."""
    return ros_env.executable(package, executable)


def missing_parts(procs=None) -> list:
    """Names of processes (default: one graph's) whose executable or node module is not there."""
    missing = []
    for proc in single_graph() if procs is None else procs:
        if installed_executable(proc.package, proc.executable) is None:
            missing.append(f"{proc.name} ({proc.package}/{proc.executable}: executable not built)")
        elif proc.node_name and importlib.util.find_spec(f"{proc.package}.node") is None:
            missing.append(f"{proc.name} ({proc.package}.node: module missing)")
    return missing


def diagnosed_motors(procs) -> set:
    """Namespaces whose diagnoser one of ``procs`` runs (alone, or among a ``nodes`` process' nodes)."""
    out = {p.namespace for p in procs if p.node_name == "diagnoser"}
    for p in procs:
        out.update(name.strip("/").rpartition("/")[0] for name in p.arguments if name.endswith("/diagnoser"))
    return out


def watched_gate(params: dict, proc) -> list:
    """``-p wait_for_subscribers:=...`` for a simulator ``proc``: its gate from the parameters
    (``params``, the file's content) plus the watcher's ``sim/truth`` subscription; else a short
    scenario may end before the watcher has matched it, leaving nothing to summarise."""
    key = f"/{proc.namespace}/{proc.node_name}" if proc.namespace else f"/{proc.node_name}"
    spec = ""
    for name in (key, proc.node_name, "/**"):
        section = (params.get(name) or {}).get("ros__parameters") or {}
        if "wait_for_subscribers" in section:
            spec = section["wait_for_subscribers"]
            break
    return ["-p", "wait_for_subscribers:=" + ",".join(filter(None, (spec, f"{topics.TRUTH.name}:1")))]


def process_argv(proc, params_file: pathlib.Path) -> list:
    """The command line of ``proc`` (a :class:`~bearing_bringup.graph.Process`); a simulator also
    waits for the watcher (:func:`watched_gate`)."""
    gate = watched_gate(yaml.safe_load(params_file.read_text()) or {}, proc) if proc.sensor else []
    return [str(installed_executable(proc.package, proc.executable)), *proc.arguments,
            *proc.ros_arguments(params_file), *gate]


@dataclass
class RunPlan:
    """What one run starts: the processes, the parameters file they read, the motors' namespaces,
    and the fleet they belong to (None for one graph)."""

    procs: list
    params_file: pathlib.Path
    namespaces: list
    fleet: object = None


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``bearing-graph``."""
    parser = argparse.ArgumentParser(prog="bearing-graph", description=__doc__.split("\n\n")[0])
    parser.add_argument("--params", type=pathlib.Path, help=f"parameters YAML (default: the installed {CONFIG_NAME}; "
                        "with a fleet: the per-node base parameters)")
    parser.add_argument("--namespace", default="", help="namespace for all nodes, e.g. motor_7")
    parser.add_argument("--fleet", type=pathlib.Path, help="run the fleet of this fleet YAML (default with --motors: "
                        "the installed fleet.yaml)")
    parser.add_argument("--motors", type=int, help="run N motors: the fleet file's first N, then motor_<k> on its "
                        "defaults")
    parser.add_argument("--foxglove", type=int, nargs="?", const=DEFAULT_PORT, metavar="PORT",
                        help=f"also serve the graph to Foxglove on PORT (default {DEFAULT_PORT}): the live_view node "
                             "(docs/live-view.md)")
    parser.add_argument("--foxglove-host", default=DEFAULT_HOST, metavar="ADDRESS",
                        help=f"address the live view listens on (default {DEFAULT_HOST}: this machine only; 0.0.0.0: "
                             "every interface, no authentication)")
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
    return parser


def plan_run(args) -> RunPlan:
    """The fleet of ``--fleet`` / ``--motors`` (its parameters written to ``--out``), else one
    graph in ``--namespace``; with ``--foxglove`` the live view too (root namespace for a fleet);
    raises FleetError for an unusable fleet file."""
    if args.fleet or args.motors is not None:
        fleet = load_fleet(args.fleet or default_fleet_file(), args.motors, args.params)
        args.out.mkdir(parents=True, exist_ok=True)
        params_file = args.out / FLEET_PARAMS
        params_file.write_text(yaml.safe_dump(parameters_file(fleet), sort_keys=False))
        plan = RunPlan(processes(fleet), params_file, [m.name for m in fleet.motors], fleet)
    else:
        plan = RunPlan(single_graph(args.namespace), args.params or config_path(), [args.namespace])
    if args.foxglove is not None:
        plan.procs.append(live_view("" if plan.fleet else args.namespace, args.foxglove, args.foxglove_host))
    return plan


def main(argv=None) -> int:
    """``bearing-graph`` (module docstring): plan the run, start and supervise it, report; the exit code."""
    args = build_parser().parse_args(argv)
    try:
        plan = plan_run(args)
    except FleetError as exc:
        print(f"bearing-graph: {exc}", file=sys.stderr)
        return EXIT_BAD_FLEET
    if not plan.params_file.is_file():
        print(f"bearing-graph: parameters file {plan.params_file} not found", file=sys.stderr)
        return EXIT_FAILED
    missing = missing_parts(plan.procs)
    runnable = [p for p in plan.procs if not any(m.startswith(f"{p.name} ") for m in missing)]

    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")  # a demo stays on this machine
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # nodes solve small systems: BLAS threads only contend
    from .graph_watcher import GraphWatcher  # rclpy: imported only when the graph runs

    policy = RestartPolicy(args.restart_delay, args.max_restarts)
    with StopSignals() as stop:
        watcher = GraphWatcher(plan.namespaces)
        group = ProcessGroup(on_line=None)
        watcher.on_change = lambda motor, text: group.echo(text, f"{motor} state" if plan.fleet else "state")
        for part in missing:
            group.echo(f"MISSING: {part}")
        try:
            sensors = start_graph(group, watcher, runnable, plan, stop)
            failure = run_to_end(group, watcher, policy, sensors, plan, args, stop)
        finally:
            codes = group.stop()
            watcher.close()

    order = [p.name for p in runnable if p.name in codes]  # the graph's order, not the start order
    group.echo("exit codes: " + ", ".join(f"{name} {codes[name]}" for name in order))
    if sensors:
        completed = all(m.returncode == 0 for m in sensors) and not stop and failure is None
    else:
        completed = bool(plan.fleet) and failure is None  # external sensors: stopped on request or at the timeout
    write_reports(watcher, plan, args.out, completed)
    if missing:
        print("bearing-graph: not runnable yet: " + "; ".join(missing), file=sys.stderr)
        return EXIT_MISSING
    others_ok = all(code in (0, -signal.SIGINT) for name, code in codes.items())
    return 0 if completed and others_ok else EXIT_FAILED


def start_graph(group: ProcessGroup, watcher, runnable: list, plan: RunPlan, stop) -> list:
    """Start the monitoring nodes, then, once the diagnosers' states reach ``watcher`` (or after
    :data:`DIAGNOSER_WAIT_S`), the simulators; return the simulators' members of ``group``."""
    monitors = [p for p in runnable if not p.sensor]
    for proc in monitors:
        group.start(proc.name, process_argv(proc, plan.params_file))
    awaited = [p.namespace for p in runnable if p.sensor and p.namespace in diagnosed_motors(monitors)]
    if awaited:
        unheard = watcher.wait_for_diagnosers(DIAGNOSER_WAIT_S, stop, awaited)
        if unheard:
            group.echo(f"no diagnoser publishing after {DIAGNOSER_WAIT_S:g} s"
                       + (f" ({', '.join(unheard)})" if plan.fleet else "") + "; starting the simulator anyway")
    for proc in runnable:
        if proc.sensor and not stop:  # Ctrl-C while waiting: no simulator to start and stop again
            group.start(proc.name, process_argv(proc, plan.params_file))
    for member in group.members:
        group.echo(f"started {member.name} (pid {member.process.pid})")
    sensor_names = {p.name for p in runnable if p.sensor}
    return [m for m in group.members if m.name in sensor_names]


def run_to_end(group: ProcessGroup, watcher, policy: RestartPolicy, sensors: list, plan: RunPlan, args,
               stop) -> str | None:
    """Supervise the graph (:func:`supervise`) until the scenario ends, ``stop`` or the timeout;
    after a completed scenario, wait up to ``--settle`` for the diagnosers to decide its end.
    Returns why the graph had to stop, or None."""
    # Without a simulator nothing ends the scenario: show that the rest starts, then stop
    # (a fleet of external sensors runs until Ctrl-C or the timeout).
    expected = any(p.sensor for p in plan.procs)
    deadline = time.monotonic() + (args.timeout if sensors or not expected else MISSING_SIMULATOR_RUN_S)
    failure = supervise(group, policy, deadline, stop, [m.name for m in sensors])
    if failure:
        group.echo(failure)
    elif sensors and all(m.returncode == 0 for m in sensors):
        group.echo("scenario ended; waiting for the diagnoser to decide the last window")
        simulated = [m.name for m in plan.fleet.motors if m.simulated] if plan.fleet else None
        late = watcher.wait_decided_to_end(args.settle, stop, simulated)
        if late:
            group.echo(f"the diagnoser did not reach the end of the data within {args.settle:g} s"
                       + (f": {', '.join(late)}" if plan.fleet else ""))
    return failure


def supervise(group: ProcessGroup, policy: RestartPolicy, deadline: float, stop,
              scenario_ends=(SIMULATOR,)) -> str | None:
    """Run until every process of ``scenario_ends`` (the simulators) has ended its scenario (exit 0;
    never, when there are none), ``stop``, or ``deadline`` (monotonic s), restarting processes that
    die as ``policy`` says; return why the graph must stop otherwise."""
    due = {}  # name -> monotonic time of its restart
    ended = set()
    while time.monotonic() < deadline and not stop:
        now = time.monotonic()
        for member in group.members:
            code = member.returncode
            if code is None or member.name in due or member.name in ended:
                continue
            if member.name in scenario_ends and code == 0:
                ended.add(member.name)
                if ended >= set(scenario_ends):
                    return None
                continue
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


def write_reports(watcher, plan: RunPlan, out: pathlib.Path, completed: bool) -> None:
    """Every motor's summary and plots (:func:`write_report`; a fleet's in ``out``/<motor>/),
    printed for one graph and for the motors that have a ground truth."""
    for motor, log in watcher.motors.items():
        report = write_report(log, out / motor if plan.fleet else out, completed)
        if report and (log.truth_changes() or not plan.fleet):
            print((f"{motor}: " if plan.fleet else "") + report, flush=True)


def write_report(log, out: pathlib.Path, completed: bool) -> str:
    """Summary table of one motor (a :class:`~.graph_watcher.MotorLog`) against sim/truth and
    plots, into ``out``; returns the table text."""
    truth = log.truth_changes()
    decided = log.state_changes(all_decisions=True)
    end = log.signal_end()
    if not truth or end is None:
        return "no ground truth received: nothing to summarise"
    out.mkdir(parents=True, exist_ok=True)
    results = evaluate(truth, decided, end)
    table = format_table(results)
    (out / "summary.md").write_text(
        f"# Monitoring run\n\nscenario completed: {completed}\n\n{table}\n")
    (out / "summary.json").write_text(json.dumps({
        "completed": completed,
        "segments": [dict(true_state=r.true_state, start=r.start, end=r.end, detected_state=r.detected_state,
                          detected_at=r.detected_at, delay=r.delay, onset=r.onset, correct=r.correct)
                     for r in results],
        "state_changes": [c.__dict__ for c in log.state_changes()],
    }, indent=2))
    log.plot(out / "states.png", truth, decided, end)
    return f"summary against ground truth (also in {out}/summary.md):\n{table}"


if __name__ == "__main__":
    sys.exit(main())
