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
Straightforward batch reference of the feature core.

Written for clarity, with plain loops over frames, from whole recordings. The streaming code
(:mod:`contact_detector.features.streaming`) must give the same numbers for any chunking; the
tests compare the two. Offline tools may use it for plots, never for training or detection
(they run the streaming code, exactly as the node does).
"""

import math
from typing import Optional

from contact_detector.features import spectral
from contact_detector.features.config import (AUDIO_FEATURES, DELTA_FEATURES, FeatureConfig,
                                              HOLD_FEATURES, NEEDS_CARRIED, ROUGH_FEATURES,
                                              SHIFT_FEATURES)
from contact_detector.features.deltas import LEVER_EPS, ROUGH_FLOOR_N
from contact_detector.features.force_torque import FT_SPECTRAL_COLUMNS
from contact_detector.features.frames import FeatureFrames
from contact_detector.features.resample import integer_ratio, WrenchResampler
import numpy as np


def batch_audio_power(*, config: FeatureConfig, audio: np.ndarray, audio_rate: float,
                      audio_t0: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Audio power of every complete frame of a recording.

    Frame i covers samples ``[e_i - W_L, e_i)`` with ``e_i = W_L + floor(i * hop_s * Fs + 0.5)``
    and ends at ``audio_t0 + (e_i - 1) / Fs``.

    Parameters
    ----------
    config : FeatureConfig
        Frame and hop durations.
    audio : np.ndarray, shape (m,)
        int16 or float samples.
    audio_rate : float
        Hz.
    audio_t0 : float
        Time of sample 0, seconds.

    Returns
    -------
    t, power : np.ndarray, shape (n_frames,)

    """
    x = np.asarray(audio)
    x = x.astype(np.float64) / 32768.0 if x.dtype == np.int16 else x.astype(np.float64)
    w = config.audio_frame_samples(audio_rate)
    hop = config.audio_hop_s * audio_rate
    times, power = [], []
    i = 0
    while True:
        end = w + int(np.floor(i * hop + 0.5))
        if end > x.size:
            break
        frame = x[end - w:end]
        power.append(float(np.sum(frame * frame)) / w)
        times.append(audio_t0 + (end - 1) / audio_rate)
        i += 1
    return np.array(times), np.array(power)


def batch_noise_floor(*, config: FeatureConfig, power: np.ndarray) -> np.ndarray:
    """Noise floor ``F_i = min(P_i, F_{i-1} exp(hop/tau))``, ``F_{-1} = inf``, shape (n,)."""
    growth = np.exp(config.audio_hop_s / config.noise_floor_tau_s)
    floor = np.empty_like(power)
    previous = np.inf
    for i, p in enumerate(power):
        previous = min(p, previous * growth)
        floor[i] = previous
    return floor


def batch_ft_features(*, config: FeatureConfig, ft_t: np.ndarray, force: np.ndarray,
                      torque: np.ndarray,
                      ft_input_rate: Optional[float] = None) -> tuple[np.ndarray, np.ndarray,
                                                                      tuple]:
    """
    F/T spectral features of a whole, gap-free recording.

    Parameters
    ----------
    config : FeatureConfig
        The feature contract.
    ft_t : np.ndarray, shape (n,)
        Stamps, seconds.
    force, torque : np.ndarray, shape (n, 3)
        N and N m.
    ft_input_rate : float or None
        Input rate; decimated by block means to ``config.ft_rate_hz`` where it is an integer
        multiple, else resampled by :class:`~contact_detector.features.resample.WrenchResampler`.

    Returns
    -------
    t : np.ndarray, shape (m,)
        Time of each feature frame's last sample: of the last input sample of its block, or
        on the interpolating path its grid time, for an F/T-only configuration the stamp of
        the input sample that completed it.
    x : np.ndarray, shape (m, n_columns)
    columns : tuple of str

    """
    rate = ft_input_rate or config.ft_rate_hz
    m = integer_ratio(input_rate=rate, output_rate=config.ft_rate_hz)
    values = np.concatenate([force, torque], axis=1).astype(np.float64)
    if m:
        n_blocks = len(ft_t) // m
        dec_t = np.array([ft_t[b * m + m - 1] for b in range(n_blocks)])
        dec = np.array([values[b * m:(b + 1) * m].mean(axis=0) for b in range(n_blocks)])
    else:
        dec_t, dec = WrenchResampler(input_rate=rate, output_rate=config.ft_rate_hz,
                                     at_completion=config.ft_only).push(
            t=np.asarray(ft_t, dtype=np.float64), values=values)
        n_blocks = len(dec_t)
    if n_blocks == 0:
        dec = np.zeros((0, 6))
    mags = [np.linalg.norm(dec[:, :3], axis=1), np.linalg.norm(dec[:, 3:], axis=1)]
    deltas = [name for name in config.extra_features if name in DELTA_FEATURES]
    n = config.ft_window
    need = (max(n, config.delta_lag + max(config.delta_window, config.baseline_window))
            if deltas else n)
    carried_names = set(NEEDS_CARRIED)
    # the vector shift's longer baseline only when a feature uses it: without one, the first
    # frames have too little history for it (its median would be of an empty slice)
    shifted = bool(set(deltas) & (set(SHIFT_FEATURES) | set(HOLD_FEATURES) | carried_names
                                  | set(ROUGH_FEATURES)))
    if shifted:
        need = max(need, config.shift_lag + max(config.delta_window, config.shift_window))
    rough_wanted = bool(set(deltas) & set(ROUGH_FEATURES))
    if rough_wanted:
        need = max(need, config.shift_lag + config.rough_window + 2)
    if set(deltas) & carried_names:
        need = max(need, config.carried_window)
    # the carried load: the per-axis median of the first carried_window samples
    carried = np.median(dec[:config.carried_window], axis=0) if n_blocks else np.zeros(6)
    floors = (config.carried_floor_force, config.carried_floor_torque)
    columns = FT_SPECTRAL_COLUMNS + tuple(deltas)
    rows, times, changes, shifts, distances = [], [], [], [], []
    previous = [None, None]
    for end in range(need - 1, n_blocks, config.ft_hop):
        row = []
        delta, change = [], []
        for s, signal in enumerate(mags):
            frame = signal[end - n + 1:end + 1][None, :]
            spectrum = spectral.magnitude_spectrum(frames=frame, window_fn=config.ft_window_fn,
                                                   detrend=config.ft_detrend)
            centroid, spread = spectral.spectral_centroid_spread(spectra=spectrum,
                                                                 window_length=n)
            en = spectral.sum_normalised(spectra=spectrum)
            prev = en if previous[s] is None else previous[s]
            flux = spectral.spectral_flux(normalised=en, previous=prev)
            previous[s] = en
            row += [centroid[0], spread[0], flux[0]]
            if deltas:
                w, lag, b = config.delta_window, config.delta_lag, config.baseline_window
                new = signal[end - w + 1:end + 1].mean()
                delta.append(new - signal[end - lag - w + 1:end - lag + 1].mean())
                change.append(new - np.median(signal[end - lag - b + 1:end - lag + 1]))
        derived = {}
        if deltas:
            derived = {'force_delta': delta[0], 'torque_delta': delta[1],
                       'ft_delta_angle': math.atan2(delta[1], delta[0]),
                       'force_change': change[0], 'torque_change': change[1],
                       'ft_change_angle': math.atan2(change[1], change[0])}
            changes.append(change)
            recent = changes[-config.change_max_frames:]
            derived['force_change_max'] = max(c[0] for c in recent)
            derived['torque_change_max'] = max(c[1] for c in recent)
        if shifted:
            # the vector change against the per-axis median baseline, force then torque
            w, lag, b = config.delta_window, config.shift_lag, config.shift_window
            new_v = dec[end - w + 1:end + 1].mean(axis=0)
            base_v = np.median(dec[end - lag - b + 1:end - lag + 1], axis=0)
            shift = [math.sqrt(sum((new_v[k] - base_v[k]) ** 2 for k in axes))
                     for axes in ((0, 1, 2), (3, 4, 5))]
            shifts.append(shift)
            derived['force_shift'], derived['torque_shift'] = shift
            if rough_wanted:
                # the RMS of the force's second difference over the newest rough_window
                # samples, and over those ending shift_lag samples earlier
                rough = []
                for last in (end, end - config.shift_lag):
                    total = 0.0
                    for k in range(last - config.rough_window + 1, last + 1):
                        total += sum((dec[k, a] - 2 * dec[k - 1, a] + dec[k - 2, a]) ** 2
                                     for a in range(3))
                    rough.append(math.sqrt(total / config.rough_window))
                derived['force_roughness'] = rough[0]
                derived['force_roughness_rel'] = rough[0] / max(rough[1], ROUGH_FLOOR_N)
            for k, (axes, side) in enumerate((((0, 1, 2), 'force'), ((3, 4, 5), 'torque'))):
                size = math.sqrt(sum(carried[a] ** 2 for a in axes))
                derived[f'{side}_shift_rel'] = shift[k] / max(size, floors[k])
                dot = sum((new_v[a] - base_v[a]) * carried[a] for a in axes)
                cos = dot / (shift[k] * size) if size >= floors[k] and shift[k] > 0 else 0.0
                derived[f'{side}_carried_cos'] = min(1.0, max(-1.0, cos))
            derived['ft_carried_lever'] = math.log((derived['torque_shift_rel'] + LEVER_EPS)
                                                   / (derived['force_shift_rel'] + LEVER_EPS))
            # the distance from the carried load, and its minimum over shift_min_frames frames
            distances.append([math.sqrt(sum((new_v[a] - carried[a]) ** 2 for a in axes))
                              for axes in ((0, 1, 2), (3, 4, 5))])
            for k, (axes, side) in enumerate((((0, 1, 2), 'force'), ((3, 4, 5), 'torque'))):
                derived[f'{side}_carried_shift'] = distances[-1][k]
                size = math.sqrt(sum(carried[a] ** 2 for a in axes))
                dot = sum((new_v[a] - carried[a]) * carried[a] for a in axes)
                scale = distances[-1][k] * size if size >= floors[k] else 0.0
                derived[f'{side}_carried_shift_cos'] = (min(1.0, max(-1.0, dot / scale))
                                                        if scale > 0 else 0.0)
                derived[f'{side}_carried_shift_min'] = min(
                    d[k] for d in distances[-config.shift_min_frames:])
            for name, frames in (('min', config.shift_min_frames),
                                 ('max', config.change_max_frames)):
                recent = shifts[-frames:]
                pick = min if name == 'min' else max
                derived[f'force_shift_{name}'] = pick(s[0] for s in recent)
                derived[f'torque_shift_{name}'] = pick(s[1] for s in recent)
            # the change that held over the newest hold_frames frames: one sign throughout
            held = [c + s for c, s in zip(changes[-config.hold_frames:],
                                          shifts[-config.hold_frames:])]
            for k, name in enumerate(('force_change_hold', 'torque_change_hold')):
                if all(h[k] > 0 for h in held):
                    derived[name] = min(h[k] for h in held)
                elif all(h[k] < 0 for h in held):
                    derived[name] = max(h[k] for h in held)
                else:
                    derived[name] = 0.0
            derived['force_shift_hold'] = min(h[2] for h in held)
            derived['torque_shift_hold'] = min(h[3] for h in held)
        rows.append(row + [derived[name] for name in deltas])
        times.append(dec_t[end])
    x = np.array(rows) if rows else np.zeros((0, len(columns)))
    return np.array(times), x, columns


def batch_features(*, config: FeatureConfig, audio: np.ndarray, audio_rate: float,
                   audio_t0: float, ft_t: np.ndarray, force: np.ndarray, torque: np.ndarray,
                   ft_input_rate: Optional[float] = None,
                   max_ft_age_s: Optional[float] = None) -> FeatureFrames:
    """
    Per-audio-frame feature vectors of a whole recording (reference implementation).

    Each audio frame ending at ``t_a`` takes the newest F/T feature frame ending at or before
    ``t_a``; the row is invalid (zeros in the F/T columns) if there is none or it is older than
    ``max_ft_age_s`` (default ``ft_hop / ft_rate_hz + 0.05``). With an F/T-only configuration
    (``config.audio`` False) every F/T feature frame is one valid row, timed at the stamp of
    the wrench sample that completed it, and the audio is unused.

    Parameters
    ----------
    config : FeatureConfig
        The feature contract.
    audio : np.ndarray, shape (m,)
        int16 or float mono samples.
    audio_rate : float
        Hz.
    audio_t0 : float
        Time of audio sample 0, seconds.
    ft_t : np.ndarray, shape (n,)
        Wrench stamps, seconds.
    force, torque : np.ndarray, shape (n, 3)
        N and N m.
    ft_input_rate : float or None
        Wrench rate, Hz (default ``config.ft_rate_hz``).
    max_ft_age_s : float or None
        Freshness limit, seconds.

    Returns
    -------
    FeatureFrames

    """
    names = config.feature_names
    if config.ft_only:
        ft_times, ft_x, columns = batch_ft_features(config=config, ft_t=np.asarray(ft_t),
                                                    force=np.asarray(force),
                                                    torque=np.asarray(torque),
                                                    ft_input_rate=ft_input_rate)
        x = np.zeros((ft_times.size, len(names)))
        for j, name in enumerate(columns):
            if name in names:       # the torque columns of a force-only configuration are not
                x[:, names.index(name)] = ft_x[:, j]
        return FeatureFrames(t=ft_times, x=x, valid=np.ones(ft_times.size, dtype=bool),
                             names=names)
    t_a, power = batch_audio_power(config=config, audio=audio, audio_rate=audio_rate,
                                   audio_t0=audio_t0)
    ft_times, ft_x, columns = batch_ft_features(config=config, ft_t=np.asarray(ft_t),
                                                force=np.asarray(force),
                                                torque=np.asarray(torque),
                                                ft_input_rate=ft_input_rate)
    age = config.ft_hop / config.ft_rate_hz + 0.05 if max_ft_age_s is None else max_ft_age_s
    x = np.zeros((t_a.size, len(names)))
    valid = np.zeros(t_a.size, dtype=bool)
    rel = None
    if any(name in names for name in AUDIO_FEATURES[1:]):
        rel = spectral.power_db_above_floor(power=power,
                                            floor=batch_noise_floor(config=config, power=power))
    for i, t in enumerate(t_a):
        x[i, 0] = power[i]
        if rel is not None:
            peak = rel[max(0, i - config.peak_frames + 1):i + 1].max()
            audio = {'audio_power_rel_db': rel[i], 'audio_peak_rel_db': peak,
                     'audio_rise_db': rel[i] - rel[max(0, i - config.rise_frames)],
                     'audio_peak_gap_db': peak - rel[i],
                     'audio_hold_db': rel[max(0, i - config.audio_hold_frames + 1):i + 1].min()}
            for name, value in audio.items():
                if name in names:
                    x[i, names.index(name)] = value
        before = np.flatnonzero(ft_times <= t)
        if before.size and t - ft_times[before[-1]] <= age:
            valid[i] = True
            for j, name in enumerate(columns):
                if name in names:
                    x[i, names.index(name)] = ft_x[before[-1], j]
    return FeatureFrames(t=t_a, x=x, valid=valid, names=names)
