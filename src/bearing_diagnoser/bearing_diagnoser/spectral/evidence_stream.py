"""The envelope-spectrum evidence of a stream of samples, window by window (the spectral front end's engine).

Schedule, derived from the bearing and the speed (nothing fitted to a recording):

* window T = 4/FTF = 8/(fr·(1 − r)) (r = d/D·cos φ), rounded up to a fast FFT length: the
  narrowest spacing any hypothesis must resolve is the ball hypothesis' cage sideband
  (FTF ≈ 0.4·fr), and a Hann main lobe spans ±2/T. That is 4·n outer-race impacts per
  window (36 for a 6205: 0.33 s at 1800 rpm, 1.0 s at 600 rpm). Hop T/2 (Hann, 50 %
  overlap);
* every :attr:`.settings.SpectralSettings.reselect_s` = 1 s of new data (every window while
  the buffer is not full yet) the speed (refined from the
  vibration inside the told tolerance, or estimated blind) and the demodulation band
  (:mod:`.band_choice`) are re-estimated on the most recent max(2 s, 2·T) of data: 2 s
  hold ≥ 20 revolutions at ≥ 10 Hz and give 0.5 Hz speed bins;
* each window: prewhiten, band-pass and demodulate in one FFT (:mod:`.envelope_spectrum`),
  normalise, test every hypothesis' comb (:mod:`.fault_combs`), check the sensor
  (:mod:`bearing_diagnoser.decision.sensor_health`) — the short horizon;
* every non-overlapping window also goes to the long horizon (:mod:`.accumulation`), whose
  evidence comes with the window's; it restarts when the geometry changes (the measured
  shaft rate moved by more than half a bin at the highest comb term), at a gap, and when
  the front end sees a change (:meth:`EvidenceStream.restart_long`).

The speed: a told one (a tachometer; a nameplate or a recording's label, ``told_tolerance``)
is a prior. The shaft rate is measured from the 1x line and its harmonics
(:mod:`.shaft_speed`, at least three lines) within the told tolerance, failing that from any
two shaft harmonics in the raw or the envelope spectrum (:func:`.shaft_speed.confirm_speed`). Two lines
of a buffer shorter than ``buffer_s`` confirm provisionally (``speed_source`` "provisional"): in its
coarser bins two families a bin apart pass for one (HIT-SM at 1200 rpm: 2 x 10.55 Hz and 2 x 20.19 Hz
in the 1 Hz bins of 1 s confirmed 20.41 Hz, and a healthy machine without its raw 1x family was
called INNER_RACE; an inner-race record at 900 rpm was confirmed 0.7 % fast), so the combs are tested
at it but not called (:mod:`.front_end`) until the full buffer confirms it, and it is withdrawn
when the full buffer does not; a sure told speed (a tachometer's, σ ≤ :data:`UNSURE_SPEED`) is
not replaced by a provisional one; the speed is re-estimated every window until an update has seen a
full buffer. When none is found
there but a shaft comb is plain within twice the tolerance, that measurement is used and
said to disagree with the told speed (``speed_source`` "measured"); otherwise the told speed
stands, with its whole tolerance as uncertainty (a wide slip search). A buffer that does not
measure the speed again keeps the last measurement only while it still shows two of its shaft
lines where the measurement put them (:meth:`EvidenceStream._still_shown`): weak lines hold a
measurement, moved ones (a ramp that smears the full series) withdraw it. Terms two hypotheses
could both match at one speed (within the slip search alone: 3·BPFO and 2·BPFI of a 6205) do not count
(:func:`.fault_combs.drop_ambiguous`); a line one hypothesis explains is taken from the
others before they are tested (explain-away), in the window as in the long horizon.

With the machine's own healthy reference (``settings.reference``, :mod:`.machine_reference`) the
told speed is corrected by its learnt ratio, and its envelope lines are held by another
explanation in every comb test (window, band choice, long horizon): no comb term on them counts.

Only past data enter a decision (causal). A gap in the samples restarts the schedule.

Snapshots (a snapshot sensor's chunks, :mod:`bearing_common.chunk_stream`): the pause before
one restarts the schedule but not the long horizon, so that evidence accumulates across
snapshots while the speed holds (the geometry check above, at the snapshot's first window)
and the condition does (:meth:`EvidenceStream.restart_long`). A snapshot at least one window
long is scored by the windows it holds, as a stretch of stream; a shorter one by one window
of its own length, for the hypotheses its resolution separates
(:func:`.fault_combs.untestable`), the others reported untested; its spectrum enters the long
horizon at that geometry (a sensor's snapshots are all equally long).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from scipy.fft import next_fast_len

from bearing_common.bearings import Bearing
from bearing_common.chunk_stream import StreamCursor
from bearing_common.indexed_buffer import IndexedBuffer
from bearing_common.states import FaultState

from ..decision.sensor_health import SensorCheck, check_window
from .accumulation import CombGeometry, LongHorizon
from .band_choice import BandChoice, choose_band, live_bands
from .distinct_evidence import distinct, explain_away
from .envelope_spectrum import band_ses, normalise, window_spectrum
from .envelope_view import EnvelopeView
from .fault_combs import (
    CombEvidence,
    comb_evidence,
    comb_terms,
    drop_ambiguous,
    highest_term,
    rho_range,
    untestable,
)
from .settings import SpectralSettings, check_resolvable
from .shaft_speed import SpeedEstimate, confirm_speed, estimate_speed

#: Relative speed uncertainty above which a told speed is unconfirmed: a tachometer's or a rig's
#: measured speed (2 %, σ = 1 %) is not; a nameplate's (10 %) the vibration has not confirmed is.
UNSURE_SPEED = 0.01


@dataclass(frozen=True)
class WindowEvidence:
    """What one analysis window shows.

    ``start``/``end``: sample indices (end exclusive); ``evidence``: per hypothesis
    (:data:`.fault_combs.HYPOTHESES`), empty when the sensor signal is unusable (then ``band``
    may be None); ``speed_hz``/``speed_sigma``: shaft rate used and its
    standard uncertainty (Hz), ``speed_source`` "told", "refined", "provisional" (refined on a buffer
    shorter than ``buffer_s``: not to be called on), "measured" (outside the told tolerance) or
    "estimated" (blind), ``told_hz`` the told rate (None: none);
    ``long``: per hypothesis the long horizon's :class:`.accumulation.HorizonEvidence`,
    resting on ``horizon_windows`` windows from sample ``horizon_start`` (empty when the long
    horizon is off or holds nothing yet); ``untested``: {hypothesis: why} the window could not
    test (a short snapshot: :func:`.fault_combs.untestable`).
    """

    start: int
    end: int
    evidence: dict
    band: BandChoice | None
    speed_hz: float
    speed_sigma: float
    speed_source: str
    sensor: SensorCheck
    told_hz: float | None = None
    long: dict = field(default_factory=dict)
    horizon_start: int = 0
    horizon_windows: int = 0
    untested: dict = field(default_factory=dict)


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
        self.long = LongHorizon(settings.max_windows, settings.mask_shaft, settings.band_criterion,
                                not settings.fundamental_only, settings.prewhiten) if settings.accumulate else None
        self._long_evidence: dict = {}
        self.envelope: EnvelopeView | None = None  # the last window's spectrum as tested (:mod:`.envelope_view`)

    @property
    def retained_from(self) -> int:
        """Absolute index of the oldest sample still held (nothing before it is needed again)."""
        return self._samples.end - self._samples.held

    # -- speed ------------------------------------------------------------------------
    def tell_speed(self, hz: float | None, tolerance: float | None = None) -> None:
        """A measured or nominal shaft rate (Hz) and its relative tolerance; None = unknown. Without
        refinement (the textbook baseline) the told speed is taken as it is: its tolerance is the
        settings' (a tachometer's), whatever the teller says."""
        if hz is None:
            self._told = None
            return
        if self.settings.reference is not None:  # the learnt speed relationship (:mod:`.machine_reference`)
            hz, tolerance = self.settings.reference.correct_speed(hz, tolerance or self.settings.told_tolerance,
                                                                  self.settings.told_tolerance)
        tol = self.settings.told_tolerance if tolerance is None or not self.settings.refine_speed else tolerance
        self._told = (float(hz), float(tol))
        measured = self.speed is not None and self.speed[2] in ("refined", "provisional", "measured")
        if not measured or abs(self.speed[0] / hz - 1.0) > 2 * tol:
            self.speed = (float(hz), tol / 2 * hz, "told")  # used until the next re-estimation

    @property
    def told(self) -> tuple[float, float] | None:
        """The told shaft rate (Hz) and its relative tolerance; None: none told."""
        return self._told

    def recent(self, end: int, seconds: float) -> np.ndarray:
        """The held samples of the ``seconds`` s before index ``end`` (those held of them)."""
        return self._held(end - int(seconds * self.fs), end)

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
        slip = rho_range(0.0, s.slip_search)  # two hypotheses share one speed: only slip tells them apart
        self.terms = drop_ambiguous(terms, slip[1] - slip[0]) if s.drop_ambiguous else terms
        self.f_top = highest_term(terms, self.rho[1]) * fr
        self._geometry_for = fr

    def _estimate_speed(self, x: np.ndarray) -> None:
        s = self.settings
        if self._told is not None:
            hz, tol = self._told
            # the tolerance must span 4 bins of the buffer's spectrum before a line in it can be told
            # from its neighbours (0.67 s at 30 Hz ± 10 %); until then the told speed stands
            resolved = x.size / self.fs >= min(s.buffer_s, 2.0 / (tol * hz))
            refine = s.refine_speed and resolved
            found = estimate_speed(x, self.fs, hz * (1 - tol), hz * (1 + tol), min_lines=s.speed_lines) \
                if refine else None
            measured = self.speed is not None and self.speed[2] in ("refined", "measured")
            source = "refined"
            if refine and not measured and (found is None or self._fault_family(found.hz, hz)):
                # any two shaft lines confirm a told speed (provisionally on a short buffer: module docstring);
                # they never replace a measurement of the full series
                found = self._confirm(x, hz, tol)
                source = "refined" if x.size >= int(s.buffer_s * self.fs) else "provisional"
            sure = tol / 2 <= UNSURE_SPEED  # a tachometer's speed stands until a full buffer refines it
            if found and not self._fault_family(found.hz, hz) and not (source == "provisional" and sure):
                self.speed = (found.hz, found.sigma, source)
                return
            wider = estimate_speed(x, self.fs, hz * (1 - 2 * tol), hz * (1 + 2 * tol), min_lines=s.speed_lines) \
                if refine else None
            wider = None if wider is None or self._fault_family(wider.hz, hz) else wider
            if wider:
                self.speed = (wider.hz, wider.sigma, "measured")
            elif not measured or (refine and not self._still_shown(x, hz, tol)):
                self.speed = (hz, tol / 2 * hz, "told")
        else:
            found = estimate_speed(x, self.fs, *s.blind_range_hz)
            if found:
                self.speed = (found.hz, found.sigma, "estimated")

    def _still_shown(self, x: np.ndarray, hz: float, tol: float) -> bool:
        """Whether buffer ``x`` still shows the held measurement's shaft lines (told rate ``hz``, relative
        tolerance ``tol``): two of its first harmonics (:func:`.shaft_speed.confirm_speed`) at a rate within
        3 σ of it. A measurement is held while its lines are weak, never while they have moved: a ramp
        smears the full series, and a speed held from before it went on being used (HIT-SM Normal_1200
        along a 20 % ramp: 20.9 Hz held for 4 s while the shaft slowed to 19.1 Hz, called BALL)."""
        held, sigma, _ = self.speed
        found = self._confirm(x, hz, 2 * tol)
        return found is not None and abs(found.hz - held) <= 3.0 * np.hypot(found.sigma, sigma)

    def _confirm(self, x: np.ndarray, hz: float, tol: float) -> SpeedEstimate | None:
        """:func:`.shaft_speed.confirm_speed` on buffer ``x`` within ``hz`` · (1 ± ``tol``), in the raw
        spectrum and in the envelope of the current demodulation band (when there is one)."""
        band = (self.band.low, self.band.high) if self.band is not None else None
        return confirm_speed(x, self.fs, hz * (1 - tol), hz * (1 + tol), band)

    def _fault_family(self, hz: float, told_hz: float) -> bool:
        """Whether a measured rate ``hz`` that departs from the told one by more than the slip search
        is rather a submultiple (1/1 to 1/5) of a fault frequency at the told speed: an outer-race
        comb's lines at k·BPFO hold a harmonic series at BPFO/3 too (HIT-SM's outer-race records)."""
        lo, hi = rho_range(0.0, self.settings.slip_search)
        if lo <= hz / told_hz <= hi:
            return False
        o = self.bearing.orders()
        return any(lo <= hz * n / (f * told_hz) <= hi for f in (o.bpfo, o.bpfi, 2 * o.bsf) for n in range(1, 6))

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
                                s.band_criterion, s.known_lines(fr))
        geometry = CombGeometry(self.fs, fr, sigma, self.window, self.rho, self.terms, self.f_top,
                                partial(s.known_lines, fr, None))
        if self.long is not None and self.long.geometry is not None and self.long.geometry.same_bins(geometry):
            self.long.retune(geometry)
        elif self.long is not None:
            bands = live_bands(np.fft.rfft(x - x.mean()), x.size, self.fs, self.f_top, usable)
            self.long.restart(end - self.window, geometry, bands)
            self._long_evidence = {}

    def long_onset(self, hypothesis: FaultState) -> int:
        """When the long horizon's evidence of ``hypothesis`` began (sample index, :meth:`.LongHorizon.onset`)."""
        return self.long.onset(hypothesis, self._long_evidence[hypothesis])

    def restart_long(self, start: int) -> None:
        """The condition changed at sample ``start``: the long horizon begins afresh with the window
        starting there (same geometry)."""
        if self.long is not None and self.long.geometry is not None:
            self.long.restart(start, self.long.geometry, self.long.bands)
            self._long_evidence = {}

    # -- samples in, evidence out -------------------------------------------------------
    def push(self, first_index: int, y, snapshot: bool = False) -> list[WindowEvidence]:
        """Every window of :meth:`windows` at once."""
        return list(self.windows(first_index, y, snapshot))

    def windows(self, first_index: int, y, snapshot: bool = False) -> Iterator[WindowEvidence]:
        """Feed samples ``y`` starting at absolute index ``first_index``; yield the windows that became due,
        each computed as it is taken: a caller that acts on a window's verdict (restarts the long
        horizon, asks for its onset) does so before the next window is added, whatever the chunk size.
        ``snapshot``: a snapshot sensor's chunk (module docstring): the pause before it keeps the
        long horizon, and a snapshot shorter than one window is scored alone."""
        y = np.asarray(y, dtype=float)
        offset = self._cursor.offset(first_index)
        if offset is not None and offset < 0:  # overlap: keep only new samples
            y = y[-offset:]
            first_index -= offset
        began = offset is None or offset > 0
        if began:  # start or gap: a new schedule
            self._samples.clear(first=first_index)
            self._origin = first_index
            self._next_end, self._last_update = None, None
            if self.long is not None and not snapshot:
                self.long.stop()
        if y.size == 0:
            return
        self._samples.append(y)
        self._cursor.advance(first_index, y.size)
        if not (snapshot and began):
            yield from self._run()
            return
        out = list(self._run())
        if self.speed is not None and self._samples.end - self._origin < self.window:
            short = self._snapshot_window()  # (the schedule's geometry is set: a speed is known)
            out = [short] if short is not None else []
        yield from out

    def _held(self, i0: int, i1: int) -> np.ndarray:
        """The held samples from index max(i0, oldest held) to i1 (a view)."""
        return self._samples.view(max(i0, self.retained_from), i1)[0]

    def _run(self) -> Iterator[WindowEvidence]:
        s = self.settings
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
            # re-estimate every window until an update has seen a full buffer
            filling = self._last_update is not None and self._last_update - self._origin < s.buffer_s * self.fs
            if self._last_update is None or end - self._last_update >= (self.hop if filling else reselect):
                self._update(end)
            if end - self._origin < self.window:  # the window grew with a slower speed
                self._next_end = self._origin + self.window
                continue
            window = self._window(end)
            if window is not None:
                yield window
            self._next_end = end + self.hop
        self._trim()

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
        evidence = self._evidence(spectrum, x.size, self.band, self.terms, self.f_top, fr, end)
        told = self._told[0] if self._told else None
        if self.long is None:
            return WindowEvidence(end - self.window, end, evidence, self.band, fr, sigma, source, sensor, told)
        if self.long.add(end - self.window, spectrum, x):
            self._long_evidence = self.long.evidence()
        return WindowEvidence(end - self.window, end, evidence, self.band, fr, sigma, source, sensor, told,
                              self._long_evidence, self.long.start or 0, self.long.windows)

    def _evidence(self, spectrum: np.ndarray, n: int, band: BandChoice, terms: dict, f_top: float,
                  fr: float, end: int) -> dict:
        """{hypothesis: CombEvidence} of the window's spectrum (its rfft, ``n`` samples to index ``end``) in
        ``band``, for the combs ``terms`` up to ``f_top`` (Hz) at shaft rate ``fr`` (Hz); kept as
        :attr:`envelope` too."""
        s = self.settings
        ses, df = band_ses(spectrum, n, self.fs, np.array([[band.low, band.high]]), f_top)
        z = normalise(ses)
        known = s.known_lines(fr, (band.low, band.high), z, df)  # the machine's own lines (:mod:`.machine_reference`)
        found = comb_evidence(z, df, fr, terms, self.rho, s.mask_shaft, band.candidates, exclude=known)
        evidence = {h: CombEvidence(float(lp[0]), float(rho[0]), float(stat[0]), int(j[0]))
                    for h, (lp, rho, stat, j) in found.items()}

        def retest(h: FaultState, held: np.ndarray) -> CombEvidence:
            lp, rho, stat, j = comb_evidence(z, df, fr, {h: terms[h]}, self.rho, s.mask_shaft, band.candidates,
                                             exclude=np.concatenate([held, known]))[h]
            return CombEvidence(float(lp[0]), float(rho[0]), float(stat[0]), int(j[0]))

        evidence = explain_away(evidence, terms, fr, retest)
        for h, e in evidence.items():  # distinct evidence only (:mod:`.distinct_evidence`)
            if e.log10p < 0.0 and not distinct(z[0], df, fr, h, terms[h], self.rho, e.rho,
                                               e.log10p - np.log10(band.candidates), s.mask_shaft,
                                               series=not s.fundamental_only, exclude=known):
                evidence[h] = CombEvidence(0.0, e.rho, e.statistic, e.terms)
        # the live view's hook (:mod:`.envelope_view`): this window's spectrum as tested, no copy
        self.envelope = EnvelopeView(end, n, self.fs, z[0], df, (band.low, band.high), f_top, fr, self.speed[2],
                                     self._told[0] if self._told else None, terms,
                                     {h: e.rho for h, e in evidence.items()})
        return evidence

    def _snapshot_window(self) -> WindowEvidence | None:
        """The snapshot held, shorter than one window, as one window of its own length (module
        docstring); None when no demodulation band could be chosen."""
        s = self.settings
        start, end = self._origin, self._samples.end
        x = self._held(start, end)
        fr, sigma, source = self.speed
        told = self._told[0] if self._told else None
        sensor = check_window(x)
        untested = untestable(self.terms, fr, self.fs / x.size, s.mask_shaft, not s.fundamental_only)
        terms = {h: t for h, t in self.terms.items() if h not in untested}
        if not sensor.ok or not terms:
            return WindowEvidence(start, end, {}, None, fr, sigma, source, sensor, told, untested=untested)
        f_top = highest_term(terms, self.rho[1]) * fr
        usable = self.usable_bandwidth or 0.45 * self.fs
        band = choose_band(x, self.fs, f_top, usable, fr, terms, self.rho, s.prewhiten, s.mask_shaft,
                           s.band_criterion, s.known_lines(fr))
        if band is None:
            return None
        spectrum = window_spectrum(x, s.prewhiten)
        evidence = self._evidence(spectrum, x.size, band, terms, f_top, fr, end)
        if self.long is None:
            return WindowEvidence(start, end, evidence, band, fr, sigma, source, sensor, told, untested=untested)
        geometry = CombGeometry(self.fs, fr, sigma, x.size, self.rho, terms, f_top, partial(s.known_lines, fr, None))
        held = self.long.geometry
        if held is not None and held.same_bins(geometry) and held.terms.keys() == terms.keys():
            self.long.retune(geometry)
        else:
            self.long.restart(start, geometry, live_bands(np.fft.rfft(x - x.mean()), x.size, self.fs, f_top, usable))
            self._long_evidence = {}
        if self.long.add(start, spectrum, x):
            self._long_evidence = self.long.evidence()
        return WindowEvidence(start, end, evidence, band, fr, sigma, source, sensor, told, self._long_evidence,
                              self.long.start or 0, self.long.windows, untested)
