"""Everything the decision computes once, done before the first window: compiled kernels and p-value tables.

Compiles (the first run after an install: about 15 s) or loads from numba's cache every
kernel with the argument types the decision uses (folding tables are read-only uint16
offsets and float weights; block sums are written into a stream's block store, a strided
view), and tabulates the comb p-values (about 2 s), so that no live window waits for
either. The folding thresholds of the simulator model sets are the fold front end's own
(:meth:`bearing_diagnoser.diagnoser.Diagnoser.warm_up`).
"""

from __future__ import annotations

import numpy as np

from .decision.stream_blocks import block_sums, sos_filter
from .decision.thesis_blocks import _train_correlation
from .fold.folding import _explain_away, _impact_phase_mask, cfar_fold, fold_peakiness
from .fold.scoring import all_finite, window_sums
from .spectral import significance
from .spectral.envelope_spectrum import normalise


def warm_up() -> None:
    """Compile or load every kernel and fill the p-value tables (see the module docstring)."""
    significance.warm_up()
    z = np.zeros(16)
    normalise(z[None, :])
    sos_filter(np.array([[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]]), np.zeros((1, 2)), z, np.zeros(16))
    block_sums(z, z, z, z, 4, np.zeros((7, 4)))
    block_sums(z, z, z, z, 4, np.zeros((7, 8))[:, 4:])  # into a stream's block store (strided)
    offsets, inv = np.zeros((16, 4), np.uint16), np.ones(64)
    offsets.setflags(write=False)
    inv.setflags(write=False)
    fold_peakiness(z, offsets, inv, 16, 2)
    cfar_fold(z, offsets, inv, 2, 16, 2)
    _explain_away(z, _impact_phase_mask(z, 4000.0, 100.0, 16, 2, 1))
    _train_correlation(z, z, 2)
    window_sums(z, z, z, z, z, 4)
    all_finite(z)
