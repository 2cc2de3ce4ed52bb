"""An observer's fault impulse trains on its sample grid, rendered once per update interval.

Cycle coordinates (fault ``psi``, shaft ``chi``, in cycles) are computed from the absolute
sample count since the last speed change (the *anchor*), so any chunking gives identical
values, and a speed change keeps them continuous. The trains (eq. 2.55 plain, or the three
eq. 2.58 components, :mod:`.impulse_trains`) put their impacts where ``psi`` equals the
impact cycle position :attr:`TrainCache.phase_c`; they are rendered for the samples up to the
next update boundary in one call and sliced per block (phase and speed are constant there).
"""

from __future__ import annotations

import numpy as np

from .impulse_trains import TWO_PI, impulse_train, modulated_train_components


class TrainCache:
    """Fault trains of one observer, from the speed anchor and the impact phase.

    Parameters
    ----------
    sample_rate : float
        Hz.
    pulse_width : float
        Impact pulse width (s).
    modulated : bool
        Inner race: the regressor trains are the three eq. 2.58 components; else the plain
        train is the one regressor.
    plain_only : bool
        Only the plain train is needed (no train input: the regressors are the plain train).
    update_n : int
        Samples between update boundaries; the cache never extends past the next one.
    """

    def __init__(self, sample_rate: float, pulse_width: float, modulated: bool, plain_only: bool,
                 update_n: int):
        self.sample_rate = float(sample_rate)
        self.pulse_width = pulse_width
        self.modulated = bool(modulated)
        self.plain_only = bool(plain_only)
        self.update_n = int(update_n)
        self.frequency = 0.0        #: fault impact frequency (Hz)
        self.shaft_frequency = 0.0  #: shaft frequency (Hz)
        self.phase_c = 0.0          #: impact cycle position (cycles)
        self.reset()

    def reset(self) -> None:
        """Anchor the cycle coordinates at sample 0 (both 0 there); drop the cache."""
        self.n_base = 0      #: absolute sample of the anchor
        self.psi_base = 0.0  #: fault cycle coordinate at the anchor (cycles)
        self.chi_base = 0.0  #: shaft cycle coordinate at the anchor (cycles)
        self._cached = None

    def set_speed(self, n_now: int, frequency: float, shaft_frequency: float) -> None:
        """New fault and shaft frequencies (Hz) from absolute sample ``n_now`` on; the cycle
        coordinates are re-anchored there, so they stay continuous."""
        self.psi_base, self.chi_base = self.cycles(n_now)
        self.n_base = n_now
        self.frequency = frequency
        self.shaft_frequency = shaft_frequency
        self._cached = None

    def set_phase(self, phase_c: float) -> None:
        """Impact cycle position (cycles) of the trains from now on; drops the cache."""
        self.phase_c = phase_c
        self._cached = None

    def cycles(self, n_abs):
        """Fault and shaft cycle positions (cycles, in [0, 1)) at absolute sample(s) n_abs."""
        t = (np.asarray(n_abs) - self.n_base) / self.sample_rate
        return (np.mod(self.psi_base + self.frequency * t, 1.0),
                np.mod(self.chi_base + self.shaft_frequency * t, 1.0))

    def render(self, n_start: int, n_end: int):
        """Unit plain train and regressor trains (shape (p, n)) for absolute samples
        ``[n_start, n_end)``, kept for the blocks up to ``n_end``.

        Pulse positions are computed per sample from the speed anchor, so a slice equals
        the block rendered on its own (to rounding of the sub-sample position, ~1e-12) and
        does not depend on how the stream is chunked.
        """
        self._cached = (n_start, n_end) + self._trains(n_end - n_start, n_start)
        return self._cached[2:]

    def block(self, n_now: int, n: int):
        """Unit train and regressor trains for the ``n`` samples from absolute sample
        ``n_now``, which never cross an update boundary (slices of the cache)."""
        c = self._cached
        if c is None or not (c[0] <= n_now and n_now + n <= c[1]):
            self.render(n_now, (n_now // self.update_n + 1) * self.update_n)
            c = self._cached
        i = n_now - c[0]
        return c[2][i:i + n], c[3][:, i:i + n]

    def _trains(self, n: int, n_start: int):
        """The trains of :meth:`render` (impact times from the speed anchor: independent of
        block boundaries)."""
        fs = self.sample_rate
        ph = TWO_PI * (self.psi_base - self.phase_c)
        i0 = int(n_start - self.n_base)
        if self.modulated and not self.plain_only:
            comps = modulated_train_components(n, fs, self.frequency, ph, start_index=i0,
                                               shaft_frequency=self.shaft_frequency,
                                               shaft_phase=TWO_PI * self.chi_base,
                                               pulse_width=self.pulse_width)
            return comps[2], comps
        unit = impulse_train(n, fs, self.frequency, ph, start_index=i0, pulse_width=self.pulse_width)
        return unit, unit[None, :]
