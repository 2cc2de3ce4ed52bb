"""The healthy recordings in ../shared/data (or $BEARING_DATA_DIR): what they are, how to read them, their speed.

One home for the list that ``make trend`` (:mod:`benchmarks.trend_report`) and the false-alarm
matrix (:mod:`benchmarks.false_alarm_matrix`) run: the continuous healthy recordings (CWRU 097,
drive and fan end channels; HIT-SM ``Normal_600/900/1200``) and the six FEMTO run-to-failure
lives (their first quarter is taken as healthy: nothing is labelled there, see
../shared/data/femto/README.md). Speeds are the nominal ones a user reads from the labels:
CWRU 097's file states 1796 rpm, HIT-SM's file names, FEMTO's operating conditions (README).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(os.environ.get("BEARING_DATA_DIR", ROOT.parent / "shared" / "data"))


@dataclass(frozen=True)
class HealthyRecording:
    """One continuous healthy recording: rig, name, file under :data:`DATA`, sample rate (Hz), channel
    (None: the file's default), nominal speed (rev/min)."""

    rig: str
    name: str
    file: str
    sample_rate: float
    channel: str | None
    rpm: float

    @property
    def label(self) -> str:
        return f"{self.rig} {self.name}"

    @property
    def path(self) -> Path:
        return DATA / self.file


CWRU_097 = "cwru/097_normal_0hp_DE48k.mat"

#: The continuous healthy recordings.
CONTINUOUS = (
    HealthyRecording("CWRU", "097 drive end", CWRU_097, 48000.0, "X097_DE_time", 1796.0),
    HealthyRecording("CWRU", "097 fan end", CWRU_097, 48000.0, "X097_FE_time", 1796.0),
    HealthyRecording("HIT-SM", "Normal_600", "hit-sm/spectraquest/Normal_600.mat", 51200.0, None, 600.0),
    HealthyRecording("HIT-SM", "Normal_900", "hit-sm/spectraquest/Normal_900.mat", 51200.0, None, 900.0),
    HealthyRecording("HIT-SM", "Normal_1200", "hit-sm/spectraquest/Normal_1200.mat", 51200.0, None, 1200.0),
)

#: The FEMTO lives (folders under DATA/femto) and their nominal speeds (rev/min): condition 1 at
#: 1800, 2 at 1650, 3 at 1500 rpm.
FEMTO_LIVES = {"Bearing1_1": 1800.0, "Bearing1_2": 1800.0, "Bearing2_1": 1650.0, "Bearing2_2": 1650.0,
               "Bearing3_1": 1500.0, "Bearing3_2": 1500.0}
