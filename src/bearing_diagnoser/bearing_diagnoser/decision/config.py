"""What the decision is configured with: the front end's settings and the core's own.

The core (window labels to published states) is the same for both front ends; the front
end is named by its settings (:mod:`bearing_diagnoser.spectral.settings`,
:mod:`bearing_diagnoser.fold.settings`), which :mod:`bearing_diagnoser.front_ends` picks
per model set. Settings of either front end answer the questions the core and the tools
ask (:class:`FrontEndSettings`), so that nothing outside that picker asks which one it is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from bearing_common.bearings import Bearing


class FrontEndSettings(Protocol):
    """What every front end's settings say about it.

    ``NAME``: "spectral" or "fold"; ``NEEDS_SPEED``: whether the decision misses faults
    without a told shaft speed (it then warns); ``EVERY_STREAM``: whether it needs every
    observer stream, or one measurement suffices; ``FOLLOWS_SPEED``: whether it can decide on
    a changing speed (resampled to shaft angle: :meth:`.front_end.FrontEnd.follow_speed`).
    """

    NAME: str
    NEEDS_SPEED: bool
    EVERY_STREAM: bool
    FOLLOWS_SPEED: bool

    def unknown_k_of_n(self) -> tuple[int, int]:
        """UNKNOWN hysteresis when the configuration states none (:mod:`.state_tracker`)."""

    def with_window(self, window_s: float):
        """These settings with an analysis window of ``window_s`` s (0: the front end's own)."""

    def describe_window(self) -> str:
        """The window, for a log line."""

    def with_false_alarm_rate(self, per_hour: float):
        """These settings with a false-alarm budget of ``per_hour`` per hour of healthy operation
        (0: the front end's own); a front end whose budget is per window (``pfa``) ignores it."""

    def describe_false_alarms(self, pfa: float) -> str:
        """The false-alarm budget in use (``pfa``: the configuration's, per window), for a log line."""

    def textbook(self):
        """The textbook squared-envelope-spectrum reference of these settings (``--method envelope``)."""

    def check_recording(self, sample_rate: float, bearing: Bearing, rpm: float | None, duration: float,
                        usable_bandwidth: float) -> None:
        """ValueError (one line) when a recording cannot be diagnosed at all."""


@dataclass(frozen=True)
class DiagnoserConfig:
    """Parameters of the decision.

    Attributes
    ----------
    front_end : SpectralSettings or FoldSettings
        The front end and its settings (module docstring).
    pfa : float
        False-alarm probability per window and hypothesis on Gaussian noise of the fold front
        end (its thresholds come from its calibration). The spectral front end states its
        budget per hour instead (:attr:`.spectral.settings.SpectralSettings.false_alarm_rate`)
        and does not use ``pfa``.
    k_of_n : (k, n)
        Hysteresis: a new state needs k of the last n window labels. The first window sets
        the initial state directly (unless it is UNKNOWN).
    normal_k_of_n : (k, n) or None
        Hysteresis for a return to NORMAL (None: ``k_of_n``). On real machines a NORMAL
        window means "no fault evidence in this window", which a faulty bearing's window
        can show, so returning needs more agreement than leaving: with (7, 7) a fault whose
        windows show evidence at least half the time falls back to NORMAL with probability
        0.5⁷ < 1 % per window (1.2 s of absent evidence at 1800 rpm, 3.5 s at 600 rpm).
    unknown_k_of_n : (k, n) or None
        Hysteresis for UNKNOWN (None: the front end's, :meth:`FrontEndSettings.unknown_k_of_n`).
    usable_bandwidth : float
        Hz up to which the sensor chain measures (0: up to 0.45·fs).
    """

    front_end: FrontEndSettings
    pfa: float = 1e-4
    k_of_n: tuple[int, int] = (2, 3)
    normal_k_of_n: tuple[int, int] | None = (7, 7)
    unknown_k_of_n: tuple[int, int] | None = None
    usable_bandwidth: float = 0.0

    def __post_init__(self):
        if not 0.0 < self.pfa < 0.5:
            raise ValueError(f"false-alarm probability must be in (0, 0.5), got {self.pfa!r}")

    @property
    def method(self) -> str:
        """The front end's name ("spectral" or "fold")."""
        return self.front_end.NAME

    def unknown_rule(self) -> tuple[int, int]:
        """The UNKNOWN hysteresis in use."""
        return self.unknown_k_of_n or self.front_end.unknown_k_of_n()
