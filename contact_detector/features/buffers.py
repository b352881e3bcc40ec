# Copyright 2026 contact_detector developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
Bounded histories of a stream: the newest rows in preallocated storage, windows and running maxima.

Values are only stored and compared here, never computed, so results do not depend on how a
stream was cut into chunks.
"""

from typing import Optional

import numpy as np


class TailBuffer:
    """
    Newest rows of a stream in preallocated storage: appending copies the new rows only.

    ``view`` is the rows kept, oldest first, contiguous. Storage is reused: the kept rows move
    to its start when it is full (once every ~``capacity`` rows), and it grows for larger
    blocks. Values are only stored, never computed, so results do not depend on it.

    Parameters
    ----------
    capacity : int
        Rows stored before the first move, at least the number of rows kept between appends.
    width : int or None
        Columns per row (None: 1-D).

    """

    def __init__(self, *, capacity: int, width: Optional[int] = None) -> None:
        self._shape = () if width is None else (width,)
        self._buf = np.zeros((2 * capacity,) + self._shape)
        self._lo = self._hi = 0
        self.view = self._buf[:0]

    def clear(self) -> None:
        """Forget every row."""
        self._lo = self._hi = 0
        self.view = self._buf[:0]

    def __len__(self) -> int:
        """Return the number of rows kept."""
        return self._hi - self._lo

    def _room(self, n: int) -> None:
        # Make room for n more rows at the end.
        kept = self._hi - self._lo
        if kept + n > self._buf.shape[0]:
            grown = np.zeros((2 * (kept + n),) + self._shape)
            grown[:kept] = self._buf[self._lo:self._hi]
            self._buf = grown
        else:
            self._buf[:kept] = self._buf[self._lo:self._hi]
        self._lo, self._hi = 0, kept

    def extend(self, rows: np.ndarray) -> None:
        """Append rows (shape (n,) or (n, width))."""
        n = rows.shape[0]
        if self._hi + n > self._buf.shape[0]:
            self._room(n)
        self._buf[self._hi:self._hi + n] = rows
        self._hi += n
        self.view = self._buf[self._lo:self._hi]

    def append(self, row) -> None:
        """Append one row (a float, or a sequence of ``width`` floats)."""
        if self._hi == self._buf.shape[0]:
            self._room(1)
        self._buf[self._hi] = row
        self._hi += 1
        self.view = self._buf[self._lo:self._hi]

    def keep_last(self, n: int) -> int:
        """Keep the newest ``n`` rows at most; return how many were dropped."""
        drop = max(0, self._hi - self._lo - n)
        if drop:
            self._lo += drop
            self.view = self._buf[self._lo:self._hi]
        return drop


def running_max(*, values: np.ndarray, before: np.ndarray, window: int) -> np.ndarray:
    """
    Maximum of each row's column over the newest ``window`` rows, earlier rows included.

    With ``rows = [before; values]`` and ``j = len(before)``:
    ``out[i] = max(rows[max(0, j + i - window + 1) : j + i + 1])`` per column, ``i < m``.

    Parameters
    ----------
    values : np.ndarray, shape (m, k)
        New rows.
    before : np.ndarray, shape (j, k)
        The rows just before them (``j < window``; fewer right after a start).
    window : int
        Rows per maximum, >= 1.

    Returns
    -------
    np.ndarray, shape (m, k)

    """
    m, k = values.shape
    if m == 0:
        return np.zeros((0, k))
    padded = np.concatenate([np.full((window - 1 - before.shape[0], k), -np.inf),
                             before, values])
    # Rows i .. i + window - 1 of padded end at new row i. Doubling: after the loop out[i] is
    # the maximum of the ``span`` rows from i (span the largest power of two <= window), and
    # two overlapping spans cover the window. log2(window) whole-array steps instead of an
    # (m, window) gather; a maximum is exact, so the grouping does not change a bit.
    out, span = padded, 1
    while 2 * span <= window:
        out = np.maximum(out[:-span], out[span:])
        span *= 2
    rest = window - span
    return np.maximum(out[:m], out[rest:rest + m]) if rest else out[:m]


def column_windows(*, signal: np.ndarray, ends: np.ndarray, window: int) -> np.ndarray:
    """
    Return the ``window`` samples ending at each of ``ends``, per column, in contiguous rows.

    ``out[..., i, :] = signal[ends[i] - window + 1 : ends[i] + 1]`` (transposed for a 2-D
    signal). Evenly spaced ``ends`` (a feature frame every ``ft_hop`` samples) are copied from
    a strided view of the columns; others (and a single window: the live case) are gathered.
    Either way the values are copies, so what is computed on them does not depend on the path.

    Parameters
    ----------
    signal : np.ndarray, shape (n,) or (n, c)
        Samples, oldest first.
    ends : np.ndarray of int, shape (m,)
        Index of the newest sample of each window, ``window - 1 <= ends < n``.
    window : int
        Samples per window, >= 1.

    Returns
    -------
    np.ndarray, shape (m, window) or (c, m, window)
        C-contiguous.

    """
    m = ends.shape[0]
    if m > 1:
        first, step = int(ends[0]) - window + 1, int(ends[1] - ends[0])
        if first >= 0 and step > 0 and int(ends[-1]) < signal.shape[0] \
                and np.all(np.diff(ends) == step):
            cols = np.ascontiguousarray(signal.T)
            size = cols.itemsize
            return np.ndarray(shape=cols.shape[:-1] + (m, window), dtype=cols.dtype,
                              buffer=cols, offset=first * size,
                              strides=cols.strides[:-1] + (step * size, size)).copy()
    # the gather keeps the transposed layout of signal.T: made C-contiguous after it
    return np.ascontiguousarray(signal.T[..., ends[:, None] + np.arange(1 - window, 1)])
