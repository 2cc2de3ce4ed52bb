"""``bearing-bag``: record, replay and inspect rosbag2 recordings of the monitoring graph,
for machines without ``ros2 bag`` (the PyPI ROS 2 wheels do not include rosbag2).

    bearing-bag record [--topics T ...] [--namespace NS] [--storage mcap|sqlite3] [--duration S] --out BAG_DIR
    bearing-bag play BAG_DIR [--rate R] [--clock] [--topics T ...] [--loop] [--delay S]
                     [--wait-for-subscribers [N]] [--namespace NS] [--chunk-duration S]
    bearing-bag info BAG_DIR
    bearing-bag from-mat FILE.mat|FILE.npz [--sample-rate HZ] [--channel NAME] [--rpm RPM] [--bearing NAME|FILE.yaml]
                         [--units g|m/s2] [--chunk-duration 0.01] [--start-time 0] [--duration S]
                         [--resample HZ] --out BAG_DIR

Bags are ordinary rosbag2 directories (MCAP by default) with the message definitions
embedded: ``ros2 bag info/play`` of a full ROS 2 install and ``bearing-diagnose BAG_DIR``
read them.  ``from-mat`` also takes a ``.npz`` (e.g. a ``bearing-sim`` run or a warped
recording); a changing ``shaft_speed`` in it goes into the bag's ``shaft_speed`` messages.
Bad input: one ``bearing-bag: error: ...`` line on stderr, exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXIT_BAD_INPUT = 2


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``bearing-bag``."""
    from .bag_record import DEFAULT_RECORD_TOPICS
    p = argparse.ArgumentParser(prog="bearing-bag", description="Record, replay and inspect rosbag2 "
                                "recordings of the bearing-monitoring graph (no ros2 CLI needed).")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    r = sub.add_parser("record", help="subscribe to the graph's topics and write a bag")
    r.add_argument("--topics", nargs="+", metavar="T", default=None,
                   help=f"topics (relative to --namespace, or absolute); default: {' '.join(DEFAULT_RECORD_TOPICS)}")
    r.add_argument("--namespace", default="", help="namespace the graph runs in (default: root)")
    r.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    r.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: until Ctrl-C/SIGTERM)")
    r.add_argument("--out", "-o", required=True, metavar="BAG_DIR", help="bag directory to create")

    pl = sub.add_parser("play", help="publish a bag back in timestamp order")
    pl.add_argument("bag", metavar="BAG_DIR")
    pl.add_argument("--rate", "-r", type=float, default=1.0, help="playback speed factor (default 1)")
    pl.add_argument("--clock", action="store_true", help="also publish /clock (recording time) for use_sim_time nodes")
    pl.add_argument("--topics", nargs="+", metavar="T", help="play only these topics")
    pl.add_argument("--loop", "-l", action="store_true", help="repeat until Ctrl-C")
    pl.add_argument("--delay", type=float, default=1.0, metavar="S",
                    help="wait S seconds for subscribers to be discovered before playing (default 1)")
    pl.add_argument("--wait-for-subscribers", type=int, nargs="?", const=1, default=0, metavar="N",
                    help="before playing, wait (up to 60 s) until every played topic has N subscribers (default 1)")
    pl.add_argument("--namespace", default=None, help="republish the graph topics under this namespace")
    pl.add_argument("--chunk-duration", type=float, metavar="S",
                    help="publish the vibration in chunks of S seconds, as a sensor sending such chunks would "
                         "(sample indices and stamps kept exactly; default: as recorded)")

    i = sub.add_parser("info", help="topics, types, message counts, duration, storage")
    i.add_argument("bag", metavar="BAG_DIR")

    m = sub.add_parser("from-mat", help="convert a MATLAB recording (CWRU, MFPT, one signal) into a bag")
    m.add_argument("mat", metavar="FILE.mat|FILE.npz")
    m.add_argument("--channel", help="variable, e.g. X105_DE_time (default: the record's drive end, "
                   "MFPT's gs, or a file's only signal)")
    m.add_argument("--sample-rate", type=float, metavar="HZ",
                   help="sample rate (Hz); required where the file does not store it (CWRU: 12000 or 48000)")
    m.add_argument("--rpm", type=float, help="shaft speed (rev/min); default the file's")
    m.add_argument("--bearing", default=None, metavar="NAME|FILE.yaml",
                   help="bearing monitored (catalog name or YAML), stored in the bag (default 6205)")
    m.add_argument("--units", choices=("g", "m/s2"), help="unit of a one-signal file (default g)")
    m.add_argument("--chunk-duration", type=float, default=0.01, metavar="S", help="seconds per chunk (default 0.01)")
    m.add_argument("--start-time", type=float, default=0.0, metavar="S", help="stamp of the first sample (default 0)")
    m.add_argument("--duration", type=float, metavar="S", help="convert only the first S seconds")
    m.add_argument("--resample", type=float, metavar="HZ",
                   help="resample (anti-aliased) to this rate first, e.g. 12000 for the CWRU model set")
    m.add_argument("--namespace", default="", help="namespace of the topics (default: root)")
    m.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    m.add_argument("--out", "-o", required=True, metavar="BAG_DIR")
    return p


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def info_lines(bag_dir) -> list:
    """``bearing-bag info`` output lines (raises BagError)."""
    from .bag_read import bag_bearing_spec, bag_namespace_hint, bag_storage, open_bag
    lines = []
    with open_bag(bag_dir) as reader:
        count = reader.message_count
        start, end = (reader.start_time, reader.end_time) if count else (0, 0)
        duration = max(0, end - start - 1) * 1e-9 if count else 0.0
        lines.append(f"bag:        {bag_dir}")
        lines.append(f"storage:    {bag_storage(bag_dir) or 'unknown'}")
        ns = bag_namespace_hint(bag_dir)
        if ns is not None:
            lines.append(f"namespace:  {'/' + ns if ns else '/ (root)'}")
        if bag_bearing_spec(bag_dir):
            lines.append(f"bearing:    {bag_bearing_spec(bag_dir)}")
        lines.append(f"duration:   {duration:.3f} s")
        if count:
            lines.append(f"start:      {start * 1e-9:.9f} s")
            lines.append(f"end:        {(end - 1) * 1e-9:.9f} s")
        lines.append(f"messages:   {count}")
        lines.append("topics:")
        width = max([len(c.topic) for c in reader.connections] + [5])
        for c in sorted(reader.connections, key=lambda c: c.topic):
            lines.append(f"  {c.topic:<{width}}  {c.msgtype:<36}  {c.msgcount:>8} msgs")
    return lines


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (0 on success, 2 on bad input)."""
    from bearing_common.bearings import BearingError, bearing_spec, load_bearing

    from .bag_types import BagError
    from .recording import InputError
    args = build_parser().parse_args(argv)
    try:
        if args.command == "info":
            for line in info_lines(args.bag):
                print(line)
        elif args.command == "from-mat":
            from .bag_write import recording_to_bag
            from .load import load_recording
            bearing = load_bearing(args.bearing)  # validated before anything is written
            if Path(args.mat).suffix.lower() not in (".mat", ".npz"):
                raise InputError(f"{args.mat}: expected a .mat or .npz file")
            rec = load_recording(args.mat, sample_rate=args.sample_rate, rpm=args.rpm, channel=args.channel,
                                 units=args.units)
            for note in rec.notes or ():
                print(f"bearing-bag: {note}", file=sys.stderr)
            res = recording_to_bag(rec, args.out, chunk_duration=args.chunk_duration, start_time=args.start_time,
                                   storage=args.storage, namespace=args.namespace, max_duration=args.duration,
                                   resample_to=args.resample, bearing=bearing_spec(bearing))
            print(f"bearing-bag: wrote {res.chunks} chunks ({res.samples} samples, {res.duration:.3f} s at "
                  f"{res.sample_rate:g} Hz, {res.rpm:g} rpm{' from the command line' if args.rpm else ''}, "
                  f"bearing {bearing.name}) to {res.path}", file=sys.stderr)
        elif args.command == "record":
            if args.duration is not None and not args.duration > 0:
                raise BagError(f"duration must be positive, got {args.duration:g} s")
            from .bag_record import record
            record(args.out, args.topics, args.namespace, args.storage, args.duration, log=_say)
        elif args.command == "play":
            from .bag_play import play
            play(args.bag, rate=args.rate, clock=args.clock, names=args.topics, loop=args.loop, log=_say,
                 delay=args.delay, namespace=args.namespace,
                 wait_for_subscribers=args.wait_for_subscribers, chunk_duration=args.chunk_duration)
    except (BagError, InputError, BearingError) as exc:
        print(f"bearing-bag: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0


if __name__ == "__main__":
    sys.exit(main())
