"""Re-cutting a chunked sample stream into chunks of another length (no rclpy).

``bearing-bag play --chunk-duration S`` publishes a recorded ``VibrationChunk`` stream as a
sensor that sends S-second chunks would have: every sample keeps its stream index, and a
chunk's stamp is the time of its first sample, taken from the recorded chunk that holds
that sample (stamp + offset / rate, in integer nanoseconds; a cut on a recorded chunk's
boundary keeps its stamp exactly). A chunk goes out once its last sample has been
recorded. Chunks are cut from the first sample of a run of consecutive samples: a gap in
the indices, an index going back (a restarted producer), another sample rate, source or
frame ends the run, and its last, shorter chunk goes out first, so the receivers see the
same gap or restart as in the recording.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class SampleChunk:
    """One chunk of a stream: stamp (ns) of its first sample, stream index of that sample."""

    stamp_ns: int
    first_index: int
    sample_rate: float  # Hz
    source: str
    frame_id: str
    samples: np.ndarray  # (n,), float64


def chunk_samples(chunk_duration: float, sample_rate: float) -> int:
    """Samples per chunk of ``chunk_duration`` s at ``sample_rate`` Hz (at least 1)."""
    return max(1, int(round(chunk_duration * sample_rate)))


class Rechunker:
    """Chunks of ``chunk_duration`` seconds from a stream of chunks of any length.

    :meth:`push` takes the recorded chunks in order and returns the chunks completed so
    far; :meth:`flush` returns what is left (a last, shorter chunk). See the module docstring.
    """

    def __init__(self, chunk_duration: float):
        if not (np.isfinite(chunk_duration) and chunk_duration > 0):
            raise ValueError(f"chunk duration must be positive, got {chunk_duration:g} s")
        self.chunk_duration = float(chunk_duration)
        self._parts: list = []  # recorded chunks (SampleChunk) not yet fully sent, the first cut at _cut
        self._cut = 0  # samples of _parts[0] already sent
        self._pending = 0  # samples held

    @property
    def _next_index(self) -> int:
        last = self._parts[-1]
        return last.first_index + last.samples.size

    def _continues(self, chunk: SampleChunk) -> bool:
        last = self._parts[-1]
        return (chunk.first_index == self._next_index and chunk.sample_rate == last.sample_rate
                and chunk.source == last.source and chunk.frame_id == last.frame_id)

    def push(self, chunk: SampleChunk) -> list[SampleChunk]:
        """Add the next recorded chunk; returns the chunks it completes (oldest first)."""
        out = []
        if self._parts and not self._continues(chunk):
            out += self.flush()
        if chunk.samples.size == 0:
            return out
        self._parts.append(chunk)
        self._pending += chunk.samples.size
        n = chunk_samples(self.chunk_duration, chunk.sample_rate)
        while self._pending >= n:
            out.append(self._take(n))
        return out

    def flush(self) -> list[SampleChunk]:
        """The samples held, as one last chunk (none when nothing is held)."""
        out = [self._take(self._pending)] if self._pending else []
        self._parts, self._cut = [], 0
        return out

    def _take(self, n: int) -> SampleChunk:
        """The next ``n`` held samples as one chunk, stamped from the recorded chunk of its first sample."""
        first = self._parts[0]
        rate = first.sample_rate
        stamp_ns = first.stamp_ns + round(self._cut * NS_PER_S / rate)
        index = first.first_index + self._cut
        pieces, need = [], n
        while need:
            part = self._parts[0]
            take = min(need, part.samples.size - self._cut)
            pieces.append(part.samples[self._cut:self._cut + take])
            need -= take
            self._cut += take
            if self._cut == part.samples.size:
                self._parts.pop(0)
                self._cut = 0
        self._pending -= n
        samples = pieces[0] if len(pieces) == 1 else np.concatenate(pieces)
        return SampleChunk(stamp_ns, index, rate, first.source, first.frame_id, samples)
