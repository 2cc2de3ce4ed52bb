"""Per-stream blocks: each observer stream's samples reduced to fixed blocks, indexed from the stream's sample 0.

A stream (one observer's residual topic) arrives in chunks with the index of their first
sample. :class:`EnergyEnvelope` reduces it to blocks of D samples (a block rate near
:data:`ENVELOPE_RATE`): the raw sums of y, y², r², |r|, u that a window's RMS and the
thesis' blocks need (:mod:`.thesis_blocks`), and, when a band is given, the band-passed
energy envelope that the fold front end folds (:mod:`bearing_diagnoser.fold`). Units: the
envelope is a mean square, (m/s²)².

:class:`StreamBlocks` holds one stream's blocks aligned to multiples of D, so that windows
of every stream line up. How a chunk continues the stream is
:class:`bearing_common.chunk_stream.StreamCursor`'s to say; here a gap pads NaN blocks (the
windows touching it are skipped) and restarts the envelope filter; a gap longer than
:data:`MAX_PAD_BLOCKS` blocks begins the stream afresh after it instead (a producer's index
jumping far ahead must not allocate the hole); an overlap or repeat drops what was seen.

The block sums are compiled (numba, strict IEEE): each reproduces its NumPy formulation bit
for bit (:mod:`.pairwise_sum`), the band-pass ``scipy.signal.sosfilt``'s.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import signal

from bearing_common.chunk_stream import StreamCursor
from bearing_common.indexed_buffer import IndexedBuffer

from .pairwise_sum import PW_BLOCK, block_sum, halved_sum

#: Longest gap padded with NaN blocks (2¹⁶ blocks: tens of seconds at the envelope rates used).
MAX_PAD_BLOCKS = 1 << 16

#: Target envelope sample rate (Hz): enough for folding at BPFI (≈ 162 Hz) with 16 bins.
ENVELOPE_RATE = 4000.0


def envelope_decimation(sample_rate: float, envelope_rate: float = ENVELOPE_RATE) -> int:
    """Integer block length D so that sample_rate / D is close to ``envelope_rate``."""
    return max(1, int(round(sample_rate / envelope_rate)))


class EnergyEnvelope:
    """Streaming band-pass energy envelope with per-block sums.

    Parameters
    ----------
    sample_rate : float
        Input rate (Hz).
    band : (lo, hi) or None
        Pass band (Hz) of the order-4 Butterworth band-pass; ``hi`` is clipped below
        0.45 · sample_rate. None: no envelope, only the block sums.
    decimation : int, optional
        Block length D (samples) of the envelope; default from :func:`envelope_decimation`.

    Each call to :meth:`push` returns a dict of arrays, one entry per completed block
    (:attr:`keys`): ``env`` = mean of the squared band-passed signal ((m/s²)²), ``b4`` = mean
    of its fourth power, and the raw sums ``y``, ``y2``, ``r2``, ``ar``, ``u`` (of y, y², r²,
    |r|, u) used for RMS, the model-explains fraction and the thesis-literal correlation.
    Samples that do not fill a block are carried over.
    """

    SUMS = ("y", "y2", "r2", "ar", "u")

    def __init__(self, sample_rate: float, band: tuple[float, float] | None, decimation: int | None = None):
        if sample_rate <= 0:
            raise ValueError(f"sample_rate must be > 0, got {sample_rate}")
        self.sample_rate = float(sample_rate)
        self.decimation = int(decimation or envelope_decimation(sample_rate))
        self.band = None
        self._sos = None
        if band is not None:
            lo, hi = float(band[0]), min(float(band[1]), 0.45 * sample_rate)
            if not 0 < lo < hi:
                raise ValueError(f"invalid band {band} at {sample_rate} Hz")
            self.band = (lo, hi)
            self._sos = signal.butter(4, [lo, hi], btype="bandpass", fs=sample_rate, output="sos")
            self._zi = np.zeros((self._sos.shape[0], 2))
        self.keys = (("env", "b4") if self._sos is not None else ()) + self.SUMS
        self._carry: tuple | None = None  # (y, r, u, b) of a partial block, if any

    @property
    def envelope_rate(self) -> float:
        """Envelope (block) rate in Hz."""
        return self.sample_rate / self.decimation

    def fresh(self) -> EnergyEnvelope:
        """A new envelope of the same rate, band and block length (filter and blocks restarted)."""
        return EnergyEnvelope(self.sample_rate, self.band, self.decimation)

    def push(self, y: np.ndarray, residual: np.ndarray | None = None,
             train: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Feed measurement ``y`` (and optionally residual and train, same length)."""
        return dict(zip(self.keys, self.blocks(y, residual, train)))

    def completed(self, n: int) -> int:
        """How many blocks ``n`` more samples complete."""
        return (n + (0 if self._carry is None else self._carry[0].size)) // self.decimation

    def blocks(self, y: np.ndarray, residual: np.ndarray | None = None,
               train: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
        """As :meth:`push`, as one array of shape (len(:attr:`keys`), completed blocks), written
        into ``out`` when given (of that shape, :meth:`completed` blocks)."""
        y = np.asarray(y, dtype=float)
        r = y if residual is None else np.asarray(residual, dtype=float)
        u = np.zeros_like(y) if train is None else np.asarray(train, dtype=float)
        b = y
        if self._sos is not None:
            b = np.empty_like(y)
            sos_filter(self._sos, self._zi, y, b)
        if self._carry is not None:
            y, r, u, b = (np.concatenate(p) for p in zip(self._carry, (y, r, u, b)))
        d = self.decimation
        n = (y.size // d) * d
        self._carry = (y[n:].copy(), r[n:].copy(), u[n:].copy(), b[n:].copy()) if n < y.size else None
        out = np.empty((len(self.keys), n // d)) if out is None else out
        block_sums(y, r, u, b, d, out)
        return out


@njit(cache=True)
def sos_filter(sos: np.ndarray, zi: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """Cascaded second-order sections, transposed direct form II: ``scipy.signal.sosfilt``.

    Parameters
    ----------
    sos : ndarray, shape (S, 6)
        Sections (b0, b1, b2, 1, a1, a2).
    zi : ndarray, shape (S, 2)
        Section states before ``x[0]``; updated in place to the states after ``x[-1]``.
    x, out : ndarray, shape (n,)
        Input and output (same unit).
    """
    for i in range(x.size):
        cur = x[i]
        for s in range(sos.shape[0]):
            new = sos[s, 0] * cur + zi[s, 0]
            zi[s, 0] = sos[s, 1] * cur - sos[s, 4] * new + zi[s, 1]
            zi[s, 1] = sos[s, 2] * cur - sos[s, 5] * new
            cur = new
        out[i] = cur


@njit(cache=True)
def block_sums(y: np.ndarray, r: np.ndarray, u: np.ndarray, b: np.ndarray, d: int, out: np.ndarray) -> None:
    """Per block of ``d`` samples, the rows of :meth:`EnergyEnvelope.blocks`.

    Column ``k`` of ``out`` gets, over samples ``k·d .. k·d + d − 1``: when ``out`` has 7
    rows, mean(b²) and mean(b⁴) of the band-passed ``b``; then Σy, Σy², Σr², Σ|r|, Σu — each
    ``x.reshape(-1, d).sum(axis=1)`` (or ``.mean``) of the elementwise products, bit for bit.

    Parameters
    ----------
    y, r, u, b : ndarray, shape (n,), n >= (columns of ``out``) · d
        Measurement, residual, train, band-passed measurement (``b`` unused for 5 rows).
    d : int
        Block length (samples).
    out : ndarray, shape (7 or 5, n // d)
        Written in place, rows in the order above.
    """
    band = out.shape[0] - 5
    t = np.empty((7, d))
    short = d <= PW_BLOCK
    for k in range(out.shape[1]):
        o = k * d
        for i in range(d):
            b2 = b[o + i] * b[o + i]
            t[0, i] = b2
            t[1, i] = b2 * b2
            t[2, i] = y[o + i]
            t[3, i] = y[o + i] * y[o + i]
            t[4, i] = r[o + i] * r[o + i]
            t[5, i] = abs(r[o + i])
            t[6, i] = u[o + i]
        for j in range(out.shape[0]):
            out[j, k] = block_sum(t, j + 2 - band, 0, d) if short else halved_sum(t, j + 2 - band, 0, d)
        for j in range(band):
            out[j, k] /= d



class StreamBlocks:
    """Block arrays of one stream (see the module docstring), held in an
    :class:`~bearing_common.indexed_buffer.IndexedBuffer` of one row per key.

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
        self._cursor = StreamCursor()  # at the next expected sample
        self._blocks = IndexedBuffer(len(envelope.keys))
        self.fault_hz: float | None = None
        self.has_model = False
        self.has_train = False

    @property
    def first_block(self) -> int | None:
        """Absolute index of the oldest held block (None before the first chunk)."""
        return self._blocks.first

    @property
    def n_blocks(self) -> int:
        """Absolute index one past the last completed block."""
        return self._blocks.end

    def push(self, first_index: int, y, r, u) -> None:
        """Append samples y, r, u (equal length) starting at stream index ``first_index``."""
        d = self.env.decimation
        offset = self._cursor.offset(first_index)
        if offset is not None and offset > MAX_PAD_BLOCKS * d:
            self.env = self.env.fresh()  # a long gap: begin afresh there instead of padding it
            offset = None
        if offset is None:  # a start: align blocks to multiples of D
            skip = (-first_index) % d
            self._blocks.clear(first=(first_index + skip) // d)
            start = first_index + skip
        elif offset > 0:  # gap: pad with NaN blocks, restart alignment
            self._blocks.reserve((offset + d - 1) // d + 1)[:] = np.nan
            self.env = self.env.fresh()
            start = self.n_blocks * d
            skip = start - first_index
        else:  # contiguous, or an overlap / repeat: drop what was seen
            skip = -offset
            start = first_index + skip
        y, r, u = y[skip:], r[skip:], u[skip:]
        self._cursor.next_index = start
        if y.size == 0:
            return
        self.env.blocks(y, r, u, out=self._blocks.reserve(self.env.completed(y.size)))
        self._cursor.advance(start, y.size)

    def window(self, b0: int, b1: int) -> dict[str, np.ndarray] | None:
        """Blocks [b0, b1) of every key (views, valid until the next push), or None when they
        are not (all) held."""
        cols = self._blocks.view(b0, b1)
        return None if cols is None else dict(zip(self.env.keys, cols))

    def trim(self, keep_from_block: int) -> None:
        """Forget blocks before ``keep_from_block`` (never more than the stream holds: a silent
        stream keeps its place, so its next chunk is seen as the gap it is)."""
        self._blocks.trim(keep_from_block)
