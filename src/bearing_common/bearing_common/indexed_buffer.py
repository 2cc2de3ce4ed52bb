"""Values held by their index in a stream: appended at the end, read by index range, forgotten from the front.

What a streaming consumer keeps of a chunked stream — the decision's recent samples, the
per-stream blocks of its envelope — indexed like the stream itself (sample or block 0 = the
stream's first), so that windows are addressed by index whatever the chunking. How a chunk
continues the stream (start, overlap, gap) is :class:`~.chunk_stream.StreamCursor`'s to say;
this only stores.
"""

from __future__ import annotations

import numpy as np


class IndexedBuffer:
    """``rows`` parallel series of values, columns indexed by stream index.

    The values live in one array of shape (rows, capacity), columns ``_start`` to ``_fill``;
    it doubles when full and is shifted down only when the forgotten part is as large as the
    held one, so that appending costs no copy of the held values (amortised O(1) per value).

    Attributes
    ----------
    first : int or None
        Stream index of the oldest held column (None: nothing held or placed yet).
    """

    def __init__(self, rows: int = 1):
        self.rows = int(rows)
        self.clear()

    def clear(self, first: int | None = None) -> None:
        """Hold nothing; the next appended column gets index ``first`` (None: not placed yet)."""
        self.first = first
        self._store = np.zeros((self.rows, 0))
        self._start = 0
        self._fill = 0

    @property
    def held(self) -> int:
        """Number of columns held."""
        return self._fill - self._start

    @property
    def end(self) -> int:
        """Stream index one past the newest held column (0 when never placed)."""
        return 0 if self.first is None else self.first + self.held

    def reserve(self, m: int) -> np.ndarray:
        """The next ``m`` columns, shape (rows, m), counted as held: a view for the caller to fill."""
        if self._fill + m > self._store.shape[1]:
            held = self.held
            if held + m > self._store.shape[1] // 2:  # grow; else shift down into the free half
                grown = np.zeros((self.rows, max(2 * self._store.shape[1], 2 * (held + m), 64)))
                grown[:, :held] = self._store[:, self._start:self._fill]
                self._store = grown
            else:
                self._store[:, :held] = self._store[:, self._start:self._fill]
            self._start, self._fill = 0, held
        self._fill += m
        return self._store[:, self._fill - m:self._fill]

    def append(self, values) -> None:
        """Append columns: an array of shape (rows, m), or (m,) for one row."""
        values = np.asarray(values, dtype=float)
        m = values.shape[-1]
        self.reserve(m)[:] = values.reshape(self.rows, m)

    def view(self, i0: int, i1: int) -> np.ndarray | None:
        """Columns [i0, i1) by stream index, shape (rows, i1 − i0): a view, valid until the next
        append; None when they are not all held."""
        if self.first is None:
            return None
        j0, j1 = i0 - self.first, i1 - self.first
        if j0 < 0 or j1 > self.held:
            return None
        return self._store[:, self._start + j0:self._start + j1]

    def trim(self, keep_from: int) -> None:
        """Forget the columns before stream index ``keep_from`` (never more than are held: the
        buffer keeps its place in the stream)."""
        if self.first is None:
            return
        cut = min(keep_from - self.first, self.held)
        if cut > 0:
            self._start += cut
            self.first += cut
