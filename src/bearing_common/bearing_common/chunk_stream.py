"""Chunked signal streams: how a chunk continues a stream, and the check every chunk passes (no rclpy).

A stream (vibration, a residual topic, a recording cut into chunks) arrives in chunks that
carry the index of their first sample. :class:`StreamCursor` is the one place that says how
a chunk continues a stream — a start, contiguous, an overlap (samples already seen), a gap
(samples missing); each consumer decides what that means for it:

* :class:`ChunkStream` — what nodes run on every received chunk (observers: vibration;
  diagnoser: residuals). Bad chunks are rejected with a reason and counted, never
  processed: empty or huge chunks, non-positive or non-finite sample rates, a rate other
  than the consumer's, NaN/inf samples, stamps that go backwards or repeat. A chunk that
  does not continue the previous one (a gap, a restarted producer) is accepted with
  ``resync`` set, so the consumer restarts its filter state instead of bridging the hole;
* the decision's sample and block buffers (:class:`bearing_common.indexed_buffer.IndexedBuffer`
  holds them) drop an overlap and pad or restart at a gap.

Snapshot sensors (:data:`INPUT_MODES`): many plant sensors send a short waveform every few
seconds to hours, each as one chunk, with a pause between them. A :class:`ChunkStream` in
``snapshot`` mode takes every chunk as one snapshot: a chunk that begins after a pause (its
stamp later than the previous chunk's end) is a new snapshot, not a gap — accepted with
``resync`` and ``snapshot`` set, counted as ``snapshots``, with no reason to log — whatever
its sample index does (sensors number the samples of their snapshots in different ways:
on as if sampling never stopped, on without the pause, or from 0 each time); only stamps
that go back are refused (at index 0: a replay restarted). In ``auto`` mode (the nodes'
default) a chunk is a snapshot when it begins after a pause and so did the chunk before it
(or that was the stream's first): a stretch of exactly one chunk between pauses, what a
snapshot sensor sends and a stream only does when it loses every other chunk. The chunk
that shows it is reported once (``reason``), and the one before it is counted as a
snapshot too; a chunk that continues its predecessor makes the stream a stream again.
``stream`` mode never takes a chunk as a snapshot.
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass

import numpy as np

from bearing_common.units import sample_rate_problem

MAX_CHUNK_SAMPLES = 2_000_000  # > 1 s at 1 MHz; larger chunks are refused as malformed

#: How a consumer takes a sensor's chunks (module docstring): ``auto`` detects snapshots from the pauses.
INPUT_MODES = ("auto", "stream", "snapshot")

#: The nodes' ``input_mode`` parameter, described.
INPUT_MODE_HELP = ("how the vibration arrives: stream (continuous chunks), snapshot (a snapshot sensor: each "
                   "chunk a short waveform of its own, pauses between them), auto = snapshots when chunks come one "
                   "at a time with pauses between them, else a stream")


class StreamCursor:
    """The index of the next sample a chunked stream expects (None: nothing yet, or forgotten)."""

    def __init__(self):
        self.next_index: int | None = None

    def offset(self, first_index: int) -> int | None:
        """How a chunk whose first sample has index ``first_index`` continues the stream:
        > 0 samples missing before it (a gap), < 0 samples of it already seen (an overlap or a
        repeat), 0 contiguous; None at a start (nothing expected)."""
        return None if self.next_index is None else first_index - self.next_index

    def advance(self, first_index: int, n: int) -> None:
        """``n`` samples from index ``first_index`` were taken: the next expected is after them."""
        self.next_index = first_index + n

    def forget(self) -> None:
        """Expect nothing: the next chunk is a start."""
        self.next_index = None


@dataclass(frozen=True)
class Verdict:
    """Outcome of checking one chunk.

    ``accepted``; ``resync``: restart filter state first (start, gap, restart, a new
    snapshot); ``restart``: the producer restarted or changed rate, so history before this
    chunk is not comparable; ``reason``: text for logs; ``snapshot``: the chunk is a snapshot
    sensor's, one snapshot of its own (module docstring).
    """

    accepted: bool
    resync: bool = False
    reason: str = ""
    restart: bool = False
    snapshot: bool = False


class ChunkStream:
    """Continuity and sanity checks for one chunked signal stream.

    Parameters
    ----------
    name : str
        Stream name used in reasons, e.g. ``vibration/drive_end``.
    sample_rate : float, optional
        Required sample rate (Hz); None accepts any positive rate but a change of
        rate is reported as a resync.
    input_mode : str
        One of :data:`INPUT_MODES` (module docstring).
    """

    def __init__(self, name: str, sample_rate: float | None = None,
                 max_samples: int = MAX_CHUNK_SAMPLES, input_mode: str = "stream"):
        if input_mode not in INPUT_MODES:
            raise ValueError(f"input_mode must be one of {', '.join(INPUT_MODES)}; got {input_mode!r}")
        self.name = name
        self.sample_rate = sample_rate
        self.max_samples = max_samples
        self.input_mode = input_mode
        self.snapshots = False  # whether the last accepted chunk was taken as a snapshot
        self._stretch = 0  # chunks in the current stretch (contiguous in time) so far
        self._stretch_was_gap = False  # whether the current stretch began at a counted gap
        self.counts = collections.Counter()
        self._cursor = StreamCursor()
        self._next_time: float | None = None
        self._last_stamp: float | None = None
        self._last_index: int | None = None
        self._rate: float | None = None

    def check(self, stamp: float, first_index: int, sample_rate: float, samples: np.ndarray) -> Verdict:
        """Check a chunk whose first sample is at ``stamp`` (s) with stream index ``first_index``."""
        n = len(samples)
        paused = (self._next_time is not None and not sample_rate_problem(sample_rate)
                  and stamp - self._next_time > 0.5 / sample_rate)  # began after a pause in time
        snapshot = self._is_snapshot(paused)
        # producer restarted (or a replay began): back to index 0, or back before the index expected
        # (a restarted producer whose first chunks this consumer missed; its stamps go back, to a
        # simulator's 0, or on, with a sensor's clock); the last chunk again (but the first of a run)
        # is a repeat, refused below by its stamp. Snapshots number their samples as they like: only
        # index 0 back in time is a restart.
        repeat = stamp == self._last_stamp and first_index == self._last_index
        offset = self._cursor.offset(first_index)
        if snapshot:
            restarted = self._last_stamp is not None and first_index == 0 and stamp <= self._last_stamp
        else:
            restarted = self._last_stamp is not None and (first_index == 0 or (
                offset is not None and offset < 0 and not repeat))
        problem = self._problem(stamp, sample_rate, samples, n, check_order=not restarted)
        if problem:  # a refused chunk changes nothing but the counts (a hole: the next one resyncs)
            self.counts["rejected"] += 1
            self.counts[problem.split(":")[0]] += 1
            if problem.startswith("non-finite"):
                self._cursor.forget()  # the hole must not be bridged: resync on the next chunk
            return Verdict(False, reason=f"{self.name}: {problem}")
        if restarted:
            self._cursor.forget()
            offset = None
        rate_changed = self._rate is not None and self._rate != sample_rate
        resync = offset is None or rate_changed
        reason = ""
        if offset is None:
            reason = "stream restarted" if restarted else (
                "resynchronised after a rejected chunk" if self.counts["rejected"] else "start of stream")
        if snapshot:
            resync = resync or paused
            reason = self._snapshot_reason(resync, paused, reason)
        elif not resync and (offset != 0 or abs(stamp - self._next_time) > 0.5 / sample_rate):
            resync = True
            reason = (f"{self.name}: gap of {offset} samples ({stamp - self._next_time:+.6f} s) before "
                      f"index {first_index}; restarting")
            self.counts["gaps"] += 1
        elif rate_changed:
            reason = f"{self.name}: sample rate changed {self._rate:g} -> {sample_rate:g} Hz; restarting"
        if self.snapshots and not snapshot and self.input_mode == "auto":
            reason = reason or f"{self.name}: chunks continue each other: a stream again"
        self._stretch_was_gap = (self._stretch_was_gap and not resync) or reason.startswith(f"{self.name}: gap")
        self._stretch = 1 if resync else self._stretch + 1
        self.snapshots = snapshot
        self._rate = sample_rate
        self._last_stamp, self._last_index = stamp, first_index
        self._cursor.advance(first_index, n)
        self._next_time = stamp + n / sample_rate
        self.counts["accepted"] += 1
        return Verdict(True, resync=resync, reason=reason, restart=restarted or rate_changed, snapshot=snapshot)

    def _is_snapshot(self, paused: bool) -> bool:
        """Whether the chunk about to be checked is a snapshot (module docstring)."""
        if self.input_mode != "auto":
            return self.input_mode == "snapshot"
        return paused and (self.snapshots or self._stretch == 1)

    def _snapshot_reason(self, new: bool, paused: bool, reason: str) -> str:
        """Count a new snapshot; the reason to log: a start or restart, or that auto mode has just
        recognised a snapshot sensor — never a snapshot's pause itself."""
        if not new:
            return reason
        self.counts["snapshots"] += 1
        if self.input_mode == "auto" and not self.snapshots:
            self.counts["snapshots"] += 1  # the chunk before this one was a snapshot too
            if self._stretch_was_gap:
                self.counts["gaps"] -= 1
            return (f"{self.name}: chunks come one at a time with pauses between them: a snapshot sensor's; "
                    "each chunk is taken as a snapshot")
        return "" if paused and reason != "stream restarted" else reason

    def _problem(self, stamp, sample_rate, samples, n, check_order: bool) -> str:
        rate_problem = sample_rate_problem(sample_rate)
        if rate_problem:
            return rate_problem
        if self.sample_rate is not None and abs(sample_rate - self.sample_rate) > 1e-9 * self.sample_rate:
            return f"wrong sample rate: {sample_rate:g} Hz, expected {self.sample_rate:g} Hz"
        if n == 0:
            return "empty chunk: no samples"
        if n > self.max_samples:
            return f"huge chunk: {n} samples > {self.max_samples}"
        if not _all_finite(samples):
            bad = int(np.count_nonzero(~np.isfinite(samples)))
            return f"non-finite samples: {bad} NaN/inf of {n}"
        if check_order and self._last_stamp is not None and stamp <= self._last_stamp:
            return f"out-of-order stamp: {stamp:.6f} s after {self._last_stamp:.6f} s"
        return ""

    def restart(self) -> None:
        """Forget continuity (e.g. after the consumer reset itself)."""
        self._cursor.forget()
        self._last_stamp = None
        self._next_time = None
        self._stretch = 0


def _all_finite(samples) -> bool:
    """Whether every sample is finite: their sum is when they are (a NaN or an infinity makes it NaN or
    infinite), and only a sum that overflowed (NumPy warns) is checked sample by sample: half the cost per
    chunk."""
    x = np.asarray(samples)
    return math.isfinite(x.sum()) or bool(np.isfinite(x).all())
