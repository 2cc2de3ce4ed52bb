"""Hammerstein-Wiener (HW) fault models (thesis section 2.4, Fig. 2.6) and their files.

Model: ``u -> w = f(u) -> x = q^-nk B(q)/F(q) w -> y = g(x)`` (eq. 2.56 with A = C = D = 1,
an output-error model), where ``u`` is the fault impulse train (dimensionless,
:mod:`bearing_observer.impulse_trains`), ``y`` the drive-end acceleration (m/s²),
``B(q) = b0 + b1 q^-1 + ... + b_{nb-1} q^-(nb-1)``, ``F(q) = 1 + f1 q^-1 + ... + f_nf q^-nf``
(MATLAB ``idpoly`` convention), ``f`` and ``g`` strictly increasing piecewise-linear.

Model file format (JSON, ``format_version`` 1), one fault type per file::

    {
      "format_version": 1,
      "kind": "bearing_observer.hw_model",
      "fault_type": "outer_race" | "inner_race",
      "sample_rate": Hz, "rpm": rev/min at identification,
      "fault_frequency": Hz at that rpm (measured), "fault_order": fault_frequency / shaft Hz,
      "train": {"equation": "2.55" | "2.58", "offset": c of eq. 2.58, "pulse_width": s},
      "linear": {"nb": int, "nf": int, "nk": int, "b": [nb floats], "f": [1, f1..f_nf]},
      "input_nonlinearity": {"x": [...], "y": [...]},   # f, dimensionless -> dimensionless
      "output_nonlinearity": {"x": [...], "y": [...]},  # g, model units -> m/s²
      "units": {...},
      "fit": {"identification": %, "held_back": %, "time_series": %, ...},
      "provenance": {"source": ..., "command": ..., "date": ISO 8601 UTC,
                     "bearing": {...}, ...}   # the bearing identified for (bearing_common YAML form, SI)
    }

``fault_order`` was measured on the identification record of a machine with
``provenance.bearing``; an observer of another bearing uses that bearing's kinematic order
instead (:func:`bearing_observer.observer.fault_order`).

A *model set* is a directory holding ``outer_race.json`` and ``inner_race.json`` identified
on one machine at one sample rate; :mod:`.model_sets` keeps the registry.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np
from scipy import signal

from bearing_common.bearings import Bearing, bearing_from_dict
from bearing_common.model_set_info import FAULT_TYPES

from .piecewise_linear import MonotonePiecewiseLinear

FORMAT_VERSION = 1
KIND = "bearing_observer.hw_model"
MODELS_DIR = Path(__file__).resolve().parent / "models"

class ModelFileError(ValueError):
    """A model file is missing, corrupt or does not match what the caller needs."""


@dataclass
class ModelFit:
    """How well one model fits its record (%, MATLAB ``compare``: ``100 (1 - |y - yhat| / |y - mean(y)|)``).

    Attributes
    ----------
    identification : float
        On the identification data.
    identification_linear_only : float
        The same with the output nonlinearity replaced by the identity (OE initialisation).
    held_back : float or None
        On the rest of the record (None when nothing is held back).
    held_back_periods_median : float or None
        Median over the held-back fault periods.
    time_series : float
        On the whole record, driven by a strictly periodic train.
    time_series_ls_amplitude : (float, float)
        ``(fit %, gain)`` of the time series with the single least-squares amplitude.
    identification_samples, held_back_samples : int
    series_seconds : float
        Length of the record (s).
    """

    identification: float
    identification_linear_only: float
    held_back: float | None
    held_back_periods_median: float | None
    time_series: float
    time_series_ls_amplitude: tuple[float, float]
    identification_samples: int
    held_back_samples: int
    series_seconds: float

    @classmethod
    def from_dict(cls, d: dict) -> ModelFit:
        unknown = set(d) - {f.name for f in fields(cls)}
        if unknown:
            raise ValueError(f"fit: unknown keys {', '.join(sorted(unknown))}")
        return cls(**{**d, "time_series_ls_amplitude": tuple(d["time_series_ls_amplitude"])})


@dataclass
class HWModel:
    """One identified HW fault model.

    Attributes
    ----------
    fault_type : str
        ``"outer_race"`` or ``"inner_race"``.
    sample_rate : float
        Sample rate (Hz) the discrete-time model runs at.
    rpm : float
        Shaft speed at identification (rev/min).
    fault_frequency : float
        Impact frequency at ``rpm`` (Hz) as measured on the identification data.
    fault_order : float
        ``fault_frequency`` / shaft frequency (dimensionless); the observer scales it with
        the current speed.
    b, f : ndarray
        ``B`` (length nb) and ``F`` (length nf + 1, ``f[0] == 1``) coefficients.
    nk : int
        Pure input delay (samples), kept out of the state vector.
    input_nonlinearity, output_nonlinearity : MonotonePiecewiseLinear
        ``f`` and ``g`` of Fig. 2.6.
    train_offset : float
        Offset ``c`` of eq. 2.58 (inner race); unused for the outer race (eq. 2.55).
    pulse_width : float
        Pulse width of the train (s).
    fit : ModelFit or None
        Fit figures on the identification record (None for a model not identified here).
    provenance : dict
        Data source, command, date.
    """

    fault_type: str
    sample_rate: float
    rpm: float
    fault_frequency: float
    fault_order: float
    b: np.ndarray
    f: np.ndarray
    nk: int
    input_nonlinearity: MonotonePiecewiseLinear
    output_nonlinearity: MonotonePiecewiseLinear
    train_offset: float = 0.0
    pulse_width: float | None = None
    fit: ModelFit | None = None
    provenance: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.fault_type not in FAULT_TYPES:
            raise ValueError(f"fault_type must be one of {FAULT_TYPES}, got {self.fault_type!r}")
        self.b = np.asarray(self.b, dtype=float).ravel()
        self.f = np.asarray(self.f, dtype=float).ravel()
        if self.f.size < 1 or self.f[0] != 1.0:
            raise ValueError("F must be monic: f[0] == 1")
        if self.b.size < 1:
            raise ValueError("B must have at least one coefficient")
        self.nk = int(self.nk)
        if self.nk < 0:
            raise ValueError("nk must be >= 0")
        if self.pulse_width is None:
            self.pulse_width = 1.0 / self.sample_rate
        if np.any(np.abs(np.roots(self.f)) >= 1.0) if self.f.size > 1 else False:
            raise ValueError("linear block is unstable (roots of F outside the unit circle)")

    # --- structure -----------------------------------------------------------------
    @property
    def nb(self) -> int:
        return int(self.b.size)

    @property
    def nf(self) -> int:
        return int(self.f.size - 1)

    @property
    def modulated(self) -> bool:
        """True for the eq. 2.58 (shaft-modulated) train of the inner race."""
        return self.fault_type == "inner_race"

    @property
    def bearing(self) -> Bearing | None:
        """The bearing the model was identified for (``provenance["bearing"]``), None if not recorded."""
        d = self.provenance.get("bearing")
        return None if d is None else bearing_from_dict(d, "model provenance bearing")

    @property
    def input_gain(self) -> float:
        """Slope of ``f`` at 0 (the input nonlinearity is a gain, see identification)."""
        return self.input_nonlinearity.slope_at(0.0)

    def poles(self) -> np.ndarray:
        """Poles of ``B/F`` (roots of F), discrete time."""
        return np.roots(self.f) if self.nf else np.zeros(0)

    # --- simulation ------------------------------------------------------------------
    def simulate_linear(self, w: np.ndarray) -> np.ndarray:
        """``x = q^-nk B/F w`` from zero initial state, along the last axis (a 2-D ``w``
        is filtered row by row in one call)."""
        w = np.asarray(w, dtype=float)
        x = signal.lfilter(self.b, self.f, w, axis=-1)
        if self.nk:
            n = x.shape[-1]
            k = min(self.nk, n)
            x = np.concatenate([np.zeros(x.shape[:-1] + (k,)), x[..., :n - k]], axis=-1)
        return x

    def simulate(self, u: np.ndarray) -> np.ndarray:
        """HW model output ``y = g(q^-nk B/F f(u))`` (m/s²) from zero initial state."""
        return self.output_nonlinearity(self.simulate_linear(self.input_nonlinearity(u)))

    # --- files -------------------------------------------------------------------------
    def to_dict(self) -> dict:
        return {
            "format_version": FORMAT_VERSION,
            "kind": KIND,
            "fault_type": self.fault_type,
            "sample_rate": float(self.sample_rate),
            "rpm": float(self.rpm),
            "fault_frequency": float(self.fault_frequency),
            "fault_order": float(self.fault_order),
            "train": {
                "equation": "2.58" if self.modulated else "2.55",
                "offset": float(self.train_offset),
                "pulse_width": float(self.pulse_width),
            },
            "linear": {
                "nb": self.nb, "nf": self.nf, "nk": self.nk,
                "b": [float(v) for v in self.b], "f": [float(v) for v in self.f],
            },
            "input_nonlinearity": self.input_nonlinearity.to_dict(),
            "output_nonlinearity": self.output_nonlinearity.to_dict(),
            "units": {
                "input": "dimensionless impulse train (unit-height pulses)",
                "output": "m/s^2 (drive-end housing acceleration, y)",
                "sample_rate": "Hz", "fault_frequency": "Hz", "rpm": "rev/min",
                "pulse_width": "s", "fit": "percent, 100*(1-|y-yhat|/|y-mean(y)|)",
            },
            "fit": _jsonable(asdict(self.fit)) if self.fit is not None else {},
            "provenance": _jsonable(self.provenance),
        }

    @classmethod
    def from_dict(cls, d: dict) -> HWModel:
        lin = d["linear"]
        b, f = lin["b"], lin["f"]
        if len(b) != int(lin["nb"]) or len(f) != int(lin["nf"]) + 1:
            raise ValueError("linear: lengths of b / f do not match nb / nf")
        return cls(
            fault_type=d["fault_type"], sample_rate=float(d["sample_rate"]), rpm=float(d["rpm"]),
            fault_frequency=float(d["fault_frequency"]), fault_order=float(d["fault_order"]),
            b=np.array(b, dtype=float), f=np.array(f, dtype=float), nk=int(lin["nk"]),
            input_nonlinearity=MonotonePiecewiseLinear.from_dict(d["input_nonlinearity"]),
            output_nonlinearity=MonotonePiecewiseLinear.from_dict(d["output_nonlinearity"]),
            train_offset=float(d["train"].get("offset", 0.0)),
            pulse_width=float(d["train"]["pulse_width"]),
            fit=ModelFit.from_dict(d["fit"]) if d.get("fit") else None, provenance=dict(d.get("provenance", {})),
        )

    def save(self, path) -> Path:
        """Write the model file (JSON, human-readable) and return its path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        return path


def same_bearing(a: Bearing, b: Bearing) -> bool:
    """True when ``a`` and ``b`` have the same characteristic orders (eqs. 2.51-2.54), whatever their names."""
    oa, ob = a.orders(), b.orders()
    return all(math.isclose(getattr(oa, k), getattr(ob, k), rel_tol=1e-9) for k in ("ftf", "bsf", "bpfo", "bpfi"))


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    return obj


def load(path, sample_rate: float | None = None, fault_type: str | None = None) -> HWModel:
    """Load a model file, checking it.

    Parameters
    ----------
    path : path-like
        The JSON model file.
    sample_rate : float, optional
        Required sample rate (Hz); a mismatch raises.
    fault_type : str, optional
        Required fault type; a mismatch raises.

    Raises
    ------
    ModelFileError
        File missing, not JSON, wrong kind or version, invalid content, or mismatch.
    """
    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"model file not found: {path}")
    try:
        d = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ModelFileError(f"model file {path} is corrupt (not valid JSON): {exc}") from None
    if not isinstance(d, dict) or d.get("kind") != KIND:
        raise ModelFileError(f"{path} is not a bearing_observer HW model file (kind != {KIND!r})")
    if d.get("format_version") != FORMAT_VERSION:
        raise ModelFileError(
            f"{path}: format_version {d.get('format_version')!r} not supported "
            f"(this code reads {FORMAT_VERSION})")
    try:
        model = HWModel.from_dict(d)
        model.bearing  # noqa: B018 (validates the recorded bearing)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:  # wrong structure anywhere
        raise ModelFileError(f"model file {path} is corrupt: {type(exc).__name__}: {exc}") from None
    if sample_rate is not None and not math.isclose(model.sample_rate, float(sample_rate),
                                                   rel_tol=1e-9):
        raise ModelFileError(
            f"{path} was identified at {model.sample_rate:g} Hz but {float(sample_rate):g} Hz "
            "was requested; resample the input or use a model set for that rate")
    if fault_type is not None and model.fault_type != fault_type:
        raise ModelFileError(f"{path} holds a {model.fault_type} model, not {fault_type}")
    return model
