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
Streaming feature core: per-audio-frame feature rows from interleaved audio and wrench messages.

:class:`StreamingFeatureExtractor` joins the two paths: every audio frame
(:class:`~contact_detector.features.audio.AudioFramer`, with its levels from
:class:`~contact_detector.features.audio.AudioLevels`) gets the newest F/T feature frame
(:class:`~contact_detector.features.force_torque.ForceTorqueStream`) whose window ends at or
before the audio frame's end time (no interpolation, nothing from the future) and comes out as
one row of the feature matrix (:class:`~contact_detector.features.frames.FeatureFrames`).

Chunks of any size are accepted (one sample to many seconds); the work per chunk is vectorised,
memory is bounded by the window lengths and ``history_s``. Time is always passed in (header
stamps, bag log times); nothing here reads a clock. The batch reference in
:mod:`contact_detector.features.batch` computes the same numbers without any streaming logic.
"""

from bisect import bisect_left
import math
from typing import Optional, Sequence

from contact_detector.errors import InputError
from contact_detector.features.audio import AudioFramer, AudioLevels, to_unit_audio
from contact_detector.features.buffers import TailBuffer
from contact_detector.features.config import AUDIO_FEATURES, FeatureConfig
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.features.frames import FeatureFrames
from contact_detector.features.noise import NOISE_JUMP_N
import numpy as np


class StreamingFeatureExtractor:
    """
    Per-audio-frame feature vectors from interleaved audio chunks and wrench samples.

    An audio frame ending at ``t_a`` is emitted once the wrench stream has delivered a sample
    later than ``t_a - 0.5 / input_rate`` (so no F/T sample at or before ``t_a`` can still
    arrive) and is given the newest F/T feature frame ending at or before ``t_a``. If that
    frame is older than ``max_ft_age_s``, or none exists, the row is marked invalid. Frames
    waiting for F/T longer than ``max_ft_wait_s`` of audio time are emitted invalid-or-aligned
    with what is there, so a dead F/T sensor cannot stall the output.

    With an F/T-only configuration (``config.audio`` False) the rows are clocked by the F/T
    stream instead: every F/T feature frame is one row, emitted by the wrench sample that
    completes it, at that sample's stamp (also where the wrench is resampled onto a grid
    point before that stamp, :mod:`~contact_detector.features.resample`), always valid (its
    features are fresh by construction). Audio chunks are then ignored (:attr:`ignored_audio`
    counts them).

    Parameters
    ----------
    config : FeatureConfig
        The feature contract.
    audio_rate : float
        Audio sample rate, Hz.
    ft_input_rate : float or None
        Wrench rate, Hz (default ``config.ft_rate_hz``).
    max_ft_age_s : float or None
        Largest accepted ``t_a - t_ft``; default ``ft_hop / ft_rate_hz + 0.05``.
    max_ft_wait_s : float
        Longest wait for F/T, seconds of audio time after the frame's chunk arrived.
    history_s : float
        How much F/T feature history is kept for late audio, seconds.
    ft_gap_reset_s : float
        Wrench gap that restarts the F/T window, seconds.
    audio_gap_tolerance_s : float
        Audio lateness that restarts the audio stream, seconds.
    noise_jump_n : float
        The F/T stream's noise check (:class:`ForceTorqueStream`), N; 0 = off.

    """

    def __init__(self, *, config: FeatureConfig, audio_rate: float,
                 ft_input_rate: Optional[float] = None, max_ft_age_s: Optional[float] = None,
                 max_ft_wait_s: float = 0.25, history_s: float = 10.0,
                 ft_gap_reset_s: float = 0.05, audio_gap_tolerance_s: float = 0.2,
                 noise_jump_n: float = NOISE_JUMP_N) -> None:
        self.config = config
        self.names = config.feature_names
        self.ft_only = config.ft_only
        self.ignored_audio = 0
        self.audio = AudioFramer(config=config, sample_rate=audio_rate,
                                 gap_tolerance_s=audio_gap_tolerance_s)
        self.ft = ForceTorqueStream(config=config,
                                    input_rate=ft_input_rate or config.ft_rate_hz,
                                    gap_reset_s=ft_gap_reset_s, noise_jump_n=noise_jump_n)
        self.levels = AudioLevels(config=config)
        self.max_ft_age_s = (config.ft_hop / config.ft_rate_hz + 0.05
                             if max_ft_age_s is None else max_ft_age_s)
        self.max_ft_wait_s = max_ft_wait_s
        self.ready_margin_s = 0.5 / self.ft.input_rate
        self.history_frames = max(16, int(history_s * config.ft_rate_hz / config.ft_hop))
        self._ft_dst = np.array([i for i, n in enumerate(self.names) if n in self.ft.columns])
        self._ft_col = np.array([self.ft.columns.index(self.names[i]) for i in self._ft_dst])
        # (column, position in a pending frame's audio tuple) of each audio feature used
        self._audio_cols = [(self.names.index(name), k) for k, name in enumerate(AUDIO_FEATURES)
                            if name in self.names]
        self._ft_ts = TailBuffer(capacity=self.history_frames + 64)
        self._ft_xs = TailBuffer(capacity=self.history_frames + 64, width=len(self.ft.columns))
        self._empty = FeatureFrames.empty(self.names)
        for array in (self._empty.t, self._empty.x, self._empty.valid):
            array.flags.writeable = False       # shared by every call that emits nothing
        self.reset()

    def reset(self) -> None:
        """Forget everything: buffers, anchors, previous spectra, pending frames."""
        self.audio.reset()
        self.ft.reset()
        self.levels.reset()
        self._ft_ts.clear()
        self._ft_xs.clear()
        self._ft_t = self._ft_ts.view       # times of the F/T feature frames kept
        self._ft_x = self._ft_xs.view       # and their features
        # Frames waiting for F/T, in Python numbers (one or two at a time live).
        self._pend_t: list = []             # end times
        self._pend_a: list = []             # one tuple per frame, in AUDIO_FEATURES' order
        self._pend_arrival: list = []       # audio time of the chunk that completed them

    @property
    def pending(self) -> int:
        """Audio frames waiting for F/T."""
        return len(self._pend_t)

    def push_audio(self, samples: np.ndarray, *, stamp: Optional[float] = None) -> FeatureFrames:
        """
        Add an audio chunk (int16 or float in [-1, 1]); return the frames now complete.

        Parameters
        ----------
        samples : np.ndarray, shape (n,)
            Mono audio.
        stamp : float or None
            Time of the chunk's last sample, seconds (see :class:`AudioFramer`).

        Raises
        ------
        InputError
            Malformed chunk, or a stamp that is not a finite number (nothing is changed).
        TimeJumpError
            The stamp jumped backwards (nothing is changed; reset and push again).

        """
        return self.push_unit_audio(to_unit_audio(samples), stamp=stamp)

    def push_unit_audio(self, unit: np.ndarray, *,
                        stamp: Optional[float] = None) -> FeatureFrames:
        """
        :meth:`push_audio` for a chunk :func:`to_unit_audio` has already returned.

        Parameters
        ----------
        unit : np.ndarray, shape (n,), float64
            Mono audio in [-1, 1], finite (not checked again).
        stamp : float or None
            Time of the chunk's last sample, seconds.

        """
        if self.ft_only:
            self.ignored_audio += 1
            return self._empty
        t, power = self.audio.push(unit, stamp=stamp)
        if t.size:
            self._pend_a.extend(self.levels.rows(power))
            self._pend_t.extend(t.tolist())
            self._pend_arrival.extend([self.audio.latest_time] * t.size)
        return self._drain(force=False)

    def push_wrench(self, *, t: np.ndarray, force: np.ndarray,
                    torque: np.ndarray) -> FeatureFrames:
        """
        Add wrench samples; return the audio frames they make complete.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Header stamps, seconds, strictly increasing.
        force, torque : np.ndarray, shape (n, 3)
            N and N m.

        Raises
        ------
        InputError
            Wrong shapes, NaN/Inf, repeated or out-of-order stamps (nothing is changed).
        TimeJumpError
            Stamps jumped backwards (nothing is changed; reset and push again).

        """
        try:
            t = np.atleast_1d(np.asarray(t, dtype=np.float64))
            force = np.atleast_2d(np.asarray(force, dtype=np.float64))
            torque = np.atleast_2d(np.asarray(torque, dtype=np.float64))
        except (TypeError, ValueError, OverflowError) as err:
            raise InputError(f'wrench arrays are not numeric: {err}') from err
        if t.ndim != 1 or force.shape != (t.size, 3) or torque.shape != (t.size, 3):
            raise InputError(f'wrench arrays have shapes t{t.shape}, force{force.shape}, '
                             f'torque{torque.shape}; expected (n,), (n, 3), (n, 3)')
        if t.size == 0:
            return FeatureFrames.empty(self.names)
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(force))
                and np.all(np.isfinite(torque))):
            raise InputError('wrench contains NaN or Inf')
        ft_t, ft_x = self.ft.push(t=t, force=force, torque=torque)
        if self.ft_only:
            return self.ft_rows(ft_t, ft_x)
        if ft_t.size:
            keep = self.history_frames
            self._ft_ts.extend(ft_t[-keep:])
            self._ft_xs.extend(ft_x[-keep:])
            self._trim_ft_history()
        return self._drain(force=False)

    def push_wrench_one(self, *, t: float, values: Sequence[float]) -> FeatureFrames:
        """
        :meth:`push_wrench` for one sample (a live message), in fewer array calls.

        Parameters
        ----------
        t : float
            Header stamp, seconds.
        values : sequence of 6 float
            Force x, y, z in N, then torque x, y, z in N m.

        Raises
        ------
        InputError
            Not 6 values, a value or stamp that is not a finite number, a repeated or
            out-of-order stamp (nothing is changed).
        TimeJumpError
            The stamp jumped backwards (nothing is changed; reset and push again).

        """
        try:
            t = float(t)
            values = [float(v) for v in values]
        except (TypeError, ValueError, OverflowError) as err:
            raise InputError(f'wrench values are not numeric: {err}') from err
        if len(values) != 6:
            raise InputError(f'a wrench sample has 6 values, got {len(values)}')
        isfinite = math.isfinite
        if not (isfinite(t) and all(map(isfinite, values))):
            raise InputError('wrench contains NaN or Inf')
        frames = self.ft.push_one(t=t, values=values)
        if self.ft_only:
            return self._empty if frames is None else self.ft_rows(*frames)
        if frames is not None:
            self._ft_ts.extend(frames[0])
            self._ft_xs.extend(frames[1])
            self._trim_ft_history()
        return self._drain(force=False)

    def ft_rows(self, ft_t: np.ndarray, ft_x: np.ndarray) -> FeatureFrames:
        """
        Rows of an F/T-only configuration: one per F/T feature frame, all valid.

        Parameters
        ----------
        ft_t : np.ndarray, shape (m,)
            Time of each F/T feature frame, seconds: the stamp of the wrench sample that
            completed it (:class:`ForceTorqueStream` with an F/T-only configuration).
        ft_x : np.ndarray, shape (m, len(self.ft.columns))
            Their features (:class:`ForceTorqueStream` columns).

        Returns
        -------
        FeatureFrames
            ``m`` rows in the order of :attr:`names`.

        """
        m = ft_t.shape[0]
        if m == 0:
            return self._empty
        x = np.zeros((m, len(self.names)))
        x[:, self._ft_dst] = ft_x[:, self._ft_col]
        return FeatureFrames(t=ft_t, x=x, valid=np.ones(m, dtype=bool), names=self.names)

    def _trim_ft_history(self) -> None:
        # Keep history_s of F/T feature frames; _ft_t/_ft_x are the kept rows, for _drain.
        self._ft_ts.keep_last(self.history_frames)
        self._ft_xs.keep_last(self.history_frames)
        self._ft_t, self._ft_x = self._ft_ts.view, self._ft_xs.view

    def flush(self) -> FeatureFrames:
        """Emit every pending frame with the F/T data there is (end of a recording)."""
        return self._drain(force=True)

    def _drain(self, *, force: bool) -> FeatureFrames:
        n = len(self._pend_t)
        if n == 0:
            return self._empty
        if force:
            count = n
        else:
            # bisect_left is np.searchsorted(side='left'): the same binary search
            last = self.ft.last_input_t
            ready = 0 if last is None else bisect_left(self._pend_t, last + self.ready_margin_s)
            latest = self.audio.latest_time
            timed_out = 0 if latest is None else bisect_left(self._pend_arrival,
                                                             latest - self.max_ft_wait_s)
            count = max(ready, timed_out)
        if count == 0:
            return self._empty
        t = self._pend_t[:count]
        audio = self._pend_a[:count]
        del self._pend_t[:count], self._pend_a[:count], self._pend_arrival[:count]
        t = np.array(t)
        audio = np.array(audio)
        x = np.zeros((count, len(self.names)))
        for col, k in self._audio_cols:
            x[:, col] = audio[:, k]
        idx = np.searchsorted(self._ft_t, t, side='right') - 1
        valid = idx >= 0
        valid[valid] &= (t[valid] - self._ft_t[idx[valid]]) <= self.max_ft_age_s
        if valid.any():
            rows = np.flatnonzero(valid)[:, None]
            x[rows, self._ft_dst] = self._ft_x[idx[valid]][:, self._ft_col]
        return FeatureFrames(t=t, x=x, valid=valid, names=self.names)
