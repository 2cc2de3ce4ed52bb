"""The classical reference detector: squared envelope spectrum (SES), ``--method envelope``.

No model and no observer: the measurement is band-passed over a fixed resonance band
(per model set: 1.5-8 kHz for the simulator, 2-5 kHz for the CWRU drive end, where the
impacts ring), squared, block-averaged to about 4 kHz (the squared envelope), and its
spectrum is examined at BPFO and BPFI ± 3 % (slip 1-2 % plus speed error), harmonics 1-3
except those that coincide with a harmonic of the other race (3·BPFO and 2·BPFI lie 0.7 %
apart: OR uses 1, 2 and IR 1, 3); each harmonic's peak is CFAR-normalised on its own and
the largest ratio counts.  Windows of at least 0.1 s (0.2 s on CWRU data): the envelope
spectrum's resolution is 1/window (thesis section 2.2, eqs. 2.53-2.54 for the
frequencies; Randall & Antoni's envelope analysis for the method).  The CFAR reference is
the median peak at decoy frequencies clear of every bearing line, the threshold the
(1 − pfa) quantile on white noise (:mod:`.calibration`), and the window labels go through the same hysteresis, onset and segment logic
as the model method, so the two compare like for like.

Optional cepstrum prewhitening (``prewhiten=True``: X/|X| over the whole record, which
removes discrete lines and the resonance colouring) is applied offline before the band
pass.  Spectral-kurtosis band selection is not implemented (fixed bands, stated above).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from bearing_common.bearings import CATALOG, fault_frequency

DRIVE_END_6205 = CATALOG["6205"]  # TODO(issue 11): bearing as input

from .decision import HYPOTHESES, Decision, Diagnoser, DiagnoserConfig


def cepstrum_prewhiten(x: np.ndarray) -> np.ndarray:
    """Cepstrum prewhitening: inverse FFT of X/|X| (unit magnitude, phase kept), same RMS scale."""
    X = np.fft.rfft(x - np.mean(x))
    mag = np.abs(X)
    X = np.where(mag > 0, X / np.where(mag > 0, mag, 1.0), 0.0)
    y = np.fft.irfft(X, x.size)
    s = np.std(y)
    return y * (np.std(x) / s) if s > 0 else y


class EnvelopeDiagnoser:
    """SES reference detector with the same interface as the offline model pipeline.

    Parameters
    ----------
    config : DiagnoserConfig
        Window, band, pfa, hysteresis (the window is at least ``envelope_window_s``,
        ``statistic`` is forced to ``"ses"`` and
        ``explain_away`` off: the classical method has no such step, and masking
        impact phases would itself put a comb into the envelope spectrum).
    model_set : str
        Only names the defaults and the output.
    prewhiten : bool
        Cepstrum-prewhiten the whole record first (offline only).
    """

    def __init__(self, config: DiagnoserConfig, model_set: str = "", prewhiten: bool = False):
        self.config = replace(config, statistic="ses", explain_away=False,
                              window_s=max(config.window_s, config.envelope_window_s))
        self.model_set = model_set
        self.prewhiten = prewhiten
        self.diagnoser = Diagnoser(self.config, model_set)

    def run(self, x: np.ndarray, fs: float, rpm: float, chunk: int = 480) -> list[Decision]:
        """Diagnose the whole measurement ``x`` (m/s², rate ``fs`` Hz) at ``rpm``."""
        if self.prewhiten:
            x = cepstrum_prewhiten(x)
        ff = {h: fault_frequency(DRIVE_END_6205, h, rpm) for h in HYPOTHESES}
        out: list[Decision] = []
        for i in range(0, x.size, chunk):
            for h in HYPOTHESES:
                out += self.diagnoser.update(h, i, fs, x[i:i + chunk], None, None, ff[h])
        out += self.diagnoser.flush()
        return out
