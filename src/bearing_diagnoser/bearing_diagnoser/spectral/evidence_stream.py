"""The envelope-spectrum evidence of a stream of samples, window by window (the spectral front end's engine).

Schedule, derived from the bearing and the speed (nothing fitted to a recording):

* window T = 4/FTF = 8/(fr·(1 − r)) (r = d/D·cos φ), rounded up to a fast FFT length: the
  narrowest spacing any hypothesis must resolve is the ball hypothesis' cage sideband
  (FTF ≈ 0.4·fr), and a Hann main lobe spans ±2/T. That is 4·n outer-race impacts per
  window (36 for a 6205: 0.33 s at 1800 rpm, 1.0 s at 600 rpm). Hop T/2 (Hann, 50 %
  overlap);
* every :attr:`.settings.SpectralSettings.reselect_s` = 1 s of new data the speed (refined from the
  vibration inside the told tolerance, or estimated blind) and the demodulation band
  (:mod:`.band_choice`) are re-estimated on the most recent max(2 s, 2·T) of data: 2 s
  hold ≥ 20 revolutions at ≥ 10 Hz and give 0.5 Hz speed bins;
* each window: prewhiten, band-pass and demodulate in one FFT (:mod:`.envelope_spectrum`),
  normalise, test every hypothesis' comb (:mod:`.fault_combs`), check the sensor
  (:mod:`bearing_diagnoser.decision.sensor_health`).

Only past data enter a decision (causal). A gap in the samples restarts the schedule.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.fft import next_fast_len

from bearing_common.bearings import Bearing
from bearing_common.chunk_stream import StreamCursor
from bearing_common.indexed_buffer import IndexedBuffer

from ..decision.sensor_health import SensorCheck, check_window
from .band_choice import BandChoice, choose_band
from .envelope_spectrum import band_ses, normalise, window_spectrum
from .fault_combs import CombEvidence, comb_evidence, comb_terms, drop_ambiguous, highest_term, rho_range
from .settings import SpectralSettings, check_resolvable
from .shaft_speed import estimate_speed


@dataclass(frozen=True)
class WindowEvidence:
    """What one analysis window shows.

    ``start``/``end``: sample indices (end exclusive); ``evidence``: per hypothesis
    (:data:`.fault_combs.HYPOTHESES`), empty when the sensor signal is unusable (then ``band``
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


class EvidenceStream:
    """Streaming envelope-spectrum evidence for one accelerometer channel.

    Parameters
    ----------
    sample_rate : float
        Hz.
    bearing : Bearing
    settings : SpectralSettings
    usable_bandwidth : float
        Hz up to which the sensor chain measures (0: up to 0.45·fs).
    """

    def __init__(self, sample_rate: float, bearing: Bearing, settings: SpectralSettings = SpectralSettings(),
                 usable_bandwidth: float = 0.0):
        self.fs = float(sample_rate)
        self.bearing = bearing
        self.settings = settings
        self.usable_bandwidth = float(usable_bandwidth)
        self._told: tuple[float, float] | None = None  # (Hz, relative tolerance)
        self._samples = IndexedBuffer()  # the recent samples, by stream index
        self._cursor = StreamCursor()
        self._origin = 0  # absolute index where the current schedule began
        self._next_end: int | None = None
        self._last_update: int | None = None
        self.speed: tuple[float, float, str] | None = None  # (Hz, sigma Hz, source)
        self.band: BandChoice | None = None
        self._geometry_for: float | None = None

    @property
    def retained_from(self) -> int:
        """Absolute index of the oldest sample still held (nothing before it is needed again)."""
        return self._samples.end - self._samples.held

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
        check_resolvable(self.fs, self.bearing, 60.0 * fr, s, self.usable_bandwidth)
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
        x = self._held(end - span, end)
        self._estimate_speed(x)
        self._last_update = end
        if self.speed is None:
            return
        fr, sigma, _ = self.speed
        self._set_geometry(fr, sigma)
        usable = self.usable_bandwidth or 0.45 * self.fs
        self.band = choose_band(x, self.fs, self.f_top, usable, fr, self.terms, self.rho, s.prewhiten, s.mask_shaft,
                                s.band_criterion)

    # -- samples in, evidence out -------------------------------------------------------
    def push(self, first_index: int, y) -> list[WindowEvidence]:
        """Feed samples ``y`` starting at absolute index ``first_index``; return windows that became due."""
        y = np.asarray(y, dtype=float)
        offset = self._cursor.offset(first_index)
        if offset is not None and offset < 0:  # overlap: keep only new samples
            y = y[-offset:]
            first_index -= offset
        if offset is None or offset > 0:  # start or gap: a new schedule
            self._samples.clear(first=first_index)
            self._origin = first_index
            self._next_end, self._last_update = None, None
        if y.size == 0:
            return []
        self._samples.append(y)
        self._cursor.advance(first_index, y.size)
        return self._run()

    def _held(self, i0: int, i1: int) -> np.ndarray:
        """The held samples from index max(i0, oldest held) to i1 (a view)."""
        return self._samples.view(max(i0, self.retained_from), i1)[0]

    def _run(self) -> list[WindowEvidence]:
        s = self.settings
        out = []
        have = self._samples.end
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
        if self._samples.held > 2 * keep:  # now and then, not per chunk
            self._samples.trim(self._samples.end - keep)

    def _window(self, end: int) -> WindowEvidence | None:
        """The window ending at ``end``: its evidence; no evidence for a sensor problem; None
        when no demodulation band could be chosen (no usable band power)."""
        s = self.settings
        x = self._held(end - self.window, end)
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

