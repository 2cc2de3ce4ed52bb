"""Settings of the fold front end (the simulator model sets), its textbook reference, what a recording must allow."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from bearing_common.bearings import Bearing

from ..decision.thesis_blocks import XCORR_LAG_S


@dataclass(frozen=True)
class FoldSettings:
    """Settings of the folding front end.

    Attributes
    ----------
    window_s, hop_s : float
        Sliding window length and hop (s).
    band : (lo, hi)
        Band-pass (Hz) before the energy envelope: the resonances the impacts excite.
    bins, search, n_decoys : int, float, int
        Phase bins of the folded profile; relative period search (±); decoy periods.
    threshold, kurtosis_threshold : float or None
        Explicit thresholds (None = derive from the configuration's pfa).
    dominance, explained_margin : float
        Ratio of CFAR statistics that picks one of two significant hypotheses; difference
        of model-explains fractions that breaks a remaining tie.
    rms_floor : float
        Window RMS (m/s²) below which the window is NORMAL without further test.
    quiet_tail, quiet_ratio : float
        A window whose newest ``quiet_tail`` holds less than ``quiet_ratio`` × the older
        part's mean band energy is NORMAL (the activity stopped).
    use_kurtosis : bool
        Label impulsive-but-aperiodic windows UNKNOWN (else NORMAL).
    statistic : ``"fold"`` or ``"ses"``
        Folded envelope (default) or the squared envelope spectrum at the fault harmonics
        (the textbook reference, ``--method envelope``).
    ses_harmonics, envelope_window_s : int, float
        Highest harmonic and shortest window of the envelope-spectrum reference.
    xcorr_lag_s : float
        Lags 0..this (s) of the thesis-literal correlation of |r| with u.
    max_lag_s : float
        A window is decided without a lagging hypothesis stream once another stream is this
        far (s) ahead of it.
    sample_rate : float or None
        The stream rate (Hz) these settings are for (their band and calibration): streams
        at another rate are refused; None: any rate.
    explain_away : bool
        Re-test the weaker hypothesis with the stronger one's impact phases masked.
    nominal_rpm : float
        Speed (rev/min) at which the decoy ratios and the calibration are computed.
    """

    window_s: float = 0.05
    hop_s: float = 0.01
    band: tuple[float, float] = (1500.0, 8000.0)
    bins: int = 16
    search: float = 0.03
    n_decoys: int = 6
    threshold: float | None = None
    kurtosis_threshold: float | None = None
    dominance: float = 1.5
    explained_margin: float = 0.1
    rms_floor: float = 1e-2
    quiet_tail: float = 0.25
    quiet_ratio: float = 0.15
    use_kurtosis: bool = True
    statistic: str = "fold"
    ses_harmonics: int = 3
    envelope_window_s: float = 0.1
    xcorr_lag_s: float = XCORR_LAG_S
    explain_away: bool = True
    nominal_rpm: float = 1800.0
    max_lag_s: float = 1.0
    sample_rate: float | None = None

    NAME = "fold"
    NEEDS_SPEED = False  # folds at the observers' fault frequencies; decoys at the nominal speed
    EVERY_STREAM = True  # explaining one hypothesis away needs the other's stream
    FOLLOWS_SPEED = False  # folds at the observers' fault periods, which assume one speed

    def unknown_k_of_n(self) -> tuple[int, int]:
        """k = ceil(window / hop) + 1 of n = k + 2: evidence spanning more than one window."""
        k = int(math.ceil(self.window_s / self.hop_s - 1e-9)) + 1
        return k, k + 2

    def with_window(self, window_s: float) -> FoldSettings:
        return replace(self, window_s=float(window_s) or self.window_s)

    def describe_window(self) -> str:
        return f"window {self.window_s:g} s"

    def with_false_alarm_rate(self, per_hour: float) -> FoldSettings:
        """Unchanged: the fold front end's budget is the configuration's ``pfa`` per window."""
        return self

    def describe_false_alarms(self, pfa: float) -> str:
        return f"false-alarm probability {pfa:g} per window and hypothesis"

    def textbook(self) -> FoldSettings:
        """The envelope spectrum at the fault harmonics instead of folding, no explain-away (masking
        impact phases would itself put a comb into the envelope spectrum), windows of at least
        ``envelope_window_s`` (the spectrum's resolution is 1/window)."""
        return replace(self, statistic="ses", explain_away=False, window_s=max(self.window_s, self.envelope_window_s))

    def check_recording(self, sample_rate: float, bearing: Bearing, rpm: float | None, duration: float,
                        usable_bandwidth: float = 0.0) -> None:
        """The band must lie below the usable bandwidth; the recording must hold one window."""
        if self.band[0] >= min(0.45 * sample_rate, usable_bandwidth or math.inf):
            raise ValueError(f"sample rate {sample_rate:g} Hz too low for the "
                             f"{self.band[0]:g}-{self.band[1]:g} Hz band")
        if duration < self.window_s:
            raise ValueError(f"recording too short: {duration:.3f} s < one {self.window_s} s window")
