"""WAV recordings (RIFF WAVE), as handheld collectors and sound cards export vibration.

Linear PCM of 1-64 bits and IEEE float of 32 or 64 bits, one or more channels (scipy's
reader). The numbers: float samples as stored; integer samples as fractions of full scale,
−1 ≤ v < 1 (8-bit unsigned about its midpoint 128). A WAV file does not say what they
measure, so ``--units`` or ``--sensitivity`` must (:mod:`.measurement_units`; for integer
samples a sensitivity in fractions of full scale per g, e.g. ``0.05/g`` for ±20 g).
``channel`` picks a channel by number from 1 (required when there are several).
"""

from __future__ import annotations

import warnings

import numpy as np

from .measurement_units import value_scale
from .recording import InputError, Recording, check_rate, check_rpm, check_samples

#: File name suffixes read as WAV.
WAV_SUFFIXES = (".wav",)


def full_scale_fraction(data: np.ndarray) -> np.ndarray:
    """Integer PCM (scipy's left-justified integers) as fractions of full scale; float as stored."""
    if data.dtype.kind == "f":
        return data.astype(float)
    if data.dtype == np.uint8:
        return (data.astype(float) - 128.0) / 128.0
    return data.astype(float) / float(2 ** (8 * data.dtype.itemsize - 1))


def load_wav(path, sample_rate: float | None = None, rpm: float | None = None, channel: str | None = None,
             units: str | None = None, sensitivity: str | None = None) -> Recording:
    """A WAV recording in m/s² (module docstring); ``sample_rate`` (Hz) overrides the file's."""
    from scipy.io import wavfile

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)  # unknown chunks (metadata) are skipped
            rate, data = wavfile.read(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.__class__.__name__}: {exc})") from None
    except Exception as exc:  # scipy raises ValueError and others on files that are not PCM/float WAV
        raise InputError(f"{path}: not a readable WAV file ({' '.join(str(exc).split())})") from None
    if data.dtype.kind not in "fiu":
        raise InputError(f"{path}: WAV samples of type {data.dtype} are not supported (PCM or float expected)")
    channels = 1 if data.ndim == 1 else data.shape[1]
    if channel is None and channels > 1:
        raise InputError(f"{path}: {channels} channels; give --channel 1 to {channels}")
    pick = 1 if channel is None else channel
    if not (str(pick).isdigit() and 1 <= int(pick) <= channels):
        raise InputError(f"{path}: no channel {pick!r}; a WAV file's channels are numbered 1 to {channels}")
    samples = data if data.ndim == 1 else data[:, int(pick) - 1]
    try:
        fs = check_rate(rate if sample_rate is None else sample_rate)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    scale, _ = value_scale(units, sensitivity, f"{path}", integer_fraction=data.dtype.kind != "f",
                           default_units=None)
    kind = f"{8 * data.dtype.itemsize}-bit {'float' if data.dtype.kind == 'f' else 'integer PCM'}"
    x = check_samples(full_scale_fraction(samples), f"{path}:{pick}") * scale
    return Recording(x, fs, None if rpm is None else check_rpm(rpm), "wav", None, str(pick), str(path),
                     notes=[f"WAV {kind}, {channels} channel(s), {rate} Hz; channel {pick}"])
