"""Healthy recordings changed the way other healthy machines differ: no visible 1x, a foreign stationary line.

Two constructions for the false-alarm matrix (:mod:`benchmarks.false_alarm_matrix`), each on
the recording's own signal:

* :func:`without_shaft_family` — a machine whose raw spectrum shows no 1x family (as HIT-SM at
  600 and 900 rpm on short buffers): zero-phase notches (``filtfilt``, Gustafsson's initial
  conditions, so the record's ends are notched too) at k·fr, k = 1..10, each with a −3 dB
  width of 1 % of its frequency, and at least the record's Hann main lobe (4/T Hz for T s),
  which a line that wanders by less than a bin fills. 1 % is the narrowest that leaves no 1x
  family to the decision's own speed measurement
  (:func:`bearing_diagnoser.spectral.shaft_speed.estimate_speed`, 2 s buffers) on any of the
  five continuous healthy recordings: with 0.5 % it still finds one on CWRU 097 and HIT-SM
  Normal_600 (measured); the main-lobe floor takes the 1x line itself down to the floor of the
  whole record's spectrum (with 1 % alone it kept 10× the floor on CWRU 097). fr is the rate
  that measurement finds on the whole record within ±3 % of the nominal speed (a motor's
  slip), the nominal one where it finds none. Lines of other families beside a harmonic
  (CWRU's 120 Hz mains line, 0.3 Hz from 4x) stay.
* :func:`with_foreign_line` — a stationary line in the envelope that belongs to no part and no
  shaft harmonic, inside one comb term's slip range (:func:`foreign_frequency`): an amplitude
  modulation x·(1 + m·cos 2πf t), which puts a line at f into the envelope of every band.
  Its depth m is set from the recording's own envelope floor (:func:`modulation_depth`): the
  line's mean height over 0.5 s windows, in the decision's normalised squared envelope
  spectrum (each bin ÷ the running median of its 101 neighbours × ln 2, so that the floor's
  mean is 1), is :data:`LINE_STRENGTH` = 7.5 (the middle of the 5-10× that real healthy
  machines show, issue 25) in the demodulation band and view where it stands highest: every
  candidate band of the decision's band choice, with and without its prewhitening (the
  baseline's view). No band either method looks at shows it stronger.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.signal import filtfilt, iirnotch

from bearing_common.bearings import Bearing
from bearing_common.states import FaultState
from bearing_diagnoser.spectral.band_choice import candidate_bands
from bearing_diagnoser.spectral.envelope_spectrum import band_ses, normalise, window_spectrum
from bearing_diagnoser.spectral.fault_combs import SHAFT_MASK_BINS, SLIP_ABOVE, SLIP_BELOW, comb_terms, highest_term
from bearing_diagnoser.spectral.shaft_speed import estimate_speed

#: Shaft harmonics notched, 1x included (the decision's speed measurement examines as many).
NOTCHED_HARMONICS = 10

#: −3 dB width of each notch, relative to its frequency (module docstring).
NOTCH_WIDTH = 0.01

#: Relative range around the nominal speed where the 1x line is looked for (a motor's slip).
SPEED_SEARCH = 0.03

#: Heights of stationary lines over the envelope floor that real healthy machines show (issue 25),
#: and the foreign line's: the middle (module docstring). A place where the recording already has a
#: line of such a height is not used.
LINE_STRENGTH_RANGE = (5.0, 10.0)
LINE_STRENGTH = 0.5 * sum(LINE_STRENGTH_RANGE)

#: How close to LINE_STRENGTH the construction brings the line's height.
STRENGTH_TOLERANCE = 0.25

#: Window (s) the line's height is measured in.
STRENGTH_WINDOW_S = 0.5

#: Where in a term's slip range the foreign line is tried, relative to the kinematic frequency: from
#: the range's lower end (the issue's example: 2.5 % below 2·BPFO) up to its upper end, in 0.5 % steps.
SLIP_OFFSETS = tuple(np.round(np.arange(-SLIP_BELOW, SLIP_ABOVE + 1e-9, 0.005), 4))

#: Terms the foreign line is tried in, in order: harmonics 2, 1, 3 of BPFO, BPFI, then of 2·BSF.
TRIED_TERMS = tuple((h, k) for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL) for k in (2, 1, 3))

#: The decision's analysis window, in cage periods (:mod:`bearing_diagnoser.spectral.front_end`).
WINDOW_CAGE_PERIODS = 4


def shaft_rate(x: np.ndarray, fs: float, nominal_hz: float) -> float:
    """The shaft rate (Hz) the raw 1x family shows within ±:data:`SPEED_SEARCH` of ``nominal_hz``, else
    ``nominal_hz``."""
    found = estimate_speed(x, fs, (1 - SPEED_SEARCH) * nominal_hz, (1 + SPEED_SEARCH) * nominal_hz)
    return found.hz if found is not None else nominal_hz


def without_shaft_family(x: np.ndarray, fs: float, fr: float) -> np.ndarray:
    """``x`` (fs Hz) with zero-phase notches at k·``fr`` Hz, k = 1..:data:`NOTCHED_HARMONICS` (below 0.45·fs),
    each :func:`notch_width` wide."""
    y = np.asarray(x, float)
    for k in range(1, NOTCHED_HARMONICS + 1):
        f = k * fr
        if f >= 0.45 * fs:
            break
        b, a = iirnotch(f, f / notch_width(f, x.size / fs), fs)
        y = filtfilt(b, a, y, method="gust")
    return y


def notch_width(hz: float, duration: float) -> float:
    """−3 dB width (Hz) of the notch at ``hz`` in a record of ``duration`` s: :data:`NOTCH_WIDTH` of its
    frequency, and at least the record's Hann main lobe (4 / duration), which a line that wanders
    less than a bin fills."""
    return max(NOTCH_WIDTH * hz, 4.0 / duration)


@dataclass(frozen=True)
class ForeignLine:
    """A foreign line: frequency (Hz), the term whose slip range it lies in (hypothesis, harmonic, relative
    offset from the kinematic frequency), modulation depth and its measured height over the floor."""

    hz: float
    hypothesis: FaultState
    harmonic: int
    offset: float
    depth: float = 0.0
    strength: float = 0.0

    def describe(self) -> str:
        name = {FaultState.OUTER_RACE: "BPFO", FaultState.INNER_RACE: "BPFI", FaultState.BALL: "2·BSF"}
        return (f"{self.hz:.2f} Hz, {100 * self.offset:+.1f} % from {self.harmonic}·{name[self.hypothesis]}, "
                f"depth {self.depth:.3g}, {self.strength:.1f}x the floor")


def foreign_frequencies(bearing: Bearing, fr: float):
    """The foreign line's candidate places, in order: each term of :data:`TRIED_TERMS` at each offset of
    :data:`SLIP_OFFSETS` whose frequency lies beyond the decision's shaft mask (more than
    :data:`~bearing_diagnoser.spectral.fault_combs.SHAFT_MASK_BINS` bins of its analysis window, 4 cage
    periods) from every shaft harmonic and every kinematic term (carriers and sidebands of every part)
    at shaft rate ``fr`` (Hz): by the decision's own rule not a shaft line, and not a part's line."""
    o = bearing.orders()
    clearance = SHAFT_MASK_BINS * o.ftf * fr / WINDOW_CAGE_PERIODS
    kinematic = np.concatenate([t[:, 0] + t[:, 1] for t in comb_terms(bearing).values()]) * fr
    rate = {FaultState.OUTER_RACE: o.bpfo, FaultState.INNER_RACE: o.bpfi, FaultState.BALL: o.ball}
    for h, k in TRIED_TERMS:
        for offset in SLIP_OFFSETS:
            f = k * rate[h] * (1 + offset) * fr
            if abs(f - max(1, round(f / fr)) * fr) > clearance and np.min(np.abs(kinematic - f)) > clearance:
                yield ForeignLine(f, h, k, float(offset))


def place_foreign_line(pieces: list[np.ndarray], fs: float, bearing: Bearing, fr: float,
                       t0s: list[float] | None = None) -> ForeignLine:
    """The first of :func:`foreign_frequencies` where the recording (``pieces``, their clocks ``t0s``)
    has no line of its own (height below :data:`LINE_STRENGTH_RANGE`'s lower end, in the pieces' own
    windows: scaled up from snapshots shorter than 0.5 s, the most a floor of few windows and many
    bands reaches would pass for a line), with the depth that
    makes it :data:`LINE_STRENGTH` × the floor (:func:`modulation_depth`); ValueError when there is none."""
    f_top = envelope_top(bearing, fr)
    for line in foreign_frequencies(bearing, fr):
        if line_strength(pieces, fs, line.hz, f_top, scaled=False) >= LINE_STRENGTH_RANGE[0]:
            continue
        depth, strength = modulation_depth(pieces, fs, line.hz, f_top, t0s=t0s)
        return replace(line, depth=depth, strength=strength)
    raise ValueError(f"no place for a foreign line in the slip ranges of {bearing.name} where the recording has no "
                     "line of its own")


def modulated(x: np.ndarray, fs: float, hz: float, depth: float, t0: float = 0.0) -> np.ndarray:
    """x·(1 + depth·cos 2π·hz·t), t = ``t0`` s at the first sample (a snapshot's clock: the line runs on
    through the pauses between snapshots)."""
    t = t0 + np.arange(x.size) / fs
    return x * (1.0 + depth * np.cos(2 * np.pi * hz * t))


def line_heights(pieces: list[np.ndarray], fs: float, hz: float, f_top: float, scaled: bool = True) -> np.ndarray:
    """Mean height over the floor of the envelope spectrum's bin nearest ``hz``, over windows of
    :data:`STRENGTH_WINDOW_S` (or each piece whole when shorter, its excess over the floor then scaled
    to that window length when ``scaled``: a stationary line's excess grows with the window), per view
    (prewhitened, not) and candidate band of the decision's band choice above ``f_top`` Hz: shape
    (2, bands)."""
    bands = candidate_bands(fs, f_top, 0.45 * fs)
    out = []
    for prewhiten in (True, False):
        heights = []  # per window: every band's height
        scale = 1.0
        for x in pieces:
            n = min(x.size, int(round(STRENGTH_WINDOW_S * fs)))
            scale = STRENGTH_WINDOW_S * fs / n if scaled else 1.0
            for i in range(0, x.size - n + 1, n):
                X = window_spectrum(x[i:i + n], prewhiten)
                row = []
                for group in bands:
                    ses, df = band_ses(X, n, fs, group, f_top)
                    row.append(normalise(ses)[:, int(round(hz / df))])
                heights.append(np.concatenate(row))
        out.append(1.0 + scale * (np.mean(heights, axis=0) - 1.0))
    return np.array(out)


def line_strength(pieces: list[np.ndarray], fs: float, hz: float, f_top: float, scaled: bool = True) -> float:
    """The line's height at ``hz`` over the floor where it stands highest (:func:`line_heights`)."""
    return float(line_heights(pieces, fs, hz, f_top, scaled).max())


def modulation_depth(pieces: list[np.ndarray], fs: float, hz: float, f_top: float,
                     target: float = LINE_STRENGTH, t0s: list[float] | None = None) -> tuple[float, float]:
    """(depth, measured height) for which the line at ``hz`` stands ``target`` × the floor
    (:func:`line_strength`; the pieces' clocks ``t0s`` as in :func:`modulated`): bisection of log depth
    over [1e-4, 1] until the height is within :data:`STRENGTH_TOLERANCE` of ``target``."""
    t0s = t0s or [0.0] * len(pieces)
    lo, hi = np.log(1e-4), 0.0
    depth, strength = 1.0, 0.0
    for _ in range(30):
        depth = float(np.exp(0.5 * (lo + hi)))
        strength = line_strength([modulated(x, fs, hz, depth, t0) for x, t0 in zip(pieces, t0s)], fs, hz, f_top)
        if abs(strength - target) <= STRENGTH_TOLERANCE:
            break
        lo, hi = (np.log(depth), hi) if strength < target else (lo, np.log(depth))
    return depth, strength


def envelope_top(bearing: Bearing, fr: float) -> float:
    """The highest envelope frequency (Hz) the decision tests at shaft rate ``fr``: the bands it chooses
    among lie above it."""
    return highest_term(comb_terms(bearing), 1 + SLIP_ABOVE) * fr
