"""`make bench` rows of a fleet: how many motors one machine monitors in real time, per chunk size,
against the per-message floor of rclpy itself.

A trial runs the monitoring graph of N motors (observers, diagnosers and the fleet node,
laid out as in a fleet file: :mod:`bearing_bringup.fleet_plan`) and feeds it from ONE
``bearing-bag play`` of a bag holding every motor's ``<motor>/vibration/drive_end`` and
``<motor>/shaft_speed`` in chunks of the trial's length, made beforehand from simulator
output (normal, outer-race and inner-race signals with sensor noise, 4.5e-3 (m/s²)/√Hz,
assigned to the motors in turn) under the source ``accelerometer``: the observers choose
model set ``none`` and the diagnosers the spectral decision, as for a real machine's sensor
(``--source simulator`` runs the simulator's model sets instead, whose folding decision
publishes a state every 0.01 s whatever the chunk). Motor k's chunks start k/N of a chunk
after motor 0's, as independent sensors' would. The player stands in for the sensors: the
29-DOF simulator costs 0.2-0.3 core per 48 kHz motor; the player's own CPU is reported apart.
A listener in this process measures:

* end-to-end latency, on the first and the last motor (a multi-node process serves the last
  motor of a burst last: the worst case; every message costs the listener 0.1-0.3 ms of CPU,
  which listening to all motors would take from the graph), two ways: from the arrival of
  the vibration chunk holding the last sample of a fault_state's window to the arrival of
  that fault_state (the graph's own latency), and from the time that sample was taken (a
  sensor sends a chunk when its last sample is in: the first latency plus the rest of the
  chunk after the window's end); chunks are taken raw and only their stamp read;
* dropped chunks: every motor's diagnoser counts the residual chunks it accepted and the
  gaps in ``first_sample_index`` (ChunkStream, in its /diagnostics); a chunk lost anywhere
  upstream (player -> observer -> diagnoser) shows as a gap or as fewer accepted chunks
  than the bag holds;
* CPU (cores: CPU seconds per wall second while the bag plays) and memory (PSS, MiB) of
  every process, from /proc.

A trial keeps real time when no chunk is dropped and the 95th percentile of the graph's
latency is below 100 ms; decisions on the first second of signal are left out (each motor's
first windows set up its decision and log it, serialised within a multi-node process). The
capacity per sample rate and chunk size is the largest N that does, searched from an
estimate (the CPU per motor of a 4-motor trial) in steps of 20 %, reported as motors per
core of this machine (N / cores: the player and the listener share the cores too).

The floor: the same trial with :mod:`benchmarks.relay_nodes` in place of the observers and
diagnosers (the same process layout, executor, topics, QoS, message types, sizes and rates,
doing nothing else) at the same N, measured in the same run; the monitoring CPU per motor
over the relay's is the ratio to the floor.

``make bench`` (:func:`bench_fleet_chunks`) runs, per sample rate and chunk size and in turn in
one run, :data:`CHUNK_MOTORS` motors monitored, the relays in their place, and one motor's
decision alone in this process on the same signals and chunks (the work no message layout
changes); motors per core there are 1 / the monitoring's CPU per motor.

The machine is shared: other users' processes (invisible to ``ps`` here) take up to a core
at times. Each trial waits for a quiet machine first and records the CPU others used while
it ran (machine busy time from /proc/stat minus the trial's processes); a trial that fails
while others used more than :data:`QUIET_CORES` is run again once the machine is quiet.

Standalone: ``python benchmarks/fleet_benchmarks.py [--rates 12000 48000] [--chunks 0.01 0.1 1]
[--layouts role] [--graph monitoring|relay] [--motors-per-process K] [--motors N ...]
[--duration S] [--source S] [--quiet-wait S]`` prints one line per trial and the capacity
rows (without ``--motors``: the capacity search).
"""

from __future__ import annotations

import argparse
import bisect
import functools
import itertools
import math
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

from bearing_bringup.fleet_plan import MOTORS_PER_PROCESS  # noqa: E402 (after the path set-up of a script run)

SIGNAL_S = 15.0  #: s of signal per motor and trial
RATES = (12000.0, 48000.0)  #: Hz
CHUNKS = (0.01, 0.1, 1.0)  #: s per chunk
RPM = 1800.0
NOISE_DENSITY = 4.5e-3  #: (m/s²)/√Hz, the CWRU normal record's level
FAULTS = ("normal", "outer_race", "inner_race")
SOURCE = "accelerometer"  #: no shipped model set: none, the spectral decision (a real machine's)
SPEED_PERIOD_S = 0.1  #: s between shaft speeds (a drive's or tachometer's rate; with the first chunk of each)
P95_LIMIT_MS = 100.0
MAX_MOTORS = 256
PROBE_MOTORS = 4  #: the trial whose CPU per motor sets the capacity search's first guess
STEP = 1.2  #: capacity search: N grows or shrinks by this factor (20 % resolution)
TARGET_LOAD = 0.85  #: the first guess puts this fraction of the cores to work

READY_TIMEOUT_S = 300.0
DRAIN_TIMEOUT_S = 20.0  #: s after the player's end for the diagnosers to report every chunk
QUIET_CORES = 0.15  #: others' CPU (cores) below which the machine counts as quiet
QUIET_WAIT_S = 600.0  #: longest wait for a quiet machine before a trial runs anyway
WARM_UP_S = 1.0  #: s of signal whose decisions the latency leaves out
MATCH_S = 2.0  #: s the player waits once the observers listen: the observers' residual publishers match the
# diagnosers meanwhile (a residual sent before would be lost, and counted as dropped)
PLAYER, LISTENER = "bag_play", "listener"  #: process names of the sensors' stand-in and of this process
GRAPHS = ("monitoring", "relay")
RELAY = pathlib.Path(__file__).resolve().parent / "relay_nodes.py"
DOMAINS = itertools.count()  #: a fresh DDS domain per trial: no endpoint of the previous one is matched


@dataclass
class Trial:
    """What one run of N motors measured; CPU in cores, memory in MiB, latency in ms."""

    rate: float
    chunk: float  # s
    graph: str  # monitoring | relay
    layout: str
    motors: int
    played: int  # chunks per motor in the bag
    dropped: int  # over all motors and both residual streams: missing + gaps + rejected
    latency_ms: np.ndarray  # chunk arrival -> fault_state
    sample_latency_ms: np.ndarray  # the window's last sample taken -> fault_state
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
    def per_motor(self) -> float:
        """Cores of the monitoring processes per motor."""
        return self.monitoring(self.cpu) / self.motors

    @property
    def processes(self) -> int:
        """Monitoring processes (the fleet node included)."""
        return len([k for k in self.pss if k not in (PLAYER, LISTENER)])

    def latencies(self) -> str:
        sample = self.sample_latency_ms
        return (f"latency p50 {np.median(self.latency_ms):.1f} ms, p95 {self.p95:.1f} ms (from the sample: "
                f"{np.median(sample):.0f} / {np.percentile(sample, 95):.0f} ms)" if self.latency_ms.size
                else "no latency measured")

    def line(self) -> str:
        return (f"{self.rate / 1000:g} kHz, {self.chunk:g} s chunks, {self.graph}, {self.layout} layout, "
                f"{self.motors} motors: {'real time' if self.real_time else 'NOT real time'}; dropped {self.dropped}; "
                f"{self.latencies()}; CPU monitoring {self.monitoring(self.cpu):.2f} cores ({self.per_motor:.4f} per "
                f"motor, busiest process {max(v for k, v in self.cpu.items() if k not in (PLAYER, LISTENER)):.2f}), "
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


def start_offsets(n: int, rate: float, chunk: float) -> list:
    """Stamp (s) of each motor's first sample: motor k starts k/n of a chunk late, on a sample."""
    return [round(k * chunk * rate / n) / rate for k in range(n)]


def make_bag(out: pathlib.Path, n: int, rate: float, chunk: float, seconds: float = SIGNAL_S,
             source: str = SOURCE) -> int:
    """A bag of ``n`` motors' vibration (the faults in turn) in chunks of ``chunk`` s and shaft speed
    every :data:`SPEED_PERIOD_S` (or chunk), motor k's ``start_offsets`` late, log time = stamp;
    returns chunks per motor."""
    from bearing_common import topics
    from bearing_recordings.bag_write import BagWriter, time_msg
    sig = signals(rate, seconds)
    names = motor_names(n)
    n_chunk = max(1, int(round(chunk * rate)))
    speed_every = n_chunk * max(1, int(round(SPEED_PERIOD_S / chunk)))  # samples between shaft speeds
    omega = RPM * 2.0 * math.pi / 60.0
    vib_type, spd_type = topics.VIBRATION.msgtype, topics.SHAFT_SPEED.msgtype
    with BagWriter(out) as bag:
        T = bag.typestore.types
        for m in names:
            bag.add_graph_topic(topics.VIBRATION, m)
            bag.add_graph_topic(topics.SHAFT_SPEED, m)
        events = sorted((t0 + i0 / rate, k, i0) for k, t0 in enumerate(start_offsets(n, rate, chunk))
                        for i0 in range(0, int(seconds * rate), n_chunk))
        for t, k, i0 in events:
            stamp = time_msg(bag.typestore, t)
            log_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
            x = sig[FAULTS[k % len(FAULTS)]]
            header = T["std_msgs/msg/Header"](stamp=stamp, frame_id="drive_end")
            msg = T[vib_type](header=header, sample_rate=rate, first_sample_index=i0, source=source,
                              samples=np.ascontiguousarray(x[i0:i0 + n_chunk]))
            bag.write(topics.qualified(names[k], topics.VIBRATION), log_ns, bag.serialize(msg, vib_type))
            if i0 % speed_every == 0:
                speed = T[spd_type](header=header, angular_velocity=omega, source=source)
                bag.write(topics.qualified(names[k], topics.SHAFT_SPEED), log_ns, bag.serialize(speed, spd_type))
    return len(range(0, int(seconds * rate), n_chunk))


def motor_decision(rate: float, source: str = SOURCE):
    """One motor's decision as its diagnoser runs it (the model set the source gets, the bag's
    shaft speed told), compiled kernels and tables loaded."""
    from bearing_common.bearings import CATALOG, DEFAULT_BEARING
    from bearing_diagnoser.diagnoser import Diagnoser
    from bearing_diagnoser.front_ends import config_for
    from bearing_diagnoser.warm_up import warm_up
    from bearing_observer.model_sets import choose_model_set
    warm_up()
    bearing = CATALOG[DEFAULT_BEARING]
    name = choose_model_set(source, rate, bearing).name
    core = Diagnoser(config_for(name), name, bearing, rate)
    core.tell_speed(RPM)  # measured: what the bag's shaft speeds tell the diagnosers
    return core


def feed(core, rate: float, x, chunk: float) -> list:
    """Both hypotheses' residual streams = ``x`` (model set none: the measurement) in chunks of
    ``chunk`` s; returns the decisions."""
    from bearing_common.states import FaultState
    n = max(1, int(round(chunk * rate)))
    return [d for i0 in range(0, x.size, n) for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE)
            for d in core.update(h, i0, rate, x[i0:i0 + n], fault_frequency=100.0)]


@functools.cache
def decision_shape(rate: float, source: str = SOURCE, seconds: float = SIGNAL_S) -> tuple:
    """(samples between two decisions of one motor, the names of a decision's scores), measured on
    the decision itself fed 3 s of the normal signal (the relay diagnosers publish alike)."""
    decisions = feed(motor_decision(rate, source), rate, signals(rate, seconds)["normal"][: int(3.0 * rate)], 3.0)
    hop = float(np.median(np.diff(sorted({d.window_end for d in decisions}))))
    return int(round(hop * rate)), tuple(decisions[-1].scores.as_dict())


def decision_cores(rate: float, chunk: float, source: str = SOURCE, seconds: float = SIGNAL_S) -> float:
    """Cores one motor's decision alone takes (CPU s per s of signal, this process, one thread),
    averaged over the bag's signals (each fault's ``seconds`` s in ``chunk``-s chunks, from its
    first sample, as in a trial): the part of a diagnoser's CPU no message layout changes."""
    cpu = 0.0
    for x in signals(rate, seconds).values():
        core = motor_decision(rate, source)
        t0 = time.process_time()
        feed(core, rate, x, chunk)
        cpu += time.process_time() - t0
    return cpu / (seconds * len(FAULTS))


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
def fleet_file(tmp: pathlib.Path, n: int, layout: str, motors_per_process: int, chunk: float) -> pathlib.Path:
    """A fleet YAML of ``n`` motors fed by external sensors (the player) sending ``chunk``-s chunks."""
    path = tmp / "fleet.yaml"
    path.write_text(yaml.safe_dump({"layout": layout, "motors_per_process": motors_per_process,
                                    "defaults": {"sensor": "external", "rpm": RPM, "chunk_duration": chunk},
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
    """The bench's own node: chunk arrivals (raw CDR), fault_state latencies, the diagnosers' chunk counts
    (the monitoring graph's) or their fault_states (the relays', which count nothing)."""

    def __init__(self, domain: int, motors: list, offsets: list, chunk: float, graph: str):
        """Chunk counts of every motor in ``motors``; latencies of the first and the last."""
        import rclpy

        from bearing_common import topics
        from bearing_common.node_main import event_executor
        from bearing_diagnoser.diagnoser_session import status_name

        self.motors, self.chunk, self.graph = motors, chunk, graph
        self.offsets = dict(zip(motors, offsets))
        self.arrivals = {m: ([], []) for m in dict.fromkeys((motors[0], motors[-1]))}  # motor -> (chunk stamps
        # s, arrival monotonic s)
        self.latencies: list = []  # s, chunk arrival -> state
        self.sample_latencies: list = []  # s, the window's last sample -> state
        self.counts: dict = {}  # motor -> chunk_counts() of its diagnoser's latest status
        self.last_state: dict = {}  # motor -> stamp (s) of its latest fault_state (the relays')
        self._by_status = {status_name(m): m for m in motors}
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node("fleet_bench_listener", context=self.context)
        vib_type = topics.message_class(topics.VIBRATION.msgtype)
        state_type = topics.message_class(topics.FAULT_STATE.msgtype)
        self.subscribed = {m: set() for m in motors}  # motor -> the topics this listener takes of it
        for m in self.arrivals:
            self.node.create_subscription(vib_type, topics.qualified(m, topics.VIBRATION),
                                          lambda raw, m=m: self._on_chunk(m, raw),
                                          topics.qos(topics.VIBRATION, depth=1000), raw=True)
            self.subscribed[m].add(topics.VIBRATION)
        for m in motors:  # both graphs alike: each of their publishers serves the same readers
            self.node.create_subscription(state_type, topics.qualified(m, topics.FAULT_STATE),
                                          lambda msg, m=m: self._on_state(m, msg),
                                          topics.qos(topics.FAULT_STATE, depth=1000))
            self.subscribed[m].add(topics.FAULT_STATE)
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
        self.last_state[motor] = t
        if motor not in self.arrivals or t - self.offsets[motor] <= WARM_UP_S:
            return
        stamps, walls = self.arrivals[motor]
        i = bisect.bisect_left(stamps, t - 1e-9) - 1  # the chunk holding the window's last sample
        if 0 <= i < len(stamps):
            self.latencies.append(arrived - walls[i])
            self.sample_latencies.append(arrived - walls[i] + (stamps[i] + self.chunk - t))

    def _on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name in self._by_status:
                self.counts[self._by_status[status.name]] = chunk_counts(status)

    def listening(self) -> bool:
        """Every motor's observers, diagnoser and the fleet node subscribed (and this listener)."""
        from bearing_common import topics
        need = ((topics.VIBRATION, 2), (topics.RESIDUAL_OUTER_RACE, 1), (topics.RESIDUAL_INNER_RACE, 1),
                (topics.FAULT_STATE, 1))
        return all(self.node.count_subscribers(topics.qualified(m, t)) >= k + (t in self.subscribed[m])
                   for m in self.motors for t, k in need)

    def signal_received(self) -> float:
        """Signal time (s from the motor's first sample) of the latest chunk received, on the latency
        motor that is furthest behind (-1 before the first; the first chunks may pass before this
        listener is matched)."""
        return min((stamps[-1] - self.offsets[m] if stamps else -1.0) for m, (stamps, _) in self.arrivals.items())

    def decided_until(self) -> float:
        """Signal time (s) up to which the least served motor has been decided (the relays')."""
        return min(self.last_state.get(m, -1.0) - self.offsets[m] for m in self.motors)

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


def trial_argv(proc, params: pathlib.Path, graph: str, shape: tuple) -> list:
    """A process's command line: the fleet's, or for a multi-node process the relays in its place
    (``shape``: :func:`decision_shape`)."""
    from bearing_bringup.graph_cli import process_argv
    if graph == "relay" and proc.executable == "nodes":
        hop, scores = shape
        return [sys.executable, str(RELAY), "--hop", str(hop), "--scores", ",".join(scores), *proc.arguments,
                *proc.ros_arguments(params)]
    return process_argv(proc, params)


@dataclass(frozen=True)
class Setup:
    """What a trial runs: sample rate (Hz), chunk (s), graph, layout, source, signal seconds."""

    rate: float
    chunk: float
    graph: str = "monitoring"
    layout: str = "role"
    motors_per_process: int = MOTORS_PER_PROCESS
    seconds: float = SIGNAL_S
    source: str = SOURCE
    quiet_wait: float = QUIET_WAIT_S


def run_trial(n: int, setup: Setup) -> Trial:
    """Run N motors fed by one bag player; see the module docstring."""
    from bearing_bringup.fleet_plan import load_fleet, parameters_file, processes
    from bearing_bringup.process_group import ProcessGroup

    if setup.graph == "relay" and setup.layout == "node":
        raise ValueError("the relays run in multi-node processes: layout role or motor")
    domain = 200 + (os.getpid() + next(DOMAINS)) % 30
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    offsets = start_offsets(n, setup.rate, setup.chunk)
    shape = decision_shape(setup.rate, setup.source, setup.seconds)
    with tempfile.TemporaryDirectory(prefix="fleet_bench_") as tmp_name:
        tmp = pathlib.Path(tmp_name)
        played = make_bag(tmp / "bag", n, setup.rate, setup.chunk, setup.seconds, setup.source)
        notes = [] if wait_quiet(timeout=setup.quiet_wait) else ["the machine was not quiet before"]
        fleet = load_fleet(fleet_file(tmp, n, setup.layout, setup.motors_per_process, setup.chunk))
        params = tmp / "fleet_params.yaml"
        params.write_text(yaml.safe_dump(parameters_file(fleet)))
        listener = Listener(domain, motor_names(n), offsets, setup.chunk, setup.graph)
        group = ProcessGroup(env=env, echo=False)
        try:
            started = time.monotonic()
            for proc in processes(fleet):
                group.start(proc.name, trial_argv(proc, params, setup.graph, shape))
            listener.spin_until(listener.listening, READY_TIMEOUT_S, "every node to listen", group)
            startup = time.monotonic() - started
            group.start(PLAYER, [sys.executable, "-m", "bearing_recordings.bag_cli", "play", str(tmp / "bag"),
                                 "--wait-for-subscribers", "2", "--delay", str(MATCH_S)])
            listener.spin_until(lambda: listener.signal_received() >= 0.0, 60.0, "the first chunk", group)
            pids = {m.name: m.process.pid for m in group.members} | {LISTENER: os.getpid()}
            cpu0, wall0, busy0 = snapshot(pids, cpu_seconds), time.monotonic(), machine_busy()
            last = (played - 1) * setup.chunk  # signal time of the last chunk's first sample
            listener.spin_until(lambda: listener.signal_received() >= last - setup.chunk - 0.1,
                                setup.seconds * 3 + 60.0, "the bag to be played", group)
            pss = snapshot(pids, pss_mib)  # while everything still runs
            listener.spin_until(lambda: listener.signal_received() >= last - 1e-6, 30.0, "the last chunks", group)
            cpu1, wall, busy = snapshot(pids, cpu_seconds), time.monotonic() - wall0, machine_busy() - busy0
            dropped = drain(listener, played, setup, shape[0], notes, group)
        finally:
            group.stop()
            listener.close()
    cpu = {k: (cpu1[k] - cpu0[k]) / wall for k in pids}
    others = max(0.0, busy / wall - sum(v for v in cpu.values() if v == v))  # NaN: a process that had gone
    return Trial(setup.rate, setup.chunk, setup.graph, setup.layout, n, played, dropped,
                 np.array(listener.latencies) * 1e3, np.array(listener.sample_latencies) * 1e3, cpu, pss, startup,
                 others, notes)


def drain(listener: Listener, played: int, setup: Setup, hop: int, notes: list, group) -> int:
    """Wait until every chunk is decided (the relays: their last states, ``hop`` samples apart);
    return the chunks dropped (the relays count none: 0)."""
    try:
        if setup.graph == "monitoring":
            listener.spin_until(lambda: listener.accepted() >= 2 * played, DRAIN_TIMEOUT_S,
                                "every chunk to be decided", group)
        else:
            end = played * setup.chunk - hop / setup.rate - setup.chunk
            listener.spin_until(lambda: listener.decided_until() >= end, DRAIN_TIMEOUT_S,
                                "every motor's last states", group)
    except RuntimeError as exc:
        notes.append(str(exc).splitlines()[0])
    return listener.dropped(played) if setup.graph == "monitoring" else 0


# -- capacity ------------------------------------------------------------------------------
def attempt(n: int, setup: Setup, report, tries: int = 3) -> Trial:
    """A trial of ``n`` motors; one that failed while others loaded the machine is run again
    (at most ``tries`` times in all): someone else's load must not set the capacity."""
    for k in range(tries):
        trial = run_trial(n, setup)
        if k:
            trial.notes.append(f"attempt {k + 1}")
        report(trial.line())
        if trial.real_time or trial.others < QUIET_CORES:
            break
    return trial


def first_guess(probe: Trial) -> int:
    """Motors that would put :data:`TARGET_LOAD` of the cores to work, from a trial's CPU per
    motor (the monitoring processes, the player and the listener)."""
    per_motor = (probe.monitoring(probe.cpu) + probe.cpu.get(PLAYER, 0.0)) / probe.motors
    return max(1, min(MAX_MOTORS, int(TARGET_LOAD * os.cpu_count() / per_motor)))


def capacity(setup: Setup, max_motors: int = MAX_MOTORS, report=print) -> tuple:
    """The largest N that keeps real time (from :func:`first_guess` of a :data:`PROBE_MOTORS`
    trial, up or down by :data:`STEP` until the verdict changes); returns (that trial or None,
    the smallest failing trial or None)."""
    probe = attempt(PROBE_MOTORS, setup, report)
    good, bad = (probe, None) if probe.real_time else (None, probe)
    n = max(first_guess(probe), PROBE_MOTORS + 1) if probe.real_time else PROBE_MOTORS - 1
    while 1 <= n <= max_motors and (good is None or n > good.motors) and (bad is None or n < bad.motors):
        trial = attempt(n, setup, report)
        if trial.real_time:
            good = trial
            n = max(n + 1, int(n * STEP))
        else:
            bad = trial
            n = min(n - 1, int(n / STEP))
    return good, bad


def capacity_rows(setup: Setup, good: Trial | None, bad: Trial | None, floor: Trial | None,
                  reference: Trial | None) -> list:
    """Rows of one sample rate and chunk: capacity, motors per core, latency, CPU against the floor;
    ``reference``: the 0.01 s capacity trial of the same run (motors per core as its multiple)."""
    what = f"fleet at {setup.rate / 1000:g} kHz, {setup.chunk:g} s chunks"
    cores = os.cpu_count()
    if good is None:
        return [(f"{what}: not even one motor kept real time", float("nan"), bad.line() if bad else "")]
    mon = good.monitoring(good.cpu)
    rows = [
        (f"{what} ({good.layout} layout, one bag player as the sensors): most motors in real time "
         f"(no dropped chunk, latency p95 < {P95_LIMIT_MS:g} ms)", good.motors, "motors"),
        (f"{what}: motors per core ({cores} cores)", round(good.motors / cores, 2), "motors/core"),
    ]
    if reference is not None and reference is not good:
        rows.append((f"{what}: motors per core / those with {reference.chunk:g} s chunks (same run)",
                     round(good.motors / reference.motors, 2), "ratio"))
    rows += [
        (f"{what}, {good.motors} motors: latency chunk arrival -> fault_state p50 / p95; from the window's last "
         "sample p50 / p95", f"{np.median(good.latency_ms):.1f} / {good.p95:.1f}; "
         f"{np.median(good.sample_latency_ms):.0f} / {np.percentile(good.sample_latency_ms, 95):.0f}", "ms"),
        (f"{what}, {good.motors} motors: CPU of the monitoring processes (per motor)",
         f"{mon:.2f} ({good.per_motor:.4f})", "cores"),
    ]
    if floor is not None:
        rows += [(f"{what}, {floor.motors} motors: CPU of bare rclpy relays in their place (per motor), same run",
                  f"{floor.monitoring(floor.cpu):.2f} ({floor.per_motor:.4f})", "cores"),
                 (f"{what}: monitoring CPU per motor / the relays' (the floor; target <= 1.5)",
                  round(good.per_motor / floor.per_motor, 2), "ratio")]
    rows.append((f"{what}, {good.motors} motors: CPU of the bag player / the listener",
                 f"{good.cpu[PLAYER]:.2f} / {good.cpu[LISTENER]:.2f}", "cores"))
    if bad is not None:
        rows.append((f"{what}, {bad.motors} motors (first failing): dropped chunks, latency p95",
                     f"{bad.dropped}, {bad.p95:.0f}", "chunks, ms"))
    return rows


def layout_rows(trials: list) -> list:
    """One row per layout of the same fleet: processes, CPU, memory, latency, start-up."""
    rows = []
    for t in trials:
        mon_pss, procs = t.monitoring(t.pss), t.processes
        rows.append((f"fleet layout {t.layout}, {t.motors} motors at {t.rate / 1000:g} kHz, {t.chunk:g} s chunks: "
                     "processes, CPU, PSS, PSS per process, latency p50 / p95, start-up",
                     f"{procs}, {t.monitoring(t.cpu):.2f} cores, {mon_pss:.0f} MiB, {mon_pss / procs:.0f} MiB, "
                     f"{np.median(t.latency_ms):.1f} / {t.p95:.1f} ms, {t.startup_s:.1f} s", ""))
    if trials:
        ref = trials[0]
        rows.append((f"fleet layouts, {ref.motors} motors: CPU of each / the {ref.layout} layout's (same run)",
                     " / ".join(f"{t.layout} {t.monitoring(t.cpu) / ref.monitoring(ref.cpu):.2f}" for t in trials),
                     "ratio"))
    return rows


LAYOUT_MOTORS = 8  #: motors of the layout comparison (48 kHz, 0.01 s chunks)


def bench_fleet_layouts() -> list:
    """The same fleet (8 motors at 48 kHz, 0.01 s chunks) in each process layout."""
    from bearing_bringup.fleet_plan import LAYOUTS
    trials = []
    for layout in LAYOUTS:
        trials.append(run_trial(LAYOUT_MOTORS, Setup(48000.0, CHUNKS[0], layout=layout)))
        print(f"[bench]   {trials[-1].line()}", flush=True)
    return layout_rows(trials)


def chunk_rows(setups: list, report) -> list:
    """Capacity and floor per setup (the first of each rate is the same run's reference)."""
    rows, reference = [], {}
    for setup in setups:
        good, bad = capacity(setup, report=report)
        floor = None
        if good is not None:
            floor = run_trial(good.motors, Setup(setup.rate, setup.chunk, "relay", setup.layout,
                                                 setup.motors_per_process, setup.seconds, setup.source,
                                                 setup.quiet_wait))
            report(floor.line())
        reference.setdefault(setup.rate, good)
        rows += capacity_rows(setup, good, bad, floor, reference[setup.rate])
    return rows


CHUNK_MOTORS = 4  #: motors of make bench's per-chunk trials
CHUNK_SIGNAL_S = 8.0  #: s of signal per motor in those trials
CHUNK_QUIET_WAIT_S = 10.0  #: their longest wait for a quiet machine (others' load is reported instead)


def per_chunk_rows(trials: dict, decision: dict) -> list:
    """Rows of :func:`bench_fleet_chunks`: ``trials[rate, chunk, graph]``, ``decision[rate, chunk]``
    (:func:`decision_cores`); motors per core are the monitoring processes' (1 / their cores per
    motor), each chunk's also as a multiple of the 0.01 s chunks'; the CPU per motor as a ratio to
    the relays' (the floor), whole and without the decision's own work."""
    rows = []
    for rate in RATES:
        reference = trials[rate, CHUNKS[0], "monitoring"]
        for chunk in CHUNKS:
            mon, floor, dec = trials[rate, chunk, "monitoring"], trials[rate, chunk, "relay"], decision[rate, chunk]
            what = f"fleet at {rate / 1000:g} kHz, {chunk:g} s chunks, {mon.motors} motors"
            verdict = "real time" if mon.real_time else f"NOT real time (dropped {mon.dropped}, p95 {mon.p95:.0f} ms)"
            rows += [
                (f"{what}: monitoring CPU per motor / bare rclpy relays' in their place (same run; "
                 f"the floor, target <= 1.5); {verdict}",
                 f"{mon.per_motor:.4f} / {floor.per_motor:.4f} = {mon.per_motor / floor.per_motor:.2f}",
                 "cores, ratio"),
                (f"{what}: one motor's decision alone (same signals and chunks, this process); its share "
                 "of the monitoring CPU per motor; (monitoring - decision) / the floor",
                 f"{dec:.4f}; {dec / mon.per_motor:.2f}; {(mon.per_motor - dec) / floor.per_motor:.2f}",
                 "cores, ratio, ratio"),
                (f"{what}: motors per core of the monitoring (1 / its CPU per motor); / those with "
                 f"{CHUNKS[0]:g} s chunks (same run; target >= 10 at 0.1 s); the same multiple for the floor",
                 f"{1 / mon.per_motor:.1f}; {reference.per_motor / mon.per_motor:.2f}; "
                 f"{trials[rate, CHUNKS[0], 'relay'].per_motor / floor.per_motor:.2f}", "motors/core, ratio, ratio"),
                (f"{what}: latency chunk arrival -> fault_state p50 / p95; from the window's last sample p50 / p95",
                 f"{np.median(mon.latency_ms):.1f} / {mon.p95:.1f}; {np.median(mon.sample_latency_ms):.0f} / "
                 f"{np.percentile(mon.sample_latency_ms, 95):.0f}" if mon.latency_ms.size else "none measured", "ms"),
            ]
    others = [t.others for t in trials.values()]
    rows.append(("fleet per-chunk trials: other users' load while they ran, min / max",
                 f"{min(others):.2f} / {max(others):.2f}", "cores"))
    return rows


def bench_fleet_chunks() -> list:
    """Per sample rate and chunk size: CPU per motor of :data:`CHUNK_MOTORS` monitored motors, of
    bare relays in their place and of one motor's decision alone, in turn in the same run; motors
    per core and the ratios to the floor (the capacity search is the standalone run, :func:`main`)."""
    trials, decision = {}, {}
    for rate in RATES:
        for chunk in CHUNKS:
            decision[rate, chunk] = decision_cores(rate, chunk, SOURCE, CHUNK_SIGNAL_S)
            print(f"[bench]   {rate / 1000:g} kHz, {chunk:g} s chunks: one motor's decision alone "
                  f"{decision[rate, chunk]:.4f} cores", flush=True)
            for graph in GRAPHS:
                setup = Setup(rate, chunk, graph, seconds=CHUNK_SIGNAL_S, quiet_wait=CHUNK_QUIET_WAIT_S)
                trials[rate, chunk, graph] = run_trial(CHUNK_MOTORS, setup)
                print(f"[bench]   {trials[rate, chunk, graph].line()}", flush=True)
    return per_chunk_rows(trials, decision)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rates", type=float, nargs="+", default=list(RATES), help="sample rates (Hz)")
    parser.add_argument("--chunks", type=float, nargs="+", default=list(CHUNKS), help="chunk durations (s)")
    parser.add_argument("--layouts", nargs="+", default=["role"], help="process layouts (role, motor, node)")
    parser.add_argument("--graph", choices=GRAPHS, default="monitoring", help="with --motors: which graph")
    parser.add_argument("--motors-per-process", type=int, default=MOTORS_PER_PROCESS, help="role layout")
    parser.add_argument("--motors", type=int, nargs="+", help="run these fleet sizes only (no capacity search)")
    parser.add_argument("--duration", type=float, default=SIGNAL_S, help="seconds of signal per trial")
    parser.add_argument("--source", default=SOURCE, help="the chunks' source (picks the model set)")
    parser.add_argument("--quiet-wait", type=float, default=QUIET_WAIT_S,
                        help="longest wait (s) for a quiet machine before each trial")
    args = parser.parse_args(argv)
    setups = [Setup(rate, chunk, args.graph, layout, args.motors_per_process, args.duration, args.source,
                    args.quiet_wait) for rate in args.rates for layout in args.layouts for chunk in args.chunks]
    if args.motors:
        for setup in setups:
            for n in args.motors:
                print(run_trial(n, setup).line(), flush=True)
        return 0
    for figure, value, unit in chunk_rows(setups, lambda line: print(line, flush=True)):
        print(f"{figure}: {value} {unit}", flush=True)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())
