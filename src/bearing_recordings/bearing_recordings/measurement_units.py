"""What the numbers of a file measure, and the factor that turns them into m/s².

Files that do not say it themselves (one-signal MATLAB files, CSV/TSV tables, WAV files) are
told on the command line in one of two ways:

* ``--units g`` or ``--units m/s2``: the numbers are accelerations in that unit;
* ``--sensitivity S``: the sensor's sensitivity, the numbers being its output. ``S`` is a
  positive number with an optional voltage unit, over an acceleration unit:
  ``100mV/g``, ``0.1V/g``, ``10.2mV/(m/s2)``: the numbers are volts (the sensor's output
  voltage), a = v / S; ``0.05/g``: the numbers are plain values, S of them per g (a WAV
  file's integer samples read as fractions of full scale: ``0.05/g`` is ±20 g full scale).

The two exclude each other. A file may state the unit itself (a CSV column named
``accel (g)`` or ``ch1 [mV]``): an acceleration unit is then used unless ``--units`` says
otherwise, and a voltage unit needs ``--sensitivity`` (the numbers are read in that voltage
unit). A WAV file's integer PCM samples are fractions of full scale, not volts, so a voltage
sensitivity is refused for them (:func:`value_scale`).
"""

from __future__ import annotations

import math
import re

from bearing_common.units import STANDARD_GRAVITY

from .recording import InputError

#: Acceleration units, as m/s² per unit.
UNITS = {"g": STANDARD_GRAVITY, "m/s2": 1.0}

#: Voltage units a file may state its numbers in, as volts per unit.
VOLTAGE_UNITS = {"V": 1.0, "mV": 1e-3, "uV": 1e-6}

#: Spellings of the acceleration units in a sensitivity's denominator.
_ACCEL_SPELLINGS = {"g": "g", "m/s2": "m/s2", "m/s^2": "m/s2", "m/s²": "m/s2", "ms-2": "m/s2"}

#: Voltage units of a sensitivity's numerator, as volts per unit.
_VOLTS = {"v": 1.0, "mv": 1e-3, "uv": 1e-6, "µv": 1e-6}

_SENSITIVITY = re.compile(r"\s*([0-9.eE+-]+)\s*([a-zA-Zµ]*)\s*/\s*\(?\s*([^()\s]+)\s*\)?\s*")


def parse_sensitivity(text: str) -> tuple[float, bool]:
    """``S`` of ``--sensitivity`` (module docstring) as (numbers per m/s², whether they are volts).

    >>> parse_sensitivity("100mV/g")  # doctest: +ELLIPSIS
    (0.0101971..., True)
    """
    m = _SENSITIVITY.fullmatch(text)
    accel = _ACCEL_SPELLINGS.get(m.group(3).lower() if m else "")
    volts = _VOLTS.get(m.group(2).lower(), None) if m and m.group(2) else 1.0
    try:
        value = float(m.group(1)) if m else math.nan
    except ValueError:
        value = math.nan
    if accel is None or volts is None or not (math.isfinite(value) and value > 0):
        raise InputError(f"--sensitivity {text!r} not understood; expected a positive number per acceleration "
                         "unit, e.g. 100mV/g, 10.2mV/(m/s2), 0.1V/g, or 0.05/g for plain values")
    return value * volts / UNITS[accel], bool(m.group(2))


def value_scale(units: str | None, sensitivity: str | None, what: str, file_units: str | None = None,
                integer_fraction: bool = False, default_units: str | None = "g") -> tuple[float, str]:
    """m/s² per number of a file, and a note for the user's log ("" when nothing was assumed).

    ``what`` names the data in messages. ``file_units``: the unit the file itself states for
    the numbers (:data:`UNITS` or :data:`VOLTAGE_UNITS`, e.g. from a column's name), which
    ``units`` overrides; numbers in volts need a voltage ``sensitivity``. ``integer_fraction``:
    the numbers are fractions of full scale (a WAV file's integer PCM), which no voltage
    sensitivity fits. ``default_units``: assumed (and said in the note) when nothing states a
    unit, None to refuse instead.
    """
    if units is not None and sensitivity is not None:
        raise InputError("give --units or --sensitivity, not both")
    if units is not None and units not in UNITS:
        raise InputError(f"unknown units {units!r}; expected one of {', '.join(UNITS)}")
    file_volts = VOLTAGE_UNITS.get(file_units or "")
    if sensitivity is not None:
        per_m_s2, volts = parse_sensitivity(sensitivity)
        if volts and integer_fraction:
            raise InputError(f"{what}: integer PCM samples are fractions of full scale, not volts; give "
                             "--sensitivity as fractions of full scale per g (e.g. 0.05/g for ±20 g full "
                             "scale) or --units")
        if file_units in UNITS:
            raise InputError(f"{what} is stated in {file_units}, an acceleration; --sensitivity is for a "
                             "sensor's output (give --units to override the stated unit)")
        if file_volts is not None and not volts:
            raise InputError(f"{what} is stated in {file_units}; give --sensitivity in volts per g, "
                             "e.g. 100mV/g")
        return (file_volts or 1.0) / per_m_s2, ""
    if file_volts is not None and units is None:
        raise InputError(f"{what} is stated in {file_units}, the sensor's output voltage; give --sensitivity "
                         "(e.g. 100mV/g)")
    if units is not None:
        return UNITS[units], ""
    if file_units in UNITS:
        return UNITS[file_units], ""
    if default_units is None:
        raise InputError(f"{what}: the file does not say what its samples measure; give --units g|m/s2 "
                         "or --sensitivity (e.g. 100mV/g)")
    return UNITS[default_units], (f"units of {what} not stated; assuming {default_units} (give --units or "
                                  "--sensitivity otherwise)")
