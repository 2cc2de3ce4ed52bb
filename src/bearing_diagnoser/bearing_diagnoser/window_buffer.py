"""Per-stream block buffers: the blocks of one hypothesis stream, indexed from the stream's sample 0.

A stream (one observer's residual topic) arrives in chunks with the index of their first
sample. :class:`StreamBlocks` turns them into fixed-length blocks (an
:class:`.periodicity.EnergyEnvelope`, with or without its band-pass) aligned to multiples
of the block length, so that windows of every stream line up. A gap pads NaN blocks (the
windows touching it are skipped) and restarts the envelope filter; a gap longer than
:data:`MAX_PAD_BLOCKS` blocks begins the stream afresh after it instead (a producer's index
jumping far ahead must not allocate the hole); an overlap or repeat drops what was seen.
"""

from __future__ import annotations

import numpy as np

from .periodicity import EnergyEnvelope

#: Longest gap padded with NaN blocks (2¹⁶ blocks: tens of seconds at the envelope rates used).
MAX_PAD_BLOCKS = 1 << 16


class StreamBlocks:
    """Block arrays of one stream (see the module docstring).

    The blocks live in one array of shape (len(keys), capacity), columns ``_start`` to
    ``_fill``; it doubles when full and is shifted down only when the forgotten part is
    as large as the held one, so that a chunk costs no copy of the held blocks.

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
        self._begin()
        self.fault_hz: float | None = None
        self.has_model = False
        self.has_train = False

    def _begin(self) -> None:
        """Hold nothing: the next chunk starts the blocks (and their alignment) afresh."""
        self.next_sample: int | None = None  # index of the next expected sample
        self.first_block: int | None = None  # absolute index of column _start
        self._store = np.zeros((len(self.env.keys), 0))
        self._start = 0
        self._fill = 0

    @property
    def n_blocks(self) -> int:
        """Absolute index one past the last completed block."""
        if self.first_block is None:
            return 0
        return self.first_block + self._fill - self._start

    def _reserve(self, m: int) -> np.ndarray:
        """The next ``m`` columns (a view, counted as held), for the caller to fill."""
        if self._fill + m > self._store.shape[1]:
            held = self._fill - self._start
            if held + m > self._store.shape[1] // 2:  # grow; else shift down into the free half
                grown = np.zeros((self._store.shape[0], max(2 * self._store.shape[1], 2 * (held + m), 64)))
                grown[:, :held] = self._store[:, self._start:self._fill]
                self._store = grown
            else:
                self._store[:, :held] = self._store[:, self._start:self._fill]
            self._start, self._fill = 0, held
        self._fill += m
        return self._store[:, self._fill - m:self._fill]

    def push(self, first_index: int, y, r, u) -> None:
        """Append samples y, r, u (equal length) starting at stream index ``first_index``."""
        d = self.env.decimation
        if self.next_sample is not None and first_index - self.next_sample > MAX_PAD_BLOCKS * d:
            self.env = self.env.fresh()  # a long gap: begin afresh there instead of padding it
            self._begin()
        if self.next_sample is None:
            skip = (-first_index) % d  # align blocks to multiples of D
            self.first_block = (first_index + skip) // d
            y, r, u = y[skip:], r[skip:], u[skip:]
            self.next_sample = first_index + skip
        elif first_index > self.next_sample:  # gap: pad with NaN blocks, restart alignment
            gap_blocks = (first_index - self.next_sample + d - 1) // d + 1
            self._reserve(gap_blocks)[:] = np.nan
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
        self.env.blocks(y, r, u, out=self._reserve(self.env.completed(y.size)))
        self.next_sample += y.size

    def window(self, b0: int, b1: int) -> dict[str, np.ndarray] | None:
        """Blocks [b0, b1) of every key (views, valid until the next push), or None when they
        are not (all) held."""
        if self.first_block is None:
            return None
        i0, i1 = b0 - self.first_block, b1 - self.first_block
        if i0 < 0 or i1 > self._fill - self._start:
            return None
        cols = self._store[:, self._start + i0:self._start + i1]
        return dict(zip(self.env.keys, cols))

    def trim(self, keep_from_block: int) -> None:
        """Forget blocks before ``keep_from_block`` (never more than the stream holds: a silent
        stream keeps its place, so its next chunk is seen as the gap it is)."""
        if self.first_block is None:
            return
        cut = min(keep_from_block - self.first_block, self._fill - self._start)
        if cut > 0:
            self._start += cut
            self.first_block += cut
