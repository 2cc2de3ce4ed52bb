"""ISO 20816-3 evaluation zones of broadband velocity RMS (10-1000 Hz), by machine class.

Zone boundaries (r.m.s. velocity, mm/s) of ISO 20816-3:2022 Annex A, Tables A.1 (group 1) and
A.2 (group 2), the values of ISO 10816-3:2009 Tables A.1 and A.2, which the 2022 edition kept:

=========================================  ======  ======  ======
machine class                               A/B     B/C     C/D
=========================================  ======  ======  ======
group 1 (300 kW-50 MW; shaft height         2.3     4.5     7.1
≥ 315 mm), rigid support
group 1, flexible support                   3.5     7.1     11.0
group 2 (15-300 kW; shaft height            1.4     2.8     4.5
160-315 mm), rigid support
group 2, flexible support                   2.3     4.5     7.1
=========================================  ======  ======  ======

Zone A: newly commissioned machines; B: unrestricted long-term operation; C: not suitable for
long-term continuous operation; D: severe enough to cause damage. A value on a boundary
belongs to the higher zone. The standard covers machines above 15 kW at 120-30 000 r/min
(10-1000 Hz band above 600 r/min), measured on bearing housings; a test rig such as
PRONOSTIA is outside its scope, so the zone is reported beside the trend state, not used
by it (the state compares the machine with its own baseline, the standard's criterion II
in spirit).
"""

from __future__ import annotations

from bisect import bisect_right

#: Zone boundaries A/B, B/C, C/D (mm/s) per machine class name.
ZONE_LIMITS_MM_S: dict[str, tuple[float, float, float]] = {
    "group1-rigid": (2.3, 4.5, 7.1),
    "group1-flexible": (3.5, 7.1, 11.0),
    "group2-rigid": (1.4, 2.8, 4.5),
    "group2-flexible": (2.3, 4.5, 7.1),
}

#: The class assumed when none is set: group 2 (15-300 kW motors) on a rigid support, the
#: most common industrial motor and the strictest limits.
DEFAULT_MACHINE_CLASS = "group2-rigid"

ZONES = ("A", "B", "C", "D")


def machine_class(name: str | None) -> str:
    """The machine class key for ``name`` (e.g. ``group2-rigid``; None = the default); ValueError if unknown."""
    key = (name or DEFAULT_MACHINE_CLASS).strip().lower().replace("_", "-").replace(" ", "-")
    if key not in ZONE_LIMITS_MM_S:
        raise ValueError(f"unknown ISO 20816-3 machine class {name!r}; expected one of "
                         f"{', '.join(ZONE_LIMITS_MM_S)}")
    return key


def iso_zone(velocity_rms: float, machine: str = DEFAULT_MACHINE_CLASS) -> str:
    """Zone ``A``-``D`` of ``velocity_rms`` (m/s, 10-1000 Hz) for ``machine``; ``""`` if not finite."""
    mm_s = velocity_rms * 1e3
    if not mm_s >= 0.0 or mm_s == float("inf"):
        return ""
    return ZONES[bisect_right(ZONE_LIMITS_MM_S[machine_class(machine)], mm_s)]
