"""What the spectral decision saw in its last window, for plotting (the ``envelope_spectrum`` topic).

The one hook between the decision and the live view: :meth:`.evidence_stream.EvidenceStream._evidence`
keeps, per window it tests, the normalised squared envelope spectrum it computed anyway (no extra
FFT), with the geometry it tested, as an :class:`EnvelopeView`; the front end hands out the last one
(:meth:`.front_end.SpectralFrontEnd.envelope_view`). Decimating and filling the message is the
diagnoser's (:mod:`bearing_diagnoser.spectrum_message`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bearing_common.states import FaultState


@dataclass(frozen=True)
class EnvelopeView:
    """One window's normalised SES and where each hypothesis' comb lines lie.

    ``end``: sample index after the window's last sample (the decision's index domain);
    ``length``: samples in the window; ``ses``: the normalised SES
    (:func:`.envelope_spectrum.normalise`, median ≈ 1 on noise), bin k at k·``bin_width`` Hz (the
    decision's own array: not to be modified); ``band``: the demodulation band (Hz); ``f_top``:
    the highest comb line tested (Hz; the tested range is [0, f_top]); ``shaft_hz``: the shaft
    rate the window was tested at and ``shaft_source`` where it came from (``"told"``,
    ``"refined"``, ``"provisional"``, ``"measured"``, ``"estimated"``); ``told_hz``: the told rate (None: none told);
    ``terms``: {hypothesis: (J, 3) array of (c, d, is_carrier)}, a line at (c·ρ + d)·f_r
    (:func:`.fault_combs.comb_terms`); ``rho``: {hypothesis: ρ where its comb matched best}.
    """

    end: int
    length: int
    sample_rate: float
    ses: np.ndarray
    bin_width: float
    band: tuple[float, float]
    f_top: float
    shaft_hz: float
    shaft_source: str
    told_hz: float | None
    terms: dict
    rho: dict

    def lines(self, hypothesis: FaultState, shaft_hz: float) -> np.ndarray:
        """Frequencies (Hz) of ``hypothesis``' comb lines at shaft rate ``shaft_hz``, without slip (ρ = 1)."""
        t = self.terms[hypothesis]
        return (t[:, 0] + t[:, 1]) * shaft_hz
