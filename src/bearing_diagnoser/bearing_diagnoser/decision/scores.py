"""What one window shows, as a typed record: the numbers every decision carries.

Both front ends fill the common part; each adds its own fields in a subclass
(:class:`bearing_diagnoser.spectral.front_end.SpectralScores`,
:class:`bearing_diagnoser.fold.scoring.FoldScores`). The names under which the numbers are
published — FaultState ``hypotheses``/``scores``, ``/diagnostics`` key-values, the JSON
segments — are made here and in the subclasses only (:meth:`WindowScores.as_dict`), at the
edge: inside the decision the numbers travel by field and by hypothesis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

from bearing_common.states import FaultState


@dataclass
class WindowScores:
    """The common part.

    Attributes
    ----------
    rms : float
        RMS of the window's measurement (m/s²).
    significance : dict
        {hypothesis: the front end's statistic ÷ its threshold}: ≥ 1 is significant
        (published as ``<hypothesis>``).
    explained, xcorr : dict
        {observer stream's hypothesis: the thesis' blocks} (:mod:`.thesis_blocks`):
        published as ``<hypothesis>_explained`` and ``<hypothesis>_xcorr``; only for streams
        that carry an identified model's estimate (explained) or an impulse train (xcorr).
    """

    rms: float = math.nan
    significance: dict = field(default_factory=dict)
    explained: dict = field(default_factory=dict)
    xcorr: dict = field(default_factory=dict)

    #: Names summarised per segment (median over its windows), in the order the JSON lists them.
    SUMMARY_KEYS: ClassVar[tuple[str, ...]] = ()

    def thesis_items(self) -> dict[str, float]:
        """The thesis' blocks by published name, stream by stream."""
        out: dict[str, float] = {}
        for h in dict.fromkeys([*self.explained, *self.xcorr]):
            if h in self.explained:
                out[f"{h.label}_explained"] = self.explained[h]
            if h in self.xcorr:
                out[f"{h.label}_xcorr"] = self.xcorr[h]
        return out

    def speed_warning(self) -> str:
        """Why the speed the window used is not the told one ("" when it is, or none was measured)."""
        return ""

    def as_dict(self) -> dict[str, float]:
        """Every number by its published name."""
        out = {h.label: v for h, v in self.significance.items()}
        out["rms"] = self.rms
        out.update(self.thesis_items())
        return out


#: The thesis' blocks of the two observer streams, in the order the JSON lists them.
THESIS_SUMMARY_KEYS = tuple(f"{h.label}_{k}" for k in ("explained", "xcorr")
                            for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE))
