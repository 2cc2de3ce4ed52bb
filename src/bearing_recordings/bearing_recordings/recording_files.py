"""Which paths are recordings: the files and rosbag2 directories named on a command line or held in folders.

A recording is a ``.mat``, ``.npz``, ``.csv``, ``.tsv`` or ``.wav`` file, or a rosbag2 directory (one holding
``metadata.yaml``, or its storage files without it: a truncated bag, which its loader then
refuses with the reason). Any other directory is a folder: walked in sorted order, hidden
entries skipped, without descending into the bags it holds; files of other types in it are
not recordings and are passed over. A path named explicitly is always taken as it is, so
that its loader says what is wrong with it (an unknown type, a missing file).
"""

from __future__ import annotations

import os
from pathlib import Path

#: File name suffixes of the recordings a folder holds (:func:`bearing_recordings.load.load_recording` reads
#: them, and ``.txt`` tables named one by one).
RECORDING_SUFFIXES = (".mat", ".npz", ".csv", ".tsv", ".wav")

#: Storage files of a rosbag2 directory.
BAG_STORAGE_SUFFIXES = (".mcap", ".db3")


def is_bag_dir(path: Path) -> bool:
    """Whether directory ``path`` is a rosbag2 recording (possibly truncated), not a folder of recordings."""
    if (path / "metadata.yaml").is_file():
        return True
    return any(p.suffix in BAG_STORAGE_SUFFIXES for p in path.iterdir() if p.is_file())


def is_folder(path) -> bool:
    """Whether ``path`` is a folder to walk for recordings (a directory that is not a bag)."""
    p = Path(path)
    return p.is_dir() and not is_bag_dir(p)


def folder_recordings(folder) -> list[Path]:
    """The recordings under ``folder`` (module docstring), in sorted path order."""
    out = []
    for root, dirs, files in os.walk(folder):
        here = Path(root)
        dirs.sort()
        keep = []
        for d in dirs:
            if d.startswith("."):
                continue
            if is_bag_dir(here / d):
                out.append(here / d)
            else:
                keep.append(d)
        dirs[:] = keep
        out.extend(here / f for f in files if not f.startswith(".") and Path(f).suffix.lower() in RECORDING_SUFFIXES)
    return sorted(out, key=lambda p: p.parts)


def expand(paths) -> tuple[list[str], list[str]]:
    """The recordings ``paths`` name, in order, each once, and the folders among them that hold none.

    A file or a bag stands for itself; a folder (:func:`is_folder`) for the recordings it
    holds. Returns ``(recordings, empty_folders)`` as strings, spelled as given (a folder's
    recordings below its spelling).
    """
    out: list[str] = []
    empty: list[str] = []
    seen: set[Path] = set()
    for given in paths:
        found = [Path(given)]
        if is_folder(given):
            found = folder_recordings(given)
            if not found:
                empty.append(str(given))
        for p in found:
            key = p.resolve()
            if key not in seen:
                seen.add(key)
                out.append(str(p))
    return out, empty
