"""A fleet: several monitored motors on one machine, from one YAML (no rclpy).

``bearing-graph --fleet FILE [--motors N]`` and ``launch/fleet.launch.py`` read a fleet
file (``config/fleet.yaml``)::

    layout: role               # processes: role | motor | node (see below)
    motors_per_process: 12     # role layout: motors per observers / diagnosers process
    parameters: ""             # per-node base parameters; "" = the installed config/monitor.yaml
    defaults: {sensor: simulator, rpm: 1800.0}        # settings of every motor
    motors:                                           # one entry per motor = its namespace
      motor_1: {scenario: or}
      motor_2: {scenario: ir, rpm: 1750.0, diagnoser: {stale_timeout: 2.0}}
    fleet: {period: 1.0}       # parameters of the fleet node

A motor's settings (:data:`SETTINGS`) go to the parameter of the same name of the nodes
that use it, on top of the base parameters: ``bearing`` (observers, diagnoser), ``rpm``
(simulator, observers, diagnoser), ``sample_rate``, ``scenario``, ``schedule``,
``segment_duration``, ``noise_density``, ``seed`` (simulator); ``speed_topic`` remaps the
motor's ``shaft_speed`` for all its nodes (a drive's topic); ``sensor`` is ``simulator``
(a simulator node stands in for the sensor) or ``external`` (a driver or ``bearing-bag
play`` publishes ``<motor>/vibration/drive_end``); a node name holds parameters of that
node alone. Every value is checked against the node's declared parameters when loaded.

``chunk_duration`` (s) is the sensor's chunk: the simulator's parameter for a simulated
motor (default the simulator's, 0.01 s, the thesis' cases), what the driver publishes for
an external one (default :data:`EXTERNAL_CHUNK_S`). Residuals and decisions then arrive
in bursts one chunk apart, so the diagnoser's and the fleet node's ``stale_timeout`` are
at least :data:`STALE_CHUNKS` chunks.

Processes (each restarted on its own by the restart policy): a simulator per simulated
motor and the ``fleet`` node always run alone; the monitoring nodes run as

* ``node``: one process per node, the single-node executables (3 per motor);
* ``motor``: one ``nodes`` process per motor with its two observers and its diagnoser;
* ``role``: one ``nodes`` process for the observers and one for the diagnosers of each
  ``motors_per_process`` motors.

Every node finds its parameters in one generated file keyed by its fully qualified name
(:func:`parameters_file`).
"""

from __future__ import annotations

import importlib
import math
import pathlib
import re
from dataclasses import dataclass, field, replace

import yaml

from bearing_common import topics

from .graph import FLEET_CONFIG_NAME, FLEET_NODE, GRAPH, Process, config_path

LAYOUTS = ("role", "motor", "node")
SENSORS = ("simulator", "external")
SPECS = {spec.name: spec for spec in GRAPH + (FLEET_NODE,)}
NODE_NAMES = tuple(spec.name for spec in GRAPH)
SIMULATOR = "simulator"
DIAGNOSER = "diagnoser"
MONITORS = tuple(spec.name for spec in GRAPH if spec.node_class)  # or_observer, ir_observer, diagnoser

#: Motor settings -> the nodes whose parameter of that name they set.
SETTINGS = {
    "bearing": MONITORS,
    "rpm": (SIMULATOR, *MONITORS),
    **{name: (SIMULATOR,) for name in ("sample_rate", "scenario", "schedule", "segment_duration", "noise_density",
                                       "seed", "chunk_duration")},
}
FILE_KEYS = ("layout", "motors_per_process", "parameters", "defaults", "motors", "fleet")
NAMESPACE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")
ROLE_PROCESS = {"observer": "observers", "diagnoser": "diagnosers"}  # role layout: executable -> process name
#: Role layout: at 48 kHz an observers process of 12 motors takes about 0.7 core (docs/fleet.md).
MOTORS_PER_PROCESS = 12
#: Chunk (s) an external sensor publishes unless the fleet file says otherwise: a tenth of the
#: messages of 0.01 s chunks for at most 0.1 s more latency (docs/fleet.md).
EXTERNAL_CHUNK_S = 0.1
#: Staleness timeouts are at least this many chunks (data arrives one chunk at a time).
STALE_CHUNKS = 3


class FleetError(ValueError):
    """A fleet file that cannot be run, with the reason."""


@dataclass(frozen=True)
class Motor:
    """One monitored motor: its namespace (no leading slash), whether a simulator stands in
    for its sensor, its nodes' parameters (node name -> {parameter: value}), its speed topic,
    its sensor's chunk (s)."""

    name: str
    simulated: bool
    parameters: dict
    speed_topic: str = ""
    chunk_duration: float = EXTERNAL_CHUNK_S

    def nodes(self) -> tuple:
        """Its node names, the simulator first when it has one."""
        return ((SIMULATOR,) if self.simulated else ()) + MONITORS


@dataclass(frozen=True)
class Fleet:
    motors: tuple
    layout: str = "role"
    motors_per_process: int = MOTORS_PER_PROCESS
    fleet_parameters: dict = field(default_factory=dict)


def load_fleet(path, motors: int | None = None, base_parameters=None) -> Fleet:
    """The fleet of the YAML at ``path``; ``motors`` = N: its first N motors, completed with
    ``motor_<k>`` on the defaults when it lists fewer; ``base_parameters`` (a path) overrides
    the file's ``parameters``. Raises FleetError naming what is wrong."""
    path = pathlib.Path(path)
    doc = _read_yaml(path)
    unknown = set(doc) - set(FILE_KEYS)
    if unknown:
        raise FleetError(f"{path}: unknown keys {', '.join(sorted(unknown))}; expected {', '.join(FILE_KEYS)}")
    layout = doc.get("layout", "role")
    if layout not in LAYOUTS:
        raise FleetError(f"{path}: layout must be one of {', '.join(LAYOUTS)}, got {layout!r}")
    per_process = doc.get("motors_per_process", MOTORS_PER_PROCESS)
    if not (isinstance(per_process, int) and per_process > 0):
        raise FleetError(f"{path}: motors_per_process must be a positive integer, got {per_process!r}")
    base_path = base_parameters or (path.parent / doc["parameters"] if doc.get("parameters") else config_path())
    base = _read_yaml(pathlib.Path(base_path))
    listed = dict(doc.get("motors") or {})
    names = list(listed)
    if motors is not None:
        if motors < 1:
            raise FleetError(f"the number of motors must be at least 1, got {motors}")
        names = names[:motors]
        k = 0
        while len(names) < motors:
            k += 1
            if f"motor_{k}" not in names:
                names.append(f"motor_{k}")
    if not names:
        raise FleetError(f"{path}: no motors listed (give motors: or --motors N)")
    defaults = doc.get("defaults") or {}
    built = tuple(_motor(name, {**defaults, **(listed.get(name) or {})}, base, path) for name in names)
    fleet_parameters = _checked(FLEET_NODE.name, {**_section(base, FLEET_NODE.name), **(doc.get("fleet") or {})},
                                f"{path}: fleet")
    _stale_floor(fleet_parameters, FLEET_NODE.name, max(m.chunk_duration for m in built))
    return Fleet(built, layout, per_process, fleet_parameters)


def _default(node: str, parameter: str):
    """The declared default of a node's parameter."""
    return next(p.default for p in importlib.import_module(SPECS[node].parameters_module).PARAMETERS
                if p.name == parameter)


def _stale_floor(params: dict, node: str, chunk_s: float) -> None:
    """Raise ``params``' stale_timeout (or the node's default) to :data:`STALE_CHUNKS` chunks."""
    floor = STALE_CHUNKS * chunk_s
    if params.get("stale_timeout", _default(node, "stale_timeout")) < floor:
        params["stale_timeout"] = floor


def _read_yaml(path: pathlib.Path) -> dict:
    try:
        doc = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise FleetError(f"cannot read {path}: {exc}") from None
    if not isinstance(doc, dict):
        raise FleetError(f"{path}: expected a mapping at the top level")
    return doc


def _section(base: dict, node: str) -> dict:
    """A node's ``ros__parameters`` in a base parameters file (by node name)."""
    return dict(((base.get(node) or {}).get("ros__parameters")) or {})


def _motor(name: str, settings: dict, base: dict, path) -> Motor:
    where = f"{path}: {name}"
    if not isinstance(name, str) or not NAMESPACE.fullmatch(name):
        raise FleetError(f"{path}: motor name {name!r} is not a namespace (letters, digits, _ and /)")
    settings = dict(settings)
    sensor = settings.pop("sensor", "simulator")
    if sensor not in SENSORS:
        raise FleetError(f"{where}: sensor must be one of {', '.join(SENSORS)}, got {sensor!r}")
    speed_topic = settings.pop("speed_topic", "")
    unknown = set(settings) - set(SETTINGS) - set(NODE_NAMES)
    if unknown:
        raise FleetError(f"{where}: unknown settings {', '.join(sorted(unknown))}; expected sensor, speed_topic, "
                         f"{', '.join(SETTINGS)} or a node name ({', '.join(NODE_NAMES)})")
    simulated = sensor == "simulator"
    if not simulated:  # no node of the motor's takes its chunk
        chunk = _external_chunk(settings.pop("chunk_duration", EXTERNAL_CHUNK_S), where)
    motor = Motor(name, simulated, {}, speed_topic)
    for node in motor.nodes():
        own = settings.get(node) or {}
        if not isinstance(own, dict):
            raise FleetError(f"{where}.{node}: expected a mapping of parameters, got {own!r}")
        params = _section(base, node)
        params.update({key: value for key, value in settings.items() if node in SETTINGS.get(key, ())})
        params.update(own)
        motor.parameters[node] = _checked(node, params, f"{where}.{node}")
    if simulated:
        chunk = motor.parameters[SIMULATOR].get("chunk_duration", _default(SIMULATOR, "chunk_duration"))
    _stale_floor(motor.parameters[DIAGNOSER], DIAGNOSER, chunk)
    return replace(motor, chunk_duration=chunk)


def _external_chunk(value, where: str) -> float:
    """An external sensor's chunk_duration (s), checked."""
    chunk = float(value) if type(value) in (int, float) else value
    if not (isinstance(chunk, float) and math.isfinite(chunk) and chunk > 0):
        raise FleetError(f"{where}.chunk_duration: expected a positive number of seconds, got {value!r}")
    return chunk


def _checked(node: str, params: dict, where: str) -> dict:
    """``params`` checked against the node's declared parameters (integers given for float
    parameters become floats, as ``ros2 param`` would need them)."""
    declared = {p.name: p for p in importlib.import_module(SPECS[node].parameters_module).PARAMETERS}
    declared["use_sim_time"] = None
    out = {}
    for key, value in params.items():
        if key not in declared:
            raise FleetError(f"{where}: {key!r} is not a parameter of {node}")
        spec = declared[key]
        if spec is None:
            out[key] = value
            continue
        if isinstance(spec.default, float) and type(value) is int:
            value = float(value)
        if type(value) is not type(spec.default):
            raise FleetError(f"{where}.{key}: expected {type(spec.default).__name__} like {spec.default!r}, "
                             f"got {value!r}")
        error = spec.validate(value)
        if error:
            raise FleetError(f"{where}.{key}: {error}")
        out[key] = value
    return out


def parameters_file(fleet: Fleet) -> dict:
    """The parameters of every node, keyed by fully qualified name (``/motor_3/diagnoser``)."""
    doc = {f"/{motor.name}/{node}": {"ros__parameters": params}
           for motor in fleet.motors for node, params in motor.parameters.items()}
    doc[f"/{FLEET_NODE.name}"] = {"ros__parameters": dict(fleet.fleet_parameters)}
    return doc


def processes(fleet: Fleet) -> list:
    """The fleet graph's processes: simulators, the monitoring nodes as ``fleet.layout`` groups
    them, the fleet node."""
    out = []
    groups: dict = {}  # process name -> [(motor, node name)] of a multi-node process
    for i, motor in enumerate(fleet.motors):
        remap = ((topics.qualified(motor.name, topics.SHAFT_SPEED), motor.speed_topic),) if motor.speed_topic else ()
        for node in motor.nodes():
            spec = SPECS[node]
            if node == SIMULATOR or fleet.layout == "node":
                out.append(Process(f"{motor.name}/{node}", spec.package, spec.executable, node, motor.name,
                                   remappings=remap, sensor=node == SIMULATOR))
            elif fleet.layout == "motor":
                groups.setdefault(f"{motor.name}/monitor", []).append((motor, node))
            else:
                shard = i // fleet.motors_per_process + 1
                groups.setdefault(f"{ROLE_PROCESS[spec.executable]}_{shard}", []).append((motor, node))
    for name, members in groups.items():
        remaps = {topics.qualified(m.name, topics.SHAFT_SPEED): m.speed_topic for m, _ in members if m.speed_topic}
        out.append(Process(name, "bearing_bringup", "nodes", arguments=tuple(f"/{m.name}/{n}" for m, n in members),
                           remappings=tuple(remaps.items())))
    out.append(Process(FLEET_NODE.name, FLEET_NODE.package, FLEET_NODE.executable, FLEET_NODE.name))
    return out


def default_fleet_file() -> pathlib.Path:
    """The installed ``config/fleet.yaml`` (else the source tree's)."""
    return config_path(FLEET_CONFIG_NAME)
