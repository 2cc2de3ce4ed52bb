"""`make bench` rows of a fleet: how many motors one machine monitors in real time.

A trial runs the monitoring graph of N motors (observers, diagnosers and the fleet node,
laid out as in a fleet file: :mod:`bearing_bringup.fleet`) and feeds it from ONE
``bearing-bag play`` of a bag holding every motor's ``<motor>/vibration/drive_end`` and
``<motor>/shaft_speed``, made beforehand from simulator output (normal, outer-race and
inner-race signals with sensor noise, 4.5e-3 (m/s²)/√Hz, assigned to the motors in turn).
The player stands in for the sensors: the 29-DOF simulator costs 0.2-0.3 core per 48 kHz
motor, which would be the bottleneck measured otherwise; the player's own CPU is reported
apart. A listener in this process measures:

* end-to-end latency: wall time at which a motor's fault_state arrives minus wall time at
  which the vibration chunk holding the last sample of its window arrived, on the first and
  the last motor (a multi-node process serves the last motor of a burst last: the worst
  case; every message costs the listener 0.1-0.3 ms of CPU, which listening to all motors
  would take from the graph); chunks are taken raw and only their stamp read;
* dropped chunks: every motor's diagnoser counts the residual chunks it accepted and the
  gaps in ``first_sample_index`` (ChunkStream, in its /diagnostics); a chunk lost anywhere
  upstream (player -> observer -> diagnoser) shows as a gap or as fewer accepted chunks
  than the bag holds;
* CPU (cores: CPU seconds per wall second while the bag plays) and memory (PSS, MiB) of
  every process, from /proc.

A trial keeps real time when no chunk is dropped and the 95th percentile latency is below
100 ms; decisions on the first second of signal are left out (each motor's first windows
set up its decision and log it, serialised within a multi-node process: once per stream).
The capacity is the largest N that does (doubling, then bisecting), per sample rate,
reported as motors per core of this machine (N / cores: the player and the listener share
the cores too).

The machine is shared: other users' processes (invisible to ``ps`` here) take up to a core
at times. Each trial waits for a quiet machine first and records the CPU others used while
it ran (machine busy time from /proc/stat minus the trial's processes); a trial that fails
while others used more than :data:`QUIET_CORES` is run again once the machine is quiet.

Standalone: ``python benchmarks/fleet_benchmarks.py [--rates 12000 48000] [--layouts role]
[--motors-per-process K] [--motors N ...] [--duration S]`` prints one line per trial and the
capacity rows (without ``--motors``: the capacity search).
"""

from __future__ import annotations

import argparse
import bisect
import itertools
import os
import pathlib
import struct
import sys
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np
import yaml

if __package__ in (None, ""):  # run as a script: `benchmarks` as a package
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

from bearing_bringup.fleet import MOTORS_PER_PROCESS  # noqa: E402 (after the path set-up of a script run)

SIGNAL_S = 15.0  #: s of signal per motor and trial
RATES = (12000.0, 48000.0)  #: Hz
RPM = 1800.0
NOISE_DENSITY = 4.5e-3  #: (m/s²)/√Hz, the CWRU normal record's level
FAULTS = ("normal", "outer_race", "inner_race")
CHUNK_S = 0.01  #: s per chunk, as the simulator and from-mat publish
P95_LIMIT_MS = 100.0
MAX_MOTORS = 64

READY_TIMEOUT_S = 180.0
DRAIN_TIMEOUT_S = 20.0  #: s after the player's end for the diagnosers to report every chunk
QUIET_CORES = 0.15  #: others' CPU (cores) below which the machine counts as quiet
QUIET_WAIT_S = 600.0  #: longest wait for a quiet machine before a trial runs anyway
WARM_UP_S = 1.0  #: s of signal whose decisions the latency leaves out
MATCH_S = 2.0  #: s the player waits once the observers listen: the observers' residual publishers match the
# diagnosers meanwhile (a residual sent before would be lost, and counted as dropped)
PLAYER, LISTENER = "bag_play", "listener"  #: process names of the sensors' stand-in and of this process
DOMAINS = itertools.count()  #: a fresh DDS domain per trial: no endpoint of the previous one is matched


@dataclass
class Trial:
    """What one run of N motors measured; CPU in cores, memory in MiB, latency in ms."""

    rate: float
    layout: str
    motors: int
    played: int  # chunks per motor in the bag
    dropped: int  # over all motors and both residual streams: missing + gaps + rejected
    latency_ms: np.ndarray
    cpu: dict  # process name -> cores
    pss: dict  # process name -> MiB
    startup_s: float  # from the processes' start until every node listened
    others: float  # cores other users' processes took while the bag played
    notes: list = field(default_factory=list)

    @property
    def p95(self) -> float:
        return float(np.percentile(self.latency_ms, 95)) if self.latency_ms.size else float("inf")

    @property
    def real_time(self) -> bool:
        return self.dropped == 0 and self.p95 < P95_LIMIT_MS

    def monitoring(self, values: dict) -> float:
        """Sum over the monitoring processes (not the player, not the listener)."""
        return sum(v for k, v in values.items() if k not in (PLAYER, LISTENER))

    @property
    def processes(self) -> int:
        """Monitoring processes (the fleet node included)."""
        return len([k for k in self.pss if k not in (PLAYER, LISTENER)])

    def line(self) -> str:
        return (f"{self.rate / 1000:g} kHz, {self.layout} layout, {self.motors} motors: "
                f"{'real time' if self.real_time else 'NOT real time'}; dropped {self.dropped}; latency p50 "
                f"{np.median(self.latency_ms):.1f} ms, p95 {self.p95:.1f} ms; CPU monitoring "
                f"{self.monitoring(self.cpu):.2f} cores ({self.monitoring(self.cpu) / self.motors:.3f} per motor, "
                f"busiest process {max(v for k, v in self.cpu.items() if k not in (PLAYER, LISTENER)):.2f}), "
                f"player {self.cpu.get(PLAYER, 0):.2f}, listener {self.cpu.get(LISTENER, 0):.2f}; PSS monitoring "
                f"{self.monitoring(self.pss):.0f} MiB in {self.processes} processes; start-up "
                f"{self.startup_s:.1f} s; others' load {self.others:.2f} cores"
                + (f" ({'; '.join(self.notes)})" if self.notes else ""))


# -- the sensors' stand-in ---------------------------------------------------------------
_SIGNALS: dict = {}


def signals(rate: float, seconds: float = SIGNAL_S) -> dict:
    """Simulated drive-end acceleration (m/s²) per fault at ``rate`` Hz, with sensor noise (cached)."""
    key = (rate, seconds)
    if key not in _SIGNALS:
        from bearing_common.states import parse_fault
        from bearing_sim.simulator import SimulationConfig, simulate
        _SIGNALS[key] = {
            fault: simulate(SimulationConfig(rpm=RPM, sample_rate=rate, noise_density=NOISE_DENSITY, seed=i),
                            [(parse_fault(fault), seconds)])["accel"]
            for i, fault in enumerate(FAULTS)}
    return _SIGNALS[key]


def motor_names(n: int) -> list:
    return [f"motor_{k + 1}" for k in range(n)]


def make_bag(out: pathlib.Path, n: int, rate: float, seconds: float = SIGNAL_S) -> int:
    """A bag of ``n`` motors' vibration and shaft speed (the faults in turn); returns chunks per motor."""
    from bearing_recordings.bag_write import write_signals_bag
    sig = signals(rate, seconds)
    return write_signals_bag(out, {m: sig[FAULTS[k % len(FAULTS)]] for k, m in enumerate(motor_names(n))},
                             rate, RPM, "simulator", chunk_duration=CHUNK_S)


# -- /proc -------------------------------------------------------------------------------
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` (all its threads)."""
    fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def machine_busy() -> float:
    """CPU seconds the machine (all cores) has been busy since boot: user, nice, system, irq, softirq."""
    user, nice, system, _idle, _iowait, irq, softirq = map(int, pathlib.Path("/proc/stat").read_text().split()[1:8])
    return (user + nice + system + irq + softirq) / CLOCK_TICKS


def wait_quiet(seconds: float = 3.0, timeout: float = QUIET_WAIT_S) -> bool:
    """Wait until the machine's busy CPU stays below :data:`QUIET_CORES` for ``seconds`` (nothing
    of ours runs between trials); False when it did not within ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        busy0 = machine_busy()
        time.sleep(seconds)
        if (machine_busy() - busy0) / seconds < QUIET_CORES:
            return True
    return False


def pss_mib(pid: int) -> float:
    """Proportional set size of ``pid`` (MiB): its private memory plus its share of shared pages."""
    for line in pathlib.Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
        if line.startswith("Pss:"):
            return int(line.split()[1]) / 1024
    return float("nan")


# -- one trial ---------------------------------------------------------------------------
def fleet_file(tmp: pathlib.Path, n: int, layout: str, motors_per_process: int) -> pathlib.Path:
    """A fleet YAML of ``n`` motors fed by an external sensor (the player)."""
    path = tmp / "fleet.yaml"
    path.write_text(yaml.safe_dump({"layout": layout, "motors_per_process": motors_per_process,
                                    "defaults": {"sensor": "external", "rpm": RPM},
                                    "motors": {m: {} for m in motor_names(n)}}))
    return path


def chunk_counts(status) -> dict:
    """The diagnoser's residual chunk counts per stream from a /diagnostics status:
    {"residual/outer_race": {"accepted": 1500, "gaps": 0, ...}, ...}."""
    out = {}
    for kv in status.values:
        if kv.key.endswith(" chunks"):
            counts = {}
            for part in filter(None, kv.value.split(", ")):
                name, _, value = part.rpartition(" ")
                counts[name] = int(value)
            out[kv.key[: -len(" chunks")]] = counts
    return out


class Listener:
    """The bench's own node: chunk arrivals (raw CDR), fault_state latencies, the diagnosers' chunk counts."""

    def __init__(self, domain: int, motors: list):
        """Chunk counts of every motor in ``motors``; latencies of the first and the last."""
        import rclpy

        from bearing_common import topics
        from bearing_common.node_main import event_executor
        from bearing_diagnoser.diagnoser_session import status_name

        self.motors = motors
        self.arrivals = {m: ([], []) for m in dict.fromkeys((motors[0], motors[-1]))}  # motor -> (chunk stamps
        # s, arrival monotonic s)
        self.latencies: list = []  # s
        self.counts: dict = {}  # motor -> chunk_counts() of its diagnoser's latest status
        self._by_status = {status_name(m): m for m in motors}
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node("fleet_bench_listener", context=self.context)
        vib_type = topics.message_class(topics.VIBRATION.msgtype)
        state_type = topics.message_class(topics.FAULT_STATE.msgtype)
        for m in self.arrivals:
            self.node.create_subscription(vib_type, topics.qualified(m, topics.VIBRATION),
                                          lambda raw, m=m: self._on_chunk(m, raw),
                                          topics.qos(topics.VIBRATION, depth=1000), raw=True)
            self.node.create_subscription(state_type, topics.qualified(m, topics.FAULT_STATE),
                                          lambda msg, m=m: self._on_state(m, msg),
                                          topics.qos(topics.FAULT_STATE, depth=1000))
        self.node.create_subscription(topics.message_class(topics.DIAGNOSTICS.msgtype), topics.DIAGNOSTICS.name,
                                      self._on_diagnostics, topics.qos(topics.DIAGNOSTICS, depth=1000))
        self.executor = event_executor(self.context)
        self.executor.add_node(self.node)

    def _on_chunk(self, motor: str, raw: bytes) -> None:
        sec, nanosec = struct.unpack_from("<iI", raw, 4)  # CDR: 4-byte encapsulation, then header.stamp
        stamps, walls = self.arrivals[motor]
        stamps.append(sec + nanosec * 1e-9)
        walls.append(time.monotonic())

    def _on_state(self, motor: str, msg) -> None:
        arrived = time.monotonic()
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9  # the end of the decided window
        if t <= WARM_UP_S:
            return
        stamps, walls = self.arrivals[motor]
        i = bisect.bisect_left(stamps, t - 1e-9) - 1  # the chunk holding the window's last sample
        if 0 <= i < len(stamps):
            self.latencies.append(arrived - walls[i])

    def _on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name in self._by_status:
                self.counts[self._by_status[status.name]] = chunk_counts(status)

    def listening(self) -> bool:
        """Every motor's observers, diagnoser and the fleet node subscribed (and this listener)."""
        from bearing_common import topics
        need = ((topics.VIBRATION, 2), (topics.RESIDUAL_OUTER_RACE, 1), (topics.RESIDUAL_INNER_RACE, 1),
                (topics.FAULT_STATE, 1))
        extra = {topics.VIBRATION: 1, topics.FAULT_STATE: 1}  # this listener's, on the latency motors
        return all(self.node.count_subscribers(topics.qualified(m, t)) >= k + (m in self.arrivals) * extra.get(t, 0)
                   for m in self.motors for t, k in need)

    def signal_received(self) -> float:
        """Stamp (s) of the latest chunk received, on the latency motor that is furthest behind
        (-1 before the first; the first chunks may pass before this listener is matched)."""
        return min((stamps[-1] if stamps else -1.0) for stamps, _ in self.arrivals.values())

    def accepted(self) -> int:
        """Residual chunks the least served diagnoser accepted, both streams together."""
        return min(sum(c.get("accepted", 0) for c in self.counts.get(m, {}).values()) for m in self.motors)

    def dropped(self, played: int) -> int:
        """Chunks lost on the way, over every motor and both residual streams: missing, gaps, rejected."""
        from bearing_common import topics
        lost = 0
        for m in self.motors:
            for stream in (topics.RESIDUAL_OUTER_RACE.name, topics.RESIDUAL_INNER_RACE.name):
                c = self.counts.get(m, {}).get(stream, {})
                lost += max(0, played - c.get("accepted", 0)) + c.get("gaps", 0) + c.get("rejected", 0)
        return lost

    def spin_until(self, condition, timeout: float, what: str, group) -> None:
        """Serve the subscriptions until ``condition()``; RuntimeError on timeout or a dead process."""
        deadline = time.monotonic() + timeout
        while not condition():
            crashed = [m.name for m in group.members if m.returncode not in (None, 0)]
            if crashed or time.monotonic() > deadline:
                tails = "\n".join(f"[{m.name}] {line}" for m in group.members for line in m.lines[-5:])
                raise RuntimeError(f"{len(self.motors)} motors: "
                                   + (f"{', '.join(crashed)} died" if crashed else f"timed out waiting for {what}")
                                   + f"\n{tails}")
            self.executor.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def snapshot(pids: dict, fn) -> dict:
    """``fn(pid)`` of each process; NaN for one that has gone."""
    out = {}
    for name, pid in pids.items():
        try:
            out[name] = fn(pid)
        except (FileNotFoundError, ProcessLookupError):
            out[name] = float("nan")
    return out


def run_trial(n: int, rate: float, layout: str = "role", motors_per_process: int = MOTORS_PER_PROCESS,
              seconds: float = SIGNAL_S) -> Trial:
    """Run N motors at ``rate`` Hz fed by one bag player; see the module docstring."""
    from bearing_bringup.fleet import load_fleet, parameters_file, processes
    from bearing_bringup.graph_cli import process_argv
    from bearing_bringup.process_group import ProcessGroup

    domain = 200 + (os.getpid() + next(DOMAINS)) % 30
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    with tempfile.TemporaryDirectory(prefix="fleet_bench_") as tmp_name:
        tmp = pathlib.Path(tmp_name)
        played = make_bag(tmp / "bag", n, rate, seconds)
        notes = [] if wait_quiet() else ["the machine was not quiet before"]
        fleet = load_fleet(fleet_file(tmp, n, layout, motors_per_process))
        params = tmp / "fleet_params.yaml"
        params.write_text(yaml.safe_dump(parameters_file(fleet)))
        listener = Listener(domain, motor_names(n))
        group = ProcessGroup(env=env, echo=False)
        try:
            started = time.monotonic()
            for proc in processes(fleet):
                group.start(proc.name, process_argv(proc, params))
            listener.spin_until(listener.listening, READY_TIMEOUT_S, "every node to listen", group)
            startup = time.monotonic() - started
            group.start(PLAYER, [sys.executable, "-m", "bearing_recordings.bag_cli", "play", str(tmp / "bag"),
                                 "--wait-for-subscribers", "2", "--delay", str(MATCH_S)])
            listener.spin_until(lambda: listener.signal_received() >= 0.0, 60.0, "the first chunk", group)
            pids = {m.name: m.process.pid for m in group.members} | {LISTENER: os.getpid()}
            cpu0, wall0, busy0 = snapshot(pids, cpu_seconds), time.monotonic(), machine_busy()
            last = (played - 1) * CHUNK_S  # stamp of the last chunk
            listener.spin_until(lambda: listener.signal_received() >= last - 0.1, seconds * 3 + 60.0,
                                "the bag to be played", group)
            pss = snapshot(pids, pss_mib)  # while everything still runs
            listener.spin_until(lambda: listener.signal_received() >= last - 1e-6, 30.0, "the last chunks", group)
            cpu1, wall, busy = snapshot(pids, cpu_seconds), time.monotonic() - wall0, machine_busy() - busy0
            try:
                listener.spin_until(lambda: listener.accepted() >= 2 * played, DRAIN_TIMEOUT_S,
                                    "every chunk to be decided", group)
            except RuntimeError as exc:
                notes.append(str(exc).splitlines()[0])
            dropped = listener.dropped(played)
        finally:
            group.stop()
            listener.close()
    cpu = {k: (cpu1[k] - cpu0[k]) / wall for k in pids}
    others = max(0.0, busy / wall - sum(v for v in cpu.values() if v == v))  # NaN: a process that had gone
    return Trial(rate, layout, n, played, dropped, np.array(listener.latencies) * 1e3, cpu, pss, startup, others,
                 notes)


# -- capacity ------------------------------------------------------------------------------
def attempt(n: int, rate: float, layout: str, motors_per_process: int, seconds: float, report,
            tries: int = 3) -> Trial:
    """A trial of ``n`` motors; one that failed while others loaded the machine is run again
    (at most ``tries`` times in all): someone else's load must not set the capacity."""
    for k in range(tries):
        trial = run_trial(n, rate, layout, motors_per_process, seconds)
        if k:
            trial.notes.append(f"attempt {k + 1}")
        report(trial.line())
        if trial.real_time or trial.others < QUIET_CORES:
            break
    return trial


def capacity(rate: float, layout: str = "role", motors_per_process: int = MOTORS_PER_PROCESS,
             seconds: float = SIGNAL_S, max_motors: int = MAX_MOTORS, report=print) -> tuple:
    """The largest N that keeps real time at ``rate`` Hz (doubling from 1, then bisecting);
    returns (that trial or None, the smallest failing trial or None)."""
    good = bad = None
    n = 1
    while n <= max_motors:
        trial = attempt(n, rate, layout, motors_per_process, seconds, report)
        if not trial.real_time:
            bad = trial
            break
        good = trial
        n *= 2
    while good is not None and bad is not None and bad.motors - good.motors > 1:
        trial = attempt((good.motors + bad.motors) // 2, rate, layout, motors_per_process, seconds, report)
        if trial.real_time:
            good = trial
        else:
            bad = trial
    return good, bad


def capacity_rows(rate: float, good: Trial | None, bad: Trial | None) -> list:
    khz = f"{rate / 1000:g} kHz"
    cores = os.cpu_count()
    if good is None:
        return [(f"fleet at {khz}: not even one motor kept real time", float("nan"), bad.line() if bad else "")]
    mon = good.monitoring(good.cpu)
    rows = [
        (f"fleet at {khz} ({good.layout} layout, one bag player as the sensors): most motors in real time "
         f"(no dropped chunk, latency p95 < {P95_LIMIT_MS:g} ms)", good.motors, "motors"),
        (f"fleet at {khz}: motors per core ({cores} cores)", round(good.motors / cores, 2), "motors/core"),
        (f"fleet at {khz}, {good.motors} motors: end-to-end latency p50 / p95",
         f"{np.median(good.latency_ms):.1f} / {good.p95:.1f}", "ms"),
        (f"fleet at {khz}, {good.motors} motors: CPU of the monitoring processes (per motor)",
         f"{mon:.2f} ({mon / good.motors:.3f})", "cores"),
        (f"fleet at {khz}, {good.motors} motors: CPU of the bag player / the listener",
         f"{good.cpu[PLAYER]:.2f} / {good.cpu[LISTENER]:.2f}", "cores"),
    ]
    if bad is not None:
        rows.append((f"fleet at {khz}, {bad.motors} motors (first failing): dropped chunks, latency p95",
                     f"{bad.dropped}, {bad.p95:.0f}", "chunks, ms"))
    return rows


def layout_rows(trials: list) -> list:
    """One row per layout of the same fleet: processes, CPU, memory, latency, start-up."""
    rows = []
    for t in trials:
        mon_pss, procs = t.monitoring(t.pss), t.processes
        rows.append((f"fleet layout {t.layout}, {t.motors} motors at {t.rate / 1000:g} kHz: processes, CPU, PSS, "
                     "PSS per process, latency p50 / p95, start-up",
                     f"{procs}, {t.monitoring(t.cpu):.2f} cores, {mon_pss:.0f} MiB, {mon_pss / procs:.0f} MiB, "
                     f"{np.median(t.latency_ms):.1f} / {t.p95:.1f} ms, {t.startup_s:.1f} s", ""))
    return rows


LAYOUT_MOTORS = 8  #: motors of the layout comparison (48 kHz)


def bench_fleet_layouts() -> list:
    """The same fleet (8 motors at 48 kHz) in each process layout."""
    from bearing_bringup.fleet import LAYOUTS
    trials = []
    for layout in LAYOUTS:
        trials.append(run_trial(LAYOUT_MOTORS, 48000.0, layout))
        print(f"[bench]   {trials[-1].line()}", flush=True)
    return layout_rows(trials)


def bench_fleet_capacity() -> list:
    """Most motors in real time per sample rate, motors per core, latency and CPU there."""
    rows = []
    for rate in RATES:
        good, bad = capacity(rate, report=lambda line: print(f"[bench]   {line}", flush=True))
        rows += capacity_rows(rate, good, bad)
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rates", type=float, nargs="+", default=list(RATES), help="sample rates (Hz)")
    parser.add_argument("--layouts", nargs="+", default=["role"], help="process layouts (role, motor, node)")
    parser.add_argument("--motors-per-process", type=int, default=MOTORS_PER_PROCESS, help="role layout")
    parser.add_argument("--motors", type=int, nargs="+", help="run these fleet sizes only (no capacity search)")
    parser.add_argument("--duration", type=float, default=SIGNAL_S, help="seconds of signal per trial")
    args = parser.parse_args(argv)
    for rate in args.rates:
        for layout in args.layouts:
            if args.motors:
                for n in args.motors:
                    print(run_trial(n, rate, layout, args.motors_per_process, args.duration).line(), flush=True)
                continue
            good, bad = capacity(rate, layout, args.motors_per_process, args.duration)
            for figure, value, unit in capacity_rows(rate, good, bad):
                print(f"{figure}: {value} {unit}", flush=True)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())
