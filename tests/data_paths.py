"""Where the repository and the recordings in ../shared/data are; importable from any test directory."""

import os
import pathlib

REPO_ROOT = pathlib.Path(__file__).resolve().parent.parent
SHARED_DIR = REPO_ROOT.parent / "shared"


def data_dir() -> pathlib.Path:
    """Directory of the recordings (cwru/, mfpt/, hit-sm/): $BEARING_DATA_DIR or ../shared/data."""
    return pathlib.Path(os.environ.get("BEARING_DATA_DIR", SHARED_DIR / "data"))
