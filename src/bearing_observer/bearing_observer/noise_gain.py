"""White-noise gain of an observer's residual filter: measured, and the linearised H2 norm.

The thesis' appendix D poles amplified white measurement noise 43-96 times
(:mod:`.realization`); these say how much the chosen gain ``L`` passes, as
RMS(residual) / RMS(noise): 1.0 for ``L = 0`` (the residual is then ``y - g(model
response)`` and the train input is off).
"""

from __future__ import annotations

import numpy as np

from .realization import ModalFilter


def measured_noise_gain(observer) -> float:
    """RMS(residual) / RMS(noise) of seeded white Gaussian noise run through ``observer``.

    ``observer`` is a fresh :class:`~.observer.FaultObserver` with the train input off
    (``drive="off"``). The noise RMS is 1e-3 of the output nonlinearity's largest breakpoint
    magnitude (in g's local linear range), over ``max(20000, 0.5 s)`` samples; the first
    tenth is left out (the filter's start).
    """
    g = observer.model.output_nonlinearity
    sigma = 1e-3 * float(np.max(np.abs(g.y)))
    rng = np.random.default_rng(12345)
    n = int(max(20000, 0.5 * observer.sample_rate))
    v = sigma * rng.standard_normal(n)
    r = observer.process(v).residual
    skip = n // 10
    return float(np.sqrt(np.mean(r[skip:] ** 2)) / np.sqrt(np.mean(v[skip:] ** 2)))


def analytic_noise_gain(A, B, C, D, L, n: int = 1 << 16) -> float:
    """H2 norm of the linearised map ``z_tilde -> z_tilde - z_hat`` (its first ``n`` impulse
    response samples) for the realization ``(A, B, C, D)`` and the observer gain ``L``."""
    if not np.any(L):
        return 1.0
    imp = np.zeros(n)
    imp[0] = 1.0
    f = ModalFilter(A - L @ C, B - L @ D, L, C, D)
    h = imp - f.run(np.zeros(n), imp)
    return float(np.sqrt(np.sum(h * h)))
