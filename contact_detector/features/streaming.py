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
Streaming feature core: ring buffers, time anchoring and causal alignment.

Three small stateful classes, each with ``reset()``:

* :class:`AudioFramer` cuts the audio stream into frames of ``audio_frame_s`` every
  ``audio_hop_s`` and gives each frame the time of its last sample;
* :class:`ForceTorqueStream` turns wrench samples into the F/T spectral features at
  ``ft_rate_hz``, one feature frame every ``ft_hop`` samples;
* :class:`StreamingFeatureExtractor` joins them: every audio frame gets the newest F/T feature
  frame whose window ends at or before the audio frame's end time (no interpolation, nothing
  from the future) and comes out as one row of the feature matrix.

Chunks of any size are accepted (one sample to many seconds); the work per chunk is vectorised,
memory is bounded by the window lengths and ``history_s``. Time is always passed in (header
stamps, bag log times); nothing here reads a clock. The batch reference in
:mod:`contact_detector.features.batch` computes the same numbers without any streaming logic.
"""

from bisect import bisect_left
from dataclasses import dataclass
import math
from typing import Optional, Sequence

from contact_detector.errors import ConfigError, InputError
from contact_detector.features import spectral
from contact_detector.features.config import (AUDIO_FEATURES, CHANGE_FEATURES, DELTA_FEATURES,
                                              FeatureConfig, PAPER_FEATURES, SHIFT_FEATURES)
from contact_detector.features.resample import WrenchResampler
import numpy as np

#: Columns produced by :class:`ForceTorqueStream`, before the optional delta features.
FT_SPECTRAL_COLUMNS = PAPER_FEATURES[1:]


_max_reduce = np.maximum.reduce


class TimeJumpError(InputError):
    """Stamps jumped backwards by more than the tolerance (e.g. a bag loop)."""


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


@dataclass(frozen=True)
class FeatureFrames:
    """
    A block of per-audio-frame feature vectors.

    Attributes
    ----------
    t : np.ndarray, shape (n,)
        End time of each audio frame (time of its last sample), seconds.
    x : np.ndarray, shape (n, n_features)
        Feature vectors, columns in the order of ``names``.
    valid : np.ndarray, shape (n,), bool
        True where fresh F/T features were available for the frame. Invalid rows carry zeros in
        the F/T columns and must never lead to a release.
    names : tuple of str
        Column names.

    """

    t: np.ndarray
    x: np.ndarray
    valid: np.ndarray
    names: tuple

    def __len__(self) -> int:
        """Return the number of frames."""
        return int(self.t.shape[0])

    @classmethod
    def empty(cls, names: Sequence[str]) -> 'FeatureFrames':
        """Return a block with no frames."""
        return cls(t=np.zeros(0), x=np.zeros((0, len(names))), valid=np.zeros(0, dtype=bool),
                   names=tuple(names))

    @classmethod
    def concat(cls, blocks: Sequence['FeatureFrames'], names: Sequence[str]) -> 'FeatureFrames':
        """Concatenate blocks in order."""
        blocks = [b for b in blocks if len(b)]
        if not blocks:
            return cls.empty(names)
        return cls(t=np.concatenate([b.t for b in blocks]),
                   x=np.concatenate([b.x for b in blocks]),
                   valid=np.concatenate([b.valid for b in blocks]), names=tuple(names))


def to_unit_audio(samples: np.ndarray) -> np.ndarray:
    """
    Validate an audio chunk and scale it to float64 in [-1, 1].

    Parameters
    ----------
    samples : np.ndarray, shape (n,)
        int16 (divided by 32768) or float (taken as already in [-1, 1]).

    Returns
    -------
    np.ndarray, shape (n,), float64

    Raises
    ------
    InputError
        Wrong dimensionality or dtype, or a NaN/Inf sample.

    """
    try:
        arr = np.asarray(samples)
    except (TypeError, ValueError) as err:     # ragged nested sequences
        raise InputError(f'audio chunk is not an array: {err}') from err
    if arr.ndim != 1:
        raise InputError(f'audio chunk must be 1-D (mono), got shape {arr.shape}')
    if arr.dtype == np.int16:
        return arr.astype(np.float64) / 32768.0
    if arr.dtype.kind != 'f':
        raise InputError(f'audio chunk must be int16 or float, got dtype {arr.dtype}')
    out = arr.astype(np.float64)
    if not np.all(np.isfinite(out)):
        raise InputError('audio chunk contains NaN or Inf')
    return out


def frame_ends(*, first: int, count: int, frame_length: int, hop: float) -> np.ndarray:
    """
    Exclusive end sample index of audio frames ``first .. first+count-1``.

    ``e_i = W_L + floor(i * hop + 0.5)`` with ``hop = audio_hop_s * Fs`` (not necessarily an
    integer): frames keep exact time spacing at any sample rate, the hop in samples alternating
    between floor and ceil where ``hop`` is fractional.
    """
    i = np.arange(first, first + count, dtype=np.float64)
    return frame_length + np.floor(i * hop + 0.5).astype(np.int64)


class AudioFramer:
    """
    Cut an audio stream into power frames with times anchored on chunk stamps.

    Sample n (counted from the last reset) is at ``anchor + n / Fs``. Each chunk's stamp is the
    time of its last sample plus a non-negative transport delay, so the anchor is the smallest
    ``stamp - (n_last / Fs)`` seen, allowed to creep up by ``drift`` seconds per second to follow
    a sound card clock that runs slow. A chunk later than ``gap_tolerance_s`` against the sample
    count means samples were lost: the stream restarts there.

    Parameters
    ----------
    config : FeatureConfig
        Frame and hop durations.
    sample_rate : float
        Audio sample rate in Hz.
    gap_tolerance_s : float
        Largest accepted lateness of a chunk stamp before a restart, seconds.
    backjump_tolerance_s : float
        Largest accepted earliness of a chunk stamp before :class:`TimeJumpError`, seconds.
    drift : float
        Rate at which the anchor may creep upwards, seconds per second.

    """

    def __init__(self, *, config: FeatureConfig, sample_rate: float,
                 gap_tolerance_s: float = 0.2, backjump_tolerance_s: float = 0.5,
                 drift: float = 5e-4) -> None:
        if not (isinstance(sample_rate, (int, float)) and math.isfinite(sample_rate)
                and 1000.0 <= sample_rate <= 384000.0):
            raise ConfigError(f'audio sample rate must be in [1000, 384000] Hz, got {sample_rate}')
        self.sample_rate = float(sample_rate)
        self.frame_length = config.audio_frame_samples(self.sample_rate)
        self.hop = config.audio_hop_s * self.sample_rate
        if self.hop < 1.0:
            raise ConfigError(f'audio hop {config.audio_hop_s} s is shorter than one sample at '
                              f'{sample_rate} Hz')
        self._offsets = np.arange(self.frame_length)
        self.gap_tolerance_s = gap_tolerance_s
        self.backjump_tolerance_s = backjump_tolerance_s
        self.drift = drift
        self.restarts = 0
        self.reset()

    def reset(self) -> None:
        """Forget all samples and the time anchor."""
        self._anchor: Optional[float] = None
        self._last_stamp: Optional[float] = None
        self._n_total = 0          # samples received since the reset
        self._next_frame = 0       # index of the next frame to complete
        self._buf = np.zeros(0)    # samples from index self._buf_start on
        self._buf_start = 0

    @property
    def latest_time(self) -> Optional[float]:
        """Time of the newest received sample, or None before the first chunk."""
        if self._anchor is None:
            return None
        return self._anchor + (self._n_total - 1) / self.sample_rate

    def anchor_step(self, *, anchor: Optional[float], last_stamp: Optional[float],
                    n_before: int, n: int, stamp: float) -> tuple[float, str]:
        """
        Return the anchor after a chunk of ``n`` samples stamped ``stamp``, and a verdict.

        ``n_before`` samples came before it since the anchor was set (``anchor`` None: first
        chunk). The verdict is 'ok', 'restart' (samples were lost: a new stream starts at this
        chunk, whose anchor is returned) or 'jump' (time went backwards; the anchor is
        unchanged). Pure: the offline block path replays the live sequence with it.
        """
        offset = stamp - (n_before + n - 1) / self.sample_rate
        if anchor is None:
            return offset, 'ok'
        crept = anchor + self.drift * max(0.0, stamp - last_stamp)
        if offset < crept - self.backjump_tolerance_s:
            return anchor, 'jump'
        if offset > crept + self.gap_tolerance_s:
            return stamp - (n - 1) / self.sample_rate, 'restart'
        return min(crept, offset), 'ok'

    def _update_anchor(self, n: int, stamp: float) -> None:
        anchor, verdict = self.anchor_step(anchor=self._anchor, last_stamp=self._last_stamp,
                                           n_before=self._n_total, n=n, stamp=stamp)
        if verdict == 'jump':
            crept = self._anchor + self.drift * max(0.0, stamp - self._last_stamp)
            offset = stamp - (self._n_total + n - 1) / self.sample_rate
            raise TimeJumpError(f'audio stamp {stamp:.6f} is '
                                f'{crept - offset:.3f} s earlier than the sample count '
                                'allows (time jumped backwards)')
        if verdict == 'restart':
            # Samples were lost: start a new stream at this chunk.
            self.restarts += 1
            self.reset()
        self._anchor = anchor
        self._last_stamp = stamp

    def push(self, samples: np.ndarray, *,
             stamp: Optional[float] = None) -> tuple[np.ndarray, np.ndarray]:
        """
        Add a chunk; return the frames it completes.

        Parameters
        ----------
        samples : np.ndarray, shape (n,)
            float64 samples in [-1, 1] (see :func:`to_unit_audio`).
        stamp : float or None
            Time of the chunk's last sample, seconds. None continues the sample count (only
            after a first stamped chunk).

        Returns
        -------
        t, power : np.ndarray, shape (n_frames,)
            End time of each completed frame (its last sample) and its power (eq. 1).

        """
        n = int(samples.shape[0])
        if n == 0:
            return np.zeros(0), np.zeros(0)
        if stamp is None:
            if self._anchor is None:
                raise InputError('the first audio chunk after a reset needs a stamp')
        else:
            try:
                stamp = float(stamp)
            except (TypeError, ValueError) as err:
                raise InputError(f'audio stamp {stamp!r} is not a number') from err
            if not math.isfinite(stamp):
                raise InputError(f'audio stamp {stamp!r} is not finite')
            self._update_anchor(n, stamp)
        self._buf = np.concatenate([self._buf, samples]) if self._buf.size else samples
        self._n_total += n
        w, hop = self.frame_length, self.hop
        # Frames i with e_i <= n_total: i <= (n_total - w + 0.5) / hop, checked exactly below.
        first = self._next_frame
        upper = int(math.floor((self._n_total - w + 0.5) / hop)) + 2 - first
        ends = [int(e) for e in frame_ends(first=first, count=max(upper, 0), frame_length=w,
                                           hop=hop)
                if e <= self._n_total]
        if len(ends) == 1:
            start = ends[0] - w - self._buf_start
            # A copy, as the fancy index below makes: the sum must not see another alignment.
            power = spectral.audio_power(frames=self._buf[start:start + w].reshape(1, w).copy())
            t = np.array([self._anchor + (ends[0] - 1) / self.sample_rate])
        elif ends:
            ends = np.array(ends)
            starts = ends - w - self._buf_start
            windows = self._buf[starts[:, None] + self._offsets]
            power = spectral.audio_power(frames=windows)
            t = self._anchor + (ends - 1) / self.sample_rate
        else:
            power, t = np.zeros(0), np.zeros(0)
        self._next_frame += len(ends)
        next_start = math.floor(self._next_frame * hop + 0.5)
        keep_from = min(max(next_start, self._buf_start), self._n_total)
        self._buf = self._buf[keep_from - self._buf_start:]
        self._buf_start = keep_from
        return t, power


class NoiseFloor:
    """
    Track the audio noise floor: falls at once to a quieter frame, rises by ``exp(hop/tau)``.

    ``F_i = min(P_i, F_{i-1} * g)`` with ``g = exp(audio_hop_s / noise_floor_tau_s)``.
    """

    def __init__(self, *, config: FeatureConfig) -> None:
        self.growth = math.exp(config.audio_hop_s / config.noise_floor_tau_s)
        self.reset()

    def reset(self) -> None:
        """Forget the floor."""
        self._floor = math.inf

    def update(self, power: np.ndarray) -> np.ndarray:
        """
        Return the floor after each frame, shape like ``power``.

        One frame at a time, so that the result does not depend on how the frames were grouped
        into calls (live single frames and offline blocks agree to the bit).
        """
        out = np.empty(power.shape[0])
        floor, growth = self._floor, self.growth
        for i, p in enumerate(power.tolist()):
            floor = min(p, floor * growth)
            out[i] = floor
        self._floor = floor
        return out


class ForceTorqueStream:
    """
    Spectral features of |F| and |T| over a sliding DFT window.

    Input at ``input_rate`` is first brought onto the ``ft_rate_hz`` grid by
    :class:`~contact_detector.features.resample.WrenchResampler` (an integer multiple M is
    averaged over blocks of M samples timed at their last sample; any other rate from 50 Hz to
    10 kHz is box-filtered and interpolated). A feature frame ends at every
    ``ft_hop``-th decimated sample once ``ft_window`` samples (and the delta history) are
    there; its time is the time of its last sample.

    Parameters
    ----------
    config : FeatureConfig
        Window, hop, window function, detrending and extra features.
    input_rate : float
        Wrench sample rate in Hz.
    gap_reset_s : float
        A stamp gap longer than this restarts the window (the DFT needs uniform samples).
    backjump_tolerance_s : float
        A stamp earlier than the previous one by more than this raises :class:`TimeJumpError`;
        by less (a duplicate or reordered message) raises :class:`InputError`.

    """

    def __init__(self, *, config: FeatureConfig, input_rate: float,
                 gap_reset_s: float = 0.05, backjump_tolerance_s: float = 0.5) -> None:
        self._resampler = WrenchResampler(input_rate=input_rate, output_rate=config.ft_rate_hz)
        self.config = config
        self.input_rate = float(input_rate)
        self.decimation = self._resampler.block     # 0: not an integer ratio (interpolated)
        self.gap_reset_s = max(gap_reset_s, 1.5 / input_rate)
        self.backjump_tolerance_s = backjump_tolerance_s
        self.use_delta = [name for name in config.extra_features if name in DELTA_FEATURES]
        n = config.ft_window
        need = (max(n, config.delta_lag + max(config.delta_window, config.baseline_window))
                if self.use_delta else n)
        if set(self.use_delta) & set(SHIFT_FEATURES):
            need = max(need, config.shift_lag + max(config.delta_window, config.shift_window))
        self.first_end = need - 1
        self.history = need
        self.columns = FT_SPECTRAL_COLUMNS + tuple(self.use_delta)
        self._offsets = np.arange(n)
        wanted = set(self.use_delta)
        self._want_delta = bool(wanted & {'force_delta', 'torque_delta', 'ft_delta_angle'})
        self._want_change = bool(wanted & set(CHANGE_FEATURES))
        self._want_change_max = bool(wanted & {'force_change_max', 'torque_change_max'})
        # (force_change, torque_change) of the frames before the newest, for *_change_max.
        self._recent_changes = TailBuffer(capacity=config.change_max_frames, width=2)
        self._want_shift = bool(wanted & set(SHIFT_FEATURES))
        # (force_shift, torque_shift) of the frames before the newest, for *_shift_min/max.
        self._recent_shifts = TailBuffer(
            capacity=max(config.change_max_frames, config.shift_min_frames), width=2)
        self._angles = [angle for angle in (('ft_delta_angle', 'force_delta', 'torque_delta'),
                                            ('ft_change_angle', 'force_change', 'torque_change'))
                        if angle[0] in wanted]
        self._mags = TailBuffer(capacity=need + 64, width=2)    # |F|, |T| of the newest samples
        self._mag_ts = TailBuffer(capacity=need + 64)            # their times
        self._vecs = TailBuffer(capacity=need + 64, width=6)     # F, T vectors (shift features)
        self.restarts = 0
        self.reset()

    def reset(self) -> None:
        """Forget everything, including the last stamp seen."""
        self.last_input_t: Optional[float] = None
        self._restart()

    def _restart(self) -> None:
        # Forget the window, previous spectra and partial block; keep the last stamp.
        self._resampler.reset()
        self._mags.clear()                  # |F|, |T| of the newest decimated samples
        self._mag_ts.clear()                # their times
        self._mag_start = 0                 # decimated index of the oldest sample kept
        self._n_dec = 0                     # decimated samples since the restart
        self._prev_en: Optional[np.ndarray] = None   # (2, n_bins) previous EN spectra
        self._recent_changes.clear()
        self._vecs.clear()
        self._recent_shifts.clear()

    def check_stamps(self, t: np.ndarray) -> None:
        """Raise InputError/TimeJumpError unless ``t`` is strictly increasing and new."""
        if t.size > 1 and not np.all(np.diff(t) > 0):
            raise InputError('wrench stamps within a message are not strictly increasing')
        if self.last_input_t is not None and t[0] <= self.last_input_t:
            back = self.last_input_t - t[0]
            if back > self.backjump_tolerance_s:
                raise TimeJumpError(f'wrench stamp {t[0]:.6f} is {back:.3f} s before the '
                                    'previous one (time jumped backwards)')
            raise InputError(f'wrench stamp {t[0]:.6f} repeats or precedes the previous one '
                             f'({self.last_input_t:.6f}); message dropped')

    def push(self, *, t: np.ndarray, force: np.ndarray,
             torque: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """
        Add wrench samples; return the feature frames they complete.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Sample stamps, seconds, strictly increasing.
        force, torque : np.ndarray, shape (n, 3)
            Force in N and torque in N m, finite.

        Returns
        -------
        t_frames : np.ndarray, shape (m,)
            Time of each feature frame's last sample.
        features : np.ndarray, shape (m, len(self.columns))

        """
        self.check_stamps(t)
        values = np.concatenate([force, torque], axis=1)
        if t.size == 1:
            # One sample (a live wrench message): the split below without its array calls.
            if self.last_input_t is not None \
                    and float(t[0]) - self.last_input_t > self.gap_reset_s:
                self.restarts += 1
                self._restart()
            out = self._push_segment(t, values)
            self.last_input_t = float(t[0])
            return out
        # Split where the stamps jump forward by more than the gap: a reset between segments.
        previous = self.last_input_t if self.last_input_t is not None else t[0]
        gaps = np.flatnonzero(np.diff(np.concatenate([[previous], t])) > self.gap_reset_s)
        bounds = list(gaps) + [t.size]
        out_t, out_f = [], []
        lo = 0
        for hi in bounds:
            if hi > lo:
                ft, ff = self._push_segment(t[lo:hi], values[lo:hi])
                out_t.append(ft)
                out_f.append(ff)
            if hi < t.size:
                self.restarts += 1
                self._restart()
            lo = hi
        self.last_input_t = float(t[-1])
        if not out_t:
            return np.zeros(0), np.zeros((0, len(self.columns)))
        return np.concatenate(out_t), np.concatenate(out_f)

    def push_one(self, *, t: float, values: Sequence[float]) -> Optional[tuple[float, list]]:
        """
        Add one wrench sample (a live message); return the feature frame it completes, if any.

        :meth:`push` with one sample: the same code, so the same numbers.

        Parameters
        ----------
        t : float
            Sample stamp, seconds, finite.
        values : sequence of 6 float
            Force x, y, z in N and torque x, y, z in N m, finite.

        Returns
        -------
        (float, list of float) or None
            The frame's time and its features (``self.columns``), or None.

        """
        row = np.array([values], dtype=np.float64)
        ft_t, ft_x = self.push(t=np.array([t], dtype=np.float64), force=row[:, :3],
                               torque=row[:, 3:])
        return (float(ft_t[0]), ft_x[0].tolist()) if ft_t.size else None

    def _change_max(self, change: np.ndarray) -> np.ndarray:
        # *_change_max of the (m, 2) new changes; keeps the newest ones for the next call.
        window = self.config.change_max_frames
        peak = running_max(values=change, before=self._recent_changes.view, window=window)
        self._recent_changes.extend(change)
        self._recent_changes.keep_last(window - 1)
        return peak

    def _shift_extremes(self, shift: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # *_shift_min and *_shift_max of the (m, 2) new shifts; keeps the newest for the next call
        before = self._recent_shifts.view
        n_before = before.shape[0]
        k_min, k_max = self.config.shift_min_frames, self.config.change_max_frames
        low = -running_max(values=-shift, before=-before[max(0, n_before - k_min + 1):],
                           window=k_min)
        high = running_max(values=shift, before=before[max(0, n_before - k_max + 1):],
                           window=k_max)
        self._recent_shifts.extend(shift)
        self._recent_shifts.keep_last(max(k_min, k_max) - 1)
        return low, high

    def _push_segment(self, t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dec_t, dec_v = self._resampler.push(t=t, values=v)
        n_blocks = dec_t.size
        if n_blocks == 0:
            return np.zeros(0), np.zeros((0, len(self.columns)))
        mag = np.stack([np.linalg.norm(dec_v[:, :3], axis=1),
                        np.linalg.norm(dec_v[:, 3:], axis=1)], axis=1)
        self._mags.extend(mag)
        self._mag_ts.extend(dec_t)
        if self._want_shift:
            self._vecs.extend(dec_v)
        first_new = self._n_dec
        self._n_dec += n_blocks
        # Frame ends (decimated indices) that fall on the new samples.
        hop, first_end = self.config.ft_hop, self.first_end
        lo = max(first_new, first_end)
        start_j = -(-(lo - first_end) // hop)
        ends = first_end + hop * np.arange(start_j, (self._n_dec - 1 - first_end) // hop + 1)
        if ends.size:
            feats = self._features(ends - self._mag_start)
            times = self._mag_ts.view[ends - self._mag_start]
        else:
            feats, times = np.zeros((0, len(self.columns))), np.zeros(0)
        self._mag_ts.keep_last(self.history)
        if self._want_shift:
            self._vecs.keep_last(self.history)
        self._mag_start += self._mags.keep_last(self.history)
        return times, feats

    def _features(self, ends: np.ndarray) -> np.ndarray:
        cfg = self.config
        n = cfg.ft_window
        m = ends.size
        # |F| and |T| windows side by side: one DFT call for both signals.
        mags = self._mags.view
        windows = mags[(ends - n + 1)[:, None] + self._offsets]             # (m, n, 2)
        # Contiguous whatever m is: numpy sums strided rows in another order, and a frame's
        # features must not depend on how many frames one call computes.
        frames = np.ascontiguousarray(windows.transpose(2, 0, 1).reshape(2 * m, n))
        spectra = spectral.magnitude_spectrum(frames=frames, window_fn=cfg.ft_window_fn,
                                              detrend=cfg.ft_detrend)
        # Divided by their maxima once for both calls (each would do it again).
        scaled = spectral.max_normalised(spectra=spectra)
        centroid, spread = spectral.spectral_centroid_spread(spectra=scaled, window_length=n,
                                                             scaled=True)
        en = spectral.sum_normalised(spectra=scaled, scaled=True).reshape(2, m, -1)
        prev = np.empty_like(en)
        prev[:, 1:] = en[:, :-1]
        prev[:, 0] = en[:, 0] if self._prev_en is None else self._prev_en
        flux = spectral.spectral_flux(normalised=en.reshape(2 * m, -1),
                                      previous=prev.reshape(2 * m, -1))
        self._prev_en = en[:, -1].copy()
        out = np.empty((m, len(self.columns)))
        out[:, 0], out[:, 1], out[:, 2] = centroid[:m], spread[:m], flux[:m]
        out[:, 3], out[:, 4], out[:, 5] = centroid[m:], spread[m:], flux[m:]
        derived = {}
        if self.use_delta:
            # |F| and |T| side by side; the newest samples' mean serves both families
            recent = window_mean(signal=mags, ends=ends, window=cfg.delta_window)
            lagged, wanted = ends - cfg.delta_lag, set(self.use_delta)
            if wanted & {'force_delta', 'torque_delta', 'ft_delta_angle'}:
                change = recent - window_mean(signal=mags, ends=lagged,
                                              window=cfg.delta_window)
                derived.update(_with_angle(('force_delta', 'torque_delta', 'ft_delta_angle'),
                                           change))
            if wanted & set(CHANGE_FEATURES):
                change = recent - window_median(signal=mags, ends=lagged,
                                                window=cfg.baseline_window)
                derived.update(_with_angle(('force_change', 'torque_change', 'ft_change_angle'),
                                           change))
                if self._want_change_max:
                    peak = self._change_max(change)
                    derived['force_change_max'], derived['torque_change_max'] = peak.T
            if self._want_shift:
                vecs = self._vecs.view
                shift = vector_shift(
                    recent=window_mean(signal=vecs, ends=ends, window=cfg.delta_window),
                    baseline=window_median(signal=vecs, ends=ends - cfg.shift_lag,
                                           window=cfg.shift_window))
                low, high = self._shift_extremes(shift)
                derived['force_shift'], derived['torque_shift'] = shift.T
                derived['force_shift_min'], derived['torque_shift_min'] = low.T
                derived['force_shift_max'], derived['torque_shift_max'] = high.T
        for col, name in enumerate(self.use_delta, start=6):
            out[:, col] = derived[name]
        return out


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
    # rows i .. i + window - 1 of padded end at new row i: one gather, one reduction
    index = np.arange(padded.shape[0] - m, padded.shape[0])[:, None] - np.arange(window)
    return _max_reduce(padded[index], axis=1)


def _with_angle(names: tuple, change: np.ndarray) -> dict:
    """Name the |F| and |T| columns of ``change`` (m, 2) and their :func:`delta_angle`."""
    f, t = change[:, 0], change[:, 1]
    return dict(zip(names, (f, t, delta_angle(force_delta=f, torque_delta=t))))


def window_mean(*, signal: np.ndarray, ends: np.ndarray, window: int) -> np.ndarray:
    """
    Mean of the ``window`` samples ending at each of ``ends``: ``mean(s[e-w+1..e])``.

    ``*_delta = window_mean(ends) - window_mean(ends - delta_lag)`` and
    ``*_change = window_mean(ends) - window_median(ends - delta_lag)``.

    Parameters
    ----------
    signal : np.ndarray, shape (n,) or (n, c)
        |F| in N and/or |T| in N m, one column each.
    ends : np.ndarray, shape (m,)
        Indices of the newest sample of each window, ``>= window - 1``.
    window : int
        Samples averaged.

    Returns
    -------
    np.ndarray, shape (m,) or (m, c)
        Same unit as ``signal``.

    """
    # np.mean's own arithmetic (the sum along the axis, then one division) without its wrapper
    return np.add.reduce(signal[ends[:, None] + np.arange(1 - window, 1)], axis=1) / window


def window_median(*, signal: np.ndarray, ends: np.ndarray, window: int) -> np.ndarray:
    """
    Median of the ``window`` samples ending at each of ``ends`` (a robust baseline).

    A knock shorter than half the window does not move it, so the ``*_change`` features do not
    see a knock again, with the opposite sign, when it leaves their baseline (as ``*_delta``
    does ``delta_lag`` samples later).

    Parameters
    ----------
    signal : np.ndarray, shape (n,) or (n, c)
        |F| in N and/or |T| in N m, one column each.
    ends : np.ndarray, shape (m,)
        Indices of the newest sample of each window, ``>= window - 1``.
    window : int
        Samples in the median.

    Returns
    -------
    np.ndarray, shape (m,) or (m, c)
        ``np.median``'s values, from one partition (``np.median`` costs ~3x as much per call).

    """
    old = signal[ends[:, None] + np.arange(1 - window, 1)]
    k = window // 2
    if window % 2:
        return np.partition(old, k, axis=1)[:, k]
    part = np.partition(old, (k - 1, k), axis=1)
    return (part[:, k - 1] + part[:, k]) / 2


def vector_shift(*, recent: np.ndarray, baseline: np.ndarray) -> np.ndarray:
    """
    Length of the change of the force and of the torque vector: ``|recent - baseline|``.

    ``force_shift = sqrt(sum_k (F_k - B_k)^2)`` over the three axes ``k``, likewise for the
    torque. A rotation of the sensor frame, a constant bias (an untared sensor) or the
    direction of gravity in the sensor frame do not change it.

    Parameters
    ----------
    recent, baseline : np.ndarray, shape (m, 6)
        Force x, y, z in N then torque x, y, z in N m: the newest samples' mean and the
        baseline's per-axis median (:func:`window_mean`, :func:`window_median`).

    Returns
    -------
    np.ndarray, shape (m, 2)
        ``force_shift`` in N and ``torque_shift`` in N m, >= 0 (0 when nothing changed).

    """
    change = recent - baseline
    return np.stack([np.linalg.norm(change[:, :3], axis=1),
                     np.linalg.norm(change[:, 3:], axis=1)], axis=1)


def delta_angle(*, force_delta: np.ndarray, torque_delta: np.ndarray) -> np.ndarray:
    """
    Direction of a load change in the (force, torque) plane: ``atan2(dT, dF)``.

    A force change of size ``dF`` acting on a line at distance ``r`` from the sensor changes the
    torque by about ``r dF``, so ``tan(angle) = dT / dF`` is that lever arm in m, whatever the
    object weighs. Contact with the table acts at the bottom of the object, inertial forces at
    its centre of mass, knocks on the hand near the sensor; the sign tells unloading
    (``dF < 0``, the table takes weight) from loading.

    Parameters
    ----------
    force_delta : np.ndarray, shape (m,)
        Change of |F| (``force_delta`` or ``force_change``), N.
    torque_delta : np.ndarray, shape (m,)
        Change of |T| over the same samples, N m.

    Returns
    -------
    np.ndarray, shape (m,)
        Angle in rad, in ``[-pi, pi]``; 0 when nothing changed.

    """
    return np.arctan2(torque_delta, force_delta)


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
    completes it, at that sample's time, always valid (its features are fresh by
    construction). Audio chunks are then ignored (:attr:`ignored_audio` counts them).

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

    """

    def __init__(self, *, config: FeatureConfig, audio_rate: float,
                 ft_input_rate: Optional[float] = None, max_ft_age_s: Optional[float] = None,
                 max_ft_wait_s: float = 0.25, history_s: float = 10.0,
                 ft_gap_reset_s: float = 0.05, audio_gap_tolerance_s: float = 0.2) -> None:
        self.config = config
        self.names = config.feature_names
        self.ft_only = config.ft_only
        self.ignored_audio = 0
        self.audio = AudioFramer(config=config, sample_rate=audio_rate,
                                 gap_tolerance_s=audio_gap_tolerance_s)
        self.ft = ForceTorqueStream(config=config,
                                    input_rate=ft_input_rate or config.ft_rate_hz,
                                    gap_reset_s=ft_gap_reset_s)
        self.floor = NoiseFloor(config=config)
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
        self._needs_rel = any(k > 0 for _, k in self._audio_cols)
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
        self.floor.reset()
        self._ft_ts.clear()
        self._ft_xs.clear()
        self._ft_t = self._ft_ts.view       # times of the F/T feature frames kept
        self._ft_x = self._ft_xs.view       # and their features
        # Frames waiting for F/T, in Python numbers (one or two at a time live).
        self._pend_t: list = []             # end times
        self._pend_a: list = []             # one tuple per frame, in AUDIO_FEATURES' order
        self._pend_arrival: list = []       # audio time of the chunk that completed them
        self._rel_hist = [-math.inf] * (self.config.peak_frames - 1)
        self._rise_hist: list = []          # the newest rise_frames dB values, oldest first

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
            self._pend_a.extend(self.audio_rows(power))
            self._pend_t.extend(t.tolist())
            self._pend_arrival.extend([self.audio.latest_time] * t.size)
        return self._drain(force=False)

    def audio_rows(self, power: np.ndarray) -> list:
        """
        Compute the audio features of the next frames (updates the noise floor and histories).

        Parameters
        ----------
        power : np.ndarray, shape (n,)
            Audio power of the next ``n`` frames (eq. 1).

        Returns
        -------
        list of tuple
            Per frame, the values of :data:`AUDIO_FEATURES` in that order: all five when any
            extra audio feature is configured, else ``(power,)``.

        """
        if not self._needs_rel:
            return [(p,) for p in power.tolist()]
        rel = spectral.power_db_above_floor(power=power, floor=self.floor.update(power))
        rel_values = rel.tolist()
        peak = self._recent_peak(rel).tolist()
        return list(zip(power.tolist(), rel_values, peak, self._rise(rel_values),
                        [pk - r for pk, r in zip(peak, rel_values)]))

    def _rise(self, rel_values: list) -> list:
        # audio_rise_db: each value minus the one rise_frames frames earlier (the oldest one
        # there while fewer frames have been seen), across chunk boundaries.
        history = self._rise_hist
        k = self.config.rise_frames
        rise = []
        for value in rel_values:
            rise.append(value - history[0] if history else 0.0)
            history.append(value)
            if len(history) > k:
                del history[0]
        return rise

    def _recent_peak(self, rel: np.ndarray) -> np.ndarray:
        # Running maximum over the newest peak_frames values, across chunk boundaries.
        k = self.config.peak_frames
        before = np.array(self._rel_hist).reshape(-1, 1)
        history = np.concatenate([self._rel_hist, rel])
        self._rel_hist = history[history.size - (k - 1):].tolist() if k > 1 else []
        return running_max(values=rel[:, None], before=before, window=k)[:, 0]

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
        frame = self.ft.push_one(t=t, values=values)
        if self.ft_only:
            if frame is None:
                return self._empty
            return self.ft_rows(np.array([frame[0]]), np.array([frame[1]]))
        if frame is not None:
            self._ft_ts.append(frame[0])
            self._ft_xs.append(frame[1])
            self._trim_ft_history()
        return self._drain(force=False)

    def ft_rows(self, ft_t: np.ndarray, ft_x: np.ndarray) -> FeatureFrames:
        """
        Rows of an F/T-only configuration: one per F/T feature frame, all valid.

        Parameters
        ----------
        ft_t : np.ndarray, shape (m,)
            Time of each F/T feature frame's last sample, seconds.
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
