"""Rolling-element bearings: geometry, characteristic fault frequencies and the catalog.

Thesis section 2.2, eqs. 2.51-2.54 (stationary outer ring, rotating inner ring), plus
the ball-spin frequency. With ``r = d/D · cos(φ)`` (element diameter d, pitch diameter D,
contact angle φ) and shaft frequency ``fr``:

* FTF  = fr/2 · (1 − r)                  cage (fundamental train), eq. 2.51
* BSF  = D/(2d) · fr · (1 − r²)          ball spin, eq. 2.52
* BPFO = n · FTF                         outer-race ball pass, eq. 2.53
* BPFI = n · (fr − FTF)                  inner-race ball pass, eq. 2.54

A ball defect strikes both races once per spin revolution, so its impact rate is 2·BSF.
Lengths in metres, angles in radians, frequencies in Hz.

A bearing is named by :func:`load_bearing`: a catalog name (:data:`CATALOG`), a YAML
file, or the four numbers ``"N,d,D,angle"`` with units, e.g. ``"9,7.94mm,39.04mm,0deg"``.
The YAML form (SI; inches and degrees accepted where the key says so)::

    name: SKF 6206              # optional
    rolling_elements: 9
    element_diameter: 0.009525  # m   (or element_diameter_in: 0.375)
    pitch_diameter: 0.0465      # m   (or pitch_diameter_in: 1.831)
    contact_angle: 0.0          # rad (or contact_angle_deg: 0)
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from .states import FaultState
from .units import INCH


class BearingError(ValueError):
    """A bearing description that cannot be used (the message is one line for the user)."""


@dataclass(frozen=True)
class FaultFrequencies:
    """Characteristic frequencies (Hz) of one bearing at one shaft speed."""

    shaft: float
    ftf: float
    bsf: float
    bpfo: float
    bpfi: float

    @property
    def ball(self) -> float:
        """Impact rate of a rolling-element defect, 2·BSF (Hz)."""
        return 2.0 * self.bsf

    def of(self, fault: FaultState) -> float:
        """Impact rate (Hz) of ``fault``: BPFO, BPFI or 2·BSF."""
        fault = FaultState(fault)
        if fault == FaultState.OUTER_RACE:
            return self.bpfo
        if fault == FaultState.INNER_RACE:
            return self.bpfi
        if fault == FaultState.BALL:
            return self.ball
        raise ValueError(f"no fault frequency for state {fault.name}")


@dataclass(frozen=True)
class Bearing:
    """Geometry of one rolling-element bearing.

    Attributes
    ----------
    name : str
    n_elements : int
        Number of rolling elements (balls or rollers).
    element_diameter : float
        d, m.
    pitch_diameter : float
        D, m.
    contact_angle : float
        φ, rad.
    """

    name: str
    n_elements: int
    element_diameter: float
    pitch_diameter: float
    contact_angle: float = 0.0

    def __post_init__(self):
        if not (isinstance(self.n_elements, int) and 3 <= self.n_elements <= 200):
            raise BearingError(f"bearing {self.name!r}: number of rolling elements must be an integer "
                               f"in 3..200, got {self.n_elements!r}")
        d, D = self.element_diameter, self.pitch_diameter
        if not (math.isfinite(d) and math.isfinite(D) and 0.0 < d < D):
            raise BearingError(f"bearing {self.name!r}: need 0 < element diameter < pitch diameter "
                               f"(m), got {d!r} and {D!r}")
        if D > 10.0:
            raise BearingError(f"bearing {self.name!r}: pitch diameter {D:g} m is not plausible "
                               "(lengths are in metres; use *_in keys for inches)")
        if not (math.isfinite(self.contact_angle) and 0.0 <= self.contact_angle < math.pi / 2):
            raise BearingError(f"bearing {self.name!r}: contact angle must be in [0, pi/2) rad, "
                               f"got {self.contact_angle!r}")
        if self.n_elements * d > math.pi * D:
            raise BearingError(f"bearing {self.name!r}: {self.n_elements} elements of {d:g} m do not fit "
                               f"on a {D:g} m pitch circle")

    @property
    def ratio(self) -> float:
        """r = d/D · cos φ (dimensionless)."""
        return self.element_diameter / self.pitch_diameter * math.cos(self.contact_angle)

    def ftf(self, shaft_hz: float) -> float:
        """Fundamental train (cage) frequency, eq. 2.51 (Hz)."""
        return 0.5 * shaft_hz * (1.0 - self.ratio)

    def bsf(self, shaft_hz: float) -> float:
        """Ball spin frequency, eq. 2.52 (Hz)."""
        return self.pitch_diameter / (2.0 * self.element_diameter) * shaft_hz * (1.0 - self.ratio**2)

    def bpfo(self, shaft_hz: float) -> float:
        """Ball pass frequency, outer race, n·FTF, eq. 2.53 (Hz)."""
        return self.n_elements * self.ftf(shaft_hz)

    def bpfi(self, shaft_hz: float) -> float:
        """Ball pass frequency, inner race, n·(fr − FTF), eq. 2.54 (Hz)."""
        return self.n_elements * (shaft_hz - self.ftf(shaft_hz))

    def frequencies(self, rpm: float) -> FaultFrequencies:
        """All characteristic frequencies (Hz) at ``rpm`` (rev/min)."""
        fr = shaft_hz(rpm)
        return FaultFrequencies(fr, self.ftf(fr), self.bsf(fr), self.bpfo(fr), self.bpfi(fr))

    def orders(self) -> FaultFrequencies:
        """The characteristic frequencies as multiples of the shaft frequency."""
        return self.frequencies(60.0)

    def to_dict(self) -> dict:
        """The YAML form (SI)."""
        return {"name": self.name, "rolling_elements": self.n_elements,
                "element_diameter": self.element_diameter, "pitch_diameter": self.pitch_diameter,
                "contact_angle": self.contact_angle}


def shaft_hz(rpm: float) -> float:
    """Shaft rotation frequency (Hz) from speed in rev/min."""
    return rpm / 60.0


def fault_frequency(bearing: Bearing, fault: int, rpm: float) -> float:
    """Impact rate (Hz) of an outer-race (BPFO), inner-race (BPFI) or ball (2·BSF) defect at ``rpm``."""
    return bearing.frequencies(rpm).of(FaultState(fault))


#: The shipped catalog, by the names the ``bearing`` parameter and ``--bearing`` accept.
CATALOG: dict[str, Bearing] = {
    # CWRU motor, drive end (CWRU "Bearing Information": BPFO 3.5848, BPFI 5.4152 x shaft)
    "6205": Bearing("SKF 6205-2RS JEM (CWRU drive end)", 9, 0.3126 * INCH, 1.537 * INCH),
    # CWRU motor, fan end (BPFO 3.0530 x shaft)
    "6203": Bearing("SKF 6203-2RS JEM (CWRU fan end)", 8, 0.2656 * INCH, 1.122 * INCH),
    # MFPT rig bearing (NICE; BPFO 81.125 Hz at 25 Hz shaft)
    "mfpt": Bearing("NICE (MFPT rig)", 8, 0.235 * INCH, 1.245 * INCH),
    # Rexnord ZA-2115 double-row roller bearing of the IMS run-to-failure rig
    "za2115": Bearing("Rexnord ZA-2115 (IMS rig)", 16, 0.331 * INCH, 2.815 * INCH, math.radians(15.17)),
    # FEMTO-ST PRONOSTIA accelerated-life test bearing (IEEE PHM 2012 challenge, Appendix A.1;
    # contact angle not stated: deep-groove ball bearing, 0): BPFO 5.611, BPFI 7.389 x shaft
    "femto": Bearing("PRONOSTIA test bearing (FEMTO-ST)", 13, 3.5e-3, 25.6e-3),
}

#: Other names accepted for catalog entries.
ALIASES = {"cwru_de": "6205", "cwru_fe": "6203", "skf6205": "6205", "skf6203": "6203", "ims": "za2115",
           "pronostia": "femto"}

#: The default bearing: the CWRU drive end (the simulator's bearing, thesis table 2.1).
DEFAULT_BEARING = "6205"


def catalog_names() -> list[str]:
    """Names :func:`load_bearing` accepts from the catalog (aliases included)."""
    return sorted(CATALOG) + sorted(ALIASES)


_LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "in": INCH}
_ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180.0}


def _quantity(text: str, units: dict, what: str, spec: str, bare_zero: bool = False) -> float:
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([a-z]*)\s*", text)
    if not m:
        raise BearingError(f"bearing {spec!r}: cannot read the {what} {text.strip()!r}")
    try:
        value = float(m.group(1))
    except ValueError:
        raise BearingError(f"bearing {spec!r}: cannot read the {what} {text.strip()!r}") from None
    unit = m.group(2)
    if not unit and bare_zero and value == 0.0:
        return 0.0
    if unit not in units:
        raise BearingError(f"bearing {spec!r}: the {what} needs a unit ({', '.join(units)}), got {text.strip()!r}")
    return value * units[unit]


def parse_bearing_numbers(spec: str) -> Bearing:
    """A bearing from ``"N,d,D[,angle]"``: lengths with a unit (m, mm, in), angle in deg or rad."""
    parts = spec.split(",")
    if len(parts) not in (3, 4):
        raise BearingError(f"bearing {spec!r}: expected 'N,d,D[,angle]', e.g. '9,7.94mm,39.04mm,0deg'")
    try:
        n = int(parts[0])
    except ValueError:
        raise BearingError(f"bearing {spec!r}: number of rolling elements {parts[0]!r} is not an integer") from None
    d = _quantity(parts[1], _LENGTH_UNITS, "element diameter", spec)
    D = _quantity(parts[2], _LENGTH_UNITS, "pitch diameter", spec)
    phi = _quantity(parts[3], _ANGLE_UNITS, "contact angle", spec, bare_zero=True) if len(parts) == 4 else 0.0
    return Bearing(spec, n, d, D, phi)


def _one_of(data: dict, si_key: str, other_key: str, scale: float, source: str, required: bool = True) -> float:
    have = [k for k in (si_key, other_key) if k in data]
    if len(have) > 1:
        raise BearingError(f"{source}: give {si_key} or {other_key}, not both")
    if not have:
        if required:
            raise BearingError(f"{source}: missing {si_key} (or {other_key})")
        return 0.0
    value = data[have[0]]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise BearingError(f"{source}: {have[0]} must be a number, got {value!r}")
    return float(value) * (scale if have[0] == other_key else 1.0)


def bearing_from_dict(data, source: str = "bearing") -> Bearing:
    """A bearing from the YAML form (see the module docstring); ``source`` names it in errors."""
    if isinstance(data, dict) and set(data) == {"bearing"}:
        data = data["bearing"]
    if not isinstance(data, dict):
        raise BearingError(f"{source}: expected a mapping with rolling_elements, element_diameter, "
                           "pitch_diameter, contact_angle")
    known = {"name", "rolling_elements", "element_diameter", "element_diameter_in", "pitch_diameter",
             "pitch_diameter_in", "contact_angle", "contact_angle_deg"}
    unknown = sorted(set(map(str, data)) - known)
    if unknown:
        raise BearingError(f"{source}: unknown keys {', '.join(map(repr, unknown))}; "
                           f"expected {', '.join(sorted(known))}")
    n = data.get("rolling_elements")
    if isinstance(n, bool) or not isinstance(n, int):
        raise BearingError(f"{source}: rolling_elements must be an integer, got {n!r}")
    d = _one_of(data, "element_diameter", "element_diameter_in", INCH, source)
    D = _one_of(data, "pitch_diameter", "pitch_diameter_in", INCH, source)
    phi = _one_of(data, "contact_angle", "contact_angle_deg", math.pi / 180.0, source, required=False)
    return Bearing(str(data.get("name", Path(source).stem)), n, d, D, phi)


def load_bearing(spec: str | Bearing | None = None) -> Bearing:
    """Resolve a bearing: catalog name, YAML file, ``"N,d,D,angle"``, or a Bearing (passed through).

    ``None`` or ``""`` gives :data:`DEFAULT_BEARING`. Raises :class:`BearingError` with one line.
    """
    if isinstance(spec, Bearing):
        return spec
    text = (spec or DEFAULT_BEARING).strip()
    key = text.lower()
    key = ALIASES.get(key, key)
    if key in CATALOG:
        return CATALOG[key]
    path = Path(text).expanduser()
    if path.suffix.lower() in (".yaml", ".yml") or path.is_file():
        return _load_yaml(path)
    if "," in text:
        return parse_bearing_numbers(text)
    raise BearingError(f"unknown bearing {text!r}: give a catalog name ({', '.join(catalog_names())}), "
                       "a YAML file, or 'N,d,D,angle' such as '9,7.94mm,39.04mm,0deg'")


def bearing_spec(bearing: Bearing) -> str:
    """A text :func:`load_bearing` reads back: the catalog name, else ``"N,dm,Dm,φrad"``."""
    for name, entry in CATALOG.items():
        if entry == bearing:
            return name
    return (f"{bearing.n_elements},{bearing.element_diameter!r}m,{bearing.pitch_diameter!r}m,"
            f"{bearing.contact_angle!r}rad")


def _load_yaml(path: Path) -> Bearing:
    import yaml
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise BearingError(f"{path}: cannot read the bearing file ({exc.__class__.__name__}: {exc})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise BearingError(f"{path}: not valid YAML ({' '.join(str(exc).split())})") from None
    return bearing_from_dict(data, str(path))
