"""Shared test fixtures: the recordings in ../shared/data, skipped with the reason when absent;
the hypothesis profiles of the property-based tests.

The suite runs the ``suite`` profile: derandomized, so that every machine runs the same cases
(those that passed here; a failure reproduces anywhere). ``make fuzz`` runs ``explore``: new
random cases on every run, many more of them, for finding what the suite's cases miss.
"""

import pathlib

import pytest
from data_paths import data_dir
from hypothesis import settings

settings.register_profile("suite", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile("suite")


def _finder(subdir: str):
    def find(name: str) -> pathlib.Path:
        path = data_dir() / subdir / name
        if not path.is_file():
            pytest.skip(f"recording {subdir}/{name} not found in {data_dir()} (provided beside the repository "
                        "as ../shared/data in CI; set BEARING_DATA_DIR to use another copy)")
        return path
    return find


@pytest.fixture
def cwru_record():
    """Path of a CWRU record by file name; skips with the reason when it is absent."""
    return _finder("cwru")


@pytest.fixture
def mfpt_record():
    """Path of an MFPT record by file name; skips with the reason when it is absent."""
    return _finder("mfpt")


@pytest.fixture
def hit_record():
    """Path of a HIT-SM SpectraQuest record by file name; skips with the reason when it is absent."""
    return _finder("hit-sm/spectraquest")


@pytest.fixture
def shared_recording():
    """Path of a recording under the data directory by rig (cwru, mfpt, hit-sm/...) and file name;
    skips with the reason when it is absent."""
    return lambda rig, name: _finder(rig)(name)
