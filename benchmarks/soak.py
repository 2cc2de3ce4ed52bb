"""`make soak`: the whole graph at real time, 48 kHz with sensor noise, for half an hour or more.

The four nodes run as separate processes (as ``bearing-graph`` starts them); the
simulator follows the schedule ``normal`` for all but the last ``--fault-minutes``,
then ``outer_race`` and ``inner_race`` for half of them each. One listener process
(this one) measures, from what it receives over DDS:

- resident memory (VmRSS) of every node, sampled each ``--period`` seconds;
  growth = last sample minus the sample after ``--warm-up`` seconds;
- chunks dropped: gaps in the sample indices of vibration/drive_end and of both
  residual topics (a chunk is dropped where ``first_sample_index`` jumps);
- end-to-end latency: arrival of a fault_state minus arrival of the vibration chunk
  holding the last sample of its window (both timed here);
- false alarms: fault states other than NORMAL whose window ends before the fault
  onset that sim/truth announces;
- on each injected fault: the share of fault states whose window lies wholly inside
  it that name it, and the state published last before it ends;
- /diagnostics: the levels each node reported, counted per level.

Writes a Markdown report (``--out``, default out/soak.md) and exits 1 when a target
is missed (memory growth < 5 MB, 0 dropped chunks, 0 false alarms, both faults named
at the end).
"""

from __future__ import annotations

import argparse
import bisect
import collections
import os
import pathlib
import platform
import sys
import threading
import time
from dataclasses import dataclass, field

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))  # `benchmarks` as a package
from benchmarks.doc_tables import add_docs_option, nested, write_block  # noqa: E402

MEMORY_GROWTH_TARGET_MB = 5.0
FAULTS = ("outer_race", "inner_race")


@dataclass
class Sequence:
    """Continuity of one chunked topic by first_sample_index."""

    chunks: int = 0
    dropped: int = 0
    next_index: int | None = None

    def add(self, first: int, length: int) -> None:
        self.chunks += 1
        if self.next_index is not None and first > self.next_index and length:
            self.dropped += round((first - self.next_index) / length)
        self.next_index = first + length


@dataclass
class Observations:
    """Everything the listener records (guarded by ``lock``)."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    sequences: dict = field(default_factory=lambda: collections.defaultdict(Sequence))
    chunk_ends: list = field(default_factory=list)      # signal time of each vibration chunk's end (s)
    chunk_wall: list = field(default_factory=list)      # its arrival (monotonic s)
    states: list = field(default_factory=list)          # (stamp s, state, arrival monotonic s)
    latencies: list = field(default_factory=list)       # s
    truth: list = field(default_factory=list)           # (onset s, state)
    levels: dict = field(default_factory=lambda: collections.defaultdict(collections.Counter))
    last_status: dict = field(default_factory=dict)     # status name -> (level, message, values)


def seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def listen(node, seen: Observations) -> None:
    """Subscribe the listener to the graph's topics (relative names, as the nodes use)."""
    from bearing_common import topics

    def on_vibration(msg):
        end = seconds(msg.header.stamp) + len(msg.samples) / msg.sample_rate
        with seen.lock:
            seen.sequences[topics.VIBRATION.name].add(msg.first_sample_index, len(msg.samples))
            seen.chunk_ends.append(end)
            seen.chunk_wall.append(time.monotonic())

    def on_residual(name):
        def callback(msg):
            with seen.lock:
                seen.sequences[name].add(msg.first_sample_index, len(msg.residual))
        return callback

    def on_state(msg):
        arrived = time.monotonic()
        t = seconds(msg.header.stamp)
        with seen.lock:
            seen.states.append((t, msg.state, arrived))
            i = bisect.bisect_left(seen.chunk_ends, t - 1e-9)
            if i < len(seen.chunk_ends):
                seen.latencies.append(arrived - seen.chunk_wall[i])

    def on_truth(msg):
        with seen.lock:
            seen.truth.append((seconds(msg.onset), msg.state))

    def on_diagnostics(msg):
        with seen.lock:
            for status in msg.status:
                level = int.from_bytes(status.level, "little") if isinstance(status.level, bytes) else int(status.level)
                seen.levels[status.name][level] += 1
                seen.last_status[status.name] = (level, status.message, {v.key: v.value for v in status.values})

    def subscribe(topic, callback, depth=None):
        node.create_subscription(topics.message_class(topic.msgtype), topic.name, callback, topics.qos(topic, depth))

    subscribe(topics.VIBRATION, on_vibration, depth=200)
    subscribe(topics.RESIDUAL_OUTER_RACE, on_residual(topics.RESIDUAL_OUTER_RACE.name), depth=200)
    subscribe(topics.RESIDUAL_INNER_RACE, on_residual(topics.RESIDUAL_INNER_RACE.name), depth=200)
    subscribe(topics.FAULT_STATE, on_state, depth=100)
    subscribe(topics.TRUTH, on_truth, depth=100)
    subscribe(topics.DIAGNOSTICS, on_diagnostics, depth=100)


def resident_mb(pid: int) -> float | None:
    """VmRSS of a process (MB), None once it has ended."""
    try:
        for line in pathlib.Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except (FileNotFoundError, ProcessLookupError):
        return None
    return None


def schedule(minutes: float, fault_minutes: float) -> str:
    normal = 60.0 * (minutes - fault_minutes)
    each = 60.0 * fault_minutes / len(FAULTS)
    return ",".join([f"normal:{normal:g}"] + [f"{f}:{each:g}" for f in FAULTS])


def run(args) -> tuple[Observations, dict, float]:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from bearing_bringup.graph import GRAPH, config_path
    from bearing_bringup.graph_cli import installed_executable
    from bearing_bringup.process_group import ProcessGroup

    domain = 150 + os.getpid() % 50
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    os.environ.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    node = rclpy.create_node("soak_listener", context=context)
    seen = Observations()
    listen(node, seen)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    memory: dict = collections.defaultdict(list)   # node -> [(minute, MB)]
    group = ProcessGroup(env=env, echo=False)
    started = time.monotonic()
    try:
        for spec in GRAPH:
            argv = [str(installed_executable(spec.package, spec.executable)), "--ros-args",
                    "-r", f"__node:={spec.name}", "--params-file", str(config_path())]
            if spec.executable == "simulator":
                argv += ["-p", f"schedule:={schedule(args.minutes, args.fault_minutes)}",
                         "-p", f"noise_density:={args.noise}", "-p", "realtime:=true", "-p", "seed:=11",
                         "-p", "wait_for_subscribers:=vibration/drive_end:3,residual/outer_race:2,"
                               "residual/inner_race:2,sim/truth:1"]
            group.start(spec.name, argv)
        sim = group.members[0]
        next_sample = started
        deadline = started + 60.0 * args.minutes + 120.0
        while sim.returncode is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
            if time.monotonic() >= next_sample:
                for m in group.members:
                    mb = resident_mb(m.process.pid)
                    if mb is not None:
                        memory[m.name].append(((time.monotonic() - started) / 60.0, mb))
                next_sample += args.period
        settle = time.monotonic() + 3.0
        while time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.01)
        exits = {m.name: m.returncode for m in group.members}
        restarts = {m.name: m.restarts for m in group.members}
    finally:
        group.stop()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return seen, {"memory": memory, "exits": exits, "restarts": restarts}, time.monotonic() - started


def state_name(state: int) -> str:
    from bearing_common.states import FaultState

    return FaultState(state).label


def fault_segments(truth: list) -> list:
    """[(state, onset s, end s)] of the injected faults, from sim/truth (the last segment ends at +inf)."""
    events = sorted(set(truth))
    return [(state, onset, events[i + 1][0] if i + 1 < len(events) else np.inf)
            for i, (onset, state) in enumerate(events) if state != 0]


def evaluate(seen: Observations, procs: dict, args) -> tuple[list, bool]:
    """Report rows (figure, value, target) and whether every target is met."""
    rows, ok = [], True
    warm = args.warm_up / 60.0
    for name, samples in procs["memory"].items():
        after = [mb for minute, mb in samples if minute >= warm]
        growth = after[-1] - after[0] if len(after) > 1 else float("nan")
        ok &= bool(growth < MEMORY_GROWTH_TARGET_MB)
        rows.append((f"{name}: resident memory after warm-up -> end (growth)",
                     f"{after[0]:.1f} -> {after[-1]:.1f} MB ({growth:+.2f} MB)" if after else "no samples",
                     f"growth < {MEMORY_GROWTH_TARGET_MB:g} MB"))
    for topic, seq in sorted(seen.sequences.items()):
        ok &= seq.dropped == 0
        rows.append((f"{topic}: chunks received / dropped", f"{seq.chunks} / {seq.dropped}", "0 dropped"))
    lat = np.array(seen.latencies) * 1e3
    if lat.size:
        rows.append(("end-to-end latency (vibration chunk -> fault_state) median / 95 % / 99 % / max",
                     " / ".join(f"{v:.1f}" for v in np.percentile(lat, [50, 95, 99, 100])) + " ms", ""))
    segments = fault_segments(seen.truth)
    onset = segments[0][1] if segments else np.inf
    normal = [(t, s) for t, s, _ in seen.states if t <= onset]
    alarms = sum(1 for _, s in normal if s != 0)
    ok &= alarms == 0 and bool(normal)
    rows.append(("fault states while the bearing is healthy / of them not NORMAL (false alarms)",
                 f"{len(normal)} / {alarms}", "0 false alarms"))
    window = args.window
    for state, begin, end in segments:
        inside = [s for t, s, _ in seen.states if begin + window <= t <= end]
        right = sum(1 for s in inside if s == state)
        last = inside[-1] if inside else None
        ok &= last == state
        rows.append((f"injected {state_name(state)} from t = {begin:.0f} s: states naming it / last state",
                     f"{right}/{len(inside)} / {state_name(last) if last is not None else 'none'}",
                     f"last = {state_name(state)}"))
    if len(segments) < len(FAULTS):
        ok = False
        rows.append(("injected faults announced on sim/truth", str(len(segments)), str(len(FAULTS))))
    for name, counter in sorted(seen.levels.items()):
        level, message, _ = seen.last_status[name]
        counts = ", ".join(f"{lvl}: {n}" for lvl, n in sorted(counter.items()))
        rows.append((f"/diagnostics '{name}': messages per level (0 OK, 1 WARN, 2 ERROR, 3 STALE); last",
                     f"{counts}; last {level} '{message}'", ""))
    for name, code in procs["exits"].items():
        ok &= code in (0, None) and procs["restarts"][name] == 0
        status = "running" if code is None else f"exit {code}"
        rows.append((f"{name}: at the end / restarts", f"{status} / {procs['restarts'][name]}",
                     "running or exit 0 / 0"))
    return rows, ok


def report(rows: list, ok: bool, args, wall: float) -> str:
    cpu = platform.processor() or platform.machine()
    lines = [f"# Soak: whole graph, real time, 48 kHz, noise {args.noise:g} (m/s²)/√Hz, {args.minutes:g} min",
             "", f"Schedule `{schedule(args.minutes, args.fault_minutes)}`; wall time {wall / 60:.1f} min; "
             f"{os.cpu_count()} cores ({cpu}); targets {'all met' if ok else 'NOT all met'}.", "",
             "| figure | value | target |", "|---|---|---|"]
    lines += [f"| {f} | {v} | {t} |" for f, v, t in rows]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=30.0, help="length of the run (simulated = wall minutes)")
    parser.add_argument("--fault-minutes", type=float, default=4.0, help="minutes of injected faults at the end")
    parser.add_argument("--noise", type=float, default=4.5e-3, help="sensor noise density ((m/s^2)/sqrt(Hz))")
    parser.add_argument("--period", type=float, default=60.0, help="seconds between memory samples")
    parser.add_argument("--warm-up", type=float, default=120.0, help="seconds before memory growth is counted")
    parser.add_argument("--window", type=float, default=1.0,
                        help="seconds after an onset before a fault state must name the fault")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/soak.md"))
    add_docs_option(parser, "docs/robustness.md")
    args = parser.parse_args(argv)
    if not 0 < args.fault_minutes < args.minutes:
        parser.error("--fault-minutes must be > 0 and < --minutes")
    seen, procs, wall = run(args)
    rows, ok = evaluate(seen, procs, args)
    text = report(rows, ok, args, wall)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    if args.docs:
        write_block(args.docs, "soak", nested(text, 1), "make soak")
    print(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
