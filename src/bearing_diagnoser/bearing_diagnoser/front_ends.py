"""Which front end decides: the defaults per model set, the textbook baseline, and the one table of front ends.

Two front ends share the rest of the decision (window schedule, hysteresis, onsets,
segments: :mod:`.decision`):

* ``spectral`` — real machines (:mod:`.spectral`): prewhitened squared envelope spectrum in
  a band chosen from the data, harmonic and sideband combs of the OR, IR and BALL
  hypotheses searched over slip, p-values against the Gaussian-noise null. Its window
  follows the bearing and the speed (4 cage periods), so it needs no per-machine setting.
* ``fold`` — the simulator model sets (:mod:`.fold`): the energy envelope of a fixed
  resonance band folded at the fault periods in 0.05 s windows, CFAR-normalised by decoy
  periods. It meets the thesis' 0.05 s detection delay on the strictly periodic,
  slip-free simulator output; the spectral front end needs 0.33 s windows at 1800 rpm to
  separate the ball hypothesis' cage sidebands, longer than the thesis' 0.2 s segments.

This module is the only one that names both; everything else asks the settings
(:class:`.decision.config.FrontEndSettings`) or the front end
(:class:`.decision.front_end.FrontEnd`).
"""

from __future__ import annotations

from dataclasses import replace

from bearing_common.bearings import Bearing
from bearing_common.model_set_info import SHIPPED_SETS

from .decision.config import DiagnoserConfig
from .decision.front_end import FrontEnd
from .fold.front_end import FoldFrontEnd
from .fold.settings import FoldSettings
from .spectral.front_end import SpectralFrontEnd
from .spectral.settings import SpectralSettings

#: Defaults per model set, with reasons:
#: sim_48k / sim_12k: simulator output, strong clean impacts; 0.05 s windows, 0.01 s hop and
#:   3-of-4 hysteresis keep every detection within 0.05 s of the change (OR period 9.3 ms:
#:   5 impacts per window). A state needs three of four windows, not two of three: windows
#:   0.01 s apart share 80 % of their samples, and where an inner-race fault's impacts line up
#:   with the outer race's period for a moment (1800 rpm: every 28.9 s) two of three windows
#:   labelled OUTER_RACE and the state flipped for 0.03 s (3 times in 150 s of inner race; with
#:   3-of-4, 0 there, and still 0 in 40 s each of outer race and normal, every thesis case's onset
#:   within 0.05 s); band 1.5-8 kHz around the housing modes (2.2-3.6 kHz); rms_floor
#:   0.05 m/s² (0.005 g), far below any real sensor noise (CWRU normal: 0.7 m/s²) but above
#:   the noise-free simulator's NORMAL state (≈ 2e-4 m/s²); pfa 1e-4 per hypothesis; the
#:   streams at the set's own rate.
#: every other set (real machines): the spectral front end, pfa 1e-4 per window.
MODEL_SET_DEFAULTS: dict[str, DiagnoserConfig] = {
    "sim_48k": DiagnoserConfig(FoldSettings(window_s=0.05, hop_s=0.01, band=(1500.0, 8000.0), rms_floor=5e-2,
                                            sample_rate=SHIPPED_SETS["sim_48k"].sample_rate),
                                k_of_n=(3, 4), normal_k_of_n=None),
    "sim_12k": DiagnoserConfig(FoldSettings(window_s=0.05, hop_s=0.01, band=(1500.0, 5500.0), rms_floor=5e-2,
                                            sample_rate=SHIPPED_SETS["sim_12k"].sample_rate),
                                k_of_n=(3, 4), normal_k_of_n=None),
}

#: Real machines: every model set not listed above, and no model set at all.
REAL_MACHINE_DEFAULTS = DiagnoserConfig(SpectralSettings())

#: The front end of each kind of settings.
_FRONT_ENDS = {SpectralSettings: SpectralFrontEnd, FoldSettings: FoldFrontEnd}


def config_for(model_set: str, **overrides) -> DiagnoserConfig:
    """Defaults of ``model_set`` with ``overrides`` of :class:`DiagnoserConfig` fields."""
    base = MODEL_SET_DEFAULTS.get(model_set, REAL_MACHINE_DEFAULTS)
    return replace(base, **overrides) if overrides else base


def envelope_baseline(config: DiagnoserConfig) -> DiagnoserConfig:
    """The textbook squared-envelope-spectrum reference of ``config`` (``--method envelope``).

    Same thresholds, windows and hysteresis, so the comparison isolates the other blocks.
    Spectral: no prewhitening, the fundamental of each fault frequency only, no
    shaft-harmonic mask, the speed as told, the kurtogram's band
    (:data:`.spectral.settings.BASELINE`). Fold: the envelope spectrum at the fault
    harmonics instead of folding (:meth:`.fold.settings.FoldSettings.textbook`).
    """
    return replace(config, front_end=config.front_end.textbook())


NO_REFERENCE = ("a machine reference is used by the spectral decision (real machines) only, not by the fold "
                "decision of the simulator's model sets")


def takes_reference(config: DiagnoserConfig) -> bool:
    """Whether ``config``'s front end judges against a machine reference (the spectral one)."""
    return isinstance(config.front_end, SpectralSettings)


def with_reference(config: DiagnoserConfig, reference) -> DiagnoserConfig:
    """``config`` judging against the machine's own healthy reference
    (:class:`.spectral.machine_reference.MachineReference`; None: blind, ``config`` as it is); ValueError
    for the fold front end (the simulator's model sets), which takes none."""
    if reference is None:
        return config
    if not takes_reference(config):
        raise ValueError(NO_REFERENCE)
    return replace(config, front_end=config.front_end.with_reference(reference))


def build_front_end(config: DiagnoserConfig, sample_rate: float, bearing: Bearing) -> FrontEnd:
    """The front end of ``config`` for streams at ``sample_rate`` (Hz); ValueError when it cannot
    decide them."""
    return _FRONT_ENDS[type(config.front_end)](config, sample_rate, bearing)
