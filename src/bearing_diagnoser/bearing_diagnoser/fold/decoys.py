"""Bearing line frequencies and the "decoy" frequencies used for CFAR normalisation.

The characteristic frequencies come from ``bearing_common.bearings`` (thesis
section 2.2, eqs. 2.51-2.54); this module only lists them and picks nearby
frequencies where no bearing or shaft line lies.  The periodicity statistic at such a
decoy frequency measures what the same stream, in the same window, gives "by chance";
dividing by it makes the statistic scale-free (constant false-alarm rate, CFAR).

All frequencies in Hz.
"""

from __future__ import annotations

import numpy as np

from bearing_common.bearings import Bearing, shaft_hz


def bearing_lines(rpm: float, geometry: Bearing,
                  max_hz: float | None = None, shaft: bool = True,
                  ball_cage: bool = True) -> np.ndarray:
    """Every frequency (Hz) a healthy or faulty bearing may put a line at.

    Defect family: harmonics 1..10 of BPFO (eq. 2.53) and BPFI (eq. 2.54), 1..5 of BSF
    and 2·BSF (eq. 2.52), 1..3 of FTF (cage, eq. 2.51); the 1/2 and 1/3 sub-harmonics of
    BPFO, BPFI and 2·BSF (folding at a sub-multiple keeps part of the line's energy); the
    IR modulation sidebands BPFI ± 1, 2 × shaft.  With ``shaft``, also
    harmonics 1..30 of the shaft; without ``ball_cage``, no BSF/FTF lines.  Sorted, positive, below ``max_hz`` if given.
    """
    fr = shaft_hz(rpm)
    g = geometry
    lines = [k * fr for k in range(1, 31)] if shaft else []
    if ball_cage:
        lines += [k * g.ftf(fr) for k in range(1, 4)]
        lines += [k * f for f in (g.bsf(fr), 2 * g.bsf(fr)) for k in range(1, 6)]
        lines += [2 * g.bsf(fr) / m for m in (2, 3)]
    lines += [k * f for f in (g.bpfo(fr), g.bpfi(fr)) for k in range(1, 11)]
    lines += [f / m for f in (g.bpfo(fr), g.bpfi(fr)) for m in (2, 3)]
    bpfi = g.bpfi(fr)
    lines += [bpfi + s * m * fr for s in (-1, 1) for m in (1, 2)]
    arr = np.unique(np.asarray(lines, dtype=float))
    arr = arr[arr > 0]
    if max_hz is not None:
        arr = arr[arr <= max_hz]
    return arr


def decoy_frequencies(fault_hz: float, rpm: float, geometry: Bearing, n_decoys: int = 6, window_s: float = 0.2,
                      search: float = 0.03, slip: float = 0.02,
                      span: tuple[float, float] = (0.3, 3.0)) -> np.ndarray:
    """Pick ``n_decoys`` frequencies near ``fault_hz`` clear of every bearing line.

    Parameters
    ----------
    fault_hz : float
        The hypothesis' fault frequency (BPFO or BPFI), Hz.
    rpm : float
        Shaft speed (rev/min) used to place the lines to avoid.
    geometry : Bearing
        The monitored bearing, whose lines are avoided.
    n_decoys : int
        How many decoys to return.
    window_s : float
        Analysis window (s).  Folding a window of length W at frequency f keeps a line L
        concentrated while |f − L| ≲ 1/(2W), so the clearance from a line L is
        search + slip + 1/(2·L·W) relative to L (the ±search period search happens at
        the decoy and the line itself may be off by slip).
    slip : float
        Allowance for slip and speed error of the line itself (default 2 %).
    search : float
        Relative period search of the statistic (± fraction).
    span : (lo, hi)
        Decoys are searched in ``[lo, hi] · fault_hz``.

    Race-defect lines (BPFO, BPFI, harmonics, sub-harmonics, IR sidebands) are always
    avoided; shaft harmonics, then ball and cage lines, are dropped from the list only
    when too few decoys remain (short windows: with 0.05 s the shaft harmonics, 18 % of
    BPFI apart, leave no room; the simulator has no ball defect and no shaft lines in its
    envelope other than the IR sidebands, which stay avoided).  Decoys are taken nearest to
    ``fault_hz`` first (same noise colour), at least 3 % apart.  Returns an array of shape (n_decoys,), Hz, sorted.
    """
    cand = fault_hz * np.geomspace(span[0], span[1], 1201)
    for with_shaft, with_ball in ((True, True), (False, True), (False, False)):
        lines = bearing_lines(rpm, geometry, max_hz=fault_hz * span[1] * 1.5, shaft=with_shaft,
                              ball_cage=with_ball)
        ok = np.ones(cand.size, bool)
        for line in lines:
            clear = search + slip + 0.5 / (line * window_s)
            ok &= np.abs(cand / line - 1.0) > clear
        good = cand[ok]
        chosen: list[float] = []
        for f in good[np.argsort(np.abs(np.log(good / fault_hz)))]:
            if all(abs(f / c - 1.0) > 0.03 for c in chosen):
                chosen.append(float(f))
            if len(chosen) == n_decoys:
                return np.sort(np.asarray(chosen))
    raise ValueError(f"only {len(chosen)} decoys clear of bearing lines near {fault_hz:.1f} Hz "
                     f"with {window_s} s windows")
