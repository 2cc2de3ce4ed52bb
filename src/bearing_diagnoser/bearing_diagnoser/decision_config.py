"""What the decision is configured with, and the defaults per model set.

Two front ends share the rest of the decision (window schedule, hysteresis, onsets,
segments):

* ``spectral`` — real machines (:mod:`.spectral_engine`): prewhitened squared envelope
  spectrum in a band chosen from the data, harmonic and sideband combs of the OR, IR and
  BALL hypotheses searched over slip, p-values against the Gaussian-noise null. Its window
  follows the bearing and the speed (4 cage periods), so it needs no per-machine setting.
* ``fold`` — the simulator model sets (:mod:`.fold_scores`): the energy envelope of a fixed
  resonance band folded at the fault periods in 0.05 s windows, CFAR-normalised by decoy
  periods. It meets the thesis' 0.05 s detection delay on the strictly periodic,
  slip-free simulator output; the spectral front end needs 0.33 s windows at 1800 rpm to
  separate the ball hypothesis' cage sidebands, longer than the thesis' 0.2 s segments.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from .fold_scores import FoldSettings
from .spectral_engine import BASELINE, SpectralSettings

METHODS = ("spectral", "fold")


@dataclass(frozen=True)
class DiagnoserConfig:
    """Parameters of the decision.

    Attributes
    ----------
    method : ``"spectral"`` or ``"fold"``
        The front end (module docstring).
    pfa : float
        False-alarm probability per window on Gaussian noise: spectral, for all hypotheses
        together; fold, per hypothesis (its thresholds come from :mod:`.calibration`).
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
        Hysteresis for UNKNOWN (None: derived by the front end, see :mod:`.state_tracker`).
    max_lag_s : float
        A window is decided without a lagging hypothesis stream once another stream is this
        far (s) ahead of it.
    spectral, fold : settings of the two front ends.
    """

    method: str = "spectral"
    pfa: float = 1e-4
    k_of_n: tuple[int, int] = (2, 3)
    normal_k_of_n: tuple[int, int] | None = (7, 7)
    unknown_k_of_n: tuple[int, int] | None = None
    max_lag_s: float = 1.0
    spectral: SpectralSettings = field(default_factory=SpectralSettings)
    fold: FoldSettings = field(default_factory=FoldSettings)

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"unknown decision method {self.method!r}; expected one of {', '.join(METHODS)}")
        if not 0.0 < self.pfa < 0.5:
            raise ValueError(f"false-alarm probability must be in (0, 0.5), got {self.pfa!r}")


#: Defaults per model set, with reasons:
#: sim_48k / sim_12k: simulator output, strong clean impacts; 0.05 s windows, 0.01 s hop and
#:   2-of-3 hysteresis keep every detection within 0.05 s of the change (OR period 9.3 ms:
#:   5 impacts per window); band 1.5-8 kHz around the housing modes (2.2-3.6 kHz); rms_floor
#:   0.05 m/s² (0.005 g), far below any real sensor noise (CWRU normal: 0.7 m/s²) but above
#:   the noise-free simulator's NORMAL state (≈ 2e-4 m/s²); pfa 1e-4 per hypothesis.
#: every other set (real machines): the spectral front end, pfa 1e-4 per window.
MODEL_SET_DEFAULTS: dict[str, DiagnoserConfig] = {
    "sim_48k": DiagnoserConfig(method="fold", normal_k_of_n=None,
                               fold=FoldSettings(window_s=0.05, hop_s=0.01, band=(1500.0, 8000.0), rms_floor=5e-2)),
    "sim_12k": DiagnoserConfig(method="fold", normal_k_of_n=None,
                               fold=FoldSettings(window_s=0.05, hop_s=0.01, band=(1500.0, 5500.0), rms_floor=5e-2)),
}

#: Real machines: every model set not listed above, and no model set at all.
REAL_MACHINE_DEFAULTS = DiagnoserConfig()


def config_for(model_set: str, **overrides) -> DiagnoserConfig:
    """Defaults of ``model_set`` with ``overrides`` of :class:`DiagnoserConfig` fields."""
    base = MODEL_SET_DEFAULTS.get(model_set, REAL_MACHINE_DEFAULTS)
    return replace(base, **overrides) if overrides else base


def envelope_baseline(config: DiagnoserConfig) -> DiagnoserConfig:
    """The textbook squared-envelope-spectrum reference of ``config`` (``--method envelope``).

    Same band choice, thresholds, windows and hysteresis, so the comparison isolates the
    other blocks. Spectral: no prewhitening, the fundamental of each fault frequency only,
    no shaft-harmonic mask, the speed as told (:data:`.spectral_engine.BASELINE`). Fold: the
    envelope spectrum at the fault harmonics instead of folding, no explain-away (masking
    impact phases would itself put a comb into the envelope spectrum), windows of at least
    ``envelope_window_s`` (the spectrum's resolution is 1/window).
    """
    fold = config.fold
    return replace(config, spectral=replace(BASELINE, usable_bandwidth=config.spectral.usable_bandwidth,
                                            told_tolerance=config.spectral.told_tolerance,
                                            blind_range_hz=config.spectral.blind_range_hz),
                   fold=replace(fold, statistic="ses", explain_away=False,
                                window_s=max(fold.window_s, fold.envelope_window_s)))
