"""Shared test fixtures: where the repository and ../shared are."""

import os
import pathlib

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parent.parent
SHARED_DIR = REPO_ROOT.parent / "shared"


def cwru_dir() -> pathlib.Path:
    """Directory of the CWRU recordings: $BEARING_CWRU_DIR or ../shared/data/cwru."""
    return pathlib.Path(os.environ.get("BEARING_CWRU_DIR", SHARED_DIR / "data" / "cwru"))


@pytest.fixture
def cwru_record():
    """Path of a CWRU record by file name; skips with the reason when it is absent."""
    def find(name: str) -> pathlib.Path:
        path = cwru_dir() / name
        if not path.is_file():
            pytest.skip(f"CWRU recording {name} not found in {cwru_dir()} "
                        "(provided beside the repository as ../shared/data/cwru in CI; "
                        "set BEARING_CWRU_DIR to use another copy)")
        return path
    return find


@pytest.fixture
def shared_recording():
    """Path of a recording under ../shared/data/<rig>/ (cwru, mfpt, hit-sm); skips with the reason when absent."""
    def find(rig: str, name: str) -> pathlib.Path:
        path = (cwru_dir() if rig == "cwru" else SHARED_DIR / "data" / rig) / name
        if not path.is_file():
            pytest.skip(f"recording {rig}/{name} not found at {path} (provided beside the repository as "
                        "../shared/data in CI; never committed)")
        return path
    return find
