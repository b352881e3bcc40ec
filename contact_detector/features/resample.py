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
Causal resampling of wrench samples of any rate onto the F/T feature grid.

The F/T features are computed on samples at ``ft_rate_hz`` (:class:`FeatureConfig`). Sensors
run at other rates (51, 125, 200, 333 Hz, 1 or 10 kHz); :class:`WrenchResampler` turns their
samples into feature-grid samples, causally and with bounded memory:

* **Integer ratio** ``M = f_in / f_out`` (within :data:`INTEGER_TOLERANCE`): the mean of each
  block of ``M`` consecutive samples, timed at the block's last sample,
  ``y_j = (1/M) sum_{i=jM}^{jM+M-1} x_i``, ``t_j = t_{jM+M-1}`` (``M = 1`` passes samples
  through). This is the path of 100 Hz and 1 kHz input, bit for bit as before this module
  existed, so the shipped model's decisions do not change.
* **Any other rate**: the samples are joined by straight lines, ``x~(s)`` (piecewise linear
  through ``(t_i, x_i)``), and the grid sample at ``g_j = g_0 + j / f_out`` is the mean of
  ``x~`` over the last output period where the input is faster (anti-aliasing, the same box
  filter as the block mean, the sensor's own decimation and the simulator's), and ``x~``
  itself where it is slower (linear interpolation):

  ``y_j = (1/W) integral_{g_j - W}^{g_j} x~(s) ds`` with ``W = 1 / f_out`` if ``f_in > f_out``,
  ``y_j = x~(g_j)`` otherwise. ``g_0 = t_0 + W`` (the first sample after a restart).

  ``y_j`` needs ``x~`` up to ``g_j``: it is emitted when the first sample at or after ``g_j``
  arrives (its *completing sample*, stamp ``c_j >= g_j``), one input step late at most;
  nothing later than ``c_j`` is used.

Times: each output is timed at its grid point ``g_j`` (the block path: the block's last
stamp), or, with ``at_completion``, at ``c_j``, the stamp of the sample that completed it
(the block path: the block's last stamp again, so nothing changes there). The values are the
same either way. Frames clocked by the F/T stream (an F/T-only model) use ``c_j``: a decision
is never timed before the data that decided it existed.

Stamps are the header stamps (seconds); a stream restart (a gap, a time jump) is a
:meth:`WrenchResampler.reset`.
"""

import math
from typing import Optional

from contact_detector.errors import ConfigError
import numpy as np

#: Wrench rates accepted, Hz.
MIN_INPUT_RATE = 50.0
MAX_INPUT_RATE = 10000.0
#: A ratio ``f_in / f_out`` this close to an integer (relative) is treated as that integer.
INTEGER_TOLERANCE = 0.01


def check_input_rate(*, rate: float) -> None:
    """
    Refuse a wrench rate the resampler cannot take.

    Parameters
    ----------
    rate : float
        Wrench rate, Hz: in [MIN_INPUT_RATE, MAX_INPUT_RATE] with 1 % slack
        (:data:`INTEGER_TOLERANCE`), as a measured 10 kHz may read 10010 Hz.

    Raises
    ------
    ConfigError
        Not finite, or outside the range.

    """
    slack = 1.0 + INTEGER_TOLERANCE
    if not (math.isfinite(rate) and MIN_INPUT_RATE / slack <= rate <= MAX_INPUT_RATE * slack):
        raise ConfigError(f'wrench rate {rate:g} Hz is outside [{MIN_INPUT_RATE:g}, '
                          f'{MAX_INPUT_RATE:g}] Hz')


def integer_ratio(*, input_rate: float, output_rate: float) -> int:
    """
    Return ``M = round(f_in / f_out)`` if the ratio is an integer >= 1, else 0.

    "Integer" means ``|r - round(r)| <= INTEGER_TOLERANCE * r``: a sensor measured at
    999.7 Hz is a 1 kHz sensor.
    """
    ratio = input_rate / output_rate
    m = int(round(ratio))
    return m if m >= 1 and abs(ratio - m) <= INTEGER_TOLERANCE * ratio else 0


class WrenchResampler:
    """
    Wrench samples at ``input_rate`` -> samples on the ``output_rate`` grid (module docstring).

    Parameters
    ----------
    input_rate : float
        Wrench rate, Hz, in [MIN_INPUT_RATE, MAX_INPUT_RATE] (1 % slack for measured rates).
    output_rate : float
        Feature grid rate ``ft_rate_hz``, Hz.
    at_completion : bool
        Time each output at the stamp of the input sample that completed it (``c_j``) instead
        of its grid point (``g_j``); only the interpolating path differs.

    Attributes
    ----------
    block : int
        ``M`` on the block-mean path, 0 on the interpolating path.

    Raises
    ------
    ConfigError
        A rate out of range.

    """

    def __init__(self, *, input_rate: float, output_rate: float,
                 at_completion: bool = False) -> None:
        check_input_rate(rate=input_rate)
        if not (math.isfinite(output_rate) and output_rate > 0):
            raise ConfigError(f'feature rate ft_rate_hz={output_rate} Hz must be > 0')
        self.input_rate = float(input_rate)
        self.output_rate = float(output_rate)
        self.block = integer_ratio(input_rate=input_rate, output_rate=output_rate)
        self.period = 1.0 / self.output_rate
        self.width = self.period if input_rate > output_rate else 0.0
        self.at_completion = bool(at_completion)
        self.reset()

    def reset(self) -> None:
        """Forget every sample (a restart: the next sample starts a new grid)."""
        self._t = np.zeros(0)
        self._v = np.zeros((0, 6))
        self._g0: Optional[float] = None
        self._next = 0

    def push(self, *, t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """
        Add samples; return the grid samples they complete.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Stamps, s, strictly increasing (also across calls).
        values : np.ndarray, shape (n, 6)
            Force (N) then torque (N m).

        Returns
        -------
        t_out : np.ndarray, shape (m,)
            Grid times ``g_j``, s, or with ``at_completion`` the completing samples' stamps
            ``c_j`` (block path: each block's last stamp, either way).
        v_out : np.ndarray, shape (m, 6)

        """
        if self.block:
            return self._push_blocks(t, values)
        return self._push_grid(t, values)

    def _push_blocks(self, t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m = self.block
        if m == 1:
            return t, v             # no partial block is ever left: nothing to prepend
        bt = np.concatenate([self._t, t])
        bv = np.concatenate([self._v, v])
        n_blocks = bt.size // m
        used = n_blocks * m
        self._t, self._v = bt[used:], bv[used:]
        if n_blocks == 0:
            return np.zeros(0), np.zeros((0, 6))
        return bt[m - 1:used:m], bv[:used].reshape(n_blocks, m, 6).mean(axis=1)

    def _push_grid(self, t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ts = np.concatenate([self._t, t])
        xs = np.concatenate([self._v, v])
        if ts.size == 0:
            return np.zeros(0), np.zeros((0, 6))
        if self._g0 is None:
            self._g0 = float(ts[0]) + self.width
        g0, period, width = self._g0, self.period, self.width
        last = int(math.floor((float(ts[-1]) - g0) / period + 1e-9))
        if last < self._next:
            self._t, self._v = ts, xs
            return np.zeros(0), np.zeros((0, 6))
        index = np.arange(self._next, last + 1)
        grid = g0 + index * period
        # The sample completing grid point j: the first whose floor index above reaches j.
        # Only new samples can (the ones kept complete nothing beyond self._next - 1); the
        # floor is monotonic in t, so searchsorted finds it; one sample completes them all.
        if t.size == 1:
            done = np.full(index.size, ts[-1])
        else:
            reached = np.floor((t - g0) / period + 1e-9)
            done = t[np.searchsorted(reached, index, side='left')]
        grid = np.minimum(grid, done)       # the 1e-9 slack above: never past that sample
        if width > 0.0:
            out = (self._integral(ts, xs, grid) - self._integral(ts, xs, grid - width)) / width
        else:
            out = self._interpolate(ts, xs, grid)
        self._next = last + 1
        # Keep the samples the next grid point needs: from the one at or before its window.
        start = g0 + self._next * period - width
        keep = max(int(np.searchsorted(ts, start, side='right')) - 1, 0)
        self._t, self._v = ts[keep:], xs[keep:]
        return (done if self.at_completion else grid), out

    @staticmethod
    def _segments(ts: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        i = np.clip(np.searchsorted(ts, q, side='right') - 1, 0, max(ts.size - 2, 0))
        if ts.size < 2:
            return i, np.zeros(q.size), np.ones(q.size)
        return i, q - ts[i], ts[i + 1] - ts[i]

    @classmethod
    def _interpolate(cls, ts: np.ndarray, xs: np.ndarray, q: np.ndarray) -> np.ndarray:
        # x~(q) = x_i + (x_{i+1} - x_i) (q - t_i) / (t_{i+1} - t_i)
        i, d, h = cls._segments(ts, q)
        if ts.size < 2:
            return xs[i]
        return xs[i] + (xs[i + 1] - xs[i]) * (d / h)[:, None]

    @classmethod
    def _integral(cls, ts: np.ndarray, xs: np.ndarray, q: np.ndarray) -> np.ndarray:
        # F(q) = integral_{t_0}^{q} x~: trapezoids up to t_i, then the partial segment
        # x_i d + (x_{i+1} - x_i) d^2 / (2 h).
        i, d, h = cls._segments(ts, q)
        if ts.size < 2:
            return np.zeros((q.size, xs.shape[1]))
        steps = 0.5 * (xs[:-1] + xs[1:]) * np.diff(ts)[:, None]
        cum = np.concatenate([np.zeros((1, xs.shape[1])), np.cumsum(steps, axis=0)])
        return (cum[i] + xs[i] * d[:, None]
                + (xs[i + 1] - xs[i]) * (d * d / (2.0 * h))[:, None])


#: Relative difference between the measured and the configured wrench rate that is reported.
RATE_MISMATCH = 0.10


class StampRate:
    """
    The rate of a stream measured from its stamps over the newest ``window`` steps.

    ``rate = count(regular) / sum(regular)``, the regular steps being those shorter than 1.5
    median steps (gaps, restarts and time jumps left out). O(1) per stamp; the median is taken
    only when :meth:`rate` is asked (the node's diagnostics period).

    Parameters
    ----------
    window : int
        Steps kept.

    """

    def __init__(self, *, window: int = 500) -> None:
        from collections import deque
        self._steps: 'deque[float]' = deque(maxlen=window)
        self._last: Optional[float] = None

    def add(self, t: float) -> None:
        """Add one stamp, s."""
        if self._last is not None and t > self._last:
            self._steps.append(t - self._last)
        self._last = t

    def rate(self, *, min_steps: int = 20) -> Optional[float]:
        """Return the measured rate, Hz, or None with fewer than ``min_steps`` steps."""
        if len(self._steps) < min_steps:
            return None
        steps = np.fromiter(self._steps, dtype=float)
        regular = steps[steps < 1.5 * np.median(steps)]
        return float(regular.size / regular.sum()) if regular.size else None


def rate_mismatch(*, measured: Optional[float], configured: float) -> Optional[str]:
    """
    Say why ``measured`` and ``configured`` disagree by more than :data:`RATE_MISMATCH`.

    Returns
    -------
    str or None
        The text for a log line and the diagnostics; None when they agree (or nothing is
        measured yet).

    """
    if measured is None or abs(measured / configured - 1.0) <= RATE_MISMATCH:
        return None
    return (f'wrench arrives at {measured:.4g} Hz but wrench.rate is {configured:g} Hz: the '
            'F/T features are computed for the wrong rate; set wrench.rate to the measured '
            'rate')
