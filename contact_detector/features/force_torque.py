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
The F/T path of the streaming feature core: wrench samples to spectral and load-change features.

:class:`ForceTorqueStream` resamples the wrench onto the ``ft_rate_hz`` grid, keeps |F|, |T|
(and the vectors, for the shift features) over the window, and computes one feature frame every
``ft_hop`` samples: the spectral centroid, spread and flux of |F| and |T| (paper eqs. 2-4,
:mod:`~contact_detector.features.spectral`) and the configured load-change features
(:mod:`~contact_detector.features.deltas`).
"""

from typing import Optional, Sequence

from contact_detector.errors import InputError
from contact_detector.features import spectral
from contact_detector.features.buffers import column_windows, running_max, TailBuffer
from contact_detector.features.carried import CarriedLoad, measure_carried_load
from contact_detector.features.config import (CARRIED_SHIFT_COS_FEATURES,
                                              CARRIED_SHIFT_FEATURES, CHANGE_FEATURES,
                                              DELTA_FEATURES, FeatureConfig, HOLD_FEATURES,
                                              NEEDS_CARRIED, PAPER_FEATURES, ROUGH_FEATURES,
                                              SHIFT_FEATURES)
from contact_detector.features.deltas import (carried_lever, relative_to_carried, ROUGH_FLOOR_N,
                                              roughness, vector_shift, window_mean, window_median,
                                              with_angle)
from contact_detector.features.frames import TimeJumpError
from contact_detector.features.noise import jump_statistics, NOISE_JUMP_N, NOISE_WINDOW, \
    REVERSAL_SHARE
from contact_detector.features.resample import WrenchResampler
import numpy as np


#: Columns produced by :class:`ForceTorqueStream`, before the optional delta features.
FT_SPECTRAL_COLUMNS = PAPER_FEATURES[1:]

#: |F| (N) and |T| (N m) of a load: a force (torque) of exactly (0, 0, 0) right after a reading
#: of at least this much is a driver's placeholder. Four times the carried-load floors: a
#: quantised sensor's noise around 0.5 N reads exactly 0 now and then (3 samples in the 3.2
#: million of the spent generator sets and the simulator's pools at the floors, none at this).
PLACEHOLDER_AFTER = np.array([2.0, 0.2])


def bias_vector(bias: Sequence[float]) -> np.ndarray:
    """
    Check an F/T sensor's zero and return it as an array.

    Parameters
    ----------
    bias : sequence of 6 float
        Force x, y, z in N, then torque x, y, z in N m.

    Returns
    -------
    np.ndarray, shape (6,)

    Raises
    ------
    InputError
        Not 6 finite numbers (a bool is not a number here).

    """
    try:
        if any(isinstance(b, bool) for b in bias):
            raise TypeError('a bool is not a bias')
        value = np.array([float(b) for b in bias], dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as err:
        raise InputError(f'the F/T bias must be 6 numbers, got {bias!r}') from err
    if value.shape != (6,) or not np.all(np.isfinite(value)):
        raise InputError(f'the F/T bias must be 6 finite numbers, got {bias!r}')
    return value


class ForceTorqueStream:
    """
    Spectral features of |F| and |T| over a sliding DFT window.

    Input at ``input_rate`` is first brought onto the ``ft_rate_hz`` grid by
    :class:`~contact_detector.features.resample.WrenchResampler` (an integer multiple M is
    averaged over blocks of M samples timed at their last sample; any other rate from 50 Hz to
    10 kHz is box-filtered and interpolated). A feature frame ends at every
    ``ft_hop``-th decimated sample once ``ft_window`` samples (and the delta history) are
    there; its time is the time of its last sample: its grid time, or, for an F/T-only
    configuration (``config.ft_only``: the frames are the rows, clocked by this stream), the
    stamp of the wrench sample that completed it (``at_completion`` of the resampler; the same
    on the block-mean path), so a row is never timed before the data that decided it.

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
    noise_jump_n : float
        A grid sample is *noisy* when the median jump of the force over the newest
        :data:`~.noise.NOISE_WINDOW` changes is at least this (N) and they reverse direction
        at least :data:`~.noise.REVERSAL_SHARE` of the time (:mod:`~.noise`); 0 = never.

    Notes
    -----
    A sample whose force (or torque) reads exactly (0, 0, 0) while the newest earlier reading
    of it that was not had a load (:data:`PLACEHOLDER_AFTER`: 2 N, 0.2 N m) is not a
    reading: drivers publish such placeholders, six zeros or a zeroed half, when a reading is
    missing, and the jump to nothing and back looks like a contact. It is left out and
    counted in :attr:`placeholders` (nothing else changes: a gap of a few samples is
    interpolated over, a longer one restarts the window). Exact zeros among readings near
    zero (a sensor zeroed while idle, quantised), or a torque that was always 0 (a driver
    without torque), are readings and kept.

    Every sample is read as ``x - bias`` (:attr:`bias`, shape (6,), N and N m: the sensor's
    zero, :meth:`set_bias`) before anything else. :meth:`measure_zero` measures what that
    corrected signal reads over the next ``carried_window`` samples at the feature rate (the
    carried-load measurement, :func:`measure_carried_load`, of an empty hand); the caller
    decides whether to add it to the bias.

    Noisy grid samples (``noise_jump_n``: interference, a loose connector) are counted in
    :attr:`noisy`; :attr:`noise_until` is the time, on the frames' clock, up to which a frame
    may have seen one in its features (``history`` samples after the newest): the detector
    lets none of those release. The features are computed as usual.

    """

    def __init__(self, *, config: FeatureConfig, input_rate: float,
                 gap_reset_s: float = 0.05, backjump_tolerance_s: float = 0.5,
                 noise_jump_n: float = NOISE_JUMP_N) -> None:
        if isinstance(noise_jump_n, bool) or not isinstance(noise_jump_n, (int, float)) \
                or not 0.0 <= noise_jump_n < float('inf'):
            raise InputError(f'noise_jump_n must be a finite number >= 0, got {noise_jump_n!r}')
        self.noise_jump_n = float(noise_jump_n)
        self._resampler = WrenchResampler(input_rate=input_rate, output_rate=config.ft_rate_hz,
                                          at_completion=config.ft_only)
        self.config = config
        self.input_rate = float(input_rate)
        self.decimation = self._resampler.block     # 0: not an integer ratio (interpolated)
        self.gap_reset_s = max(gap_reset_s, 1.5 / input_rate)
        self.backjump_tolerance_s = backjump_tolerance_s
        self.use_delta = [name for name in config.extra_features if name in DELTA_FEATURES]
        n = config.ft_window
        need = (max(n, config.delta_lag + max(config.delta_window, config.baseline_window))
                if self.use_delta else n)
        # the *_hold features hold both the changes and the shifts; the carried-load features
        # compare the vector change with the load measured over the first carried_window
        # samples, which every frame after a start must have
        vector = set(SHIFT_FEATURES) | set(HOLD_FEATURES) | set(NEEDS_CARRIED) \
            | set(ROUGH_FEATURES)
        if set(self.use_delta) & vector:
            need = max(need, config.shift_lag + max(config.delta_window, config.shift_window))
        # force_roughness: rough_window second differences of three samples each, now and
        # shift_lag samples earlier
        self._want_rough = bool(set(self.use_delta) & set(ROUGH_FEATURES))
        if self._want_rough:
            need = max(need, config.shift_lag + config.rough_window + 2)
        #: Whether the features use the carried load (then it is measured, else never).
        self.uses_carried = config.measures_carried
        if self.uses_carried:
            need = max(need, config.carried_window)
        self.first_end = need - 1
        self.history = need
        self.columns = FT_SPECTRAL_COLUMNS + tuple(self.use_delta)
        wanted = set(self.use_delta)
        self._want_delta = bool(wanted & {'force_delta', 'torque_delta', 'ft_delta_angle'})
        self._want_change = bool(wanted & set(CHANGE_FEATURES))
        self._want_change_max = bool(wanted & {'force_change_max', 'torque_change_max'})
        # (force_change, torque_change) of the frames before the newest, for *_change_max.
        self._recent_changes = TailBuffer(capacity=config.change_max_frames, width=2)
        self._want_shift = bool(wanted & vector)
        # (force_shift, torque_shift) of the frames before the newest, for *_shift_min/max.
        self._recent_shifts = TailBuffer(
            capacity=max(config.change_max_frames, config.shift_min_frames), width=2)
        # (change, shift) of |F| and |T| of the frames before the newest, for *_hold.
        self._want_hold = bool(wanted & set(HOLD_FEATURES))
        self._recent_holds = TailBuffer(capacity=config.hold_frames, width=4)
        # (force, torque) distance from the carried load of the frames before the newest, for
        # *_carried_shift_min
        self._want_carried_cos = bool(wanted & set(CARRIED_SHIFT_COS_FEATURES))
        self._want_carried_shift = bool(wanted & set(CARRIED_SHIFT_FEATURES)) \
            or self._want_carried_cos
        self._want_carried_min = bool(wanted & set(CARRIED_SHIFT_FEATURES[2:]))
        self._recent_carried_shifts = TailBuffer(capacity=config.shift_min_frames, width=2)
        self._angles = [angle for angle in (('ft_delta_angle', 'force_delta', 'torque_delta'),
                                            ('ft_change_angle', 'force_change', 'torque_change'))
                        if angle[0] in wanted]
        self._mags = TailBuffer(capacity=need + 64, width=2)    # |F|, |T| of the newest samples
        self._mag_ts = TailBuffer(capacity=need + 64)            # their times
        self._vecs = TailBuffer(capacity=need + 64, width=6)     # F, T vectors (shift features)
        # the carried load: the per-axis median of the first carried_window samples after a
        # reset or measure_carried(); kept across the window restarts of a wrench gap
        self._carried_rows = TailBuffer(capacity=config.carried_window, width=6)
        self._floor = np.array([config.carried_floor_force, config.carried_floor_torque])
        # the sensor's zero (set_bias) and its measurement (measure_zero), kept across resets:
        # the sensor does not change when the stream state is forgotten
        self.bias = np.zeros(6)
        self._biased = False
        self._zero_rows = TailBuffer(capacity=config.carried_window, width=6)
        self._zeroing = False
        #: The last completed zero measurement (what the corrected signal read), or None.
        self.zero_measurement: Optional[CarriedLoad] = None
        #: Samples left out as a driver's placeholder (a force or torque of exactly 0 after
        #: a load).
        self.placeholders = 0
        # the newest raw force and torque that were not (0, 0, 0), side by side
        self._last_reading: Optional[np.ndarray] = None
        self.restarts = 0
        #: Noisy grid samples, and bursts of them (a noisy sample after the hold had ended).
        self.noisy = 0
        self.noise_bursts = 0
        #: The median jump of the newest noisy sample, N (0 before any).
        self.noise_level = 0.0
        # the newest grid force vectors, for the jump statistics of the next samples
        self._recent_forces = TailBuffer(capacity=NOISE_WINDOW + 64, width=3)
        self.reset()

    def set_bias(self, bias: Sequence[float]) -> None:
        """
        Read every later sample as ``x - bias``; the caller resets the stream state.

        Parameters
        ----------
        bias : sequence of 6 float
            Force x, y, z in N, then torque x, y, z in N m, finite.

        Raises
        ------
        InputError
            Not 6 finite numbers (:func:`bias_vector`).

        """
        self.bias = bias_vector(bias)
        self._biased = bool(np.any(self.bias != 0.0))

    def measure_zero(self) -> None:
        """
        Measure what the corrected signal reads over the next ``carried_window`` samples.

        The result, :attr:`zero_measurement` (a new object), is the carried-load measurement
        of those samples at the feature rate: their per-axis median and how far it moved. With
        an empty hand held still it is what :meth:`set_bias` should add to the bias.
        """
        self._zero_rows.clear()
        self._zeroing = True

    def reset(self) -> None:
        """Forget everything, including the last stamp seen and the carried load."""
        self.last_input_t: Optional[float] = None
        #: No frame timed before this (s) may release: its features may hold a noisy sample.
        self.noise_until = -float('inf')
        #: The last completed measurement (load, how far it moved), None before the first.
        self.carried_load: Optional[CarriedLoad] = None
        self.measure_carried()
        self._restart()

    def measure_carried(self) -> None:
        """
        Measure the carried load again over the next ``carried_window`` F/T samples.

        Called by a reset (a start, ``~/reset``, a time jump) and by each arming: the hand
        now carries what it will carry into the approach. Until the new measurement is
        complete the frames keep the previous carried load (after a reset there is none, but
        no frame comes before ``carried_window`` samples). A wrench gap restarts the DFT
        window, not this: the object in the hand has not changed.
        """
        self._carried_rows.clear()
        self._measuring = self.uses_carried

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
        self._recent_holds.clear()
        self._recent_carried_shifts.clear()
        self._recent_forces.clear()         # a change across a gap is no jump of the reading
        # a measurement that completes from now on applies from its sample on
        self._previous_carried: Optional[np.ndarray] = None
        self._carried_from = 0

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
            Time of each feature frame's last sample (class docstring: its grid time, or
            for an F/T-only configuration the stamp of the sample that completed it).
        features : np.ndarray, shape (m, len(self.columns))

        """
        self.check_stamps(t)
        values = np.concatenate([force, torque], axis=1)
        if values.shape[0] == 1:
            row = values[0].tolist()
            whole = any(row[:3]) and any(row[3:])
        else:
            whole = bool(np.all(values[:, :3].any(axis=1)) and np.all(values[:, 3:].any(axis=1)))
        if not whole:
            keep = ~self._placeholder_rows(values)
            if not keep.all():
                t, values = t[keep], values[keep]
                if t.size == 0:
                    return np.zeros(0), np.zeros((0, len(self.columns)))
        elif values.shape[0]:
            self._last_reading = values[-1]         # whether it has a load: when needed
        if self._biased:
            values = values - self.bias
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

    def push_one(self, *, t: float,
                 values: Sequence[float]) -> Optional[tuple[np.ndarray, np.ndarray]]:
        """
        Add one wrench sample (a live message); return the feature frames it completes, if any.

        :meth:`push` with one sample: the same code, so the same numbers. A sample completes
        two frames at times where the input is slower than the grid (50, 51 Hz); both are
        returned.

        Parameters
        ----------
        t : float
            Sample stamp, seconds, finite.
        values : sequence of 6 float
            Force x, y, z in N and torque x, y, z in N m, finite.

        Returns
        -------
        (np.ndarray, np.ndarray) or None
            The frames' times, shape (m,), and features, shape (m, len(self.columns)); None
            when the sample completes none.

        """
        row = np.array([values], dtype=np.float64)
        ft_t, ft_x = self.push(t=np.array([t], dtype=np.float64), force=row[:, :3],
                               torque=row[:, 3:])
        return (ft_t, ft_x) if ft_t.size else None

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

    def _carried_shift_min(self, distance: np.ndarray) -> np.ndarray:
        # *_carried_shift_min of the (m, 2) new distances; keeps the newest for the next call
        window = self.config.shift_min_frames
        low = -running_max(values=-distance, before=-self._recent_carried_shifts.view,
                           window=window)
        self._recent_carried_shifts.extend(distance)
        self._recent_carried_shifts.keep_last(window - 1)
        return low

    def _held(self, values: np.ndarray) -> np.ndarray:
        # *_change_hold (columns 0, 1) and *_shift_hold (2, 3) of the (m, 4) new changes and
        # shifts over the newest hold_frames frames; keeps the newest for the next call.
        window = self.config.hold_frames
        before = self._recent_holds.view
        high = running_max(values=values, before=before, window=window)
        low = -running_max(values=-values, before=-before, window=window)
        self._recent_holds.extend(values)
        self._recent_holds.keep_last(window - 1)
        # the signed change that held: its smallest size if it kept one sign, else 0
        held = np.maximum(low, 0.0) + np.minimum(high, 0.0)
        held[:, 2:] = low[:, 2:]
        return held

    def _collect(self, rows: TailBuffer, dec_v: np.ndarray) -> Optional[CarriedLoad]:
        # Add decimated samples to a measurement of carried_window rows (the carried load or
        # the zero); return the measurement once it is complete, else None.
        missing = self.config.carried_window - rows.view.shape[0]
        rows.extend(dec_v[:missing])
        if dec_v.shape[0] < missing:
            return None
        return measure_carried_load(rows=rows.view, floor=self._floor)

    def _measure(self, dec_v: np.ndarray) -> None:
        # Feed the carried-load measurement; the decimated index from which the new carried
        # load applies is self._carried_from (frames before it keep the previous one).
        before = self._carried_rows.view.shape[0]
        done = self._collect(self._carried_rows, dec_v)
        if done is not None:
            self._previous_carried = self.carried
            self.carried_load = done
            self._carried_from = self._n_dec + self.config.carried_window - before - 1
            self._measuring = False

    def _placeholder_rows(self, values: np.ndarray) -> np.ndarray:
        # (n,) rows whose force (or torque) reads exactly (0, 0, 0) while the newest earlier
        # reading of it that was not (in this call or an earlier one) had a load, |F| or |T|
        # at or above PLACEHOLDER_AFTER; counts them and keeps the newest non-zero reading
        drop = np.zeros(values.shape[0], dtype=bool)
        last = (np.zeros(6) if self._last_reading is None else self._last_reading).copy()
        for cols, floor in ((slice(0, 3), PLACEHOLDER_AFTER[0]),
                            (slice(3, 6), PLACEHOLDER_AFTER[1])):
            part = values[:, cols]
            zero = ~part.any(axis=1)
            index = np.where(zero, -1, np.arange(zero.size))
            newest = np.maximum.accumulate(index)       # newest non-zero row at or before
            loaded = np.linalg.norm(part, axis=1) >= floor
            earlier = bool(np.linalg.norm(last[cols]) >= floor)
            drop |= zero & np.where(newest >= 0, loaded[np.maximum(newest, 0)], earlier)
            if newest[-1] >= 0:
                last[cols] = part[newest[-1]]
        self._last_reading = last
        self.placeholders += int(drop.sum())
        return drop

    def _measure_zero(self, dec_v: np.ndarray) -> None:
        # Feed the zero measurement (measure_zero) with the corrected samples.
        done = self._collect(self._zero_rows, dec_v)
        if done is not None:
            self.zero_measurement = done
            self._zeroing = False

    @property
    def carried(self) -> Optional[np.ndarray]:
        """Return the carried load, shape (6,) (N, N m): :attr:`carried_load`'s, or None."""
        return None if self.carried_load is None else self.carried_load.load

    def _carried_per_frame(self, ends: np.ndarray) -> np.ndarray:
        # (m, 6) carried load of each frame (decimated indices ends + self._mag_start)
        m = ends.size
        if self.carried is None:
            return np.zeros((m, 6))
        rows = np.broadcast_to(self.carried, (m, 6))
        if self._previous_carried is None:
            return rows
        older = ends + self._mag_start < self._carried_from
        if not older.any():
            return rows
        return np.where(older[:, None], self._previous_carried, rows)

    def _push_segment(self, t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dec_t, dec_v = self._resampler.push(t=t, values=v)
        n_blocks = dec_t.size
        if n_blocks == 0:
            return np.zeros(0), np.zeros((0, len(self.columns)))
        if self._measuring:
            self._measure(dec_v)
        if self._zeroing:
            self._measure_zero(dec_v)
        if self.noise_jump_n > 0:
            self._check_noise(dec_t, dec_v[:, :3])
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

    @property
    def noise_hold_s(self) -> float:
        """Return how long after a noisy grid sample frames may still hold it, s."""
        return self.history / self.config.ft_rate_hz

    def _check_noise(self, dec_t: np.ndarray, force: np.ndarray) -> None:
        # Count the new grid samples that are noisy (jump_statistics) and move noise_until to
        # noise_hold_s after the newest; keeps the newest NOISE_WINDOW forces.
        jump, reversals = jump_statistics(
            force=np.concatenate([self._recent_forces.view, force]))
        self._recent_forces.extend(force)
        self._recent_forces.keep_last(NOISE_WINDOW)
        # the windows end at the newest samples: those of the new ones are the last
        noisy = (jump >= self.noise_jump_n) & (reversals >= REVERSAL_SHARE)
        if not noisy.any():
            return
        times = dec_t[dec_t.size - jump.size:][noisy]
        if times[0] > self.noise_until:
            self.noise_bursts += 1
        self.noisy += int(noisy.sum())
        self.noise_level = float(jump[noisy][-1])
        self.noise_until = float(times[-1]) + self.noise_hold_s

    def _features(self, ends: np.ndarray) -> np.ndarray:
        cfg = self.config
        n = cfg.ft_window
        m = ends.size
        # |F| and |T| windows one after the other: one DFT call for both signals. Contiguous
        # whatever m is: numpy sums strided rows in another order, and a frame's features
        # must not depend on how many frames one call computes.
        mags = self._mags.view
        frames = column_windows(signal=mags, ends=ends, window=n).reshape(2 * m, n)
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
                derived.update(with_angle(('force_delta', 'torque_delta', 'ft_delta_angle'),
                                          change))
            if wanted & (set(CHANGE_FEATURES) | set(HOLD_FEATURES)):
                change = recent - window_median(signal=mags, ends=lagged,
                                                window=cfg.baseline_window)
                derived.update(with_angle(('force_change', 'torque_change', 'ft_change_angle'),
                                          change))
                if self._want_change_max:
                    peak = self._change_max(change)
                    derived['force_change_max'], derived['torque_change_max'] = peak.T
            if self._want_shift:
                vecs = self._vecs.view
                recent_v = window_mean(signal=vecs, ends=ends, window=cfg.delta_window)
                base_v = window_median(signal=vecs, ends=ends - cfg.shift_lag,
                                       window=cfg.shift_window)
                change_v = recent_v - base_v
                shift = vector_shift(change=change_v)
                if self.uses_carried:
                    carried = self._carried_per_frame(ends)
                    rel, cos = relative_to_carried(change=change_v, shift=shift,
                                                   carried=carried, floor=self._floor)
                    derived['force_shift_rel'], derived['torque_shift_rel'] = rel.T
                    derived['force_carried_cos'], derived['torque_carried_cos'] = cos.T
                    derived['ft_carried_lever'] = carried_lever(rel=rel)
                    if self._want_carried_shift:
                        # the same length as the shift's, against the carried load
                        away = recent_v - carried
                        distance = vector_shift(change=away)
                        derived['force_carried_shift'], derived['torque_carried_shift'] = \
                            distance.T
                        if self._want_carried_cos:
                            # the cosine of relative_to_carried, for the whole change
                            _, cos = relative_to_carried(change=away, shift=distance,
                                                         carried=carried, floor=self._floor)
                            derived['force_carried_shift_cos'], \
                                derived['torque_carried_shift_cos'] = cos.T
                        if self._want_carried_min:
                            low_c = self._carried_shift_min(distance)
                            derived['force_carried_shift_min'], \
                                derived['torque_carried_shift_min'] = low_c.T
                low, high = self._shift_extremes(shift)
                derived['force_shift'], derived['torque_shift'] = shift.T
                if self._want_rough:
                    rough = roughness(signal=vecs, ends=ends, window=cfg.rough_window)
                    before = roughness(signal=vecs, ends=ends - cfg.shift_lag,
                                       window=cfg.rough_window)
                    derived['force_roughness'] = rough
                    derived['force_roughness_rel'] = rough / np.maximum(before, ROUGH_FLOOR_N)
                derived['force_shift_min'], derived['torque_shift_min'] = low.T
                derived['force_shift_max'], derived['torque_shift_max'] = high.T
            if self._want_hold:
                held = self._held(np.stack(
                    [derived['force_change'], derived['torque_change'],
                     derived['force_shift'], derived['torque_shift']], axis=1))
                for name, column in zip(HOLD_FEATURES, held.T):
                    derived[name] = column
        for col, name in enumerate(self.use_delta, start=6):
            out[:, col] = derived[name]
        return out
