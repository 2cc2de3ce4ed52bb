"""``bearing-diagnose``: offline diagnosis of a recording, one JSON object per state segment.

    bearing-diagnose FILE [--rpm RPM] [--sample-rate HZ] [--channel NAME]
                     [--model-set NAME] [--method model|envelope] [--plot DIR]

FILE is a ``bearing-sim`` .npz, a CWRU-style .mat (g; ``--sample-rate`` required) or a
rosbag2 directory.  Stdout: one JSON object per line (see ``shared/CONTRACT.md``);
stderr: the model set used, any resampling, and on bad input one ``error:`` line with a
non-zero exit status (2 = bad input).
"""

from __future__ import annotations

import argparse
import json
import sys

EXIT_BAD_INPUT = 2


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``bearing-diagnose``."""
    p = argparse.ArgumentParser(prog="bearing-diagnose",
                                description="Diagnose a bearing vibration recording offline.")
    p.add_argument("file", help="bearing-sim .npz, CWRU-style .mat, or rosbag2 directory")
    p.add_argument("--rpm", type=float, help="shaft speed (rev/min); default from the file")
    p.add_argument("--sample-rate", type=float, help="input sample rate (Hz); required for .mat")
    p.add_argument("--channel", help="channel/variable name, e.g. X105_DE_time (default: drive end)")
    p.add_argument("--model-set", help="sim_48k, sim_12k or cwru_de_6205 (default: from the input)")
    p.add_argument("--method", choices=("model", "envelope"), default="model",
                   help="model: observers + folded-energy CFAR (default); envelope: squared envelope spectrum")
    p.add_argument("--plot", metavar="DIR", help="write figures to DIR")
    return p


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (0 on success)."""
    from bearing_recordings.load import load_recording
    from bearing_recordings.recording import InputError

    from .offline import diagnose_recording

    args = build_parser().parse_args(argv)
    try:
        rec = load_recording(args.file, sample_rate=args.sample_rate, rpm=args.rpm, channel=args.channel)
        res = diagnose_recording(rec, model_set=args.model_set, method=args.method, rpm=args.rpm,
                                 keep_streams=bool(args.plot))
    except InputError as exc:
        print(f"bearing-diagnose: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    for seg in res.segments:
        print(json.dumps(seg.to_json()), flush=True)
    if args.plot:
        try:
            from .plots import write_figures
            paths = write_figures(res, args.plot)
            print(f"bearing-diagnose: wrote {len(paths)} figures to {args.plot}", file=sys.stderr)
        except OSError as exc:
            print(f"bearing-diagnose: error: cannot write figures to {args.plot}: {exc}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
