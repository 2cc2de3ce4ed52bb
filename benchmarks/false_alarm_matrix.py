"""`make false-alarm-matrix` (also run by `make accuracy`): every healthy recording, many bearings and speeds, no alarm.

Issue 25, item 5. Every healthy recording in ../shared/data (:mod:`benchmarks.healthy_data`:
CWRU 097 drive and fan end, HIT-SM ``Normal_600/900/1200``, and the first quarter of each of the
six FEMTO lives as its snapshots) is diagnosed

* with every catalog bearing (:data:`bearing_common.bearings.CATALOG`) and with bearings whose
  BPFO or BPFI lies on or within ±3 % of a shaft harmonic (:data:`HARMONIC_GEOMETRIES`: 8 balls
  with d/D 0.25, BPFO 3x and BPFI 5x; 9 balls with d/D 1/3, 3x and 6x; 10 balls with d/D 0.22,
  3.9x and 6.1x; contact angle 0; the catalog's 6203 is one too, BPFO 3.05x);
* told its own nominal speed, and told 7 % below and 7 % above it (:data:`SPEEDS`);
* as recorded, with its 1x family notched out, and with a foreign stationary line in its
  envelope (:data:`VARIANTS`, :mod:`benchmarks.healthy_variants`);
* by each mode of :data:`MODES`: ours (what ``bearing-diagnose FILE --bearing B --rpm NOMINAL
  --sample-rate FS`` runs: the model set chosen from the input, the observers where it has a
  model); ours with the machine's own reference (the first half of a recording learnt as
  ``--baseline`` learns it, the second half monitored; not for snapshots, which are not learnt
  from); and the textbook baseline (``--method envelope``). The FEMTO snapshots (0.1 s each, one
  a minute) go through the diagnoser session as the node runs a snapshot sensor (input mode
  ``snapshot``, model set ``none``, as ``bearing-trend`` feeds them), since ``bearing-diagnose``
  refuses a file shorter than one analysis window.

Every cell's outcome: the fault states its segments call (any diagnosed segment other than
NORMAL — OUTER_RACE, INNER_RACE, BALL, or UNKNOWN, "abnormal" — is a false alarm, and on a
healthy machine every named part is a wrong one), the share of its windows not diagnosed, and
whether it was refused as bad input (exit 2). Reported per rig, geometry, told speed and
variant, for each mode, with the list of alarms.

    .venv/bin/python benchmarks/false_alarm_matrix.py [--jobs N] [--quick] [--out FILE] [--docs docs/results.md]
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from collections import Counter, defaultdict
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from functools import cache, partial
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # `benchmarks` as a package

from bearing_common.bearings import CATALOG, Bearing, BearingError  # noqa: E402
from bearing_common.states import FaultState  # noqa: E402
from bearing_diagnoser.decision.segments import Segment, segments_from_decisions  # noqa: E402
from bearing_diagnoser.decision.state_tracker import Decision  # noqa: E402
from bearing_diagnoser.diagnoser import STREAMS  # noqa: E402
from bearing_diagnoser.front_ends import config_for, envelope_baseline  # noqa: E402
from bearing_diagnoser.pipeline import MonitorPipeline  # noqa: E402
from bearing_diagnoser.recording_diagnosis import diagnose_recording  # noqa: E402
from bearing_recordings.load import load_recording  # noqa: E402
from bearing_recordings.recording import InputError, Recording  # noqa: E402
from bearing_recordings.snapshots import open_snapshots  # noqa: E402
from benchmarks import healthy_variants as hv  # noqa: E402
from benchmarks.doc_tables import add_docs_option, nested, write_block  # noqa: E402
from benchmarks.healthy_data import CONTINUOUS, DATA, FEMTO_LIVES  # noqa: E402

#: Pitch diameter (m) of the constructed bearings (the kinematics depend on d/D and n alone).
PITCH = 0.039

#: Share of a FEMTO life, from its first snapshot, taken as healthy.
HEALTHY_SHARE = 0.25


def harmonic_bearing(balls: int, ratio: float, label: str) -> Bearing:
    """A deep-groove ball bearing of ``balls`` balls with d/D = ``ratio``, contact angle 0."""
    return Bearing(f"{balls} balls, d/D {label}", balls, ratio * PITCH, PITCH)


#: Bearings whose BPFO or BPFI lies on or near a shaft harmonic (name: bearing; orders in the names).
HARMONIC_GEOMETRIES = {
    "8 balls d/D 0.25 (BPFO 3x, BPFI 5x)": harmonic_bearing(8, 0.25, "0.25"),
    "9 balls d/D 1/3 (BPFO 3x, BPFI 6x)": harmonic_bearing(9, 1 / 3, "1/3"),
    "10 balls d/D 0.22 (BPFO 3.9x, BPFI 6.1x)": harmonic_bearing(10, 0.22, "0.22"),
}

#: Every bearing of the matrix.
GEOMETRIES: dict[str, Bearing] = dict(CATALOG) | HARMONIC_GEOMETRIES

#: The speed told, as a factor of the nominal one.
SPEEDS = {"own speed": 1.0, "told 7 % low": 0.93, "told 7 % high": 1.07}

VARIANTS = ("as recorded", "1x family notched", "foreign line")


@dataclass(frozen=True)
class Machine:
    """One healthy source: rig, label, the signal as pieces (one for a recording, one per snapshot)
    with their clocks (s), sample rate (Hz), nominal speed (rev/min), the shaft rate its 1x family
    shows (Hz), and for a recording its file and channel (None: snapshots)."""

    rig: str
    label: str
    pieces: tuple
    clocks: tuple
    fs: float
    rpm: float
    fr: float
    file: Path | None = None
    channel: str | None = None

    def recording(self, told_rpm: float, accel: np.ndarray) -> Recording:
        """The recording as ``bearing-diagnose FILE --rpm TOLD --sample-rate FS [--channel C]`` reads it,
        its signal replaced by ``accel``."""
        rec = load_recording(self.file, sample_rate=self.fs, rpm=told_rpm, channel=self.channel)
        return replace(rec, accel=accel)


def sources() -> list[str]:
    """Labels of every healthy source, recordings first."""
    return [h.label for h in CONTINUOUS] + [f"FEMTO {life}" for life in FEMTO_LIVES]


@cache
def machine(label: str) -> Machine:
    """The source ``label`` of :func:`sources`, read once per process."""
    for h in CONTINUOUS:
        if h.label == label:
            rec = load_recording(h.path, sample_rate=h.sample_rate, channel=h.channel)
            fr = hv.shaft_rate(rec.accel, rec.sample_rate, h.rpm / 60.0)
            return Machine(h.rig, label, (rec.accel,), (0.0,), rec.sample_rate, h.rpm, fr, h.path, h.channel)
    life = label.removeprefix("FEMTO ")
    snaps = list(open_snapshots(DATA / "femto" / life))
    end = snaps[0].t + HEALTHY_SHARE * (snaps[-1].t - snaps[0].t)
    healthy = [s for s in snaps if s.t < end]
    rpm = FEMTO_LIVES[life]  # a 0.1 s snapshot resolves 10 Hz: its 1x family cannot refine the speed
    return Machine("FEMTO", label, tuple(s.samples for s in healthy), tuple(s.t for s in healthy),
                   healthy[0].sample_rate, rpm, rpm / 60.0)


@cache
def variant(label: str, name: str, geometry: str) -> tuple[tuple, str]:
    """The pieces of source ``label`` in variant ``name`` (the foreign line placed for ``geometry``),
    and a description of what was changed."""
    m = machine(label)
    if name == "as recorded":
        return m.pieces, ""
    if name == "1x family notched":
        return tuple(hv.without_shaft_family(x, m.fs, m.fr) for x in m.pieces), f"notched at k·{m.fr:.3f} Hz"
    line = hv.place_foreign_line(list(m.pieces), m.fs, GEOMETRIES[geometry], m.fr, list(m.clocks))
    return tuple(hv.modulated(x, m.fs, line.hz, line.depth, t0) for x, t0 in zip(m.pieces, m.clocks)), \
        line.describe()


def decide(m: Machine, pieces: tuple, told_rpm: float, bearing: Bearing, method: str,
           **options) -> tuple[list[Segment], list[Decision]]:
    """Segments and window decisions of ``method`` on ``pieces`` of machine ``m``, told ``told_rpm``:
    a recording through :func:`~bearing_diagnoser.recording_diagnosis.diagnose_recording` as
    ``bearing-diagnose`` runs it (``options`` go to it), snapshots through the diagnoser session as a
    snapshot sensor's node runs them. InputError where the input is refused (exit 2)."""
    if m.file is not None:
        res = diagnose_recording(m.recording(told_rpm, pieces[0]), method=method, rpm=told_rpm, bearing=bearing,
                                 **options)
        return res.segments, res.decisions
    config = config_for("none")
    config = envelope_baseline(config) if method == "envelope" else config
    pipeline = MonitorPipeline(bearing, "none", config, told_rpm, observed=False, streams=STREAMS[:1],
                               parameters={"input_mode": "snapshot"}, strict=False)
    for x, t in zip(pieces, m.clocks):
        pipeline.feed(int(round((t - m.clocks[0]) * m.fs)), m.fs, x, "femto", stamp=t)
    decisions = pipeline.finish()
    return segments_from_decisions(decisions, m.clocks[-1] - m.clocks[0] + pieces[-1].size / m.fs, "none"), decisions


#: Share of a recording, from its start, learnt as the machine's reference in the with-reference mode: as
#: long a commissioning as the stretch then monitored (the reference's level scatter and the monitored
#: evidence are then known about equally well).
REFERENCE_SHARE = 0.5


def decide_with_reference(m: Machine, pieces: tuple, told_rpm: float,
                          bearing: Bearing) -> tuple[list[Segment], list[Decision]]:
    """Ours with the machine's own reference: the first :data:`REFERENCE_SHARE` of the recording (in the
    same variant, told the same speed) learnt as ``bearing-diagnose REST --baseline FIRST`` learns it, the
    rest monitored (recordings only: :data:`RECORDINGS_ONLY`)."""
    x = pieces[0]
    cut = int(REFERENCE_SHARE * x.size)
    return decide(m, (x[cut:],), told_rpm, bearing, method="model", baseline=m.recording(told_rpm, x[:cut]))


#: The modes compared: name -> run(machine, pieces, told rpm, bearing) -> (segments, decisions).
MODES: dict[str, Callable] = {
    "ours": partial(decide, method="model"),
    "ours, with reference": decide_with_reference,
    "baseline": partial(decide, method="envelope"),
}

#: Modes run on the recordings alone: snapshots are not learnt from (a period of pauses is no stretch
#: of signal), so the FEMTO lives have no with-reference cells.
RECORDINGS_ONLY = {"ours, with reference"}


@dataclass(frozen=True)
class Cell:
    source: str
    geometry: str
    speed: str
    variant: str
    mode: str


@dataclass
class Outcome:
    """A cell's fault calls (state labels of its diagnosed segments other than NORMAL), windows, windows
    not diagnosed (by kind), error (bad input: exit 2; ``""``), why its variant could not be built
    (``""``: it was), what its variant changed, CPU time (s)."""

    cell: Cell
    rig: str
    calls: tuple = ()
    windows: int = 0
    not_diagnosed: Counter = field(default_factory=Counter)
    error: str = ""
    unbuilt: str = ""
    change: str = ""
    cpu_s: float = 0.0

    @property
    def alarm(self) -> bool:
        return bool(self.calls)


def run_cell(cell: Cell) -> Outcome:
    """One cell of the matrix."""
    cpu = time.process_time()
    m = machine(cell.source)
    out = Outcome(cell, m.rig)
    try:
        pieces, out.change = variant(cell.source, cell.variant, cell.geometry)
    except ValueError as exc:  # no place for a foreign line
        out.unbuilt = str(exc)
        out.cpu_s = time.process_time() - cpu
        return out
    try:
        segments, decisions = MODES[cell.mode](m, pieces, SPEEDS[cell.speed] * m.rpm, GEOMETRIES[cell.geometry])
    except (InputError, BearingError) as exc:
        out.error = str(exc)
    else:
        out.calls = tuple(dict.fromkeys(s.state.label for s in segments
                                        if s.not_diagnosed is None and s.state != FaultState.NORMAL))
        out.windows = len(decisions)
        out.not_diagnosed = Counter(d.not_diagnosed.kind for d in decisions if not d.diagnosed)
    out.cpu_s = time.process_time() - cpu
    return out


def cells(quick: bool = False) -> list[Cell]:
    """Every cell, grouped by source (each worker then reads few sources); ``quick``: a subset that
    still holds every rig, variant and mode, a catalog and a harmonic geometry, own speed and 7 % low."""
    chosen = sources()
    geometries, speeds = list(GEOMETRIES), list(SPEEDS)
    if quick:
        chosen = ["CWRU 097 drive end", "HIT-SM Normal_1200", "FEMTO Bearing3_1"]
        geometries = ["6205", next(iter(HARMONIC_GEOMETRIES))]
        speeds = speeds[:2]
    recorded = {h.label for h in CONTINUOUS}
    return [Cell(s, g, v, var, mode) for s in chosen for g in geometries for var in VARIANTS for v in speeds
            for mode in MODES if s in recorded or mode not in RECORDINGS_ONLY]


def run(todo: list[Cell], jobs: int = 1, progress: Callable[[int, int], None] | None = None) -> list[Outcome]:
    """Outcomes of ``todo``, in its order, over ``jobs`` worker processes."""
    out = []
    if jobs <= 1:
        results = map(run_cell, todo)
        for r in results:
            out.append(r)
            if progress:
                progress(len(out), len(todo))
        return out
    with ProcessPoolExecutor(jobs) as pool:
        for r in pool.map(run_cell, todo, chunksize=max(1, len(todo) // (8 * jobs))):
            out.append(r)
            if progress:
                progress(len(out), len(todo))
    return out


def _summary(outcomes: list[Outcome]) -> str:
    """"alarms/cells (parts named), not diagnosed %, exit 2, not built" of a group of cells (the cells whose
    variant could not be built are counted apart, not among the cells)."""
    unbuilt = sum(bool(o.unbuilt) for o in outcomes)
    outcomes = [o for o in outcomes if not o.unbuilt]
    if not outcomes:
        return f"not built: {unbuilt}" if unbuilt else "-"
    alarms = [o for o in outcomes if o.alarm]
    parts = Counter(c for o in alarms for c in o.calls)
    named = f" ({', '.join(f'{k} {n}' for k, n in sorted(parts.items()))})" if parts else ""
    windows = sum(o.windows for o in outcomes)
    nd = sum(sum(o.not_diagnosed.values()) for o in outcomes)
    share = f"{100 * nd / windows:.0f} %" if windows else "-"
    refused = sum(bool(o.error) for o in outcomes)
    return (f"{len(alarms)}/{len(outcomes)}{named}, {share}" + (f", exit 2: {refused}" if refused else "")
            + (f", not built: {unbuilt}" if unbuilt else ""))


def table(outcomes: list[Outcome], key: Callable[[Outcome], str], title: str) -> list[str]:
    """One row per value of ``key``, one column per mode."""
    modes = list(dict.fromkeys(o.cell.mode for o in outcomes))
    groups: dict = defaultdict(list)
    for o in outcomes:
        groups[key(o)].append(o)
    rows = [f"| {title} | " + " | ".join(modes) + " |", "|---|" + "---|" * len(modes)]
    for name, group in groups.items():
        rows.append(f"| {name} | " + " | ".join(_summary([o for o in group if o.cell.mode == m]) for m in modes)
                    + " |")
    return rows


def detail(outcomes: list[Outcome]) -> list[str]:
    """Rig × geometry rows, variant × mode columns: alarms/cells."""
    modes = list(dict.fromkeys(o.cell.mode for o in outcomes))
    variants = list(dict.fromkeys(o.cell.variant for o in outcomes))
    groups: dict = defaultdict(list)
    for o in outcomes:
        groups[(o.rig, o.cell.geometry)].append(o)
    cols = [(v, m) for v in variants for m in modes]
    rows = ["| rig | geometry | " + " | ".join(f"{v}: {m}" for v, m in cols) + " |", "|---|---|" + "---|" * len(cols)]
    for (rig, geometry), group in groups.items():
        cells_ = []
        for v, m in cols:
            g = [o for o in group if o.cell.variant == v and o.cell.mode == m and not o.unbuilt]
            cells_.append(f"{sum(o.alarm for o in g)}/{len(g)}")
        rows.append(f"| {rig} | {geometry} | " + " | ".join(cells_) + " |")
    return rows


def alarm_list(outcomes: list[Outcome], modes=None) -> list[str]:
    """Every alarm, refusal and cell not built (of ``modes``; None: all), one row each."""
    rows = ["| source | geometry | speed | variant | mode | called | variant's change |", "|---" * 7 + "|"]
    for o in outcomes:
        if (o.alarm or o.error or o.unbuilt) and (modes is None or o.cell.mode in modes):
            c = o.cell
            rows.append(f"| {c.source} | {c.geometry} | {c.speed} | {c.variant} | {c.mode} | "
                        f"{', '.join(o.calls) or ('exit 2: ' + o.error if o.error else 'not built')} | "
                        f"{o.change or o.unbuilt} |")
    return rows


def markdown(outcomes: list[Outcome], wall_s: float, quick: bool, listed=None) -> str:
    """The report; the alarms of the modes ``listed`` (None: all) one by one."""
    total = ["| all | " + " | ".join(_summary([o for o in outcomes if o.cell.mode == m])
                                    for m in dict.fromkeys(o.cell.mode for o in outcomes)) + " |"]
    lines = ["# False alarms on healthy machines: the matrix", "",
             (__doc__ or "").split("\n\n", 1)[1].split("\n\n    .venv")[0], "",
             "Each cell of the tables: alarms / cells (the states called, counted once per cell), the share of "
             "windows not diagnosed, the cells refused as bad input (exit 2), and those whose variant could not be "
             "built (no place for a foreign line: not counted among the cells)." + (" **Quick subset.**" if quick
                                                                                    else ""), "",
             "## Totals", ""]
    lines += table(outcomes, lambda o: o.cell.variant, "variant") + total
    lines += ["", "## Per rig", ""] + table(outcomes, lambda o: o.rig, "rig")
    lines += ["", "## Per geometry", ""] + table(outcomes, lambda o: o.cell.geometry, "geometry")
    lines += ["", "## Per told speed", ""] + table(outcomes, lambda o: o.cell.speed, "speed told")
    lines += ["", "## Per source", ""] + table(outcomes, lambda o: o.cell.source, "source")
    lines += ["", "## Rig and geometry by variant", ""] + detail(outcomes)
    lines += ["", "## Every alarm" + (f" of {', '.join(listed)}" if listed else ""), ""] + alarm_list(outcomes,
                                                                                                       listed)
    cpu = sum(o.cpu_s for o in outcomes)
    lines += ["", f"({len(outcomes)} cells, {cpu:.0f} s of CPU, {wall_s:.0f} s wall)"]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--quick", action="store_true", help="a subset: three sources, two geometries, two speeds")
    p.add_argument("--out", type=Path, default=ROOT / "out" / "false_alarm_matrix.md")
    add_docs_option(p, "docs/results.md")
    args = p.parse_args(argv)
    missing = [h.path for h in CONTINUOUS if not h.path.is_file()] + \
        [DATA / "femto" / life for life in FEMTO_LIVES if not (DATA / "femto" / life).is_dir()]
    if missing:
        print(f"false-alarm-matrix: {len(missing)} recordings missing (first {missing[0]}); set BEARING_DATA_DIR",
              file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.ERROR)
    start = time.monotonic()
    every = max(1, len(cells(args.quick)) // 20)

    def progress(done: int, total: int) -> None:
        if done % every == 0 or done == total:
            print(f"false-alarm-matrix: {done}/{total} cells, {time.monotonic() - start:.0f} s", file=sys.stderr,
                  flush=True)

    outcomes = run(cells(args.quick), max(1, args.jobs), progress)
    wall = time.monotonic() - start
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(markdown(outcomes, wall, args.quick))
    if args.docs:  # the baseline's alarms (about one cell in four) listed in the out/ file only
        ours = [m for m in MODES if m != "baseline"]
        write_block(args.docs, "false-alarm-matrix", nested(markdown(outcomes, wall, args.quick, ours), 2),
                    "make false-alarm-matrix")
    print(f"false-alarm-matrix: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
