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
The audio path of the streaming feature core: samples to timed power frames and dB levels.

* :func:`to_unit_audio` checks a chunk and scales it to [-1, 1];
* :class:`AudioFramer` cuts the stream into frames of ``audio_frame_s`` every ``audio_hop_s``
  and gives each frame the time of its last sample, anchored on the chunk stamps;
* :class:`NoiseFloor` tracks the quietest recent power;
* :class:`AudioLevels` turns frame powers into the audio features of
  :data:`~contact_detector.features.config.AUDIO_FEATURES` (power, dB above the floor, recent
  peak, rise, drop from the peak, recent minimum).

Time is passed in (chunk stamps); nothing here reads a clock.
"""

import math
from typing import Optional

from contact_detector.errors import ConfigError, InputError
from contact_detector.features import spectral
from contact_detector.features.buffers import running_max
from contact_detector.features.config import AUDIO_FEATURES, FeatureConfig
from contact_detector.features.frames import TimeJumpError
import numpy as np


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
        out = arr.astype(np.float64)
        out /= 32768.0              # in place: no second array (a whole recording offline)
        return out
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


class AudioLevels:
    """
    The audio features of each frame from its power: level above the noise floor and its shape.

    Per frame, in :data:`~contact_detector.features.config.AUDIO_FEATURES`' order: the power
    (eq. 1), ``audio_power_rel_db`` (dB above the :class:`NoiseFloor`), ``audio_peak_rel_db``
    (its maximum over the newest ``peak_frames`` frames), ``audio_rise_db`` (its change over
    ``rise_frames`` frames), ``audio_peak_gap_db`` (the drop from that peak) and
    ``audio_hold_db`` (its minimum over the newest ``audio_hold_frames`` frames; fewer right
    after a start). Histories carry across calls, so the values do not depend on how the frames
    were grouped into calls.

    Parameters
    ----------
    config : FeatureConfig
        Hop, noise floor time constant, ``peak_frames``, ``rise_frames``,
        ``audio_hold_frames`` and the features used.

    """

    def __init__(self, *, config: FeatureConfig) -> None:
        self.config = config
        self.floor = NoiseFloor(config=config)
        self.needs_rel = any(name in config.feature_names for name in AUDIO_FEATURES[1:])
        # audio_hold_db is no column of the shipped models: skip its running minimum there
        self.needs_hold = 'audio_hold_db' in config.feature_names
        self.reset()

    def reset(self) -> None:
        """Forget the floor and the histories."""
        self.floor.reset()
        self._rel_hist = [-math.inf] * (self.config.peak_frames - 1)
        self._hold_hist: list = []          # the newest audio_hold_frames - 1 dB values
        self._rise_hist: list = []          # the newest rise_frames dB values, oldest first

    def rows(self, power: np.ndarray) -> list:
        """
        Compute the audio features of the next frames (updates the noise floor and histories).

        Parameters
        ----------
        power : np.ndarray, shape (n,)
            Audio power of the next ``n`` frames (eq. 1).

        Returns
        -------
        list of tuple
            Per frame, the values of :data:`AUDIO_FEATURES` in that order: all six when any
            extra audio feature is configured (``audio_hold_db`` 0 unless it is), else
            ``(power,)``.

        """
        if not self.needs_rel:
            return [(p,) for p in power.tolist()]
        rel = spectral.power_db_above_floor(power=power, floor=self.floor.update(power))
        rel_values = rel.tolist()
        peak = self._recent_peak(rel).tolist()
        return list(zip(power.tolist(), rel_values, peak, self._rise(rel_values),
                        [pk - r for pk, r in zip(peak, rel_values)],
                        self._held(rel).tolist() if self.needs_hold else [0.0] * len(peak)))

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

    def _held(self, rel: np.ndarray) -> np.ndarray:
        # audio_hold_db: running minimum over the newest audio_hold_frames values (over those
        # seen while fewer), across chunk boundaries; -max(-x) is exactly min(x).
        k = self.config.audio_hold_frames
        before = -np.array(self._hold_hist).reshape(-1, 1)
        history = self._hold_hist + rel.tolist()
        self._hold_hist = history[max(0, len(history) - (k - 1)):] if k > 1 else []
        return -running_max(values=-rel[:, None], before=before, window=k)[:, 0]
