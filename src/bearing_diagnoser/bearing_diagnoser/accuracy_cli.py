"""``bearing-accuracy MANIFEST.yaml [--methods model envelope] [--out FILE.md]``: the accuracy report
of :mod:`.accuracy` for the labelled recordings a manifest lists."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def main(argv=None) -> int:
    """Run the CLI; returns the exit status (2 on a bad manifest)."""
    p = argparse.ArgumentParser(prog="bearing-accuracy", description="Accuracy of the diagnosis on labelled "
                                "recordings listed in a manifest (YAML).")
    p.add_argument("manifest")
    p.add_argument("--methods", nargs="+", default=["model", "envelope"], choices=("model", "envelope"))
    p.add_argument("--out", help="write the Markdown report here (default: stdout)")
    args = p.parse_args(argv)
    from bearing_recordings.recording import InputError

    from .accuracy import load_manifest, markdown, run, summary_line  # the diagnosis: not for --help

    try:
        records = load_manifest(args.manifest)
    except InputError as exc:
        print(f"bearing-accuracy: error: {exc}", file=sys.stderr)
        return 2
    results = run(records, args.methods, progress=lambda r: print(f"bearing-accuracy: {summary_line(r)}",
                                                                  file=sys.stderr))
    text = markdown(results, tuple(args.methods))
    if args.out:
        Path(args.out).write_text(text)
    else:
        print(text)
    return 0



if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
