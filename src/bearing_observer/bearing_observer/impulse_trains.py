"""Fault impulse trains in time units: thesis eqs. 2.55 (outer race) and 2.58 (inner race).

One definition, used by identification and by the observers alike:

* Impact times. A defect of impact frequency ``f`` (Hz) with fault phase ``phi`` (rad)
  strikes at the times ``t_k = (k - phi / (2 pi)) / f`` (s), k integer, i.e. where the
  fault cycle coordinate ``f t + phi / (2 pi)`` is an integer.
* Impact weights. Outer race (eq. 2.55): every impact has weight 1 (the amplitude ``a``
  of the thesis is carried by the model's input gain). Inner race (eq. 2.58): the weight is
  ``cos(2 pi f_s t_k + theta) + c`` with shaft frequency ``f_s`` (Hz), shaft phase
  ``theta`` (rad) and offset ``c``. The thesis requires ``c >= 1`` (non-negative weights);
  the project allows any ``c`` because in the simulator the sign of the IR impacts in y
  follows the shaft angle (``c`` near 0), see ``shared/model-notes.md``.
* Pulse shape and sampling. Each impact is a rectangular pulse of unit height and width
  ``w`` seconds (default: one sample period) starting at ``t_k``. Sample ``n`` (time
  ``t_n = t0 + n / fs``) holds the mean of the continuous train over ``[t_n, t_n + 1/fs)``.
  A pulse therefore keeps its sub-sample position (it splits over two samples) and
  its area ``w`` does not depend on the sample rate. Appendix D of the thesis builds
  its trains from step pairs at fixed sample offsets; this definition replaces that.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TWO_PI = 2.0 * math.pi


def impact_times(t_start: float, t_end: float, fault_frequency: float, phase: float = 0.0):
    """Impact times ``t_k`` (s) in ``[t_start, t_end)`` and their indices ``k``.

    Parameters
    ----------
    t_start, t_end : float
        Time interval (s).
    fault_frequency : float
        Impact frequency ``f`` (Hz), > 0 (BPFO or BPFI, eqs. 2.53-2.54).
    phase : float
        Fault phase ``phi`` (rad): impacts where ``f t + phi/(2 pi)`` is an integer.

    Returns
    -------
    t_k : ndarray, shape (K,)
        Impact times (s), increasing.
    k : ndarray of int64, shape (K,)
        Impact indices.
    """
    if not fault_frequency > 0.0:
        raise ValueError(f"fault_frequency must be > 0 Hz, got {fault_frequency!r}")
    c = phase / TWO_PI
    # t_k = (k - c) / f >= t_start  <=>  k >= f t_start + c
    k0 = math.ceil(t_start * fault_frequency + c - 1e-9)
    k1 = math.ceil(t_end * fault_frequency + c + 1e-9)
    k = np.arange(k0, max(k0, k1), dtype=np.int64)
    t_k = (k - c) / fault_frequency
    keep = (t_k >= t_start - 1e-15) & (t_k < t_end)
    return t_k[keep], k[keep]


def _render(n: int, sample_rate: float, start_time: float, t_k: np.ndarray,
            weights: np.ndarray, pulse_width: float, start_index: int = 0) -> np.ndarray:
    """Sample unit-height rectangular pulses of width ``pulse_width`` (s) at ``t_k``.

    ``weights`` has shape (K,) or (m, K) (m trains at the same impact times); the result
    has shape (n,) or (m, n).
    """
    weights = np.asarray(weights, dtype=float)
    multi = weights.ndim == 2
    w2 = weights if multi else weights[None, :]
    out = np.zeros((w2.shape[0], n))
    if t_k.size == 0 or n == 0:
        return out if multi else out[0]
    # Position of pulse start/end in samples relative to the first sample. Subtracting the
    # integer start_index is exact, so consecutive blocks of one grid get bit-identical
    # positions whatever the block boundaries.
    a = (t_k - start_time) * sample_rate - start_index
    b = a + pulse_width * sample_rate
    span = int(math.ceil(pulse_width * sample_rate)) + 1
    add_pulses(out, a, b, np.ascontiguousarray(w2), span)
    return out if multi else out[0]


def _check(n, sample_rate, pulse_width):
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    if not sample_rate > 0.0:
        raise ValueError(f"sample_rate must be > 0 Hz, got {sample_rate!r}")
    width = 1.0 / sample_rate if pulse_width is None else float(pulse_width)
    if not width > 0.0:
        raise ValueError(f"pulse_width must be > 0 s, got {pulse_width!r}")
    return width


def impulse_train(n: int, sample_rate: float, fault_frequency: float, phase: float = 0.0,
                  start_time: float = 0.0, shaft_frequency: float | None = None,
                  shaft_phase: float = 0.0, offset: float = 1.0,
                  pulse_width: float | None = None, start_index: int = 0) -> np.ndarray:
    """Sampled fault impulse train, eq. 2.55 (plain) or eq. 2.58 (shaft-modulated).

    Parameters
    ----------
    n : int
        Number of samples; sample ``i`` is at ``start_time + (start_index + i) / sample_rate``
        (s).
    sample_rate : float
        Sample rate ``fs`` (Hz).
    fault_frequency : float
        Impact frequency (Hz): BPFO for the outer race, BPFI for the inner race.
    phase : float
        Fault phase ``phi`` (rad), see the module docstring.
    start_time : float
        Time of the first sample (s).
    shaft_frequency : float or None
        Shaft frequency ``f_s`` (Hz). None: plain train of eq. 2.55 (unit weights).
        Otherwise the weights are ``cos(2 pi f_s t_k + shaft_phase) + offset`` (eq. 2.58).
    shaft_phase : float
        Shaft phase ``theta`` (rad) of eq. 2.58.
    offset : float
        Offset ``c`` of eq. 2.58 (dimensionless).
    pulse_width : float or None
        Pulse width ``w`` (s); default one sample period.
    start_index : int
        Index of the first sample on the grid that starts at ``start_time``; blocks of one
        stream rendered with increasing ``start_index`` concatenate bit-exactly.

    Returns
    -------
    ndarray, shape (n,)
        Sample means of the unit-height pulse train (dimensionless).
    """
    width = _check(n, sample_rate, pulse_width)
    t_k = _impacts_for(n, sample_rate, fault_frequency, phase, start_time, start_index, width)
    if shaft_frequency is None:
        weights = np.ones_like(t_k)
    else:
        weights = np.cos(TWO_PI * shaft_frequency * t_k + shaft_phase) + offset
    return _render(n, sample_rate, start_time, t_k, weights, width, start_index)


def _impacts_for(n, sample_rate, fault_frequency, phase, start_time, start_index, width):
    t_first = start_time + start_index / sample_rate
    t_end = t_first + (n + 1) / sample_rate
    return impact_times(t_first - width - 1.0 / sample_rate, t_end, fault_frequency, phase)[0]


def modulated_train_components(n: int, sample_rate: float, fault_frequency: float,
                               phase: float = 0.0, start_time: float = 0.0,
                               shaft_frequency: float = 0.0, shaft_phase: float = 0.0,
                               pulse_width: float | None = None,
                               start_index: int = 0) -> np.ndarray:
    """The three trains whose combination gives any eq. 2.58 train.

    ``impulse_train(..., shaft_frequency=fs_, shaft_phase=th, offset=c)`` equals
    ``cos(th) * U[0] - sin(th) * U[1] + c * U[2]`` with ``U`` returned here (weights
    ``cos(2 pi f_s t_k + shaft_phase)``, ``sin(2 pi f_s t_k + shaft_phase)`` and 1). Used for
    least-squares estimation of the unknown shaft phase and offset: the train is linear in
    ``(a cos th, a sin th, a c)``.

    Returns
    -------
    ndarray, shape (3, n)
    """
    width = _check(n, sample_rate, pulse_width)
    t_k = _impacts_for(n, sample_rate, fault_frequency, phase, start_time, start_index, width)
    ang = TWO_PI * shaft_frequency * t_k + shaft_phase
    weights = np.stack([np.cos(ang), np.sin(ang), np.ones_like(t_k)])
    return _render(n, sample_rate, start_time, t_k, weights, width, start_index)


# compiled inner loop (numba; strict IEEE arithmetic, no fastmath)
@njit(cache=True)
def add_pulses(out: np.ndarray, a: np.ndarray, b: np.ndarray, weights: np.ndarray,
               span: int) -> None:
    """Add unit-height pulses over ``[a[k], b[k])`` (in samples) times ``weights[:, k]``.

    For pulse ``k`` and sample ``i = floor(a[k]) + s``, ``s = 0..span``, the overlap of
    ``[i, i + 1)`` with ``[a[k], b[k])`` (fraction of a sample) times ``weights[j, k]`` is
    added to ``out[j, i]`` when ``0 <= i < n`` and the overlap is positive, in order of
    ``k`` then ``s`` (the order of ``np.bincount`` over the flattened (k, s) grid).

    Parameters
    ----------
    out : ndarray, shape (m, n)
        Trains to add to (dimensionless), modified in place.
    a, b : ndarray, shape (K,)
        Pulse start and end positions (samples from ``out[:, 0]``), ``b >= a``.
    weights : ndarray, shape (m, K)
        Pulse heights per train (dimensionless).
    span : int
        Samples after ``floor(a)`` that a pulse can reach, ``>= ceil(b - a)``.
    """
    n = out.shape[1]
    for k in range(a.size):
        first = np.int64(np.floor(a[k]))
        for s in range(span + 1):
            i = first + s
            fi = np.float64(i)
            ov = min(fi + 1.0, b[k]) - max(fi, a[k])
            if ov > 0.0 and 0 <= i < n:
                for j in range(out.shape[0]):
                    out[j, i] += ov * weights[j, k]
