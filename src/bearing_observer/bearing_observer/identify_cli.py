"""``bearing-identify``: identify the OR / IR Hammerstein-Wiener models, write model files.

Examples (the first three reproduce the shipped model sets)::

    bearing-identify --source sim --sample-rate 48000 --model-set sim_48k
    bearing-identify --source sim --sample-rate 12000 --mode series --model-set sim_12k
    bearing-identify --source outer_race=../shared/data/cwru/130_OR007at6_0hp_DE12k.mat \\
                     --source inner_race=../shared/data/cwru/105_IR007_0hp_DE12k.mat \\
                     --sample-rate 12000 --orders 6 6 0 --max-seconds 2 --model-set cwru_de_6205
    bearing-identify --source outer_race=OuterRaceFault_vload_1.mat \\
                     --source inner_race=InnerRaceFault_vload_1.mat --bearing mfpt --model-set my_mfpt

``--source sim`` simulates each fault (``bearing_sim.simulator``, its drive-end bearing,
noise off, 1800 rpm by default) for ``--duration`` seconds. ``--source FAULT=FILE`` (or
``FILE --fault FAULT``) reads a recording of a known fault: anything ``bearing-diagnose``
reads (CWRU / MFPT / one-signal .mat, .npz, rosbag2; channel rule of
``bearing_recordings.mat_files``). Sample rate and speed come from the file where it stores
them (MFPT), else from ``--sample-rate`` / ``--rpm`` (CWRU: rate; one-signal files such as
HIT-SM: both, units g unless ``--units``). ``--bearing`` names the machine's bearing
(catalog name, YAML file or ``N,d,D,angle``; default 6205) and is recorded in the model
files. ``--order-search`` prints the fit per order and keeps the order with the best
held-back fit. Model files go to ``--out DIR/<model-set>/<fault>.json`` (default: the
package's ``models/`` directory); use the set by name (observer ``model_set``,
``bearing-diagnose --model-set``) or, when written elsewhere, by its directory.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shlex
import sys
import time
from pathlib import Path

from bearing_common.bearings import DEFAULT_BEARING, Bearing, BearingError, load_bearing
from bearing_common.model_set_info import FAULT_TYPES, NONE

# the identification and the model files (numpy, scipy, numba) are imported where they are used:
# not for --help or a rejected argument

ORDER_GRID = [(n, n, k) for n in (4, 6, 8, 10, 12) for k in (0, 1)]


def _sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _parse_sources(sources, fault):
    """-> list of (fault_type, source) pairs."""
    pairs = []
    for s in sources:
        if "=" in s:
            f, src = s.split("=", 1)
            if f not in FAULT_TYPES:
                raise ValueError(f"unknown fault {f!r} in --source {s!r}; expected {FAULT_TYPES}")
            pairs.append((f, src))
        elif s == "sim":
            for f in (FAULT_TYPES if fault in (None, "both") else (fault,)):
                pairs.append((f, "sim"))
        else:
            if fault in (None, "both"):
                raise ValueError(f"--source {s} needs --fault outer_race|inner_race")
            pairs.append((fault, s))
    return pairs


def _simulated(fault: str, args, bearing: Bearing | None):
    """(accel m/s², rate Hz, rpm, bearing, provenance) of a noise-free simulation of ``fault``."""
    import numpy as np

    from bearing_common.states import parse_fault
    from bearing_sim.model_parameters import DRIVE_END
    from bearing_sim.simulator import SimulationConfig, simulate

    from .hw_model import same_bearing

    if args.sample_rate is None:
        raise ValueError("--source sim needs --sample-rate")
    if bearing is not None and not same_bearing(bearing, DRIVE_END):
        raise ValueError(f"the simulator's drive-end bearing is {DRIVE_END.name}, not {bearing.name}")
    rpm = args.rpm or 1800.0
    cfg = SimulationConfig(rpm=rpm, sample_rate=args.sample_rate, noise_density=0.0)
    y = np.asarray(simulate(cfg, [(parse_fault(fault), args.duration)])["accel"], dtype=float)
    prov = {"source": "simulator", "simulator": "bearing_sim.simulator (noise off)",
            "rpm": rpm, "duration_s": args.duration}
    return y, args.sample_rate, rpm, DRIVE_END, prov


def _recorded(src: str, args, bearing: Bearing | None):
    """(accel m/s², rate Hz, rpm, bearing, provenance) of the recording ``src``."""
    from bearing_recordings.load import load_recording

    rec = load_recording(src, sample_rate=args.sample_rate, rpm=args.rpm, channel=args.channel, units=args.units)
    for note in rec.notes or ():
        print(f"bearing-identify: {src}: {note}", file=sys.stderr)
    if rec.rpm is None:
        raise ValueError(f"{src} states no shaft speed; give --rpm")
    y = rec.accel[: int(args.max_seconds * rec.sample_rate)] if args.max_seconds else rec.accel
    prov = {"source": "recording", "file": Path(src).name,
            "sha256": _sha256(src) if Path(src).is_file() else None,
            "channel": rec.channel, "units_in_file": args.units or "g",
            "note": "derived model only; the recording itself is not part of the project"}
    return y, rec.sample_rate, rec.rpm, bearing or rec.bearing or load_bearing(DEFAULT_BEARING), prov


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="bearing-identify", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", action="append", required=True,
                   help="'sim', FAULT=FILE or FILE (with --fault); repeatable")
    p.add_argument("--fault", choices=list(FAULT_TYPES) + ["both"], default=None)
    p.add_argument("--bearing", default=None,
                   help=f"the machine's bearing: catalog name, YAML file or 'N,d,D,angle' (default {DEFAULT_BEARING}; "
                        "sim: the simulator's)")
    p.add_argument("--sample-rate", type=float, default=None,
                   help="Hz (required for sim and for files that do not store it: CWRU, one-signal .mat)")
    p.add_argument("--rpm", type=float, default=None,
                   help="rev/min (default: 1800 for sim, the file's speed where it stores one)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--orders", type=int, nargs=3, metavar=("NB", "NF", "NK"))
    g.add_argument("--order-search", action="store_true")
    p.add_argument("--mode", choices=("thesis", "series"), default="thesis")
    p.add_argument("--n-average", type=int, default=None,
                   help="inner-race periods averaged (default: the identification's, N_AVERAGE_IR)")
    p.add_argument("--duration", type=float, default=1.0, help="simulated seconds per fault")
    p.add_argument("--max-seconds", type=float, default=None,
                   help="use at most this many seconds of a recording")
    p.add_argument("--channel", default=None)
    p.add_argument("--units", choices=("g", "m/s2"), default=None, help="units of a one-signal .mat file (default g)")
    p.add_argument("--model-set", required=True, help="name of the set (a directory under --out)")
    p.add_argument("--out", default=None, help="directory holding model sets (default: the package's models/)")
    return p


def _identify(y, fault, base, args, prov):
    """The identification result, with the order search when asked for."""
    from .fault_identification import DEFAULT_ORDERS, identify_fault_model

    if not args.order_search:
        orders = tuple(args.orders) if args.orders else DEFAULT_ORDERS[fault]
        return identify_fault_model(y, fault=fault, orders=orders, provenance=dict(prov), **base)
    rows = []
    for orders in ORDER_GRID:
        r = identify_fault_model(y, fault=fault, orders=orders, provenance=dict(prov), **base)
        rows.append((r.model.fit.held_back, orders, r))
        fit = r.model.fit
        print(f"{fault} nb={orders[0]:2d} nf={orders[1]:2d} nk={orders[2]} "
              f"fit id {fit.identification:6.2f} % held-back {fit.held_back:6.2f} % "
              f"series {fit.time_series:6.2f} %", flush=True)
    result = max(rows, key=lambda row: row[0])[2]
    result.model.provenance["order_search"] = [{"orders": list(o), "held_back": hb} for hb, o, _ in rows]
    return result


def main(argv=None) -> int:
    """Entry point of ``bearing-identify``; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        pairs = _parse_sources(args.source, args.fault)
        bearing = load_bearing(args.bearing) if args.bearing else None
        if args.model_set == NONE or not args.model_set or "/" in args.model_set:
            raise ValueError(f"invalid model set name {args.model_set!r} ('{NONE}' is the no-model set)")
    except (ValueError, BearingError) as exc:
        print(f"bearing-identify: error: {exc}", file=sys.stderr)
        return 2
    command = "bearing-identify " + " ".join(shlex.quote(a) for a in (argv if argv is not None else sys.argv[1:]))
    from .fault_identification import N_AVERAGE_IR
    from .model_sets import MODELS_DIR

    out_dir = Path(args.out or MODELS_DIR) / args.model_set
    set_rate = None
    for fault, src in pairs:
        t0 = time.perf_counter()
        try:
            y, fs, rpm, used_bearing, prov = (_simulated(fault, args, bearing) if src == "sim"
                                              else _recorded(src, args, bearing))
            if set_rate not in (None, fs):
                raise ValueError(f"a model set runs at one sample rate: {src} is at {fs:g} Hz, the set at "
                                 f"{set_rate:g} Hz (resample one recording, or identify two sets)")
            set_rate = fs
            prov["command"] = command
            base = dict(sample_rate=fs, rpm=rpm, bearing=used_bearing, mode=args.mode,
                        n_average=N_AVERAGE_IR if args.n_average is None else args.n_average,
                        refine_frequency=(src != "sim"))
            result = _identify(y, fault, base, args, prov)
        except (ValueError, OSError) as exc:  # InputError and BearingError are ValueErrors
            print(f"bearing-identify: error ({fault}, {src}): {exc}", file=sys.stderr)
            return 1
        result.model.provenance["model_set"] = args.model_set
        path = result.model.save(out_dir / f"{fault}.json")
        m = result.model
        print(json.dumps({"fault": fault, "file": str(path), "bearing": used_bearing.name,
                          "sample_rate": fs, "orders": [m.nb, m.nf, m.nk],
                          "fit": {"identification": m.fit.identification, "held_back": m.fit.held_back,
                                  "time_series": m.fit.time_series},
                          "fault_frequency": m.fault_frequency,
                          "seconds": round(time.perf_counter() - t0, 2)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
