"""``bearing-identify``: identify the OR / IR Hammerstein-Wiener models, write model files.

Examples (each reproduces one shipped model set)::

    bearing-identify --source sim --sample-rate 48000 --model-set sim_48k
    bearing-identify --source sim --sample-rate 12000 --mode series --model-set sim_12k
    bearing-identify --source outer_race=../shared/data/cwru/130_OR007at6_0hp_DE12k.mat \\
                     --source inner_race=../shared/data/cwru/105_IR007_0hp_DE12k.mat \\
                     --sample-rate 12000 --orders 6 6 0 --max-seconds 2 --model-set cwru_de_6205

``--source sim`` simulates each fault (``bearing_sim.simulator``, noise off, 1800 rpm by
default) for ``--duration`` seconds. ``--source FILE --fault F`` reads a recording of a
known fault (any file ``bearing-diagnose`` reads: CWRU / MFPT / one-signal .mat, .npz,
rosbag2; channel rule of ``bearing_recordings.mat_files``; rpm from the file or ``--rpm``). ``--order-search`` prints the fit per order
and keeps the order with the best held-back fit. Model files go to
``--out DIR/<model-set>/<fault>.json`` (default: the package's ``models/`` directory).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

from bearing_recordings.load import load_recording

from .fault_identification import DEFAULT_ORDERS, N_AVERAGE_IR, identify_fault_model
from .hw_model import FAULT_TYPES, MODELS_DIR


def _sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _simulate(fault: str, sample_rate: float, rpm: float, duration: float):
    from bearing_common.states import parse_fault
    from bearing_sim.simulator import SimulationConfig, simulate

    cfg = SimulationConfig(rpm=rpm, sample_rate=sample_rate, noise_density=0.0)
    data = simulate(cfg, [(parse_fault(fault), duration)])
    return np.asarray(data["accel"], dtype=float)


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


ORDER_GRID = [(n, n, k) for n in (4, 6, 8, 10, 12) for k in (0, 1)]


def main(argv=None) -> int:
    """Entry point of ``bearing-identify``; returns the exit status."""
    p = argparse.ArgumentParser(prog="bearing-identify", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", action="append", required=True,
                   help="'sim', FILE.mat (with --fault) or FAULT=FILE.mat; repeatable")
    p.add_argument("--fault", choices=list(FAULT_TYPES) + ["both"], default=None)
    p.add_argument("--sample-rate", type=float, required=True, help="Hz")
    p.add_argument("--rpm", type=float, default=None,
                   help="rev/min (default: 1800 for sim, the file's RPM variable for .mat)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--orders", type=int, nargs=3, metavar=("NB", "NF", "NK"))
    g.add_argument("--order-search", action="store_true")
    p.add_argument("--mode", choices=("thesis", "series"), default="thesis")
    p.add_argument("--n-average", type=int, default=N_AVERAGE_IR)
    p.add_argument("--duration", type=float, default=1.0, help="simulated seconds per fault")
    p.add_argument("--max-seconds", type=float, default=None,
                   help="use at most this many seconds of a recording")
    p.add_argument("--channel", default=None)
    p.add_argument("--units", choices=("g", "m/s2"), default=None, help="units of a one-signal .mat file (default g)")
    p.add_argument("--model-set", required=True)
    p.add_argument("--out", default=str(MODELS_DIR), help="directory holding model sets")
    args = p.parse_args(argv)
    try:
        pairs = _parse_sources(args.source, args.fault)
    except ValueError as exc:
        print(f"bearing-identify: error: {exc}", file=sys.stderr)
        return 2
    command = "bearing-identify " + " ".join(shlex.quote(a) for a in (argv if argv is not None else sys.argv[1:]))
    out_dir = Path(args.out) / args.model_set
    for fault, src in pairs:
        t0 = time.perf_counter()
        try:
            if src == "sim":
                rpm = args.rpm or 1800.0
                fs = args.sample_rate
                y = _simulate(fault, fs, rpm, args.duration)
                prov = {"source": "simulator", "simulator": "bearing_sim.simulator (noise off)",
                        "rpm": rpm, "duration_s": args.duration}
            else:
                rec = load_recording(src, sample_rate=args.sample_rate, rpm=args.rpm, channel=args.channel,
                                     units=args.units)
                y, rpm, fs = rec.accel, rec.rpm, rec.sample_rate
                if rpm is None:
                    raise ValueError(f"{src} states no shaft speed; give --rpm")
                if args.max_seconds:
                    y = y[: int(args.max_seconds * fs)]
                prov = {"source": "recording", "file": Path(src).name,
                        "sha256": _sha256(src) if Path(src).is_file() else None,
                        "channel": rec.channel, "units_in_file": args.units or "g",
                        "note": "derived model only; the recording itself is not part of the project"}
            prov["command"] = command
            base = dict(sample_rate=fs, rpm=rpm, fault=fault, mode=args.mode,
                        n_average=args.n_average, refine_frequency=(src != "sim"))
            if args.order_search:
                rows = []
                for orders in ORDER_GRID:
                    r = identify_fault_model(y, orders=orders, provenance=dict(prov), **base)
                    rows.append((r.model.fit.held_back, orders, r))
                    fit = r.model.fit
                    print(f"{fault} nb={orders[0]:2d} nf={orders[1]:2d} nk={orders[2]} "
                          f"fit id {fit.identification:6.2f} % held-back {fit.held_back:6.2f} % "
                          f"series {fit.time_series:6.2f} %", flush=True)
                best = max(rows, key=lambda row: row[0])
                result = best[2]
                result.model.provenance["order_search"] = [
                    {"orders": list(o), "held_back": hb} for hb, o, _ in rows]
            else:
                orders = tuple(args.orders) if args.orders else DEFAULT_ORDERS[fault]
                result = identify_fault_model(y, orders=orders, provenance=dict(prov), **base)
        except (ValueError, OSError) as exc:  # InputError is a ValueError
            print(f"bearing-identify: error ({fault}, {src}): {exc}", file=sys.stderr)
            return 1
        result.model.provenance["model_set"] = args.model_set
        path = result.model.save(out_dir / f"{fault}.json")
        m = result.model
        print(json.dumps({"fault": fault, "file": str(path),
                          "orders": [m.nb, m.nf, m.nk],
                          "fit": {"identification": m.fit.identification, "held_back": m.fit.held_back,
                                  "time_series": m.fit.time_series},
                          "fault_frequency": m.fault_frequency,
                          "seconds": round(time.perf_counter() - t0, 2)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
