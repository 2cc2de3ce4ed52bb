"""Settings of the envelope-spectrum front end, its textbook baseline, and what a recording must allow.

Every field switches one block of :mod:`.front_end` (the ablations of ``make accuracy``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from bearing_common.bearings import Bearing

from .fault_combs import comb_terms, highest_term, rho_range

if TYPE_CHECKING:
    from .machine_reference import MachineReference


@dataclass(frozen=True)
class SpectralSettings:
    """What the envelope-spectrum decision uses.

    Attributes
    ----------
    prewhiten, slip_search, mask_shaft, refine_speed : bool
        Cepstral prewhitening; slip search of the fault frequencies; shaft-harmonic mask;
        refinement of a told speed from the vibration.
    fundamental_only : bool
        Test the fundamental of each fault frequency only (no harmonics, no sidebands).
    drop_ambiguous : bool
        Leave out terms two hypotheses could both match over the slip search
        (:func:`.fault_combs.drop_ambiguous`); off, such a line counts for both.
    buffer_s, reselect_s : float
        Seconds of recent data the speed and band are estimated on, and how often (s).
    told_tolerance : float
        Relative half-range within which a told speed is refined when the teller states none
        (a tachometer: 2 %; the nameplate of a drive-fed motor, a recording's label: 10 %).
    blind_range_hz : (float, float)
        Shaft rates (Hz) searched when no speed is told.
    window_s : float
        Analysis window (s); 0: derived, 4 cage periods (:mod:`.front_end`).
    band_criterion : ``"evidence"`` or ``"kurtogram"``
        How the demodulation band is chosen (:mod:`.band_choice`).
    accumulate, max_windows : bool, int
        Run the long horizon (:mod:`.accumulation`), over at most this many non-overlapping windows.
    speed_lines : int
        Shaft harmonics (1x included) a measured speed must rest on.
    false_alarm_rate : float
        False alarms per hour of healthy operation (Gaussian noise) that the tests may give
        together, every window's short-horizon test and every long-horizon evaluation counted
        (a union bound: :mod:`.front_end`).
    reference : MachineReference or None
        The machine's own healthy reference (:mod:`.machine_reference`): the told speed corrected by
        its ratio, its envelope lines held by another explanation in every comb test; None: blind.
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
    window_s: float = 0.0
    band_criterion: str = "evidence"
    accumulate: bool = True
    max_windows: int = 32
    speed_lines: int = 3
    false_alarm_rate: float = 1e-3
    reference: MachineReference | None = None

    NAME = "spectral"
    NEEDS_SPEED = True  # estimated blind, the speed misses most faults (bearing-accuracy ablation)
    EVERY_STREAM = False  # one measurement: either observer's y = r + ŷ
    FOLLOWS_SPEED = True  # resampled to shaft angle in front of it (:mod:`.angle_domain`)

    def unknown_k_of_n(self) -> tuple[int, int]:
        """3 of 5: evidence spanning more than one window (hop = window / 2)."""
        return 3, 5

    def with_window(self, window_s: float) -> SpectralSettings:
        return replace(self, window_s=float(window_s))

    def describe_window(self) -> str:
        return f"window {self.window_s:g} s" if self.window_s else "window 4 cage periods of the bearing"

    def with_false_alarm_rate(self, per_hour: float) -> SpectralSettings:
        return replace(self, false_alarm_rate=float(per_hour)) if per_hour else self

    def describe_false_alarms(self, pfa: float) -> str:
        return f"false alarms at most {self.false_alarm_rate:g} per hour of healthy operation"

    def with_reference(self, reference: MachineReference | None) -> SpectralSettings:
        return replace(self, reference=reference)

    def known_lines(self, fr: float, band: tuple[float, float] | None = None, spectrum: np.ndarray | None = None,
                    df: float = 0.0, k: int = 1) -> np.ndarray:
        """The reference's envelope lines (Hz) at shaft rate ``fr`` (Hz) in ``band`` that have not grown in
        ``spectrum`` (:meth:`.machine_reference.MachineReference.known_lines`); none without a reference."""
        return np.empty(0) if self.reference is None else self.reference.known_lines(fr, band, spectrum, df, k)

    def textbook(self) -> SpectralSettings:
        """:data:`BASELINE` with this decision's speed handling (tolerance, blind range); blind (no reference)."""
        return replace(BASELINE, told_tolerance=self.told_tolerance, blind_range_hz=self.blind_range_hz)

    def check_recording(self, sample_rate: float, bearing: Bearing, rpm: float | None, duration: float,
                        usable_bandwidth: float = 0.0) -> None:
        """:func:`check_resolvable` at ``rpm`` (unknown: the fastest shaft of the blind search)."""
        check_resolvable(sample_rate, bearing, rpm or 60.0 * self.blind_range_hz[1], self, usable_bandwidth,
                         duration)


#: The textbook baseline (Randall & Antoni 2011): the squared envelope spectrum of the kurtogram's
#: band, read at each fundamental fault frequency (± slip) with the speed as told, whatever
#: other line lies near it.
BASELINE = SpectralSettings(prewhiten=False, mask_shaft=False, refine_speed=False, fundamental_only=True,
                            drop_ambiguous=False, band_criterion="kurtogram")


def check_resolvable(sample_rate: float, bearing: Bearing, rpm: float, settings: SpectralSettings = SpectralSettings(),
                     usable_bandwidth: float = 0.0, duration: float | None = None) -> None:
    """Raise ValueError (one line) when a recording cannot be diagnosed at all.

    The highest tested envelope line f_top must fit a demodulation band [f_top, 3·f_top]
    below the usable bandwidth (0.45·fs, or the sensor's ``usable_bandwidth`` Hz), and a
    recording of ``duration`` seconds must hold at least one analysis window.
    """
    fr = rpm / 60.0
    u = settings.told_tolerance / 2
    f_top = highest_term(comb_terms(bearing, fundamental_only=settings.fundamental_only),
                         rho_range(u, settings.slip_search)[1]) * fr
    usable = min(0.45 * sample_rate, usable_bandwidth or np.inf)
    if 3.0 * f_top > usable:
        raise ValueError(f"sample rate {sample_rate:g} Hz too low for bearing {bearing.name} at {rpm:g} rpm: "
                         f"the fault lines up to {f_top:.0f} Hz need a demodulation band from {f_top:.0f} to "
                         f"{3 * f_top:.0f} Hz, above the usable {usable:.0f} Hz")
    window_s = settings.window_s or 4.0 / bearing.orders().ftf / fr
    if duration is not None and duration < window_s:
        raise ValueError(f"recording too short: {duration:.3f} s < one {window_s:.3f} s analysis window "
                         f"(4 cage periods of bearing {bearing.name} at {rpm:g} rpm)")
