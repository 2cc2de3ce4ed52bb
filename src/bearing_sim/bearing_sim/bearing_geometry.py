"""Rolling-element bearing geometry and its characteristic fault frequencies.

Thesis section 2.2, eqs. 2.51-2.54, for a deep-groove ball bearing with a
stationary outer ring. Lengths in metres, frequencies in Hz.
"""

from dataclasses import dataclass
import math

from .fault_states import FaultState

INCH = 0.0254  # m per inch


@dataclass(frozen=True)
class BearingGeometry:
    """Geometry of one ball bearing.

    Attributes: ``n_balls``; ``ball_diameter`` Bd (m); ``pitch_diameter`` Pd (m);
    ``contact_angle`` phi (rad).
    """

    name: str
    n_balls: int
    ball_diameter: float
    pitch_diameter: float
    contact_angle: float = 0.0

    def __post_init__(self):
        if self.n_balls < 1:
            raise ValueError(f"n_balls must be >= 1, got {self.n_balls}")
        if not 0.0 < self.ball_diameter < self.pitch_diameter:
            raise ValueError("need 0 < ball_diameter < pitch_diameter")

    @property
    def _ratio(self) -> float:
        return self.ball_diameter / self.pitch_diameter * math.cos(self.contact_angle)

    def ftf(self, shaft_hz: float) -> float:
        """Fundamental train (cage) frequency, eq. 2.51 (Hz)."""
        return 0.5 * shaft_hz * (1.0 - self._ratio)

    def bsf(self, shaft_hz: float) -> float:
        """Ball spin frequency, eq. 2.52 (Hz)."""
        return self.pitch_diameter / (2.0 * self.ball_diameter) * shaft_hz * (1.0 - self._ratio**2)

    def bpfo(self, shaft_hz: float) -> float:
        """Ball pass frequency, outer race: N * FTF, eq. 2.53 (Hz)."""
        return self.n_balls * self.ftf(shaft_hz)

    def bpfi(self, shaft_hz: float) -> float:
        """Ball pass frequency, inner race: N * (shaft - FTF), eq. 2.54 (Hz)."""
        return self.n_balls * (shaft_hz - self.ftf(shaft_hz))


#: Drive-end bearing of the CWRU motor, SKF 6205-2RS JEM (BPFO 3.5848, BPFI 5.4152 x shaft).
DRIVE_END_6205 = BearingGeometry("SKF 6205-2RS JEM", 9, 0.3126 * INCH, 1.537 * INCH)
#: Fan-end bearing of the CWRU motor, SKF 6203-2RS JEM (BPFO 3.0530 x shaft).
FAN_END_6203 = BearingGeometry("SKF 6203-2RS JEM", 8, 0.2656 * INCH, 1.122 * INCH)


def shaft_hz(rpm: float) -> float:
    """Shaft rotation frequency (Hz) from speed in rev/min."""
    return rpm / 60.0


def fault_frequency(geometry: BearingGeometry, fault: int, rpm: float) -> float:
    """Impact frequency (Hz) of an outer- (1) or inner-race (2) defect at ``rpm``."""
    fr = shaft_hz(rpm)
    if fault == FaultState.OUTER_RACE:
        return geometry.bpfo(fr)
    if fault == FaultState.INNER_RACE:
        return geometry.bpfi(fr)
    raise ValueError(f"no race fault frequency for state {fault!r}")
