"""Anti-aliased sample-rate conversion of recordings (polyphase, Kaiser window)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy import signal


def resample(x: np.ndarray, rate_in: float, rate_out: float) -> np.ndarray:
    """``x`` sampled at ``rate_in`` Hz resampled to ``rate_out`` Hz (scipy.signal.resample_poly).

    The ratio is approximated by a fraction with denominator ≤ 1000 (relative rate error
    below 1e-6 for the usual rates).
    """
    if abs(rate_in - rate_out) < 1e-9 * rate_out:
        return x
    frac = Fraction(rate_out / rate_in).limit_denominator(1000)
    return signal.resample_poly(x, frac.numerator, frac.denominator)
