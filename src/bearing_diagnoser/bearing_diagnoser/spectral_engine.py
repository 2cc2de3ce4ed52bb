"""The envelope-spectrum decision front end for real machines: push samples, get window evidence.

Schedule, derived from the bearing and the speed (nothing fitted to a recording):

* window T = 4/FTF = 8/(fr·(1 − r)) (r = d/D·cos φ), rounded up to a fast FFT length: the
  narrowest spacing any hypothesis must resolve is the ball hypothesis' cage sideband
  (FTF ≈ 0.4·fr), and a Hann main lobe spans ±2/T. That is 4·n outer-race impacts per
  window (36 for a 6205: 0.33 s at 1800 rpm, 1.0 s at 600 rpm). Hop T/2 (Hann, 50 %
  overlap);
* every :attr:`SpectralSettings.reselect_s` = 1 s of new data the speed (refined from the
  vibration inside the told tolerance, or estimated blind) and the demodulation band
  (:mod:`.band_selection`) are re-estimated on the most recent max(2 s, 2·T) of data: 2 s
  hold ≥ 20 revolutions at ≥ 10 Hz and give 0.5 Hz speed bins;
* each window: prewhiten, band-pass and demodulate in one FFT (:mod:`.envelope_spectrum`),
  normalise, test every hypothesis' comb (:mod:`.fault_lines`), check the sensor
  (:mod:`.sensor_health`).

Only past data enter a decision (causal). A gap in the samples restarts the schedule.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.fft import next_fast_len

from bearing_common.bearings import Bearing

from .band_selection import BandChoice, choose_band
from .envelope_spectrum import band_ses, normalise, window_spectrum
from .fault_lines import CombEvidence, comb_evidence, comb_terms, drop_ambiguous, highest_term, rho_range
from .sensor_health import SensorCheck, check_window
from .speed_estimate import estimate_speed


@dataclass(frozen=True)
class SpectralSettings:
    """What the envelope-spectrum decision uses; every field switches one block (for the ablations).

    Attributes
    ----------
    prewhiten, slip_search, mask_shaft, refine_speed : bool
        Cepstral prewhitening; slip search of the fault frequencies; shaft-harmonic mask;
        refinement of a told speed from the vibration.
    fundamental_only : bool
        Test the fundamental of each fault frequency only (no harmonics, no sidebands).
    drop_ambiguous : bool
        Leave out terms two hypotheses could both match over the slip search
        (:func:`.fault_lines.drop_ambiguous`); off, such a line counts for both.
    buffer_s, reselect_s : float
        Seconds of recent data the speed and band are estimated on, and how often (s).
    told_tolerance : float
        Relative half-range within which a told speed is refined (a tachometer or the file:
        2 %; a nameplate speed: say 10 %).
    blind_range_hz : (float, float)
        Shaft rates (Hz) searched when no speed is told.
    usable_bandwidth : float
        Hz up to which the sensor chain measures (0: up to 0.45·fs).
    window_s : float
        Analysis window (s); 0: derived, 4 cage periods (module docstring).
    band_criterion : ``"evidence"`` or ``"kurtogram"``
        How the demodulation band is chosen (:mod:`.band_selection`).
    """

    prewhiten: bool = True
    slip_search: bool = True
    mask_shaft: bool = True
    refine_speed: bool = True
    fundamental_only: bool = False
    drop_ambiguous: bool = True
    buffer_s: float = 2.0
    reselect_s: float = 1.0
    told_tolerance: float = 0.02
    blind_range_hz: tuple[float, float] = (5.0, 60.0)
    usable_bandwidth: float = 0.0
    window_s: float = 0.0
    band_criterion: str = "evidence"


#: The textbook baseline (Randall & Antoni 2011): the squared envelope spectrum of the kurtogram's
#: band, read at each fundamental fault frequency (± slip) with the speed as told, whatever
#: other line lies near it.
BASELINE = SpectralSettings(prewhiten=False, mask_shaft=False, refine_speed=False, fundamental_only=True,
                            drop_ambiguous=False, band_criterion="kurtogram")


@dataclass(frozen=True)
class WindowEvidence:
    """What one analysis window shows.

    ``start``/``end``: sample indices (end exclusive); ``evidence``: per hypothesis
    (:data:`.fault_lines.HYPOTHESES`), empty when the sensor signal is unusable (then ``band``
    may be None); ``speed_hz``/``speed_sigma``: shaft rate used and its
    standard uncertainty (Hz), ``speed_source`` "told", "refined" or "estimated".
    """

    start: int
    end: int
    evidence: dict
    band: BandChoice | None
    speed_hz: float
    speed_sigma: float
    speed_source: str
    sensor: SensorCheck


class SpectralEngine:
    """Streaming envelope-spectrum evidence for one accelerometer channel.

    Parameters
    ----------
    sample_rate : float
        Hz.
    bearing : Bearing
    settings : SpectralSettings
    """

    def __init__(self, sample_rate: float, bearing: Bearing, settings: SpectralSettings = SpectralSettings()):
        self.fs = float(sample_rate)
        self.bearing = bearing
        self.settings = settings
        self._told: tuple[float, float] | None = None  # (Hz, relative tolerance)
        self._store = np.zeros(0)  # samples live in _store[:_fill]; grown by doubling, not per chunk
        self._fill = 0
        self._buf_start = 0  # absolute index of the first held sample
        self._next_index: int | None = None  # absolute index of the next expected sample
        self._origin = 0  # absolute index where the current schedule began
        self._next_end: int | None = None
        self._last_update: int | None = None
        self.speed: tuple[float, float, str] | None = None  # (Hz, sigma Hz, source)
        self.band: BandChoice | None = None
        self._geometry_for: float | None = None

    @property
    def retained_from(self) -> int:
        """Absolute index of the oldest sample still held (nothing before it is needed again)."""
        return self._buf_start

    # -- speed ------------------------------------------------------------------------
    def tell_speed(self, hz: float | None, tolerance: float | None = None) -> None:
        """A measured or nominal shaft rate (Hz) and its relative tolerance; None = unknown."""
        if hz is None:
            self._told = None
            return
        tol = self.settings.told_tolerance if tolerance is None else tolerance
        self._told = (float(hz), float(tol))
        if self.speed is None or self.speed[2] != "refined" or abs(self.speed[0] / hz - 1.0) > tol:
            self.speed = (float(hz), tol / 2 * hz, "told")  # used until the next re-estimation

    # -- geometry that follows the speed -----------------------------------------------
    def _set_geometry(self, fr: float, sigma: float) -> None:
        """Window, slip range and comb terms at shaft rate ``fr`` (Hz); ValueError when the sample
        rate cannot resolve the bearing's fault lines at that speed (:func:`check_resolvable`)."""
        s = self.settings
        check_resolvable(self.fs, self.bearing, 60.0 * fr, s)
        window_s = s.window_s or 4.0 / self.bearing.orders().ftf / fr
        self.window = next_fast_len(int(np.ceil(window_s * self.fs)))
        self.hop = self.window // 2
        self.rho = rho_range(sigma / fr, s.slip_search)
        terms = comb_terms(self.bearing, fundamental_only=s.fundamental_only)
        self.terms = drop_ambiguous(terms, self.rho[1] - self.rho[0]) if s.drop_ambiguous else terms
        self.f_top = highest_term(terms, self.rho[1]) * fr
        self._geometry_for = fr

    def _estimate_speed(self, x: np.ndarray) -> None:
        s = self.settings
        if self._told is not None:
            hz, tol = self._told
            found = estimate_speed(x, self.fs, hz * (1 - tol), hz * (1 + tol), min_lines=2) \
                if s.refine_speed else None
            self.speed = (found.hz, found.sigma, "refined") if found else (hz, tol / 2 * hz, "told")
        else:
            found = estimate_speed(x, self.fs, *s.blind_range_hz)
            if found:
                self.speed = (found.hz, found.sigma, "estimated")

    def _update(self, end: int) -> None:
        """Re-estimate speed and band on the recent buffer ending at sample ``end``."""
        s = self.settings
        span = int(max(s.buffer_s, 2.0 * (self.window / self.fs if self._geometry_for else 0.0)) * self.fs)
        x = self._buf[max(0, end - span - self._buf_start): end - self._buf_start]
        self._estimate_speed(x)
        self._last_update = end
        if self.speed is None:
            return
        fr, sigma, _ = self.speed
        self._set_geometry(fr, sigma)
        usable = s.usable_bandwidth or 0.45 * self.fs
        self.band = choose_band(x, self.fs, self.f_top, usable, fr, self.terms, self.rho, s.prewhiten, s.mask_shaft,
                                s.band_criterion)

    # -- samples in, evidence out -------------------------------------------------------
    def push(self, first_index: int, y) -> list[WindowEvidence]:
        """Feed samples ``y`` starting at absolute index ``first_index``; return windows that became due."""
        y = np.asarray(y, dtype=float)
        if self._next_index is not None and first_index < self._next_index:  # overlap: keep only new samples
            y = y[self._next_index - first_index:]
            first_index = self._next_index
        if self._next_index is None or first_index > self._next_index:  # start or gap: a new schedule
            self._fill, self._buf_start, self._origin = 0, first_index, first_index
            self._next_end, self._last_update = None, None
        if y.size == 0:
            return []
        if self._fill + y.size > self._store.size:
            grown = np.zeros(max(2 * self._store.size, self._fill + y.size))
            grown[:self._fill] = self._store[:self._fill]
            self._store = grown
        self._store[self._fill:self._fill + y.size] = y
        self._fill += y.size
        self._next_index = first_index + y.size
        return self._run()

    @property
    def _buf(self) -> np.ndarray:
        """The held samples (a view)."""
        return self._store[:self._fill]

    def _run(self) -> list[WindowEvidence]:
        s = self.settings
        out = []
        have = self._buf_start + self._buf.size
        reselect = int(s.reselect_s * self.fs)
        while True:
            if self._next_end is None:  # the schedule starts once a speed is known
                if self.speed is None:  # blind: estimate it on buffer_s of data, retry every reselect_s
                    due = self._origin + int(s.buffer_s * self.fs)
                    if have < due or (self._last_update is not None and have - self._last_update < reselect):
                        break
                    self._update(have)
                    if self.speed is None:
                        break
                self._set_geometry(*self.speed[:2])
                self._next_end = self._origin + self.window
            end = self._next_end
            if end > have:
                break
            if self._last_update is None or end - self._last_update >= reselect:
                self._update(end)
            if end - self._origin < self.window:  # the window grew with a slower speed
                self._next_end = self._origin + self.window
                continue
            window = self._window(end)
            if window is not None:
                out.append(window)
            self._next_end = end + self.hop
        self._trim()
        return out

    def _trim(self) -> None:
        """Keep what the next re-estimation and window need."""
        window_s = self.window / self.fs if self._geometry_for else 0.0
        keep = int((max(self.settings.buffer_s, 2.0 * window_s) + window_s + 1.0) * self.fs)
        if self._fill > 2 * keep:  # shift down only now and then: amortised O(1) per sample
            drop = self._fill - keep
            self._store[:keep] = self._store[drop:self._fill]
            self._fill = keep
            self._buf_start += drop

    def _window(self, end: int) -> WindowEvidence | None:
        """The window ending at ``end``: its evidence; no evidence for a sensor problem; None
        when no demodulation band could be chosen (no usable band power)."""
        s = self.settings
        x = self._buf[end - self.window - self._buf_start: end - self._buf_start]
        sensor = check_window(x)
        fr, sigma, source = self.speed
        if not sensor.ok or self.band is None:
            return None if sensor.ok else WindowEvidence(end - self.window, end, {}, self.band, fr, sigma, source,
                                                         sensor)
        spectrum = window_spectrum(x, s.prewhiten)
        ses, df = band_ses(spectrum, x.size, self.fs, np.array([[self.band.low, self.band.high]]), self.f_top)
        found = comb_evidence(normalise(ses), df, fr, self.terms, self.rho, s.mask_shaft, self.band.candidates)
        evidence = {h: CombEvidence(float(lp[0]), float(rho[0]), float(stat[0]), int(j[0]))
                    for h, (lp, rho, stat, j) in found.items()}
        return WindowEvidence(end - self.window, end, evidence, self.band, fr, sigma, source, sensor)



def check_resolvable(sample_rate: float, bearing: Bearing, rpm: float, settings: SpectralSettings = SpectralSettings(),
                     duration: float | None = None) -> None:
    """Raise ValueError (one line) when a recording cannot be diagnosed at all.

    The highest tested envelope line f_top must fit a demodulation band [f_top, 3·f_top]
    below the usable bandwidth (0.45·fs, or the sensor's), and a recording of ``duration``
    seconds must hold at least one analysis window.
    """
    fr = rpm / 60.0
    u = settings.told_tolerance / 2
    f_top = highest_term(comb_terms(bearing, fundamental_only=settings.fundamental_only),
                         rho_range(u, settings.slip_search)[1]) * fr
    usable = min(0.45 * sample_rate, settings.usable_bandwidth or np.inf)
    if 3.0 * f_top > usable:
        raise ValueError(f"sample rate {sample_rate:g} Hz too low for bearing {bearing.name} at {rpm:g} rpm: "
                         f"the fault lines up to {f_top:.0f} Hz need a demodulation band from {f_top:.0f} to "
                         f"{3 * f_top:.0f} Hz, above the usable {usable:.0f} Hz")
    window_s = settings.window_s or 4.0 / bearing.orders().ftf / fr
    if duration is not None and duration < window_s:
        raise ValueError(f"recording too short: {duration:.3f} s < one {window_s:.3f} s analysis window "
                         f"(4 cage periods of bearing {bearing.name} at {rpm:g} rpm)")
