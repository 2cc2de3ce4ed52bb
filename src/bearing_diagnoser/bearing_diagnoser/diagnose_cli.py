"""``bearing-diagnose``: offline diagnosis of a recording, one JSON object per state segment.

    bearing-diagnose FILE [--rpm RPM] [--sample-rate HZ] [--channel NAME] [--bearing NAME|FILE.yaml]
                     [--units g|m/s2] [--model-set NAME] [--method model|envelope] [--plot DIR]

FILE is a ``bearing-sim`` .npz, a MATLAB recording (CWRU, MFPT, or one signal such as
HIT-SM; see ``bearing_recordings.mat_files``) or a rosbag2 directory. Stdout: one JSON object
per line (``shared/CONTRACT.md``); stderr: the model set, bearing, any resampling, the
speed, sensor problems, and on bad input one ``error:`` line with exit status 2.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys

EXIT_BAD_INPUT = 2


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``bearing-diagnose``."""
    p = argparse.ArgumentParser(prog="bearing-diagnose",
                                description="Diagnose a bearing vibration recording offline.")
    p.add_argument("file", help="bearing-sim .npz, MATLAB .mat (CWRU, MFPT, one signal) or rosbag2 directory")
    p.add_argument("--rpm", type=float, help="shaft speed (rev/min); default from the file, else estimated")
    p.add_argument("--rpm-tolerance", type=float, metavar="FRACTION",
                   help="relative accuracy of --rpm (default 0.10, a nameplate's; the speed is measured from the "
                        "vibration within it, and beyond it reported); a file's own speed keeps the file's")
    p.add_argument("--sample-rate", type=float, help="input sample rate (Hz); required where the file has none")
    p.add_argument("--channel", help="channel/variable name, e.g. X105_DE_time (default: the drive end)")
    p.add_argument("--bearing", metavar="NAME|FILE.yaml",
                   help="monitored bearing: catalog name (6205, 6203, mfpt, za2115), YAML file or "
                        "'N,d,D,angle' (default: the recording's, else 6205)")
    p.add_argument("--units", choices=("g", "m/s2"), help="unit of a one-signal .mat file (default g)")
    p.add_argument("--model-set", help="sim_48k, sim_12k, cwru_de_6205 or none (default: from the input)")
    p.add_argument("--method", choices=("model", "envelope"), default="model",
                   help="model: observers + envelope-spectrum decision (default); envelope: textbook reference")
    p.add_argument("--plot", metavar="DIR", help="write figures to DIR")
    return p


class _OneLine(logging.Formatter):
    def format(self, record):
        return f"bearing-diagnose: {record.getMessage()}"


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (0 on success)."""
    from bearing_common.bearings import BearingError, load_bearing
    from bearing_recordings.load import load_recording
    from bearing_recordings.recording import InputError

    from .recording_diagnosis import diagnose_recording

    args = build_parser().parse_args(argv)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_OneLine())
    log = logging.getLogger("bearing_diagnoser")
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    logging.getLogger("bearing_recordings").addHandler(handler)
    try:
        rec = load_recording(args.file, sample_rate=args.sample_rate, rpm=args.rpm, channel=args.channel,
                             units=args.units)
        for note in rec.notes or ():
            log.info(note)
        bearing = load_bearing(args.bearing) if args.bearing else rec.bearing
        if args.rpm_tolerance is not None and not 0.0 < args.rpm_tolerance < 0.5:
            raise InputError(f"--rpm-tolerance must be in (0, 0.5), got {args.rpm_tolerance:g}")
        res = diagnose_recording(rec, model_set=args.model_set, method=args.method, rpm=args.rpm, bearing=bearing,
                                 keep_streams=bool(args.plot), rpm_tolerance=args.rpm_tolerance)
    except (InputError, BearingError) as exc:
        print(f"bearing-diagnose: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    finally:
        log.removeHandler(handler)
        logging.getLogger("bearing_recordings").removeHandler(handler)
    for start, end, problem in res.not_diagnosed[:1]:
        print(f"bearing-diagnose: warning: {len(res.not_diagnosed)} windows not diagnosed, "
              f"first at {start:.3f}-{end:.3f} s: {problem}", file=sys.stderr)
    for seg in res.segments:
        print(json.dumps(seg.to_json()), flush=True)
    if args.plot:
        try:
            from .plots import write_figures
            paths = write_figures(res, args.plot)
            print(f"bearing-diagnose: wrote {len(paths)} figures to {args.plot}", file=sys.stderr)
        except ImportError as exc:
            print(f"bearing-diagnose: error: --plot needs matplotlib ({exc})", file=sys.stderr)
            return 1
        except OSError as exc:
            print(f"bearing-diagnose: error: cannot write figures to {args.plot}: {exc}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
