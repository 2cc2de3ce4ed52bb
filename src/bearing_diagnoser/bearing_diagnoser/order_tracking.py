"""Order tracking: vibration as a function of shaft angle, and the shaft speed from the vibration.

Building blocks (pure numpy/scipy). The decision resamples its stream to shaft angle as it arrives
(:mod:`.spectral.angle_domain`, the same interpolation and anti-aliasing as :func:`resample_to_angle`);
offline, a recording without a measured speed may take :func:`track_speed`'s
(:func:`.recording_diagnosis.diagnose_recording`'s ``track_speed``, ``bearing-diagnose --track-speed``):

* :func:`resample_to_angle` — computed order tracking: a window resampled to equal
  increments of shaft angle, the angle taken from a speed per sample or tachometer pulses
  (:mod:`bearing_common.shaft_angle`) or from :func:`track_speed`. The instants at which
  the shaft reaches each angle are found by linear interpolation of the per-sample angle
  (error ≤ |dω/dt|/(8 fs²ω) s: 8e-12 s on a 900→1800 rev/min run-up at 12 kHz), and the
  signal is sampled there by band-limited interpolation
  (:func:`bearing_recordings.resampling.sample_at`) with an anti-aliasing cutoff that
  follows the local output rate, R/2.2 for R = ω/Δφ output samples per second: orders up
  to 0.36·N of N samples per revolution are clean (error ≤ 2e-5 of their amplitude).
* :func:`order_spectrum` — amplitude spectrum over orders (multiples of the shaft speed).
* :func:`track_speed` — tacho-less instantaneous speed from the vibration itself, inside a
  given speed range, by following the shaft's harmonic comb (orders 1..K):

  1. *coarse*: a short-time spectrum (frames of ≥ 1 s and ≥ 12 revolutions, hop 0.25 s),
     each bin's power over the running median of its frame (a line stands out, the
     resonances' colouring does not), scored log(max(ratio / 3, 1)) (only lines count);
     the comb score of a candidate speed is the sum over k of the score at k× it,
     weighted 1/k (a comb must carry the low orders, where the shaft's lines are: the
     harmonics of a fault comb, e.g. BPFO's at 4× and 8× of a wrong speed, must not pass
     for the shaft), on a grid of 0.1 % steps; the track is the best path through the
     frames with at most ``max_rate`` relative change per second (dynamic programming),
     so one frame where another line family wins cannot make it jump;
  2. *refinement*, twice: the signal resampled to shaft angle along the current track
     (:func:`resample_to_angle`: where the track is right, the shaft lines stand still at
     whole orders however the speed changes) and, per frame of ≥ 2 s (the lines no longer
     smear, so frames can be long and their bins fine), the same comb over orders k·c for a
     correction c in steps of 0.02 %, followed through the frames the same way with c
     changing by at most 2·``max_rate`` per second (the truth and the track may each change
     at ``max_rate``); the new track is c times the track's mean speed over each frame (its
     angle over its duration), at the frame's centre, linear between centres (the coarse
     track's hop-to-hop jitter goes; ``linear=False``: the track times c, keeping its changes
     from hop to hop, a constant speed's wander) and, beyond the first and last centre, along
     the line fitted to the centres within one frame of that end (frames also end at the last
     sample). The first round searches the whole told range about the track, the second
     ±1 %: the coarse frames' 1 Hz bins, a strong line's skirt and the ±1 bin tolerance merge
     line families 5-10 % apart, which the angle domain separates (HIT-SM IR8_900 warped along
     a ramp: the huge 1× line and the inner-race line made a family at 0.91× the shaft;
     Normal_900 along −20 and −40 %: a family at 1.1× it, whose 3rd and 6th harmonics are the
     mains' 50 and 100 Hz, which the warp made shaft-synchronous; both tracked 7-16 % off,
     within 0.75 % since).

  3. *evidence*: in each frame of the last refinement, the chosen comb's line at each order k
     (the largest of ±1 bin about k·c) over its running median. A frame **shows the shaft**
     when the orders whose line exceeds :data:`LINE_EVIDENCE` (11.6×: noise exceeds it in one of
     3 bins with probability 1e-3) have no common factor (:func:`shows_the_shaft`): the 1× line
     alone will do, 3× and 4× will, 4× and 8× (a foreign comb at 4× the track) will not. A track
     is refused when more than one frame's length lies between frames that show the shaft (the
     first and last frames' centres counting as ends): some stretch of it then lies in no frame
     with evidence for it (:meth:`SpeedTrack.unsupported` says why; ``bearing-diagnose
     --track-speed`` then does not diagnose the record). The path through frames without a shaft
     line follows noise and drifts through the told range, or follows another line family.

  Measured accuracy (``python -m benchmarks.speed_tracking``): on a synthetic harmonic
  series along a ±20 % ramp 0.04 % RMS; on the warped development recordings see the
  README. It needs shaft lines: on the simulator's noisy and outer-race +20 % ramps, where
  the only shaft-synchronous excitation (a tiny unbalance) makes no line above the sensor
  noise or the impacts' floor, the path followed single noise bins at scattered orders
  (one per frame, no family), drifting to the told range's edges, 22-23 % off; 0-6 % of its
  2 s frames show the shaft there, none over 7.5 s of the record, and the track is refused
  (the noise-free healthy ramp, whose 1× line stands 10⁴-10⁵× over its floor: every frame,
  0.42 % off, used). On every warped development ramp within 1 % the frames that show the
  shaft lie at most 1.54 s apart (none refused). A track that leaves the shaft halfway (a weak
  1× line under an outer-race comb: the second half at 0.90× the shaft, 10 % off) is refused
  though half its frames show the shaft (the simulator gives its tachometer).

Angles in rad, speeds in rad/s, times in s; orders are multiples of the shaft speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from bearing_common.shaft_angle import RPM_TO_RAD_S, angle_from_speed
from bearing_recordings.resampling import sample_at

#: Output instants per revolution of the angle-domain signal the tracker refines on (orders < 23 clean).
TRACK_SAMPLES_PER_REV = 64

#: Cutoff of the anti-aliasing low-pass relative to the output rate (module docstring).
ANTI_ALIAS = 1.0 / 2.2

#: The comb counts a bin's power only above this multiple of the running median, in log units above it
#: (noise alone, exponential, exceeds it in 12.5 % of the bins and then mostly by little).
LINE_LEVEL = 3.0

#: Shortest coarse frame, in revolutions at the lowest speed of the range (bins ≤ 1/12 of the 1× rate).
COARSE_MIN_REVS = 12

#: A shaft line counts as evidence for the track above this multiple of its floor: noise exceeds it in one of
#: the 3 bins searched with probability 3·2^−level = 1e-3 (a noise bin's power is exponential, its median
#: ln 2 times its mean, so it exceeds r times the median with probability 2^−r).
LINE_EVIDENCE = math.log2(3.0 / 1e-3)


@dataclass
class AngleSignal:
    """A signal sampled at equal increments of shaft angle.

    samples : ndarray (m,) — the values; angles : ndarray (m,) — the shaft angle of each (rad,
    on the input's angle axis); times : ndarray (m,) — when the shaft reached it (s);
    samples_per_rev : int.
    """

    samples: np.ndarray
    angles: np.ndarray
    times: np.ndarray
    samples_per_rev: int


def resample_to_angle(x, sample_rate: float, angle, samples_per_rev: int = 64) -> AngleSignal:
    """``x`` (sampled at ``sample_rate`` Hz) at the instants where the shaft angle ``angle``
    (rad per sample, increasing) reaches whole multiples of 2π / ``samples_per_rev``.

    Anti-aliased: each value is band-limited to min(fs/2, R/2.2) Hz for the local output
    rate R = ω / Δφ (module docstring). Raises ValueError unless the angle increases strictly
    over at least one increment.
    """
    x = np.asarray(x, dtype=float)
    phi = np.asarray(angle, dtype=float)
    if x.ndim != 1 or phi.shape != x.shape:
        raise ValueError("x and angle must be 1-D arrays of the same length")
    if np.any(np.diff(phi) <= 0.0):
        raise ValueError("the shaft angle must increase strictly (positive speed)")
    n = int(samples_per_rev)
    if n < 4:
        raise ValueError(f"samples_per_rev must be >= 4, got {samples_per_rev!r}")
    fs = float(sample_rate)
    step = 2.0 * math.pi / n
    k = np.arange(math.ceil(phi[0] / step), math.floor(phi[-1] / step) + 1)
    if k.size < 2:
        raise ValueError("the window turns less than one angle increment")
    angles = k * step
    t_in = np.arange(x.size) / fs
    times = np.interp(angles, phi, t_in)
    speed = np.interp(times, t_in, np.gradient(phi) * fs)  # rad/s
    cutoff = np.minimum(0.5 * fs, ANTI_ALIAS * speed / step)
    return AngleSignal(sample_at(x, fs, times, cutoff), angles, times, n)


def order_spectrum(samples, samples_per_rev: int):
    """Amplitude spectrum over orders of an angle-domain signal (Hann window, amplitude-corrected:
    a sinusoid of amplitude A at a bin's order reads A). Returns (orders, amplitude)."""
    y = np.asarray(samples, dtype=float)
    w = np.hanning(y.size)
    spec = np.abs(np.fft.rfft((y - y.mean()) * w)) * 2.0 / w.sum()
    return np.fft.rfftfreq(y.size, 1.0 / samples_per_rev), spec


@dataclass
class SpeedTrack:
    """Shaft speed estimated from the vibration, per input sample (rad/s), and the evidence for it.

    ``evidence_times`` (s): the centres of the last refinement's frames, ``evidence_frame`` (s) their
    length; ``line_ratio`` (frames, K): in each, the power at shaft order k of the track (the corrected
    comb's k·c, the largest of ±1 bin) over its running median. Empty when the track was not refined
    (``refine=0``): no evidence.
    """

    speed: np.ndarray
    sample_rate: float
    evidence_times: np.ndarray = field(default_factory=lambda: np.empty(0))
    evidence_frame: float = 0.0
    line_ratio: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))

    @property
    def rpm(self) -> np.ndarray:
        """rev/min per sample."""
        return self.speed / RPM_TO_RAD_S

    def angle(self) -> np.ndarray:
        """Shaft angle per sample (rad, 0 at the first)."""
        return angle_from_speed(self.speed, self.sample_rate)

    def evidenced(self) -> float:
        """The share of the refinement's frames that show the shaft (:func:`shows_the_shaft`); 0 unrefined."""
        return float(np.mean(shows_the_shaft(self.line_ratio))) if self.line_ratio.size else 0.0

    def longest_unsupported(self) -> float:
        """The longest stretch (s) between frames that show the shaft, the first and last frames' centres
        counting as ends; inf when none does."""
        shown = self.evidence_times[shows_the_shaft(self.line_ratio)] if self.line_ratio.size else []
        if len(shown) == 0:
            return math.inf
        return float(np.max(np.diff(np.r_[self.evidence_times[0], shown, self.evidence_times[-1]])))

    def unsupported(self) -> str | None:
        """Why the track must not be used (one line), or None when no stretch longer than one frame lies
        between frames that show the shaft (module docstring)."""
        gap = self.longest_unsupported()
        if gap <= self.evidence_frame:
            return None
        shown = ("none of the tracker's" if math.isinf(gap) else
                 f"{100 * self.evidenced():.0f} % of the tracker's")
        where = "" if math.isinf(gap) else f", none over {gap:.1f} s of the record"
        return (f"no shaft comb to track the speed on: {shown} {self.evidence_frame:.1f} s frames show one (lines at "
                f"shaft orders without a common factor, each over {LINE_EVIDENCE:.1f}x its floor){where}; measure "
                "the speed (a tachometer or a speed channel)")


def shows_the_shaft(line_ratio: np.ndarray, level: float | None = None) -> np.ndarray:
    """Per frame (row of ``line_ratio``, orders 1..K): whether the orders whose line exceeds ``level`` (default
    :data:`LINE_EVIDENCE`) have no common factor (1 alone will do). A line family at m× the track (m ≥ 2: an
    outer-race comb at 3.58× the shaft taken at 0.90× it, m = 4) puts lines only at multiples of m; noise
    rarely exceeds the level (module docstring)."""
    k = np.arange(1, line_ratio.shape[1] + 1)
    lines = np.where(line_ratio > (LINE_EVIDENCE if level is None else level), k, 0)
    return np.gcd.reduce(lines, axis=1) == 1


def track_speed(x, sample_rate: float, rpm_lo: float, rpm_hi: float, *, harmonics: int = 8,
                frame: float = 1.0, hop: float = 0.25, max_rate: float = 0.15,
                refine: int = 2, linear: bool = True) -> SpeedTrack:
    """Tacho-less instantaneous shaft speed of ``x`` between ``rpm_lo`` and ``rpm_hi`` rev/min
    (module docstring).

    Parameters
    ----------
    x : ndarray (n,), the vibration; sample_rate : Hz.
    rpm_lo, rpm_hi : the range the speed stays in (e.g. the drive's range, or a nameplate
        speed ± its tolerance plus the expected change); narrower than an octave, so that the
        comb cannot settle on half or twice the speed.
    harmonics : shaft orders 1..K of the comb. frame, hop : coarse short-time spectrum (s).
    max_rate : largest relative speed change per second followed (1/s): 0.15 covers a
        900→1800 rev/min run-up in 10 s.
    refine : rounds of refinement in the angle domain (0: the coarse track only).
    linear : the refined track is linear between the refinement frames' centres (a speed that
        changes smoothly: the coarse track's hop-to-hop jitter goes); False keeps the coarse
        track's changes from hop to hop, corrected by the refinement (a constant speed's own
        wander, ±0.15 % within tenths of a second on CWRU, which the coarse frames resolve).

    Raises ValueError on a bad range or a signal too short for two coarse frames.
    """
    x = np.asarray(x, dtype=float)
    fs = float(sample_rate)
    if not (0.0 < rpm_lo < rpm_hi and math.isfinite(rpm_hi)):
        raise ValueError(f"need 0 < rpm_lo < rpm_hi, got {rpm_lo!r}, {rpm_hi!r}")
    frame = max(frame, COARSE_MIN_REVS * 60.0 / rpm_lo)
    n_frame = int(round(frame * fs))
    if x.size < 2 * n_frame:
        raise ValueError(f"need at least {2 * frame:g} s of signal to track the speed, got {x.size / fs:.3g} s")
    n_hop = max(1, int(round(hop * fs)))
    starts = _frame_starts(x.size, n_frame, n_hop)
    f_lo, f_hi = rpm_lo / 60.0, rpm_hi / 60.0
    df = fs / n_frame
    score = _line_score(_line_ratio(_frame_power(x, starts, n_frame), int((harmonics + 1) * f_hi / df) + 3,
                                    int(f_lo / df)))
    score = ndimage.maximum_filter1d(score, 3, axis=1)  # lines smear while the speed changes: ±1 bin
    grid = f_lo * np.exp(np.arange(int(math.log(f_hi / f_lo) / _GRID_STEP) + 1) * _GRID_STEP)
    path = _best_path(_comb(score, grid / df, harmonics), max(1, int(math.ceil(max_rate * hop / _GRID_STEP))))
    t = np.arange(x.size) / fs
    speed = 2.0 * math.pi * np.interp(t, (starts + 0.5 * n_frame) / fs, grid[path])
    bounds = (2.0 * math.pi * f_lo, 2.0 * math.pi * f_hi)
    track = SpeedTrack(speed, fs)
    for round_ in range(max(0, int(refine))):
        span = _SCALE_RANGES[min(round_, len(_SCALE_RANGES) - 1)]
        if span is None:  # the whole told range about the track
            span = max(bounds[1] / float(track.speed.min()), float(track.speed.max()) / bounds[0]) - 1.0
        track = SpeedTrack(*_refine(x, fs, track.speed, harmonics, max_rate, span, bounds, linear))
    return track


#: Relative spacing of the candidate speeds of the coarse comb search.
_GRID_STEP = 0.001

#: Refinement: frame (s) and its least number of revolutions, hops per frame, zero padding.
_REFINE_FRAME, _REFINE_REVS, _REFINE_OVERLAP, _REFINE_PAD = 2.0, 16, 4, 4

#: Relative step of the refinement's correction, and its range (±) per round (None: the whole told range).
_SCALE_STEP, _SCALE_RANGES = 2e-4, (None, 0.01)


def _frame_starts(n: int, n_frame: int, hop: int) -> np.ndarray:
    """Starts of frames of ``n_frame`` samples every ``hop`` over ``n`` samples, the last one ending at the last
    sample (a frame centre, where the track is measured, as near the end as a frame goes)."""
    starts = np.arange(0, n - n_frame + 1, hop)
    return starts if starts[-1] == n - n_frame else np.r_[starts, n - n_frame]


def _frame_power(x: np.ndarray, starts: np.ndarray, n: int, pad: int = 1) -> np.ndarray:
    """Power spectra (frames, bins) of the Hann-windowed, mean-removed frames x[s:s+n], zero-padded to pad·n."""
    frames = np.lib.stride_tricks.sliding_window_view(x, n)[starts]
    return np.abs(np.fft.rfft((frames - frames.mean(axis=1, keepdims=True)) * np.hanning(n), n=pad * n,
                              axis=1)) ** 2


def _line_ratio(power: np.ndarray, n_bins: int, median_bins: int) -> np.ndarray:
    """P / running median of P (over ``median_bins``, at least 9) of the first ``n_bins`` bins of each frame."""
    power = power[:, :min(power.shape[1], n_bins)]
    background = ndimage.median_filter(power, size=(1, max(9, median_bins) | 1), mode="nearest")
    return power / np.maximum(background, 1e-300)


def _line_score(ratio: np.ndarray) -> np.ndarray:
    """log(max(ratio / LINE_LEVEL, 1)): only lines count."""
    return np.log(np.maximum(ratio / LINE_LEVEL, 1.0))


def _comb(score: np.ndarray, rates: np.ndarray, harmonics: int) -> np.ndarray:
    """Comb score (frames, candidates): Σ_k score at k·rate (in bins, linearly interpolated) / k."""
    pos = np.minimum(np.arange(1, harmonics + 1)[:, None] * rates[None, :], score.shape[1] - 1.001)
    i0 = pos.astype(int)
    w = pos - i0
    at = score[:, i0] * (1.0 - w) + score[:, i0 + 1] * w  # (frames, K, candidates)
    return (at / np.arange(1, harmonics + 1)[:, None]).sum(axis=1)


def _best_path(score: np.ndarray, reach: int) -> np.ndarray:
    """Indices (one per row) maximising the summed score with steps of at most ``reach`` columns."""
    total = np.empty_like(score)
    total[0] = score[0]
    for i in range(1, score.shape[0]):  # one vectorised step per frame (a few per second of signal)
        total[i] = score[i] + ndimage.maximum_filter1d(total[i - 1], 2 * reach + 1, mode="constant", cval=-np.inf)
    path = np.empty(score.shape[0], dtype=int)
    path[-1] = int(np.argmax(total[-1]))
    for i in range(score.shape[0] - 2, -1, -1):
        lo, hi = max(0, path[i + 1] - reach), min(score.shape[1], path[i + 1] + reach + 1)
        path[i] = lo + int(np.argmax(total[i, lo:hi]))
    return path


def _refine(x, fs, speed, harmonics, max_rate, span, bounds, linear):
    """One refinement round (module docstring): the correction c within ±``span`` that puts the most
    line power at orders k·c in the angle-domain frames, the corrected speed kept within ``bounds``
    (rad/s); the new track is c times the frames' mean speeds, linear between them (``linear``), or
    the per-sample speed times c interpolated. Returns :class:`SpeedTrack`'s fields: the new track, ``fs``,
    the frames' centres and length (s) and the chosen comb's lines over their floor (frames, K)."""
    a = resample_to_angle(x, fs, angle_from_speed(speed, fs), TRACK_SAMPLES_PER_REV)
    rev_s = 2.0 * math.pi / float(np.mean(speed))
    revs = min(max(_REFINE_REVS, int(round(_REFINE_FRAME / rev_s))), a.samples.size // TRACK_SAMPLES_PER_REV)
    n_frame = revs * TRACK_SAMPLES_PER_REV
    hop = max(1, n_frame // _REFINE_OVERLAP)
    starts = _frame_starts(a.samples.size, n_frame, hop)
    d_order = TRACK_SAMPLES_PER_REV / (_REFINE_PAD * n_frame)  # orders per bin
    power = _frame_power(a.samples, starts, n_frame, _REFINE_PAD)
    scales = 1.0 + np.arange(-min(span, 0.9), span + 0.5 * _SCALE_STEP, _SCALE_STEP)
    ratio = _line_ratio(power, int((harmonics * scales[-1] + 1.5) / d_order), int(1.0 / d_order))
    score = _line_score(ratio)
    # c = truth / track changes at most as fast as both together: 2·max_rate
    reach = max(1, int(math.ceil(2.0 * max_rate * hop / TRACK_SAMPLES_PER_REV * rev_s / _SCALE_STEP)))
    t0, t1 = a.times[starts], a.times[starts + n_frame - 1]
    mean_speed = 2.0 * math.pi * (n_frame - 1) / TRACK_SAMPLES_PER_REV / (t1 - t0)  # the track's, per frame
    candidates = mean_speed[:, None] * scales[None, :]
    comb = np.where((candidates >= bounds[0]) & (candidates <= bounds[1]), _comb(score, scales / d_order, harmonics),
                    -np.inf)
    c = scales[_best_path(comb, reach)]
    t, knots, frame_s = np.arange(x.size) / fs, 0.5 * (t0 + t1), float(np.median(t1 - t0))
    lines = _comb_line(ratio, c / d_order, harmonics)
    if linear:
        return _piecewise_linear(t, knots, c * mean_speed, frame_s), fs, knots, frame_s, lines
    return speed * _piecewise_linear(t, knots, c, frame_s), fs, knots, frame_s, lines


def _comb_line(ratio: np.ndarray, rates: np.ndarray, harmonics: int) -> np.ndarray:
    """(frames, K): per frame (row of ``ratio``) the largest ratio within ±1 bin of k·rate (bins), k = 1..K."""
    pos = np.rint(np.arange(1, harmonics + 1)[None, :] * rates[:, None]).astype(int)  # (frames, K)
    near = np.clip(pos[:, :, None] + np.arange(-1, 2), 0, ratio.shape[1] - 1)  # (frames, K, 3)
    return np.take_along_axis(ratio, near.reshape(ratio.shape[0], -1), axis=1).reshape(near.shape).max(axis=2)


def _piecewise_linear(t: np.ndarray, knots: np.ndarray, values: np.ndarray, span: float) -> np.ndarray:
    """``values`` at ``knots`` interpolated linearly at ``t``; beyond the first and last knot, extended along
    the straight line fitted (least squares) to the knots within ``span`` of that end (a ramp goes on to the
    record's ends; one knot's noise must not set the slope)."""
    out = np.interp(t, knots, values)
    for end, near in ((t < knots[0], knots <= knots[0] + span), (t > knots[-1], knots >= knots[-1] - span)):
        if np.any(end):
            line = np.polyfit(knots[near], values[near], 1) if np.count_nonzero(near) > 1 else values[near][:1]
            out[end] = np.polyval(line, t[end])
    return out
