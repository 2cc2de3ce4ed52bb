"""The model-set registry: which fault models an observer runs on, and the rule that picks them.

A model set is a directory holding ``outer_race.json`` and ``inner_race.json``
(:mod:`.hw_model`) identified on one machine, for its bearing, at one sample rate.

| set | sample rate | chosen for source | bearing |
|---|---|---|---|
| ``sim_48k`` | 48 kHz | ``simulator`` | 6205 (the simulator's drive end) |
| ``sim_12k`` | 12 kHz | ``simulator`` | 6205 |
| ``cwru_de_6205`` | 12 kHz | ``cwru`` | 6205 (CWRU drive end) |
| ``none`` | any | everything else | any |

``none`` is no model: the observer passes the measurement through (residual = y,
estimate = 0) and still publishes the impulse train at the bearing's fault frequency,
its phase estimated online (:func:`passthrough_model`), so the thesis' cross-correlation
of |r| with the train stays computable. It is what a machine without an identified set
gets (MFPT, HIT-SM, a user's sensor). Sets identified with ``bearing-identify`` are used
by name (``models/<name>`` or ``root/<name>``) or by their directory; the automatic choice
(:func:`choose_model_set`) only picks shipped sets, so a set identified for a test never
replaces one silently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from bearing_common.bearings import CATALOG, DEFAULT_BEARING, Bearing
from bearing_common.model_set_info import NONE, SHIPPED_SETS
from bearing_common.states import parse_fault

from .hw_model import FAULT_TYPES, HWModel, ModelFileError, load, same_bearing
from .piecewise_linear import MonotonePiecewiseLinear

MODELS_DIR = Path(__file__).resolve().parent / "models"

#: Time constant (s) of the impact response the ``none`` set assumes for its phase
#: estimate: the energy of a ring-down of a few housing-resonance cycles (2-10 kHz).
NONE_DECAY_S = 2.5e-4


@dataclass(frozen=True)
class ModelSet:
    """One registry entry.

    Attributes
    ----------
    name : str
    sample_rate : float or None
        Hz; None: any rate (``none``).
    source : str or None
        The data source (VibrationChunk ``source``, recording kind) the set is chosen for
        automatically; None: chosen by name only.
    bearing : Bearing or None
        The bearing the set was identified for; None: any (``none``).
    directory : Path or None
        Where the model files are; None for ``none``.
    """

    name: str
    sample_rate: float | None
    source: str | None
    bearing: Bearing | None
    directory: Path | None


#: The shipped sets (:data:`bearing_common.model_set_info.SHIPPED_SETS`) with their files.
SHIPPED = {s.name: ModelSet(s.name, s.sample_rate, s.source, s.bearing, MODELS_DIR / s.name)
           for s in SHIPPED_SETS.values()}
NO_MODEL = ModelSet(NONE, None, None, None, None)


def choose_model_set(source: str, sample_rate: float, bearing: Bearing | None,
                     resample: bool = False) -> ModelSet:
    """The set for data from ``source`` at ``sample_rate`` (Hz) of a machine with ``bearing``.

    A shipped set identified for that source and bearing (same orders) at that rate; with
    ``resample`` (callers that resample the input to the set's rate) any rate will do:
    the lowest at or above ``sample_rate``, else the highest. Otherwise ``none``.
    """
    bearing = bearing or CATALOG[DEFAULT_BEARING]
    candidates = [s for s in SHIPPED.values()
                  if s.source == str(source).lower() and same_bearing(s.bearing, bearing)]
    exact = [s for s in candidates if math.isclose(s.sample_rate, float(sample_rate), rel_tol=1e-9)]
    if exact:
        return exact[0]
    if resample and candidates:
        above = [s for s in candidates if s.sample_rate >= sample_rate]
        return min(above, key=lambda s: s.sample_rate) if above else max(candidates, key=lambda s: s.sample_rate)
    return NO_MODEL


def model_set(name: str, root=None) -> ModelSet:
    """The registry entry of ``name``: ``none``, a shipped set, or a set identified into
    ``root`` (default the package's ``models/``) or given as a directory path.

    Raises
    ------
    ModelFileError
        No such set, or its files are missing or corrupt.
    """
    if name == NONE:
        return NO_MODEL
    if name in SHIPPED and root is None:
        return SHIPPED[name]
    if not name or name.startswith("."):
        raise ModelFileError(f"invalid model set name {name!r}")
    directory = Path(name).expanduser() if "/" in name else Path(root or MODELS_DIR) / name
    if not directory.is_dir():
        raise ModelFileError(f"unknown model set {name!r} (no directory {directory}); known: "
                             f"{', '.join(available_model_sets(root))}, or a directory holding "
                             "outer_race.json and inner_race.json")
    first = load(directory / f"{FAULT_TYPES[0]}.json")
    return ModelSet(name, first.sample_rate, None, first.bearing, directory)


def available_model_sets(root=None) -> list[str]:
    """Names of the sets in ``root`` (default the package's ``models/``), and ``none``."""
    base = Path(root) if root is not None else MODELS_DIR
    found = [p.name for p in base.iterdir() if p.is_dir() and all((p / f"{ft}.json").is_file() for ft in FAULT_TYPES)
             ] if base.is_dir() else []
    return sorted(found) + [NONE]


def load_model_set(name: str, sample_rate: float | None = None, root=None,
                   bearing: Bearing | None = None) -> dict[str, HWModel]:
    """The models of set ``name`` (see :func:`model_set`), by fault type.

    ``sample_rate`` (Hz), if given, must be the set's; ``none`` needs it and takes
    ``bearing`` (default :data:`~bearing_common.bearings.DEFAULT_BEARING`).

    Returns
    -------
    dict
        ``{"outer_race": HWModel, "inner_race": HWModel}``.

    Raises
    ------
    ModelFileError
        Unknown set, missing/corrupt file, or sample-rate mismatch.
    """
    entry = model_set(name, root)
    if entry.directory is None:
        if sample_rate is None:
            raise ModelFileError(f"model set {NONE!r} runs at the data's rate: give the sample rate")
        b = bearing or CATALOG[DEFAULT_BEARING]
        return {ft: passthrough_model(ft, sample_rate, b) for ft in FAULT_TYPES}
    return {ft: load(entry.directory / f"{ft}.json", sample_rate=sample_rate, fault_type=ft) for ft in FAULT_TYPES}


def passthrough_model(fault_type: str, sample_rate: float, bearing: Bearing) -> HWModel:
    """The ``none`` set's model of ``fault_type`` for ``bearing`` at ``sample_rate`` (Hz).

    Undriven (the observer runs it with ``drive="phase"``), it subtracts nothing. Its fault
    order is the bearing's kinematic one (eqs. 2.53-2.54, no slip correction); its
    linear block, a one-pole decay of time constant :data:`NONE_DECAY_S`, only shapes the
    energy template that locates the impacts (the phase estimate). ``rpm`` is NaN: it
    was identified at no speed, so the observer needs one.
    """
    order = bearing.orders().of(parse_fault(fault_type))
    return HWModel(fault_type=fault_type, sample_rate=float(sample_rate), rpm=math.nan,
                   fault_frequency=math.nan, fault_order=order, b=[1.0],
                   f=[1.0, -math.exp(-1.0 / (NONE_DECAY_S * sample_rate))], nk=0,
                   input_nonlinearity=MonotonePiecewiseLinear.gain(1.0),
                   output_nonlinearity=MonotonePiecewiseLinear.identity(),
                   provenance={"model_set": NONE, "bearing": bearing.to_dict(),
                               "note": "no model: the measurement is passed through"})
