"""Evidence that accumulates: the squared envelope spectra of a stationary stretch, averaged (the long horizon).

A window alone holds little evidence of a weak fault; a stationary fault adds the same
evidence every window. :class:`Accumulation` sums the SES of non-overlapping windows
(independent under Gaussian noise) of every candidate band at one geometry (shaft rate,
window, comb terms, slip range), each window's SES scaled by its own median first (so
that a window louder than the others does not outweigh them). The mean of K windows has
Gamma(K, 1/K) bins under the null, normalised and tested exactly like one window's
(:func:`.significance.averaged_comb_log10p`): the floor's scatter shrinks √K-fold while a
fault line stays, so a comb too weak for one window becomes overwhelming over many (Welch
1967). The band is chosen on the accumulated spectra themselves, paying for the choice
(Bonferroni over the candidates), or, for the textbook baseline, as the band of the highest
mean spectral kurtosis.

:class:`LongHorizon` keeps two lanes. Each lane keeps two accumulations staggered by half of
its length: the evidence always rests on between half and all of ``max_windows`` windows
(10-11 s at 1800 rpm for a 6205), so that an old condition does not dilute a new one for ever,
and a deterministic residue of a healthy machine cannot grow without bound.

* The coarse lane sums the analysis windows' spectra.
* The fine lane sums the spectra of blocks of :data:`FINE` = 4 contiguous windows: bins 4×
  narrower, so that the resolution grows with the evidence. A fault line sits off the shaft
  harmonic next to it by its slip (1-2 %), which the analysis window's bin cannot tell from the
  harmonic where a fault frequency is nearly an integer order (BPFO = 3.00× for 8 balls with
  d/D = 0.25; 2·BPFO of a 6205 at 600 rpm lies 1 Hz from 6×): the shaft-harmonic mask
  (1.5 bins) then covers the fault's own terms, and one term is left, which is no series
  (:mod:`.distinct_evidence`). Four windows resolve slip offsets a quarter as large; the
  fine lane holds a quarter as many spectra, so its floor is rougher.

Each lane's evidence pays for its two accumulations, and the long horizon's for both lanes
(four tests). A change of geometry (the shaft rate moved by more than half a bin at the
highest comb term), a gap, or a change the short horizon sees (:mod:`.front_end`) restarts
both lanes; a re-estimate of the same speed only retunes the combs (the spectra summed so far
hold). The onset of a condition is read from the coarse lane's windows.

Only distinct evidence counts, judged on the accumulated spectrum exactly as on one window's
(:mod:`.distinct_evidence`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from bearing_common.states import FaultState

from .distinct_evidence import distinct, explain_away
from .envelope_spectrum import band_kurtosis, band_ses, normalise, window_spectrum
from .fault_combs import comb_evidence, highest_term, recent_run_evidence
from .significance import averaged_median


@dataclass(frozen=True)
class CombGeometry:
    """What the combs are tested at: shaft rate ``fr`` (Hz) and its uncertainty ``sigma`` (Hz), the window
    (samples) at sample rate ``fs`` (Hz), the slip range ``rho``, the ``terms`` per hypothesis
    (:func:`.fault_combs.comb_terms`), the highest tested envelope frequency ``f_top`` (Hz), the machine's
    own envelope lines: ``known(spectrum, df, k)`` gives those (Hz) that have not grown in a spectrum of k
    windows (:mod:`.machine_reference`: no comb term on them counts)."""

    fs: float
    fr: float
    sigma: float
    window: int
    rho: tuple[float, float]
    terms: dict = field(compare=False)
    f_top: float = 0.0
    known: Callable = field(default=lambda spectrum, df, k: np.empty(0), compare=False)

    def same_bins(self, other: CombGeometry) -> bool:
        """Whether ``other``'s combs fall in the same bins: window unchanged, shaft rate within half a bin
        at the highest term (a re-estimate of the same speed: the spectra summed so far still hold)."""
        df = self.fs / self.window
        return other.window == self.window and abs(other.fr - self.fr) * self.f_top / self.fr < 0.5 * df


@dataclass(frozen=True)
class HorizonEvidence:
    """One hypothesis' best comb match over an accumulated horizon: log10 p (corrected for the slip
    search, the band choice and the horizons tested), the scale ρ, the band (Hz), S and J."""

    log10p: float
    rho: float
    band: tuple[float, float]
    statistic: float
    terms: int


class Accumulation:
    """SES sums of the non-overlapping windows from sample ``start`` on, every band of ``bands`` (one
    (m, 2) array of (f_lo, f_hi) per width), at ``geometry``; ``criterion`` "evidence" or "kurtogram"
    (:mod:`.band_choice`)."""

    def __init__(self, start: int, geometry: CombGeometry, bands: list[np.ndarray], mask_shaft: bool = True,
                 criterion: str = "evidence", series: bool = True):
        self.start = start
        self.geometry = geometry
        self.bands = bands
        self.mask_shaft = mask_shaft
        self.criterion = criterion
        self.series = series
        self.windows = 0
        self.df = geometry.fs / geometry.window  # SES bin width (Hz)
        self._sums: list[np.ndarray | None] = [None] * len(bands)
        self._kurtosis = [np.zeros(len(g)) for g in bands]
        self.n_bands = sum(len(g) for g in bands)

    def spectra(self, spectrum: np.ndarray) -> list[np.ndarray]:
        """One window's SES per band group, each row scaled by its median, from its rfft (prewhitened or
        not) of ``geometry.window`` samples."""
        g = self.geometry
        out = []
        for group in self.bands:
            ses, _ = band_ses(spectrum, g.window, g.fs, group, g.f_top)
            out.append(ses / np.maximum(np.median(ses, axis=1, keepdims=True), 1e-300))
        return out

    def add(self, spectrum: np.ndarray, spectra: list[np.ndarray]) -> None:
        """One more window: its rfft and its :meth:`spectra`."""
        g = self.geometry
        for i, ses in enumerate(spectra):
            self._sums[i] = ses.copy() if self._sums[i] is None else self._sums[i] + ses
            if self.criterion == "kurtogram":
                self._kurtosis[i] += band_kurtosis(spectrum, g.window, g.fs, self.bands[i])
        self.windows += 1

    def evidence(self, tests: int = 1) -> dict:
        """{hypothesis: HorizonEvidence}, every p-value multiplied by ``tests`` more (other horizons)."""
        if not self.windows:
            return {}
        g, k = self.geometry, self.windows
        level = averaged_median(k)[1]
        z = [normalise(s / k, level=level) for s in self._sums]
        rows = self._stack(z, self._rows())
        n_bands = (self.n_bands if self.criterion == "evidence" else 1) * tests
        found = {h: e for h in g.terms if (e := self._best(z, rows, h, n_bands)) is not None}
        found = explain_away(found, g.terms, g.fr, lambda h, held: self._best(z, rows, h, n_bands, held))
        return {h: e.evidence if e.evidence.log10p == 0.0 or distinct(
            e.row, self.df, g.fr, h, g.terms[h], g.rho, e.evidence.rho, e.evidence.log10p - np.log10(n_bands),
            self.mask_shaft, self.windows, self.series, g.known(e.row[None, :], self.df, self.windows))
            else replace(e.evidence, log10p=0.0)
            for h, e in found.items()}

    def _rows(self) -> list:
        """The (group, rows) tested: every band, or the band of the highest mean kurtosis."""
        if self.criterion == "evidence":
            return [(i, slice(None)) for i in range(len(self.bands))]
        i = int(np.argmax([k.max() for k in self._kurtosis]))
        j = int(np.argmax(self._kurtosis[i]))
        return [(i, slice(j, j + 1))]

    def _stack(self, z: list, rows: list) -> list:
        """``rows`` as (stacked spectra, [(group, row)] of each): the groups' rows in one array, cut to
        the shortest group's bins, when every comb term at every searched scale lies below that (so
        that the comb sums are the groups' own); else one entry per group."""
        g = self.geometry
        parts = [z[i][sel] for i, sel in rows]
        length = min(p.shape[1] for p in parts)
        top_bin = int(np.ceil(highest_term(g.terms, g.rho[1]) * g.fr / self.df)) + 2
        index = [(i, r) for i, sel in rows for r in np.arange(len(z[i]))[sel]]
        if len(parts) > 1 and top_bin < length:
            return [(np.concatenate([p[:, :length] for p in parts]), index)]
        return [(p, [(i, r) for i, r in index if i == gi]) for p, (gi, _) in zip(parts, rows)]

    def _best(self, z: list, rows: list, h: FaultState, n_bands: int, exclude=()) -> _Best | None:
        """``h``'s best comb match over the tested rows, with the spectrum row it was found on."""
        g = self.geometry
        best = None
        for spectra, index in rows:
            held = np.concatenate([np.ravel(exclude), g.known(spectra, self.df, self.windows)])
            lp, rho, s, j = comb_evidence(spectra, self.df, g.fr, {h: g.terms[h]}, g.rho, self.mask_shaft, n_bands,
                                          self.windows, held, prune=True)[h]
            r = int(np.argmin(lp))
            if best is None or lp[r] < best.log10p:
                i, row = index[r]
                band = self.bands[i][row]
                best = _Best(HorizonEvidence(float(lp[r]), float(rho[r]), (float(band[0]), float(band[1])),
                                             float(s[r]), int(j[r])), z[i][row])
        return best


@dataclass(frozen=True)
class _Best:
    """A hypothesis' best match and the normalised spectrum row it was found on (its distinctness is
    judged there)."""

    evidence: HorizonEvidence
    row: np.ndarray

    @property
    def log10p(self) -> float:
        return self.evidence.log10p

    @property
    def rho(self) -> float:
        return self.evidence.rho


class Lane:
    """Two accumulations of windows of one length, staggered by ``max_windows``/2 (module docstring)."""

    def __init__(self, max_windows: int, mask_shaft: bool = True, criterion: str = "evidence", series: bool = True):
        self.max_windows = int(max_windows)
        self._options = (mask_shaft, criterion, series)
        self.open: list[Accumulation] = []
        self._next_start: int | None = None  # first sample a window must start at (non-overlapping)

    def restart(self, start: int, geometry: CombGeometry, bands: list[np.ndarray]) -> None:
        self.open = [Accumulation(start, geometry, bands, *self._options)]
        self._next_start = start

    def retune(self, geometry: CombGeometry) -> None:
        for acc in self.open:
            acc.geometry = replace(geometry, window=acc.geometry.window, f_top=acc.geometry.f_top)

    def stop(self) -> None:
        self.open, self._next_start = [], None

    def add(self, start: int, spectrum: np.ndarray) -> list[np.ndarray] | None:
        """The window starting at sample ``start`` (its rfft), when it overlaps no window already taken:
        its :meth:`Accumulation.spectra` (None: not taken)."""
        if not self.open or start < self._next_start:
            return None
        first = self.open[0]
        spectra = first.spectra(spectrum)
        for acc in self.open:
            acc.add(spectrum, spectra)
        self._next_start = start + first.geometry.window
        if first.windows >= self.max_windows:
            self.open.pop(0)
        if len(self.open) == 1 and self.open[0].windows >= self.max_windows // 2:
            self.open.append(Accumulation(self._next_start, first.geometry, first.bands, *self._options))
        return spectra

    def evidence(self, tests: int) -> dict:
        """{hypothesis: HorizonEvidence}: the stronger of the two accumulations, paying for both and for
        ``tests`` more."""
        out: dict = {}
        for acc in self.open:
            for h, e in acc.evidence(tests=2 * tests).items():
                if h not in out or e.log10p < out[h].log10p:
                    out[h] = e
        return out


#: Windows per block of the fine lane: its spectra resolve FINE times finer (module docstring).
FINE = 4


class LongHorizon:
    """The coarse lane (the analysis windows) and the fine lane (blocks of :data:`FINE` contiguous
    windows), both restarted together (module docstring); ``prewhiten`` as the windows' spectra."""

    def __init__(self, max_windows: int = 32, mask_shaft: bool = True, criterion: str = "evidence",
                 series: bool = True, prewhiten: bool = True):
        self.max_windows = int(max_windows)
        self.mask_shaft = mask_shaft
        self.prewhiten = prewhiten
        self.coarse = Lane(max_windows, mask_shaft, criterion, series)
        self.fine = Lane(max(2, max_windows // FINE), mask_shaft, criterion, series)
        self._block: list[np.ndarray] = []  # the contiguous windows of the next fine block
        self._block_start = 0
        self._fine_evidence: dict = {}
        self._recent: deque = deque(maxlen=self.max_windows)  # (start, spectra) of the windows held

    @property
    def _open(self) -> list[Accumulation]:
        return self.coarse.open

    @property
    def geometry(self) -> CombGeometry | None:
        return self._open[0].geometry if self._open else None

    @property
    def start(self) -> int | None:
        """First sample of the evidence (the older accumulation's start)."""
        return self._open[0].start if self._open else None

    @property
    def bands(self) -> list[np.ndarray]:
        """The candidate bands the evidence is accumulated in (one (m, 2) array per width, Hz)."""
        return self._open[0].bands

    def restart(self, start: int, geometry: CombGeometry, bands: list[np.ndarray]) -> None:
        """Forget everything: the evidence begins afresh with the window starting at ``start``."""
        self.coarse.restart(start, geometry, bands)
        self.fine.restart(start, replace(geometry, window=FINE * geometry.window), bands)
        self._forget()

    def retune(self, geometry: CombGeometry) -> None:
        """A re-estimate of the same speed (:meth:`CombGeometry.same_bins`): the sums stand, the combs are
        tested at the new rate and slip range from now on (the spectra keep their length: ``f_top``)."""
        self.coarse.retune(geometry)
        self.fine.retune(geometry)

    def stop(self) -> None:
        """Hold no evidence (no geometry yet, a gap)."""
        self.coarse.stop()
        self.fine.stop()
        self._forget()

    def _forget(self) -> None:
        self._block, self._fine_evidence = [], {}
        self._recent.clear()

    def add(self, start: int, spectrum: np.ndarray, x: np.ndarray) -> bool:
        """The window of samples ``x`` starting at sample ``start`` (its rfft ``spectrum``), when it overlaps
        no window already taken; whether it was taken. Every :data:`FINE` contiguous windows taken make
        one block of the fine lane."""
        spectra = self.coarse.add(start, spectrum)
        if spectra is None:
            return False
        self._recent.append((start, spectra))
        if self._block and start != self._block_start + sum(b.size for b in self._block):
            self._block = []  # not contiguous (snapshots): a block holds one stretch of signal
        if not self._block:
            self._block_start = start
        self._block.append(np.array(x, float))
        if len(self._block) == FINE:
            block = np.concatenate(self._block)
            self.fine.add(self._block_start, window_spectrum(block, self.prewhiten))
            self._block = []
            self._fine_evidence = self.fine.evidence(tests=2)
        return True

    @property
    def windows(self) -> int:
        """Windows the evidence rests on (the coarse lane's older accumulation's)."""
        return self._open[0].windows if self._open else 0

    def onset(self, hypothesis: FaultState, evidence: HorizonEvidence) -> int:
        """When the evidence of ``hypothesis`` began (a sample index): the start of the run of the most
        recent windows whose mean spectrum, in the evidence's band and slip range, holds the
        strongest evidence — the whole horizon for a condition present throughout, the windows since
        a change for a new one (a likelihood estimate of the change point)."""
        acc = self._open[0]
        i, row = next((i, j) for i, g in enumerate(acc.bands) for j, b in enumerate(g)
                      if b[0] == evidence.band[0] and b[1] == evidence.band[1])
        held = list(self._recent)
        if not held:
            return acc.start
        runs = np.arange(1, len(held) + 1)  # the last k windows, k = 1, 2, ...
        totals = np.cumsum([spectra[i][row] for _, spectra in reversed(held)], axis=0)
        levels = np.array([averaged_median(k)[1] for k in runs])[:, None]
        lp = recent_run_evidence(normalise(totals / runs[:, None], level=levels), acc.df, acc.geometry,
                                 hypothesis, self.mask_shaft)
        strongest = int(np.argmin(lp))  # the first of equals: the shortest run
        return held[len(held) - 1 - strongest][0] if lp[strongest] < 0.0 else held[0][0]

    def evidence(self) -> dict:
        """{hypothesis: HorizonEvidence}: the strongest of the two lanes' accumulations, paying for all four
        (the fine lane's evaluated when a block completes)."""
        out = self.coarse.evidence(tests=2)
        for h, e in self._fine_evidence.items():
            if h not in out or e.log10p < out[h].log10p:
                out[h] = e
        return out
