"""What every package may know of the model sets: names, sample rates, data sources, bearings.

A model set is the pair of fault models an observer runs on (``bearing_observer.model_sets``
holds the registry with their files). The decision and the tools only need to know which
sets exist, at which rate they were identified and for which data, and the name of the set
without a model; that is this table.
"""

from __future__ import annotations

from dataclasses import dataclass

from .bearings import CATALOG, Bearing

#: The model set without a model: the observers pass the measurement through.
NONE = "none"

#: The faults a model set holds a model of (one model file each, named after the fault).
FAULT_TYPES = ("outer_race", "inner_race")


@dataclass(frozen=True)
class ModelSetInfo:
    """One shipped model set: ``sample_rate`` (Hz) it was identified at, the data ``source``
    (VibrationChunk ``source``, recording kind) it is chosen for, the ``bearing`` it models."""

    name: str
    sample_rate: float
    source: str
    bearing: Bearing


#: The model sets shipped with the observer package, by name.
SHIPPED_SETS = {s.name: s for s in (
    ModelSetInfo("sim_48k", 48000.0, "simulator", CATALOG["6205"]),
    ModelSetInfo("sim_12k", 12000.0, "simulator", CATALOG["6205"]),
    ModelSetInfo("cwru_de_6205", 12000.0, "cwru", CATALOG["6205"]),
)}
