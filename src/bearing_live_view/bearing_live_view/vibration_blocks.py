"""A sample stream reduced for a live plot: min, max and RMS per block of samples (no rclpy).

A plot panel draws one point per message against time, and a 48 kHz stream is 48 000 points a
second. Each block of ``block_s`` seconds of signal becomes one message with its minimum, maximum
and RMS: min and max draw the waveform's envelope (an oscilloscope's peak-detect mode), so that
every impact's peak shows, where keeping every k-th sample would miss most of them (an
outer-race impact rings for about 1 ms); the RMS draws the level. Blocks are aligned to sample
indices (block k holds indices [k·B, (k+1)·B), B = round(block_s · rate)), so the blocks do not
depend on how the sensor chunks the stream; a chunk is checked like every consumer checks one
(:class:`bearing_common.chunk_stream.ChunkStream`: refused chunks counted), and a gap or restart
drops the block it breaks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bearing_common.chunk_stream import ChunkStream


@dataclass(frozen=True)
class Block:
    """One block: ``stamp`` of its first sample (s), ``duration`` (s), min, max and RMS (signal units)."""

    stamp: float
    duration: float
    min: float
    max: float
    rms: float


class BlockReducer:
    """Chunks of one stream in, completed :class:`Block` s out.

    Parameters
    ----------
    name : str
        The stream's name, for refusal reasons.
    block_s : float
        Seconds of signal per block (> 0); at least one sample.
    """

    def __init__(self, name: str, block_s: float):
        if not block_s > 0:
            raise ValueError(f"block_s must be > 0, got {block_s!r}")
        self.block_s = float(block_s)
        self.stream = ChunkStream(name)
        self.rate: float | None = None
        self._open: tuple | None = None  # the block being filled: (first index, stamp, min, max, sum of squares, n)

    def push(self, stamp: float, first_index: int, sample_rate: float, samples) -> list[Block]:
        """One chunk (first sample at ``stamp`` s, index ``first_index``); returns the blocks it completed.
        Raises ValueError (the stream's reason) for a chunk the stream refuses."""
        x = np.asarray(samples, dtype=float)
        verdict = self.stream.check(stamp, first_index, sample_rate, x)
        if not verdict.accepted:
            raise ValueError(verdict.reason)
        if verdict.resync:
            self._open = None
        self.rate = float(sample_rate)
        size = max(1, round(self.block_s * self.rate))
        out = []
        i, k = int(first_index), 0  # stream index and chunk position of the next sample to take
        while k < x.size:
            head = -i % size  # samples to the next block boundary (0: at one)
            if self._open is None and head:  # a block begun before the stream's start or a gap: not whole
                k, i = k + head, i + head
                continue
            if self._open is None and x.size - k >= size:  # whole blocks at once
                n = (x.size - k) // size
                whole = x[k:k + n * size].reshape(n, size)
                rms = np.sqrt(np.mean(whole ** 2, axis=1))
                for j, (lo, hi, r) in enumerate(zip(whole.min(axis=1), whole.max(axis=1), rms)):
                    out.append(Block(stamp + (k + j * size) / self.rate, size / self.rate, float(lo), float(hi),
                                     float(r)))
                k, i = k + n * size, i + n * size
                continue
            start, t0, lo, hi, ss, n = self._open or (i, stamp + k / self.rate, np.inf, -np.inf, 0.0, 0)
            part = x[k:k + (start + size - i)]
            self._open = (start, t0, min(lo, part.min()), max(hi, part.max()), ss + float(part @ part), n + part.size)
            k, i = k + part.size, i + part.size
            if self._open[5] == size:
                start, t0, lo, hi, ss, n = self._open
                out.append(Block(t0, size / self.rate, float(lo), float(hi), float(np.sqrt(ss / n))))
                self._open = None
        return out
