"""CSV and TSV recordings, as data loggers export them: one row per sample, one column per channel.

The file: text (UTF-8), lines starting with ``#`` are comments; the first other line may be a
header of column names (it is one when any of its cells is not a number); then rows of
numbers separated by commas, semicolons, tabs or spaces (the first data row tells which: tab,
then ``;``, then ``,``, else spaces; with ``;`` a decimal comma is read too, as European
spreadsheets write ``0,125;0,5``). Every row has the same number of cells.

Columns are named by the header, else numbered from 1; ``channel`` picks one by name or by
number (``--channel 2``). A column whose name is a time (``t``, ``time``, ``timestamp``,
``seconds``, ``elapsed``, with an optional unit ``s``, ``ms`` or ``us``: ``time (ms)``,
``t_s``, ``Time [s]``) gives the sample rate, (n − 1) / (t_last − t_first), when its
samples are evenly spaced (each within half a sample period of the line through the first
and the last; a rate within 1e-6 of a whole number of Hz is that number); a given
``sample_rate`` overrides it and is needed without one. The signal is the one column that
is not the time when there is one, else the one named by ``channel``. Its name may state
its unit (``accel_g``, ``a (m/s^2)``, ``ch1 [mV]``: :mod:`.measurement_units`).

:func:`read_table` reads any columns by name (:meth:`Table.column`), so another reader can
take a second channel, such as a tachometer's, from the same file.
"""

from __future__ import annotations

import io
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .measurement_units import value_scale
from .recording import MAX_SAMPLES, InputError, Recording, check_rate, check_rpm, check_samples

#: File name suffixes read as tables.
TABLE_SUFFIXES = (".csv", ".tsv", ".txt")

#: A time column's name and unit (s per unit).
_TIME_NAME = re.compile(r"(t|time|timestamp|seconds?|secs?|elapsed(?:[ _]time)?)"
                        r"(?:[ _]*[(\[]?\s*(s|sec|ms|us|µs)\s*[)\]]?)?", re.IGNORECASE)
_TIME_UNITS = {None: 1.0, "s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}

#: A signal column's unit at the end of its name: ``accel_g``, ``a (m/s^2)``, ``ch1 [mV]``.
_UNIT_SUFFIX = re.compile(r".*?(?:[\s_]+|[\s_]*[(\[])(g|m/s\^?2|m/s²|v|mv|uv|µv)[)\]]?\s*", re.IGNORECASE)
_UNIT_NAMES = {"g": "g", "m/s2": "m/s2", "m/s^2": "m/s2", "m/s²": "m/s2", "v": "V", "mv": "mV", "uv": "uV",
               "µv": "uV"}

#: Relative distance from a whole number of Hz within which a time column's rate is that number
#: (printed stamps round the span by far less; the fault lines move by as little).
WHOLE_HZ = 1e-6

#: How far (sample periods) a time stamp may lie from the fitted line: rounding of printed
#: stamps stays far below it; a dropped or repeated sample does not.
TIME_JITTER = 0.5


@dataclass
class Table:
    """A table of numbers: ``names`` of its columns (header, or ``"1"``, ``"2"``, ...), ``data``
    (rows × columns), ``header`` whether the file named them, ``path``."""

    path: str
    names: list[str]
    data: np.ndarray
    header: bool

    def index(self, name: str) -> int:
        """The column called ``name`` (case-insensitive), or numbered so from 1; InputError otherwise."""
        lowered = [n.lower() for n in self.names]
        if name.lower() in lowered:
            return lowered.index(name.lower())
        if name.isdigit() and 1 <= int(name) <= len(self.names):
            return int(name) - 1
        raise InputError(f"{self.path}: no column {name!r}; columns: {self.listing()}")

    def column(self, name: str) -> np.ndarray:
        """The column ``name`` (:meth:`index`) as float64."""
        return self.data[:, self.index(name)]

    def listing(self) -> str:
        """The columns, for messages: ``time, accel_x, accel_y`` or ``1, 2, 3 (no header)``."""
        return ", ".join(self.names) + ("" if self.header else " (no header)")

    def unit(self, index: int) -> str | None:
        """The unit the name of column ``index`` states (``g``, ``m/s2``, ``V``, ``mV``, ``uV``), else None."""
        m = _UNIT_SUFFIX.fullmatch(self.names[index]) if self.header else None
        return _UNIT_NAMES[m.group(1).lower()] if m else None

    def time_column(self) -> tuple[int, float] | None:
        """(index, s per unit) of the time column, None when there is none (module docstring)."""
        for i, name in enumerate(self.names if self.header else ()):
            m = _TIME_NAME.fullmatch(name.strip())
            if m:
                return i, _TIME_UNITS[m.group(2).lower() if m.group(2) else None]
        return None


def _cells(line: str, delimiter: str | None) -> list[str]:
    return [c.strip().strip('"').strip() for c in line.split(delimiter)]


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _delimiter(line: str) -> str | None:
    for d in ("\t", ";", ","):
        if d in line:
            return d
    return None


def _content_lines(text: str, start: int = 0):
    """(line number from 1, offset of the line's end, line) of each line of ``text`` from offset
    ``start`` on that is neither blank nor a comment, lazily: the caller takes the first few only."""
    number = text.count("\n", 0, start)
    while start < len(text):
        stop = text.find("\n", start)
        stop = len(text) if stop < 0 else stop
        number += 1
        line = text[start:stop]
        if line.strip() and not line.lstrip().startswith("#"):
            yield number, stop, line
        start = stop + 1


def _first_bad_row(text: str, start: int, delimiter: str | None) -> str:
    """Why numpy could not read the rows of ``text`` from offset ``start``: the first row that differs
    (run only when reading failed)."""
    width = None
    for number, _end, line in _content_lines(text, start):
        cells = line.replace('"', "").split(delimiter)
        width = len(cells) if width is None else width
        if len(cells) != width:
            return f"line {number} has {len(cells)} cells, the first row {width}"
        for cell in cells:
            if not _is_number(cell):
                return f"line {number}: {cell.strip()!r} is not a number"
    return "not a table of numbers"


def read_table(path) -> Table:
    """The table in ``path`` (module docstring); InputError with the reason when it is not one.

    The rows are parsed by numpy's reader in one call (no Python loop over them); the header
    and the separator are found from the first lines."""
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (CSV/TSV expected)") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.__class__.__name__}: {exc})") from None
    rows = text.count("\n") + 1
    if rows > MAX_SAMPLES:
        raise InputError(f"{path}: {rows} rows is more than the {MAX_SAMPLES} this tool reads at once; "
                         "split the recording")
    found = _content_lines(text)
    first = next(found, None)
    if first is None:
        raise InputError(f"{path}: no rows (an empty table)")
    header, body_start = None, 0
    if not all(_is_number(c) for c in _cells(first[2], _delimiter(first[2]))):
        header, body_start = first[2], first[1] + 1
        first = next(found, None)
        if first is None:
            raise InputError(f"{path}: a header ({', '.join(_cells(header, _delimiter(header)))}) and no rows of "
                             "numbers")
    delimiter = _delimiter(first[2])
    body = text[body_start:]
    if delimiter == ";":
        body = body.replace(",", ".")  # decimal commas
    try:
        data = np.loadtxt(io.StringIO(body), delimiter=delimiter, ndmin=2, dtype=float, comments="#",
                          quotechar='"')
    except ValueError:
        raise InputError(f"{path}: {_first_bad_row(text[:body_start] + body, body_start, delimiter)}") from None
    if header is None:
        names = [str(k + 1) for k in range(data.shape[1])]
    elif delimiter is None and data.shape[1] == 1:  # one column: the whole line names it, spaces and all
        names = [_cells(header, "\n")[0]]
    else:
        names = _cells(header, delimiter)
    if len(names) != data.shape[1]:
        raise InputError(f"{path}: the header names {len(names)} columns ({', '.join(names)}), the rows hold "
                         f"{data.shape[1]}")
    return Table(str(path), names, data, header is not None)


def table_rate(table: Table, sample_rate: float | None) -> tuple[float, float]:
    """(sample rate in Hz, time of the first sample in s): ``sample_rate`` when given, else from the
    time column (module docstring); InputError when neither gives one."""
    found = table.time_column()
    if found is None:
        if sample_rate is None:
            raise InputError(f"{table.path}: no time column (t, time, ... ) and no --sample-rate; give "
                             f"--sample-rate (columns: {table.listing()})")
        return check_rate(sample_rate), 0.0
    index, unit = found
    t = table.data[:, index] * unit
    if sample_rate is not None:
        return check_rate(sample_rate), float(t[0])
    if t.size < 2:
        raise InputError(f"{table.path}: one row: its time column gives no sample rate; give --sample-rate")
    step = np.diff(t)
    if not np.all(step > 0):
        k = int(np.argmax(~(step > 0)))
        raise InputError(f"{table.path}: the time column {table.names[index]!r} does not increase at row {k + 2} "
                         f"({t[k]:g} s, then {t[k + 1]:g} s)")
    period = (t[-1] - t[0]) / (t.size - 1)
    off = np.abs(t - (t[0] + period * np.arange(t.size))) / period
    if off.max() > TIME_JITTER:
        k = int(np.argmax(off))
        raise InputError(f"{table.path}: the time column {table.names[index]!r} is not evenly spaced (row {k + 1} "
                         f"lies {off[k]:.2g} sample periods off); resample the recording, or give --sample-rate")
    rate = 1.0 / period
    if round(rate) and abs(rate / round(rate) - 1.0) <= WHOLE_HZ:
        rate = float(round(rate))
    try:
        return check_rate(rate, "sample rate of the time column"), float(t[0])
    except InputError as exc:
        raise InputError(f"{table.path}: {exc}") from None


def signal_column(table: Table, channel: str | None) -> int:
    """The index of the vibration column: ``channel``'s, else the only column besides the time."""
    time = table.time_column()
    if channel is not None:
        index = table.index(channel)
        if time is not None and index == time[0]:
            raise InputError(f"{table.path}: --channel {channel!r} is the time column; columns: {table.listing()}")
        return index
    rest = [i for i in range(len(table.names)) if time is None or i != time[0]]
    if len(rest) != 1:
        raise InputError(f"{table.path}: {len(rest)} signal columns; give --channel (columns: {table.listing()})")
    return rest[0]


def load_table(path, sample_rate: float | None = None, rpm: float | None = None, channel: str | None = None,
               units: str | None = None, sensitivity: str | None = None) -> Recording:
    """A CSV/TSV recording in m/s² (module docstring); ``units`` or ``sensitivity``: what its numbers
    measure (:mod:`.measurement_units`; default g, said in the notes)."""
    table = read_table(path)
    index = signal_column(table, channel)
    fs, start = table_rate(table, sample_rate)
    name = table.names[index]
    try:
        scale, note = value_scale(units, sensitivity, f"column {name!r}", file_units=table.unit(index))
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    x = check_samples(table.data[:, index], f"{path}:{name}") * scale
    notes = [note] if note else []
    if sample_rate is None:
        notes.append(f"sample rate {fs:.6g} Hz from the time column {table.names[table.time_column()[0]]!r}")
    return Recording(x, fs, None if rpm is None else check_rpm(rpm), "csv", None, name, str(path),
                     start_time=start, notes=notes)
