"""The machine's own healthy reference (commissioning): what the decision learns of one machine before judging it.

Condition monitoring judges change against the machine's own baseline, taken when it is known
to be healthy (ISO 17359, ISO 13373-1); the thesis' residual is the same idea. The blind
decision's null hypothesis is Gaussian noise, while a real machine's envelope carries
stationary lines of its own (shaft harmonics, the supply, a coupling, a neighbour), which the
long horizon sharpens like a fault's. From a stated healthy period (at most
:data:`MAX_PERIOD_S` of it), :func:`learn_reference` learns:

* the speed relationship: the shaft rate the vibration shows (the raw 1x family,
  :func:`.shaft_speed.estimate_speed`, within the told tolerance, on each ``buffer_s`` of the
  period) over the told rate — a label or a nameplate off by a constant factor —, with its
  scatter over the buffers. Without a 1x family the told rate stands (ratio not measured);
  without a told rate the blind estimate must succeed;
* the envelope spectrum's stationary lines, per candidate demodulation band
  (:func:`.band_choice.live_bands`), at the decision's own window geometry (its window, its
  prewhitening, non-overlapping windows): a bin is a *line* when the mean of the K windows'
  spectra, normalised as the long horizon normalises it, exceeds what Gaussian noise exceeds
  with probability :data:`LINE_FALSE_ALARM` anywhere in the bins tested — a Bonferroni
  correction over every bin of every band up to the highest comb term, with the exact null law
  of a K-window mean and its normalising median (:func:`.significance.averaged_comb_log10p`);
  a line spans the Hann main lobe, so only local maxima count. Each line's frequency is then
  refined on the mean spectrum of the whole period in segments up to :data:`FINE_FACTOR` windows
  long (that many times finer bins); its level and scatter are the mean and standard deviation over
  the windows of its normalised bin (× the local median, ln 2-scaled: median 1 on noise);
* the raw spectrum's lines (the same test on the buffers' power spectra, up to the highest comb
  term or the 10th shaft harmonic): the shaft family and what else the machine shows.

How the decision uses it (``SpectralSettings.reference``): a told speed is corrected by the
learnt ratio (:meth:`MachineReference.correct_speed`), and the reference's envelope lines are
frequencies another explanation holds (:meth:`MachineReference.known_lines`): in every comb
test — the window's, the band choice's, the long horizon's — a comb term within 1.5 bins of one
does not count (:func:`.fault_combs.comb_evidence`'s ``exclude``). Lines follow the speed as
shaft orders while the shaft rate lies within the reference's range (the measured rates ±
:data:`SAME_SPEED`: the accuracy a tachometer states); a line at a multiple of a supply
frequency (50 or 60 Hz, within a bin) that is no shaft harmonic stays in Hz at any speed;
outside the range the other lines are not known (another operating point has lines of its own),
and the decision is blind to them.

Saved as JSON (:meth:`MachineReference.save`, :func:`load_reference`) with a format name and
version, so that a node restart or a later offline run reuses it instead of learning again.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.fft import next_fast_len

from bearing_common.bearings import Bearing, bearing_spec

from ..decision.sensor_health import check_window
from .band_choice import live_bands
from .envelope_spectrum import band_ses, hanning, normalise, window_spectrum
from .fault_combs import comb_terms, highest_term, rho_range
from .shaft_speed import N_HARMONICS, estimate_speed
from .significance import averaged_comb_log10p, averaged_median

#: Chance that Gaussian noise puts one line anywhere in the bins tested (all bands together).
LINE_FALSE_ALARM = 0.01

#: Seconds of the healthy period learnt from, at most: 180 windows of a 6205 at 1800 rpm, whose
#: levels' scatter is then known to about 5 %; more adds little and costs memory live.
MAX_PERIOD_S = 60.0

#: Non-overlapping windows the period must hold: a stationary line is one seen in more than one. (The
#: scatter of a level over K windows is itself uncertain by about 1/√(2(K − 1)): 70 % at K = 2, 27 % at
#: K = 8; a longer period, a better reference.)
MIN_WINDOWS = 2

#: Raw-spectrum buffers averaged at least (each ``buffer_s`` long, or shorter in a short period).
RAW_BUFFERS = 4

#: Fine resolution: the whole period's mean spectrum in segments this many windows long at most (and at
#: most half the period, so that two are averaged; at least two windows long, else no refinement).
FINE_FACTOR = 8

#: Relative half-range around the learnt shaft rates within which the machine is at the
#: reference's operating point: the accuracy a tachometer states (the decision's told_tolerance).
SAME_SPEED = 0.02

#: Supply frequencies (Hz) whose multiples do not follow the shaft speed.
SUPPLY_HZ = (50.0, 60.0)

#: Power ratio over its learnt level at which a known line has grown and counts as evidence again:
#: twice the amplitude (+6 dB), the alert step over a machine's baseline common in condition-monitoring
#: practice (ISO 13373-1 and ISO 17359 leave the levels to it). The learnt level is a mean over
#: windows; a healthy line's window-to-window scatter rarely doubles its amplitude.
GROWTH = 4.0

#: Offsets (bins) of the points that stand for a line's Hann main lobe in :meth:`MachineReference.known_lines`.
MAIN_LOBE_POINTS = np.array([-0.5, 0.0, 0.5])

FORMAT = "bearing_diagnoser machine reference"
VERSION = 1


class MachineReferenceError(ValueError):
    """A healthy period that cannot give a reference, or a reference file that cannot be read (one line)."""


@dataclass(frozen=True)
class ReferenceLine:
    """One stationary line of the healthy machine: frequency (Hz) at the reference's shaft rate, as a
    shaft order, its level (mean normalised bin: median 1 on noise) and scatter (standard deviation
    over the windows), and whether it follows the shaft speed (no: a supply multiple)."""

    hz: float
    order: float
    level: float
    scatter: float
    follows_speed: bool = True


@dataclass(frozen=True)
class BandLines:
    """The envelope lines of one demodulation band (Hz)."""

    band: tuple[float, float]
    lines: tuple[ReferenceLine, ...]


@dataclass(frozen=True)
class MachineReference:
    """What the decision knows of one healthy machine (module docstring).

    ``source``: where it was learnt (file and period, or node and period); ``bearing``: the bearing
    (:func:`bearing_common.bearings.bearing_spec`); ``sample_rate`` (Hz) and ``period_s`` (s) of
    the signal learnt from; ``told_hz``: the told shaft rate (Hz; None: none told); ``shaft_hz``:
    the shaft rate of the period (measured, else told); ``speed_ratio``: measured / told (None:
    not measured) and ``ratio_scatter`` its relative standard deviation over the buffers;
    ``speed_range_hz``: the shaft rates at which the lines apply as orders; ``bin_width``: the
    window's envelope bin (Hz) and ``windows`` how many were averaged; ``envelope``: lines per
    band; ``raw``: lines of the raw spectrum.
    """

    source: str
    bearing: str
    sample_rate: float
    period_s: float
    told_hz: float | None
    shaft_hz: float
    speed_ratio: float | None
    ratio_scatter: float
    speed_range_hz: tuple[float, float]
    bin_width: float
    windows: int
    envelope: tuple[BandLines, ...]
    raw: tuple[ReferenceLine, ...]

    def correct_speed(self, told_hz: float, tolerance: float, floor: float) -> tuple[float, float]:
        """A told shaft rate (Hz) and its relative tolerance, corrected by the learnt ratio. At the
        reference's told speed (within :data:`SAME_SPEED`) the ratio was measured there: the
        tolerance shrinks to 3 σ of the ratio, not below ``floor`` (the decision's own for a
        measured speed); at another told speed the tolerance stays (the ratio may differ there)."""
        if self.speed_ratio is None:
            return told_hz, tolerance
        hz = told_hz * self.speed_ratio
        if self.told_hz is not None and abs(told_hz / self.told_hz - 1.0) <= SAME_SPEED:
            return hz, min(tolerance, max(3.0 * self.ratio_scatter, floor))
        return hz, tolerance

    def known_lines(self, fr: float, band: tuple[float, float] | None = None, spectrum: np.ndarray | None = None,
                    df: float = 0.0, k: int = 1) -> np.ndarray:
        """Frequencies (Hz) of the reference's envelope lines at shaft rate ``fr`` (Hz) in ``band`` (the
        union over every band when None or not learnt): orders × ``fr`` within the speed range, supply
        multiples in Hz at any speed (module docstring). Each line is given as its Hann main lobe,
        ±2 bins of the window: three points half a bin apart, each of which holds 1.5 bins around it
        (:func:`.fault_combs.comb_evidence`): a stationary line's skirt adds the same excess every
        window, which the long horizon would otherwise accumulate into evidence.

        Judged by what is new: given the normalised ``spectrum`` under test (rows, bins; bin width ``df``
        Hz; the mean of ``k`` windows), a line whose value there (the largest over the rows, within a
        bin) exceeds :data:`GROWTH` × its learnt level (in the same normalisation) has grown and is not
        known any more: a fault on a line the healthy machine carried counts."""
        chosen = [b for b in self.envelope if band is not None and np.allclose(b.band, band)] or self.envelope
        in_range = self.speed_range_hz[0] <= fr <= self.speed_range_hz[1]
        lines = np.asarray([(line.order * fr if line.follows_speed else line.hz, line.level) for b in chosen
                            for line in b.lines if in_range or not line.follows_speed], float).reshape(-1, 2)
        f, level = lines[:, 0], lines[:, 1]
        if spectrum is not None and f.size:
            z = np.atleast_2d(spectrum).max(axis=0)
            i = np.clip(np.rint(f / df).astype(int)[:, None] + np.arange(-1, 2), 0, z.size - 1)
            f = f[z[i].max(axis=1) < GROWTH * level * averaged_median(k)[1] / math.log(2.0)]
        return np.unique((f[:, None] + MAIN_LOBE_POINTS * self.bin_width).ravel())

    def describe(self) -> str:
        """One line: where it was learnt, the speed relationship, the lines."""
        n = len(np.unique([round(line.order, 2) for b in self.envelope for line in b.lines]))
        speed = (f"shaft {60 * self.shaft_hz:.1f} rpm = {self.speed_ratio:.4f} x told ± "
                 f"{100 * self.ratio_scatter:.2f} %" if self.speed_ratio is not None else
                 f"shaft {60 * self.shaft_hz:.1f} rpm as told (no 1x family to measure it)")
        return (f"{self.source} ({self.period_s:.1f} s, {self.windows} windows; {speed}; {n} envelope lines, "
                f"{len(self.raw)} raw lines)")

    # -- files ----------------------------------------------------------------------------
    def save(self, path) -> None:
        """Write the reference as JSON (format name and version first)."""
        data = {"format": FORMAT, "version": VERSION} | asdict(self)
        Path(path).write_text(json.dumps(data, indent=1) + "\n")


def load_reference(path) -> MachineReference:
    """The reference saved at ``path``; :class:`MachineReferenceError` for a missing, corrupt, foreign or
    newer file."""
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise MachineReferenceError(f"{path}: cannot read the machine reference: {exc.strerror or exc}") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise MachineReferenceError(f"{path}: not a machine reference (not JSON: {exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise MachineReferenceError(f"{path}: not a machine reference (no format {FORMAT!r})")
    if data.get("version") != VERSION:
        raise MachineReferenceError(f"{path}: machine reference version {data.get('version')!r}; this program "
                                    f"reads version {VERSION} (learn it again)")
    try:
        def lines(items):
            return tuple(ReferenceLine(float(d["hz"]), float(d["order"]), float(d["level"]), float(d["scatter"]),
                                       bool(d["follows_speed"])) for d in items)
        ratio = data["speed_ratio"]
        return MachineReference(
            str(data["source"]), str(data["bearing"]), float(data["sample_rate"]), float(data["period_s"]),
            None if data["told_hz"] is None else float(data["told_hz"]), float(data["shaft_hz"]),
            None if ratio is None else float(ratio), float(data["ratio_scatter"]),
            (float(data["speed_range_hz"][0]), float(data["speed_range_hz"][1])), float(data["bin_width"]),
            int(data["windows"]),
            tuple(BandLines((float(b["band"][0]), float(b["band"][1])), lines(b["lines"])) for b in data["envelope"]),
            lines(data["raw"]))
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise MachineReferenceError(f"{path}: corrupt machine reference ({type(exc).__name__}: {exc})") from None


# -- learning -------------------------------------------------------------------------------
def learn_reference(x: np.ndarray, fs: float, bearing: Bearing, told_rpm: float | None, tolerance: float,
                    settings, usable_bandwidth: float = 0.0, source: str = "") -> MachineReference:
    """Learn the reference from the healthy signal ``x`` (m/s², ``fs`` Hz; its first :data:`MAX_PERIOD_S`)
    of a machine with ``bearing``, told to turn at ``told_rpm`` (None: unknown) within the relative
    ``tolerance``, for the decision's :class:`.settings.SpectralSettings` ``settings`` (window,
    prewhitening, speed search); bands up to the sensor's ``usable_bandwidth`` (Hz; 0: 0.45·fs).
    ``source`` says where the signal came from.

    Raises :class:`MachineReferenceError` (one line) when the signal cannot give one: too short for
    :data:`MIN_WINDOWS` windows, a sensor problem in most windows, no shaft speed told or found.
    """
    x = np.asarray(x, float)[: int(MAX_PERIOD_S * fs)]
    told_hz = None if not told_rpm else told_rpm / 60.0
    fr, ratio, scatter, rates = _speed(x, fs, told_hz, tolerance, settings)
    window = next_fast_len(int(np.ceil((settings.window_s or 4.0 / bearing.orders().ftf / fr) * fs)))
    k = x.size // window
    if k < MIN_WINDOWS:
        raise MachineReferenceError(f"healthy period too short: {x.size / fs:.2f} s holds {k} analysis windows "
                                    f"of {window / fs:.3f} s, {MIN_WINDOWS} needed")
    windows = [x[i * window:(i + 1) * window] for i in range(k)]
    checks = [check_window(w) for w in windows]
    good = [w for w, c in zip(windows, checks) if c.ok]
    if len(good) < max(MIN_WINDOWS, k / 2):
        problem = next(c.problem for c in checks if not c.ok)
        raise MachineReferenceError(f"healthy period unusable: {k - len(good)} of {k} windows show a sensor "
                                    f"problem ({problem})")
    f_top = highest_term(comb_terms(bearing), rho_range(settings.told_tolerance, True)[1]) * fr
    usable = usable_bandwidth or 0.45 * fs
    groups = live_bands(np.fft.rfft(x - x.mean()), x.size, fs, f_top, usable)
    if not groups:
        raise MachineReferenceError(f"no demodulation band above {f_top:.0f} Hz below the usable {usable:.0f} Hz")
    df = fs / window
    n_bins = int(np.ceil(f_top / df)) + 1
    spectra = [window_spectrum(w, settings.prewhiten) for w in good]
    per_group = [np.stack([band_ses(s, window, fs, g, f_top)[0][:, :n_bins] for s in spectra], axis=1)
                 for g in groups]  # (bands, K, bins) per group
    n_tests = sum(p.shape[0] for p in per_group) * (n_bins - 1)
    fine = _fine_spectra(x, fs, window, groups, f_top, settings.prewhiten)
    envelope = []
    for g, p, (fine_ses, fine_df) in zip(groups, per_group, fine):
        for b in range(len(g)):
            found = _lines(p[b], df, fr, n_tests, fine_ses[b] if fine_ses is not None else None, fine_df)
            if found:
                envelope.append(BandLines((float(g[b, 0]), float(g[b, 1])), found))
    raw = _raw_lines(x, fs, fr, max(f_top, (N_HARMONICS + 1) * fr), settings.buffer_s)
    measured = rates if rates.size else np.array([fr])
    lo, hi = float(measured.min()) * (1 - SAME_SPEED), float(measured.max()) * (1 + SAME_SPEED)
    return MachineReference(source or "healthy signal", bearing_spec(bearing), float(fs), x.size / fs, told_hz,
                            float(fr), ratio, scatter, (lo, hi), float(df), len(good), tuple(envelope), raw)


def _speed(x: np.ndarray, fs: float, told_hz: float | None, tolerance: float, settings):
    """(shaft rate Hz, ratio measured/told or None, its relative scatter, the buffers' measured rates)."""
    n = max(1, int(settings.buffer_s * fs))
    lo, hi = (told_hz * (1 - tolerance), told_hz * (1 + tolerance)) if told_hz else settings.blind_range_hz
    found = [estimate_speed(x[i:i + n], fs, lo, hi, min_lines=settings.speed_lines)
             for i in range(0, max(1, x.size - n + 1), n)]
    rates = np.array([f.hz for f in found if f is not None])
    sigmas = np.array([f.sigma for f in found if f is not None])
    if not rates.size:
        if told_hz is None:
            raise MachineReferenceError("no shaft speed: none told, and no 1x family found in the vibration "
                                        f"between {60 * lo:.0f} and {60 * hi:.0f} rpm")
        return told_hz, None, 0.0, rates
    fr = float(np.median(rates))
    spread = float(np.std(rates, ddof=1)) if rates.size > 1 else 0.0
    scatter = max(spread, float(np.median(sigmas))) / fr  # at least one estimate's own uncertainty
    return fr, (fr / told_hz if told_hz else None), scatter, rates


def _fine_spectra(x: np.ndarray, fs: float, window: int, groups: list, f_top: float, prewhiten: bool) -> list:
    """Per band group, (mean SES of the period in segments of up to :data:`FINE_FACTOR` windows and half the
    period (bands, bins), its bin width Hz); (None, 0) when such a segment would hold fewer than two windows."""
    seg = min(FINE_FACTOR * window, x.size // 2)
    m = x.size // seg
    if seg < 2 * window:
        return [(None, 0.0)] * len(groups)
    out = []
    for g in groups:
        total = sum(band_ses(window_spectrum(x[i * seg:(i + 1) * seg], prewhiten), seg, fs, g, f_top)[0]
                    for i in range(m))
        out.append((total / m, fs / seg))
    return out


def _lines(per_window: np.ndarray, df: float, fr: float, n_tests: int, fine: np.ndarray | None = None,
           fine_df: float = 0.0) -> tuple[ReferenceLine, ...]:
    """The lines of K windows' spectra ``per_window`` (K, bins), bin width ``df`` Hz, at shaft rate ``fr``
    Hz, tested against ``n_tests`` bins in all (module docstring); frequencies refined on ``fine`` (the
    period's mean spectrum at ``fine_df`` Hz bins) when given."""
    k = per_window.shape[0]
    scaled = per_window / np.maximum(np.median(per_window, axis=1, keepdims=True), 1e-300)
    z = normalise(scaled.mean(axis=0), level=averaged_median(k)[1])[0]
    each = normalise(per_window)  # (K, bins), median ≈ 1 on noise
    significant = averaged_comb_log10p(z, 1, k) < math.log10(LINE_FALSE_ALARM / n_tests)
    significant[0] = False
    left, right = np.r_[-np.inf, z[:-1]], np.r_[z[1:], -np.inf]
    out = []
    for i in np.flatnonzero(significant & (z >= left) & (z > right)):
        hz = _refined(fine, fine_df, i * df, df) if fine is not None else i * df
        around = each[:, max(i - 1, 0):i + 2].max(axis=1)  # the line may drift by a bin between windows
        out.append(ReferenceLine(float(hz), float(hz / fr), float(around.mean()), float(around.std(ddof=1)),
                                 _follows_speed(hz, fr, df)))
    return tuple(out)


def _refined(fine: np.ndarray, fine_df: float, hz: float, df: float) -> float:
    """The peak of the fine spectrum within one coarse bin of ``hz`` (parabolic on the log values)."""
    i0, i1 = max(1, int(np.floor((hz - df) / fine_df))), min(fine.size - 2, int(np.ceil((hz + df) / fine_df)))
    if i1 <= i0:
        return hz
    j = i0 + int(np.argmax(fine[i0:i1 + 1]))
    a, c, e = np.log(np.maximum(fine[j - 1:j + 2], 1e-300))
    curvature = a - 2 * c + e
    return (j + float(np.clip(0.5 * (a - e) / curvature if curvature < 0 else 0.0, -0.5, 0.5))) * fine_df


def _follows_speed(hz: float, fr: float, df: float) -> bool:
    """False for a supply multiple (within a bin) that is no shaft harmonic (within a bin)."""
    shaft = abs(hz - round(hz / fr) * fr) <= df
    supply = any(round(hz / f) >= 1 and abs(hz - round(hz / f) * f) <= df for f in SUPPLY_HZ)
    return bool(shaft or not supply)


def _raw_lines(x: np.ndarray, fs: float, fr: float, f_max: float, buffer_s: float) -> tuple[ReferenceLine, ...]:
    """Lines of the raw power spectrum up to ``f_max`` Hz, over the period in buffers of ``buffer_s`` s (at
    most a :data:`RAW_BUFFERS`-th of the period, so that the test averages that many)."""
    n = min(int(buffer_s * fs), x.size // RAW_BUFFERS)
    k = x.size // n
    df = fs / n
    bins = min(n // 2 + 1, int(min(f_max, 0.45 * fs) / df) + 1)
    power = np.stack([np.abs(np.fft.rfft((b - b.mean()) * hanning(n)))[:bins] ** 2
                      for b in (x[i * n:(i + 1) * n] for i in range(k))])
    return _lines(power, df, fr, bins - 1)
