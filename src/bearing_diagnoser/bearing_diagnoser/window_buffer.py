"""Per-stream block buffers: the blocks of one hypothesis stream, indexed from the stream's sample 0.

A stream (one observer's residual topic) arrives in chunks with the index of their first
sample. :class:`StreamBlocks` turns them into fixed-length blocks (an
:class:`.periodicity.EnergyEnvelope`, with or without its band-pass) aligned to multiples
of the block length, so that windows of every stream line up. A gap pads NaN blocks (the
windows touching it are skipped) and restarts the envelope filter; an overlap or repeat
drops what was seen.
"""

from __future__ import annotations

import numpy as np

from .periodicity import EnergyEnvelope


class StreamBlocks:
    """Block arrays of one stream (see the module docstring).

    Attributes
    ----------
    fault_hz : float or None
        The fault frequency the stream's observer last reported (Hz).
    has_model : bool
        Whether the stream carries an identified model's estimate (not model set ``none``).
    has_train : bool
        Whether the stream has carried an impulse train (u ≠ 0).
    """

    def __init__(self, envelope: EnergyEnvelope):
        self.env = envelope
        self.next_sample: int | None = None  # index of the next expected sample
        self.first_block: int | None = None
        self._blocks: dict[str, list[np.ndarray]] = {k: [] for k in envelope.keys}
        self._arrays: dict[str, np.ndarray] = {k: np.zeros(0) for k in envelope.keys}
        self.fault_hz: float | None = None
        self.has_model = False
        self.has_train = False

    @property
    def n_blocks(self) -> int:
        """Absolute index one past the last completed block."""
        if self.first_block is None:
            return 0
        return self.first_block + self._arrays["y"].size + sum(a.size for a in self._blocks["y"])

    def _consolidate(self) -> None:
        if self._blocks["y"]:
            for k in self.env.keys:
                self._arrays[k] = np.concatenate([self._arrays[k]] + self._blocks[k])
                self._blocks[k] = []

    def push(self, first_index: int, y, r, u) -> None:
        """Append samples y, r, u (equal length) starting at stream index ``first_index``."""
        d = self.env.decimation
        if self.next_sample is None:
            skip = (-first_index) % d  # align blocks to multiples of D
            self.first_block = (first_index + skip) // d
            y, r, u = y[skip:], r[skip:], u[skip:]
            self.next_sample = first_index + skip
        elif first_index > self.next_sample:  # gap: pad with NaN blocks, restart alignment
            self._consolidate()
            gap_blocks = (first_index - self.next_sample + d - 1) // d + 1
            for k in self.env.keys:
                self._arrays[k] = np.concatenate([self._arrays[k], np.full(gap_blocks, np.nan)])
            self.env = self.env.fresh()
            target = self.n_blocks * d
            skip = target - first_index
            y, r, u = y[skip:], r[skip:], u[skip:]
            self.next_sample = target
        elif first_index < self.next_sample:  # overlap / repeat: drop what was seen
            skip = self.next_sample - first_index
            y, r, u = y[skip:], r[skip:], u[skip:]
        if y.size == 0:
            return
        out = self.env.push(y, r, u)
        for k in self.env.keys:
            self._blocks[k].append(out[k])
        self.next_sample += y.size

    def window(self, b0: int, b1: int) -> dict[str, np.ndarray] | None:
        """Blocks [b0, b1) of every key, or None when they are not (all) held."""
        self._consolidate()
        if self.first_block is None:
            return None
        i0, i1 = b0 - self.first_block, b1 - self.first_block
        if i0 < 0 or i1 > self._arrays["y"].size:
            return None
        return {k: v[i0:i1] for k, v in self._arrays.items()}

    def trim(self, keep_from_block: int) -> None:
        """Forget blocks before ``keep_from_block`` (never more than the stream holds: a silent
        stream keeps its place, so its next chunk is seen as the gap it is)."""
        self._consolidate()
        if self.first_block is None:
            return
        cut = min(keep_from_block - self.first_block, self._arrays["y"].size)
        if cut > 0:
            for k in self.env.keys:
                self._arrays[k] = self._arrays[k][cut:]
            self.first_block += cut
