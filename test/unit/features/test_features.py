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

"""Feature core on synthetic signals: known answers, streaming == batch, causality, bad input."""

from dataclasses import replace

from contact_detector.errors import ConfigError, InputError
from contact_detector.features import (FeatureConfig, FeatureFrames, StreamingFeatureExtractor,
                                       TimeJumpError)
from contact_detector.features import spectral
from contact_detector.features.batch import batch_features
from contact_detector.features.buffers import column_windows, running_max
from contact_detector.features.config import CARRIED_DERIVED, CARRIED_FEATURES, EXTRA_FEATURES
from contact_detector.features.deltas import window_median
from contact_detector.features.force_torque import ForceTorqueStream
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest

T0 = 1_700_000_000.0


# --- pure per-frame functions -------------------------------------------------------------

@pytest.mark.parametrize('k0', [1, 3, 7, 15])
def test_pure_tone_centroid_is_its_frequency(k0):
    n = 32
    frames = np.sin(2 * np.pi * k0 * np.arange(n) / n)[None, :]
    spectra = spectral.magnitude_spectrum(frames=frames)
    centroid, spread = spectral.spectral_centroid_spread(spectra=spectra, window_length=n)
    # bin k0 of an N-point DFT at rate Fs is k0 * Fs / N Hz; normalised by Fs/2: 2 k0 / N
    assert centroid[0] == pytest.approx(2 * k0 / n, abs=1e-9)
    assert spread[0] == pytest.approx(0.0, abs=1e-6)


def test_white_noise_centroid_and_spread_of_a_flat_spectrum():
    rng = np.random.default_rng(1)
    frames = rng.normal(size=(400, 1024))
    spectra = spectral.magnitude_spectrum(frames=frames)
    centroid, spread = spectral.spectral_centroid_spread(spectra=spectra, window_length=1024)
    # a flat spectrum over nu in [0, 1] has centroid 1/2 and spread 1/sqrt(12)
    assert np.median(centroid) == pytest.approx(0.5, abs=0.01)
    assert np.median(spread) == pytest.approx(1 / np.sqrt(12), abs=0.01)


def test_flux_of_identical_frames_is_zero_and_of_disjoint_tones_is_two():
    n = 32
    a = spectral.sum_normalised(spectra=spectral.magnitude_spectrum(
        frames=np.sin(2 * np.pi * 3 * np.arange(n) / n)[None, :]))
    b = spectral.sum_normalised(spectra=spectral.magnitude_spectrum(
        frames=np.sin(2 * np.pi * 9 * np.arange(n) / n)[None, :]))
    assert spectral.spectral_flux(normalised=a, previous=a)[0] == 0.0
    assert spectral.spectral_flux(normalised=a, previous=b)[0] == pytest.approx(2.0, abs=1e-9)


def test_audio_power_of_known_signals():
    assert spectral.audio_power(frames=np.full((1, 512), 0.5))[0] == pytest.approx(0.25)
    sine = np.sin(2 * np.pi * 1000 * np.arange(16000) / 16000)[None, :]
    assert spectral.audio_power(frames=sine)[0] == pytest.approx(0.5, abs=1e-9)


def test_silence_gives_zeros_not_nan():
    zeros = np.zeros((2, 32))
    spectra = spectral.magnitude_spectrum(frames=zeros)
    centroid, spread = spectral.spectral_centroid_spread(spectra=spectra, window_length=32)
    en = spectral.sum_normalised(spectra=spectra)
    assert np.all(centroid == 0) and np.all(spread == 0)
    assert np.all(spectral.spectral_flux(normalised=en, previous=en) == 0)


def test_mean_detrend_removes_the_static_load():
    rng = np.random.default_rng(2)
    wiggle = rng.normal(size=(1, 32))
    light = spectral.magnitude_spectrum(frames=2.0 + wiggle, detrend='mean')
    heavy = spectral.magnitude_spectrum(frames=15.0 + wiggle, detrend='mean')
    np.testing.assert_allclose(light, heavy, atol=1e-12)


# --- windows over a stream: exact values whatever the method --------------------------------

@pytest.mark.parametrize('window', [1, 2, 3, 10, 15, 40, 50, 64])
def test_running_max_is_the_maximum_of_the_newest_window_rows(window):
    rows = np.random.default_rng(window).normal(size=(150, 2))
    for held in sorted({0, window // 2, window - 1}):
        out = running_max(values=rows[held:], before=rows[:held], window=window)
        expected = [rows[max(0, i - window + 1):i + 1].max(axis=0) for i in range(held, 150)]
        assert np.array_equal(out, np.array(expected)), held


@pytest.mark.parametrize('window', [1, 2, 15, 40])
@pytest.mark.parametrize('columns', [None, 2, 6])
def test_window_median_is_numpys_median_of_each_window(window, columns):
    shape = (120,) if columns is None else (120, columns)
    signal = np.random.default_rng(window).normal(size=shape).round(1)   # ties too
    for ends in (np.arange(window - 1, 120), np.arange(window + 3, 120, 5),
                 np.array([window - 1, window + 7, 119]), np.array([119])):
        out = window_median(signal=signal, ends=ends, window=window)
        expected = np.array([np.median(signal[e - window + 1:e + 1], axis=0) for e in ends])
        assert out.shape == expected.shape and np.array_equal(out, expected), ends


def test_column_windows_are_contiguous_copies_of_the_windows():
    signal = np.random.default_rng(5).normal(size=(90, 2))
    for ends in (np.arange(7, 90), np.arange(7, 90, 4), np.array([7, 8, 30]), np.array([89])):
        out = column_windows(signal=signal, ends=ends, window=8)
        assert out.shape == (2, ends.size, 8) and out.flags['C_CONTIGUOUS']
        for col in range(2):
            for i, e in enumerate(ends):
                assert np.array_equal(out[col, i], signal[e - 7:e + 1, col])
        out[...] = 0.0                  # a copy: the stream's history is not touched
    assert np.all(signal != 0.0)


@pytest.mark.parametrize('lever_m', [0.1, 0.25])
def test_delta_angle_measures_the_lever_arm_of_a_load_change(lever_m):
    # 10 N hanging at 0.1 m from the sensor; then 2 N of it is taken at lever_m (the table
    # under the object's bottom, or a change at its centre of mass)
    config = FeatureConfig(extra_features=('force_delta', 'torque_delta', 'ft_delta_angle'))
    stream = ForceTorqueStream(config=config, input_rate=100.0)
    n = 60
    up = np.where(np.arange(n) >= 40, 2.0, 0.0)
    force = np.stack([np.zeros(n), np.zeros(n), -10.0 + up], axis=1)
    torque = np.stack([np.zeros(n), 1.0 - lever_m * up, np.zeros(n)], axis=1)
    t, x = stream.push(t=T0 + np.arange(n) / 100, force=force, torque=torque)
    assert stream.columns[-3:] == ('force_delta', 'torque_delta', 'ft_delta_angle')
    settled = t >= T0 + 0.42     # both halves of the delta see the step's two sides
    changed = settled & (t < T0 + 0.5)
    np.testing.assert_allclose(x[changed, -3], -2.0)
    np.testing.assert_allclose(x[changed, -2], -2.0 * lever_m)
    np.testing.assert_allclose(np.tan(x[changed, -1]), lever_m)
    assert np.all(x[changed, -1] < -np.pi / 2)     # unloading: the force dropped
    # no change at all gives 0, not NaN
    assert np.all(x[t < T0 + 0.4, -1] == 0.0)


def test_change_against_the_median_baseline_does_not_echo_a_knock():
    # a 20 ms knock loads the hand by 8 N; 0.1 s later the plain delta sees it leave its old
    # window as an 8 N unloading, which looks like the table taking the weight
    config = FeatureConfig(extra_features=('force_delta', 'force_change'))
    stream = ForceTorqueStream(config=config, input_rate=100.0)
    n = 80
    force = np.zeros((n, 3))
    force[:, 2] = -10.0
    force[40:42, 2] -= 8.0
    t, x = stream.push(t=T0 + np.arange(n) / 100, force=force, torque=np.zeros((n, 3)))
    echo = (t >= T0 + 0.505) & (t <= T0 + 0.525)   # two of the three old samples are the knock
    assert echo.sum() == 2
    np.testing.assert_allclose(x[echo, -2], -8.0 * 2 / 3)
    np.testing.assert_allclose(x[echo, -1], 0.0)
    # while the knock is on, both see the loading
    assert np.all(x[(t >= T0 + 0.40) & (t <= T0 + 0.41), -1] > 2.5)
    # a lasting change is seen by both
    force[60:, 2] += 2.0
    stream.reset()
    t, x = stream.push(t=T0 + np.arange(n) / 100, force=force, torque=np.zeros((n, 3)))
    late = (t >= T0 + 0.62) & (t <= T0 + 0.765)   # until the baseline has moved too
    np.testing.assert_allclose(x[late, -1], -2.0)


def test_change_max_remembers_the_push_of_a_knock_and_not_a_touch():
    # a knock pushes the load up by 8 N for 20 ms and rings back 3 N below it; a touch unloads
    # by 3 N with no push first. force_change alone is -3 N in both; its recent maximum is not.
    config = FeatureConfig(extra_features=('force_change', 'force_change_max'), delta_window=1,
                           change_max_frames=15)
    n = 120
    force = np.zeros((n, 3))
    force[:, 2] = -10.0
    knock = force.copy()
    knock[40:42, 2] -= 8.0
    knock[46:50, 2] += 3.0
    touch = force.copy()
    touch[46:, 2] += 3.0
    seen = {}
    for name, f in (('knock', knock), ('touch', touch)):
        stream = ForceTorqueStream(config=config, input_rate=100.0)
        t, x = stream.push(t=T0 + np.arange(n) / 100, force=f, torque=np.zeros((n, 3)))
        seen[name] = dict(zip(np.round((t - T0) * 100).astype(int), x[:, -2:].tolist()))
    # 0.48 s: both unload by 3 N against the baseline; only the knock pushed up 6-8 frames ago
    assert seen['knock'][48][0] == pytest.approx(-3.0) == seen['touch'][48][0]
    assert seen['knock'][48][1] == pytest.approx(8.0)
    assert seen['touch'][48][1] == pytest.approx(0.0)
    # 15 frames after the push ends, it is forgotten
    assert seen['knock'][42 + 15][1] < 1.0
    # silence (a constant load) gives zeros
    assert seen['touch'][35] == [0.0, 0.0]


def _random_rotation(seed):
    q = np.random.default_rng(seed).normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


SHIFT_CONFIG = FeatureConfig(extra_features=('force_shift', 'torque_shift', 'force_shift_min',
                                             'torque_shift_min', 'force_shift_max',
                                             'torque_shift_max'),
                             delta_window=1, shift_min_frames=10, change_max_frames=50)


def _shift_features(force, torque):
    stream = ForceTorqueStream(config=SHIFT_CONFIG, input_rate=100.0)
    t, x = stream.push(t=T0 + np.arange(force.shape[0]) / 100, force=force, torque=torque)
    return np.round((t - T0) * 100).astype(int), x[:, -6:]


def test_shift_features_do_not_depend_on_sensor_orientation_or_tare():
    # the same load transfer (the table takes 4 N of a 6 N weight at 0.15 m) seen by a sensor
    # held at a random orientation, with or without a bias, gives the same shift features;
    # the signed |F| change does not (it even flips sign on a tared sensor)
    n = 120
    force = np.zeros((n, 3))
    force[:, 0] = -6.0
    force[60:, 0] += np.minimum(np.arange(n - 60) / 5, 1.0) * 4.0
    torque = np.cross([0.0, 0.0, 0.15], force)
    _, ref = _shift_features(force, torque)
    for seed in range(5):
        rot = _random_rotation(seed)
        bias_f, bias_t = np.array([3.0, -2.0, 40.0]) * seed, np.array([0.2, 0.1, -0.3]) * seed
        _, got = _shift_features(force @ rot.T + bias_f, torque @ rot.T + bias_t)
        np.testing.assert_allclose(got, ref, atol=1e-9)
    t, x = _shift_features(force, torque)
    frame = dict(zip(t.tolist(), x.tolist()))
    assert frame[59] == [0.0] * 6                       # a constant load gives zeros
    assert frame[70][0] == pytest.approx(4.0)           # the whole transfer, in N
    assert frame[70][1] == pytest.approx(0.6)           # and 0.15 m x 4 N of torque


def _knock_and_touch(n: int) -> tuple:
    """(n, 3) forces holding 10 N: a 20 ms knock of 8 N that rings back; a 3 N touch for good."""
    force = np.zeros((n, 3))
    force[:, 2] = -10.0
    knock = force.copy()
    knock[80:82, 2] -= 8.0
    knock[83:87, 2] += 3.0 * np.array([1, -1, 1, -1])
    touch = force.copy()
    touch[80:, 2] += 3.0
    return knock, touch


def test_shift_min_tells_a_lasting_load_change_from_a_knock():
    # a 20 ms knock of 8 N that rings back, against a touch that moves 3 N for good: the
    # newest shift is large in both, its minimum over the last 10 frames only for the touch
    n = 160
    knock, touch = _knock_and_touch(n)
    zero = np.zeros((n, 3))
    tk, xk = _shift_features(knock, zero)
    tt, xt = _shift_features(touch, zero)
    at = {int(a): row for a, row in zip(tk, xk)}
    bt = {int(a): row for a, row in zip(tt, xt)}
    assert at[81][0] == pytest.approx(8.0) and bt[81][0] == pytest.approx(3.0)
    assert at[90][2] == pytest.approx(0.0)               # the knock: nothing lasted
    assert bt[90][2] == pytest.approx(3.0)               # the touch: 3 N for 10 frames
    assert at[90][4] == pytest.approx(8.0)               # the maximum remembers the knock


def test_hold_features_see_that_a_load_change_stayed_and_a_knock_fell_back():
    # the knock and the touch of the test above: a touch's change holds one sign for the last
    # 4 frames from 40 ms after it, a knock's pulse and ringing do not
    config = FeatureConfig(extra_features=('force_change', 'force_shift', 'force_change_hold',
                                           'torque_change_hold', 'force_shift_hold'),
                           delta_window=1, hold_frames=4)
    n = 160
    knock, touch = _knock_and_touch(n)
    seen = {}
    for name, f in (('knock', knock), ('touch', touch)):
        stream = ForceTorqueStream(config=config, input_rate=100.0)
        t, x = stream.push(t=T0 + np.arange(n) / 100, force=f, torque=np.zeros((n, 3)))
        seen[name] = dict(zip(np.round((t - T0) * 100).astype(int).tolist(),
                              x[:, -5:].tolist()))
    pulse = knock
    knock, touch = seen['knock'], seen['touch']
    assert touch[79] == [0.0] * 5                       # a constant load gives zeros
    # the touch: |F| fell 3 N; held for 4 frames only from its 4th frame on
    assert touch[80][0] == pytest.approx(-3.0) and touch[80][2] == pytest.approx(0.0)
    assert touch[83][2] == pytest.approx(-3.0)           # unloading that held: negative
    assert touch[83][4] == pytest.approx(3.0)            # and the vector shift held
    assert touch[83][3] == 0.0                           # no torque moved
    # the knock: as large a change, but it does not hold
    assert knock[80][0] == pytest.approx(8.0)
    assert knock[81][2] == 0.0 and knock[81][4] == 0.0
    assert all(knock[k][2] == 0.0 for k in range(80, 100))
    assert knock[86][4] == pytest.approx(3.0)            # 4 frames of ringing, +-3 N
    assert all(knock[k][4] == 0.0 for k in range(87, 100))
    # the 20 ms push lasted 2 frames: over 2 frames it held, as loading (> 0)
    short = ForceTorqueStream(config=replace(config, hold_frames=2), input_rate=100.0)
    t, x = short.push(t=T0 + np.arange(n) / 100, force=pulse, torque=np.zeros((n, 3)))
    assert x[np.round((t - T0) * 100).astype(int) == 81, -3][0] == pytest.approx(8.0)


# --- streaming extractor ------------------------------------------------------------------

CARRIED_CONFIG = FeatureConfig(extra_features=('force_shift', 'torque_shift') + CARRIED_FEATURES,
                               delta_window=1)


def _carried_features(force, torque, *, config=CARRIED_CONFIG, t=None):
    stream = ForceTorqueStream(config=config, input_rate=100.0)
    t = T0 + np.arange(force.shape[0]) / 100 if t is None else t
    ft, x = stream.push(t=t, force=force, torque=torque)
    return dict(zip(np.round((ft - T0) * 100).astype(int).tolist(), x[:, -6:].tolist()))


def _carried_load(n: int, *, lever_m: float = 0.15) -> tuple:
    """(n, 3) force and torque of a 6 N weight along -x held at ``lever_m`` along z."""
    force = np.zeros((n, 3))
    force[:, 0] = -6.0
    return force, np.cross([0.0, 0.0, lever_m], force)


def test_carried_features_relate_the_change_to_the_carried_load_in_any_sensor_frame():
    # the table takes 4 N of a 6 N weight under the hand (0.15 m along z): the change is 2/3 of
    # the carried load, against it (cosine -1), for the force and its torque alike, whatever
    # the sensor's orientation (rotations of the frame change neither lengths nor angles)
    n = 120
    force, torque = _carried_load(n)
    force[80:, 0] += np.minimum(np.arange(n - 80) / 5, 1.0) * 4.0
    torque = np.cross([0.0, 0.0, 0.15], force)
    ref = _carried_features(force, torque)
    assert ref[79] == [0.0] * 6                          # nothing changed yet
    assert ref[90][:2] == pytest.approx([4.0, 0.6])      # force_shift, torque_shift
    assert ref[90][2:] == pytest.approx([4 / 6, 4 / 6, -1.0, -1.0])
    for seed in range(4):
        rot = _random_rotation(seed)
        got = _carried_features(force @ rot.T, torque @ rot.T)
        for k in ref:
            np.testing.assert_allclose(got[k], ref[k], atol=1e-9)


def _lever_features(force, torque):
    """``force_carried_cos`` and ``ft_carried_lever`` per frame (keyed by sample index)."""
    config = FeatureConfig(extra_features=CARRIED_FEATURES + CARRIED_DERIVED, delta_window=1)
    stream = ForceTorqueStream(config=config, input_rate=100.0)
    ft, x = stream.push(t=T0 + np.arange(force.shape[0]) / 100, force=force, torque=torque)
    keys = np.round((ft - T0) * 100).astype(int).tolist()
    return dict(zip(keys, x[:, -3].tolist())), dict(zip(keys, x[:, -1].tolist()))


def test_carried_lever_tells_a_brush_from_the_table_taking_the_weight():
    # 6 N carried along -x (gravity), its centre of mass 0.15 m along z: 0.9 N m. The table
    # takes 4 N off under the centre of mass (on the line of the weight, 0.1 m further
    # along -x): force and torque fall by the same share (2/3), lever 0. A brush 5 cm from the
    # sensor pushes up (+x, against the weight, like the table) with a sideways part (+y) and
    # a stick-slip fluctuation: the torque changes by a far smaller share than the force.
    # The carried cosine calls both a load taken off (< -0.8); the lever does not.
    n, weight_at = 140, np.array([0.0, 0.0, 0.15])
    force, torque = _carried_load(n)
    table = force.copy()
    table[80:, 0] += np.minimum(np.arange(n - 80) / 3, 1.0) * 4.0
    table_torque = torque + np.cross(weight_at + [-0.1, 0.0, 0.0], table - force)
    rng = np.random.default_rng(3)
    slip = np.clip(1 + 0.35 * rng.standard_normal(n - 80), 0.0, None)
    push = np.zeros((n, 3))
    push[80:] = np.outer(np.minimum(np.arange(n - 80) / 3, 1.0) * slip, [1.5, 1.0, 0.0])
    brush_torque = torque + np.cross([0.0, 0.0, 0.05], push)
    cos_t, lever_t = _lever_features(table, table_torque)
    cos_b, lever_b = _lever_features(force + push, brush_torque)
    assert lever_t[79] == 0.0 and lever_b[79] == 0.0        # nothing changed: ln(e / e)
    for k in range(84, 100):                                 # 40-200 ms into either
        assert lever_t[k] == pytest.approx(0.0, abs=1e-9)
        assert cos_t[k] == pytest.approx(-1.0)
        assert cos_b[k] < -0.8
        assert lever_b[k] < -0.7
    # the brush's share of force and torque, whatever its fluctuation: 0.3 and 0.1 of the load
    steady = np.ones(n - 80)
    push[80:] = np.outer(np.minimum(np.arange(n - 80) / 3, 1.0) * steady, [1.5, 1.0, 0.0])
    _, lever = _lever_features(force + push, torque + np.cross([0.0, 0.0, 0.05], push))
    share_f, share_t = np.hypot(1.5, 1.0) / 6.0, np.hypot(0.075, 0.05) / 0.9
    assert lever[90] == pytest.approx(np.log((share_t + 0.02) / (share_f + 0.02)))
    # lengths and shares do not change when the sensor frame rotates
    rot = _random_rotation(5)
    _, rotated = _lever_features((force + push) @ rot.T,
                                 (torque + np.cross([0.0, 0.0, 0.05], push)) @ rot.T)
    assert all(rotated[k] == pytest.approx(lever[k], abs=1e-9) for k in lever)


def test_carried_features_on_a_tared_sensor_fall_back_to_the_floor():
    # the same unloading seen by a tared sensor (the carried load subtracted): nothing to
    # compare with, so the ratio is the shift in units of the floor and the cosine is 0
    n = 120
    force, torque = _carried_load(n)
    force[80:, 0] += 4.0
    torque = np.cross([0.0, 0.0, 0.15], force)
    tared = _carried_features(force - force[0], torque - torque[0])
    floor = (CARRIED_CONFIG.carried_floor_force, CARRIED_CONFIG.carried_floor_torque)
    assert tared[90][:2] == pytest.approx([4.0, 0.6])
    assert tared[90][2:] == pytest.approx([4.0 / floor[0], 0.6 / floor[1], 0.0, 0.0])
    # a bias that leaves a load above the floor is a carried load like any other
    assert _carried_features(force, torque)[90][4] == pytest.approx(-1.0)


def test_carried_cosine_tells_a_lasting_unload_from_a_lateral_push():
    # both move the force by 3 N for good: the table takes it off the carried load (-1), a
    # person pushing the object sideways adds it across the load (0), pulling it down adds it
    # to the load (+1); the ratio does not tell them apart
    n = 120
    seen = {}
    for name, direction in (('unload', [1.0, 0, 0]), ('push', [0, 3 / 5, 4 / 5]),
                            ('pull', [-1.0, 0, 0])):
        force, torque = _carried_load(n)
        force[80:] += 3.0 * np.array(direction)
        seen[name] = _carried_features(force, torque)[100]
    assert seen['unload'][4] == pytest.approx(-1.0)
    assert seen['push'][4] == pytest.approx(0.0, abs=1e-12)
    assert seen['pull'][4] == pytest.approx(1.0)
    assert all(seen[k][2] == pytest.approx(0.5) for k in seen)


CARRIED_SHIFT_CONFIG = FeatureConfig(
    extra_features=('force_shift', 'force_carried_shift', 'torque_carried_shift',
                    'force_carried_shift_min', 'torque_carried_shift_min'),
    delta_window=1, shift_min_frames=10)


def _carried_shift_features(force, torque):
    """Per frame (keyed by sample index): force_shift and the four *_carried_shift columns."""
    stream = ForceTorqueStream(config=CARRIED_SHIFT_CONFIG, input_rate=100.0)
    ft, x = stream.push(t=T0 + np.arange(force.shape[0]) / 100, force=force, torque=torque)
    return dict(zip(np.round((ft - T0) * 100).astype(int).tolist(), x[:, -5:].tolist()))


def test_carried_shift_keeps_a_slow_transfer_the_sliding_shift_forgets():
    # a soft layer takes 4 N of a 6 N weight over 1 s, linearly from sample 100: the sliding
    # shift compares with a baseline 0.2-0.6 s back and sees only part of it, the distance
    # from the carried load sees all of it, for the force and its torque (0.15 m) alike
    n = 260
    force, torque = _carried_load(n)
    force[100:, 0] += np.minimum(np.arange(n - 100) / 100, 1.0) * 4.0
    torque = np.cross([0.0, 0.0, 0.15], force)
    got = _carried_shift_features(force, torque)
    assert got[99][1:] == [0.0] * 4                          # nothing moved yet
    assert got[200][1] == pytest.approx(4.0)                 # force_carried_shift
    assert got[200][2] == pytest.approx(0.6)                 # torque_carried_shift
    assert got[200][3] == pytest.approx(3.64)                # its minimum: 10 frames back
    assert got[200][0] < 2.0                                 # the sliding shift: part of it
    assert got[259][0] == pytest.approx(0.0) and got[259][1] == pytest.approx(4.0)


def test_carried_shift_does_not_depend_on_sensor_orientation_or_bias():
    # any rotation of the sensor frame, and a constant bias (the carried load is read by the
    # same sensor), leave the distance from the carried load as it was
    n = 140
    force, torque = _carried_load(n)
    force[80:, 0] += 3.0
    torque = np.cross([0.0, 0.0, 0.15], force)
    ref = _carried_shift_features(force, torque)
    assert ref[100][1:] == pytest.approx([3.0, 0.45, 3.0, 0.45])
    for seed in range(3):
        rot = _random_rotation(seed)
        bias = np.random.default_rng(seed).normal(scale=5.0, size=6)
        got = _carried_shift_features(force @ rot.T + bias[:3], torque @ rot.T + bias[3:])
        for k in ref:
            np.testing.assert_allclose(got[k], ref[k], atol=1e-9)


SHIFT_COS_CONFIG = FeatureConfig(
    extra_features=('force_carried_cos', 'force_carried_shift', 'force_carried_shift_cos',
                    'torque_carried_shift_cos'), delta_window=1)


def test_carried_shift_cosine_keeps_the_direction_of_a_settled_change():
    # the table takes 3 N off a 6 N weight (-1), a hand pushes the object sideways (0) or down
    # (+1), each for good from sample 80, under 0.02 N of sensor noise. Once the change has
    # settled, the newest change is noise and its cosine (force_carried_cos) turns with it; the
    # cosine of the whole distance from the carried load keeps the change's direction
    n = 200
    rng = np.random.default_rng(3)
    for direction, want in (([1.0, 0, 0], -1.0), ([0, 3 / 5, 4 / 5], 0.0), ([-1.0, 0, 0], 1.0)):
        force, torque = _carried_load(n)
        force[80:] += 3.0 * np.array(direction)
        force += rng.normal(scale=0.02, size=force.shape)
        stream = ForceTorqueStream(config=SHIFT_COS_CONFIG, input_rate=100.0)
        ft, x = stream.push(t=T0 + np.arange(n) / 100, force=force,
                            torque=np.cross([0.0, 0.0, 0.15], force))
        late = x[np.round((ft - T0) * 100) >= 150, -4:]
        np.testing.assert_allclose(late[:, 2], want, atol=0.02)
        np.testing.assert_allclose(late[:, 3], want, atol=0.05)
        assert np.ptp(late[:, 0]) > 0.5                  # the newest change's cosine wanders
    # a tared sensor has no carried load to compare with: 0
    force, torque = _carried_load(n)
    force[80:, 0] += 3.0
    stream = ForceTorqueStream(config=SHIFT_COS_CONFIG, input_rate=100.0)
    _, x = stream.push(t=T0 + np.arange(n) / 100, force=force - force[0],
                       torque=np.zeros((n, 3)))
    assert x[-1, -3] == pytest.approx(3.0) and x[-1, -2:].tolist() == [0.0, 0.0]


def test_carried_shift_min_tells_a_lasting_transfer_from_a_knock():
    # the 20 ms knock of 8 N that rings back, against the 3 N touch: both are far from the
    # carried load while they last; 10 frames later only the touch is
    n = 160
    knock, touch = _knock_and_touch(n)
    zero = np.zeros((n, 3))
    at, bt = _carried_shift_features(knock, zero), _carried_shift_features(touch, zero)
    assert at[81][1] == pytest.approx(8.0) and bt[81][1] == pytest.approx(3.0)
    assert at[92][3] == pytest.approx(0.0)                   # the knock did not last
    assert bt[92][3] == pytest.approx(3.0)                   # the touch did


def test_carried_load_is_measured_at_the_start_and_again_on_arming_not_after_a_gap():
    # 6 N carried at the start, then 10 N (another object) from 1 s on, a 0.2 s wrench gap at
    # 1.5 s, an arming at 2 s and the table taking 2 N at 2.15 s: the gap restarts the window
    # but keeps the carried load; the arming measures it again over the next carried_window
    # (20) samples, and the frames before that keep the old one
    n = 300
    force, torque = _carried_load(n)
    force[100:, 0] = -10.0
    force[215:, 0] = -8.0
    torque = np.cross([0.0, 0.0, 0.15], force)
    t = T0 + np.arange(n) / 100
    t[150:] += 0.2
    config = replace(CARRIED_CONFIG, carried_window=20)
    got = {}
    for single in (False, True):
        stream = ForceTorqueStream(config=config, input_rate=100.0)
        stream.push(t=t[:200], force=force[:200], torque=torque[:200])
        assert stream.restarts == 1
        assert stream.carried[:3] == pytest.approx([-6.0, 0.0, 0.0])   # the start's
        stream.measure_carried()
        if single:
            rows = [stream.push(t=t[k:k + 1], force=force[k:k + 1], torque=torque[k:k + 1])
                    for k in range(200, n)]
            got[single] = (np.concatenate([r[0] for r in rows]),
                           np.concatenate([r[1] for r in rows]))
        else:
            got[single] = stream.push(t=t[200:], force=force[200:], torque=torque[200:])
        assert stream.carried[:3] == pytest.approx([-10.0, 0.0, 0.0])  # the arming's
    assert all(np.array_equal(a, b) for a, b in zip(got[True], got[False]))
    frame = dict(zip(np.round((got[True][0] - T0) * 100 - 20).astype(int).tolist(),
                     got[True][1][:, -6:].tolist()))
    assert frame[214][2] == 0.0
    assert frame[218][2] == pytest.approx(2 / 6)         # the old carried load
    assert frame[219][2] == pytest.approx(2 / 10)        # the new one, from its 20th sample
    assert frame[218][4] == pytest.approx(-1.0) and frame[219][4] == pytest.approx(-1.0)


def test_carried_config_fields_are_validated_and_written_only_when_changed():
    assert 'carried_window' not in FeatureConfig().to_dict()
    changed = replace(FeatureConfig(), carried_window=30, carried_floor_force=1.0)
    assert FeatureConfig.from_dict(changed.to_dict()) == changed
    for bad in ({'carried_window': 0}, {'carried_floor_force': 0.0},
                {'carried_floor_torque': float('nan')}):
        with pytest.raises(ConfigError, match=next(iter(bad))):
            FeatureConfig(**bad)


def make_signals(*, seed, seconds, audio_rate, ft_rate, ft_offset=0.00123):
    rng = np.random.default_rng(seed)
    audio = (rng.normal(0, 0.05, int(seconds * audio_rate)) * 32767).astype(np.int16)
    n_ft = int(seconds * ft_rate)
    ft_t = T0 + ft_offset + np.arange(n_ft) / ft_rate
    force = rng.normal(0, 1, (n_ft, 3)) + [0.0, 0.0, 5.0]
    torque = rng.normal(0, 0.1, (n_ft, 3))
    return audio, ft_t, force, torque


def stream(*, extractor, audio, audio_rate, ft_t, force, torque, audio_chunks, ft_chunks,
           flush=True, single=False):
    """
    Push chunks in the order of their last sample's time, as they would arrive.

    With ``single``, one-sample wrench chunks go through ``push_wrench_one`` (the live path).
    """
    a_ends = np.minimum(np.cumsum(audio_chunks), audio.size)
    f_ends = np.minimum(np.cumsum(ft_chunks), ft_t.size)
    a_ends = sorted(set(a_ends.tolist()) | {audio.size})
    f_ends = sorted(set(f_ends.tolist()) | {ft_t.size})
    events = [(T0 + (e - 1) / audio_rate, 0, e) for e in a_ends]
    events += [(ft_t[e - 1], 1, e) for e in f_ends]
    out, la, lf = [], 0, 0
    for _, kind, end in sorted(events):
        if kind == 0:
            out.append(extractor.push_audio(audio[la:end], stamp=T0 + (end - 1) / audio_rate))
            la = end
        elif single and end - lf == 1:
            out.append(extractor.push_wrench_one(
                t=ft_t[lf], values=force[lf].tolist() + torque[lf].tolist()))
            lf = end
        else:
            out.append(extractor.push_wrench(t=ft_t[lf:end], force=force[lf:end],
                                             torque=torque[lf:end]))
            lf = end
    if flush:
        out.append(extractor.flush())
    return FeatureFrames.concat(out, extractor.names)


configs = st.builds(
    FeatureConfig,
    ft_window=st.sampled_from([8, 16, 32]),
    ft_hop=st.sampled_from([1, 2, 5]),
    ft_window_fn=st.sampled_from(['rect', 'hann']),
    ft_detrend=st.sampled_from(['none', 'mean']),
    extra_features=st.sampled_from([
        (), ('audio_power_rel_db', 'audio_peak_rel_db', 'force_delta', 'torque_delta'),
        ('audio_peak_rel_db',), ('ft_delta_angle',),
        ('audio_power_rel_db', 'audio_peak_rel_db', 'force_delta', 'torque_delta',
         'ft_delta_angle'), ('torque_change', 'ft_change_angle', 'force_delta'),
        ('audio_rise_db',), ('audio_peak_gap_db', 'audio_rise_db', 'force_change'),
        ('torque_change_max',), ('force_change_max', 'force_delta', 'torque_change'),
        ('force_shift', 'torque_shift_min'), ('torque_shift', 'force_shift_max', 'force_delta'),
        ('force_carried_cos', 'torque_shift_rel'), ('force_shift_rel', 'torque_carried_cos'),
        ('ft_carried_lever',), ('force_shift', 'ft_carried_lever', 'torque_carried_cos'),
        ('audio_hold_db',), ('audio_peak_rel_db', 'audio_hold_db', 'force_shift'),
        ('force_carried_shift', 'torque_carried_shift_min'),
        ('torque_carried_shift', 'force_carried_shift_min', 'force_shift_rel'),
        ('force_carried_shift_cos', 'torque_shift'), ('torque_carried_shift_cos',),
        ('force_roughness',), ('force_roughness_rel', 'force_carried_shift'),
        EXTRA_FEATURES]),
    rise_frames=st.sampled_from([1, 2, 3, 12]),
    peak_frames=st.sampled_from([1, 4, 10]),
    change_max_frames=st.sampled_from([1, 2, 15, 40]),
    shift_min_frames=st.sampled_from([1, 3, 10]),
    shift_lag=st.sampled_from([1, 5, 20]),
    shift_window=st.sampled_from([1, 4, 40]),
    hold_frames=st.sampled_from([1, 2, 4, 7]),
    carried_window=st.sampled_from([1, 7, 50]),
    audio_hold_frames=st.sampled_from([1, 2, 4, 8, 13]),
    rough_window=st.sampled_from([1, 5, 20, 33]),
)


@settings(max_examples=30, deadline=None)
@given(config=configs,
       rates=st.sampled_from([(16000, 100), (44100, 100), (48000, 1000), (22050, 200)]),
       seed=st.integers(0, 10_000),
       audio_chunk=st.integers(1, 20_000),
       ft_chunk=st.integers(1, 60))
def test_streaming_equals_batch_for_any_chunking(config, rates, seed, audio_chunk, ft_chunk):
    audio_rate, ft_rate = rates
    if ft_rate % config.ft_rate_hz:
        ft_rate = 100
    audio, ft_t, force, torque = make_signals(seed=seed, seconds=1.5, audio_rate=audio_rate,
                                              ft_rate=ft_rate)
    rng = np.random.default_rng(seed)
    audio_chunks = rng.integers(1, audio_chunk + 1, size=audio.size)
    ft_chunks = rng.integers(1, ft_chunk + 1, size=ft_t.size)
    extractor = StreamingFeatureExtractor(config=config, audio_rate=audio_rate,
                                          ft_input_rate=ft_rate, max_ft_wait_s=1e9)
    got = stream(extractor=extractor, audio=audio, audio_rate=audio_rate, ft_t=ft_t,
                 force=force, torque=torque, audio_chunks=audio_chunks, ft_chunks=ft_chunks)
    ref = batch_features(config=config, audio=audio, audio_rate=audio_rate, audio_t0=T0,
                         ft_t=ft_t, force=force, torque=torque, ft_input_rate=ft_rate)
    assert len(got) == len(ref) > 0
    np.testing.assert_allclose(got.t, ref.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got.x, ref.x, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got.valid, ref.valid)
    assert ref.valid.sum() > len(ref) // 2


@settings(max_examples=25, deadline=None)
@given(config=configs,
       baseline=st.sampled_from([(3, 10, 15), (2, 4, 6), (5, 20, 9)]),
       ft_rate=st.sampled_from([100, 200]),
       seed=st.integers(0, 10_000),
       ft_chunk=st.integers(1, 4))
def test_single_sample_wrench_path_gives_the_same_bits(config, baseline, ft_rate, seed,
                                                       ft_chunk):
    # push_wrench_one (the node's path, one sample per message) against push_wrench with the
    # same chunks, one-sample chunks mixed with longer ones, across a gap that restarts the window
    delta_window, delta_lag, baseline_window = baseline
    config = replace(config, delta_window=delta_window, delta_lag=delta_lag,
                     baseline_window=baseline_window)
    audio, ft_t, force, torque = make_signals(seed=seed, seconds=2.0, audio_rate=16000,
                                              ft_rate=ft_rate)
    keep = (ft_t < T0 + 0.9) | (ft_t > T0 + 1.0)
    ft_t, force, torque = ft_t[keep], force[keep], torque[keep]
    force[::37] *= 0.0                                  # zero magnitudes, ties in the median
    rng = np.random.default_rng(seed)
    ft_chunks = rng.integers(1, ft_chunk + 1, size=ft_t.size)
    got = {}
    for single in (False, True):
        extractor = StreamingFeatureExtractor(config=config, audio_rate=16000,
                                              ft_input_rate=ft_rate)
        got[single] = stream(extractor=extractor, audio=audio, audio_rate=16000, ft_t=ft_t,
                             force=force, torque=torque, audio_chunks=[160] * 200,
                             ft_chunks=ft_chunks, single=single)
    assert len(got[True]) > 100 and got[True].valid.sum() > 50
    for field in ('t', 'x', 'valid'):
        assert np.array_equal(getattr(got[True], field), getattr(got[False], field))


def test_single_sample_wrench_path_rejects_bad_input_and_changes_nothing():
    extractor = StreamingFeatureExtractor(config=FeatureConfig(), audio_rate=16000)
    extractor.push_wrench_one(t=T0, values=[0, 0, 1, 0, 0, 0])
    with pytest.raises(InputError, match='NaN or Inf'):
        extractor.push_wrench_one(t=T0 + 0.01, values=[np.nan, 0, 1, 0, 0, 0])
    with pytest.raises(InputError, match='NaN or Inf'):
        extractor.push_wrench_one(t=np.inf, values=[0, 0, 1, 0, 0, 0])
    with pytest.raises(InputError, match='6 values'):
        extractor.push_wrench_one(t=T0 + 0.01, values=[0, 1, 0, 0, 0])
    with pytest.raises(InputError, match='not numeric'):
        extractor.push_wrench_one(t=T0 + 0.01, values=['a', 1, 0, 0, 0, 0])
    with pytest.raises(InputError, match='repeats or precedes'):
        extractor.push_wrench_one(t=T0, values=[0, 0, 1, 0, 0, 0])
    with pytest.raises(TimeJumpError, match='backwards'):
        extractor.push_wrench_one(t=T0 - 5, values=[0, 0, 1, 0, 0, 0])
    extractor.push_wrench_one(t=T0 + 0.01, values=[0, 0, 1, 0, 0, 0])
    assert extractor.ft.last_input_t == T0 + 0.01


@pytest.mark.parametrize('audio_rate', [16000, 44100, 48000])
def test_frame_timing_is_the_same_at_every_audio_rate(audio_rate):
    config = FeatureConfig()
    extractor = StreamingFeatureExtractor(config=config, audio_rate=audio_rate)
    t, _ = extractor.audio.push(np.zeros(audio_rate), stamp=T0 + (audio_rate - 1) / audio_rate)
    # 32 ms frames every 10 ms: frame i ends at 0.032 + 0.010 i s (its last sample)
    expected = T0 + 0.032 + 0.010 * np.arange(t.size) - 1 / audio_rate
    assert t.size == 97
    np.testing.assert_allclose(t, expected, atol=0.5 / audio_rate)
    assert extractor.audio.frame_length == round(0.032 * audio_rate)


def test_features_use_no_future_samples():
    config = FeatureConfig(extra_features=('force_delta', 'torque_delta'))
    audio, ft_t, force, torque = make_signals(seed=3, seconds=2.0, audio_rate=16000,
                                              ft_rate=100)
    ref = batch_features(config=config, audio=audio, audio_rate=16000, audio_t0=T0, ft_t=ft_t,
                         force=force, torque=torque)
    cut = T0 + 1.2
    future_force = force.copy()
    future_force[ft_t > cut] += 50.0
    future_audio = audio.copy()
    future_audio[int(1.2 * 16000) + 1:] = 30000
    changed = batch_features(config=config, audio=future_audio, audio_rate=16000, audio_t0=T0,
                             ft_t=ft_t, force=future_force, torque=torque)
    before = ref.t <= cut
    np.testing.assert_array_equal(ref.x[before], changed.x[before])
    assert not np.array_equal(ref.x[~before], changed.x[~before])


def test_audio_rise_and_peak_gap_tell_a_sound_starting_from_one_decaying():
    # silence, then a knock at 0.5 s that decays over ~0.1 s
    rate = 16000
    n = np.arange(rate)
    audio = np.where(n >= rate // 2, 0.5 * np.exp(-(n - rate // 2) / (0.03 * rate)), 0.0)
    audio = audio * np.sin(2 * np.pi * 2000 * n / rate)
    config = FeatureConfig(extra_features=('audio_power_rel_db', 'audio_peak_rel_db',
                                           'audio_rise_db', 'audio_peak_gap_db'))
    extractor = StreamingFeatureExtractor(config=config, audio_rate=rate)
    ft_t = T0 + np.arange(101) / 100
    frames = stream(extractor=extractor, audio=audio, audio_rate=rate, ft_t=ft_t,
                    force=np.zeros((101, 3)), torque=np.zeros((101, 3)),
                    audio_chunks=[160] * 100, ft_chunks=[1] * 101)
    t = frames.t - T0
    rise = frames.x[:, config.feature_names.index('audio_rise_db')]
    gap = frames.x[:, config.feature_names.index('audio_peak_gap_db')]
    assert np.all(rise[t < 0.5] == 0) and np.all(gap[t < 0.5] == 0)     # silence: zeros
    starting = (t > 0.5) & (t <= 0.52)
    assert np.all(rise[starting] > 10) and np.all(gap[starting] == 0)
    decaying = (t > 0.56) & (t < 0.62)
    assert np.all(rise[decaying] < -1) and np.all(gap[decaying] > 1)


def test_audio_hold_tells_a_lasting_scrape_from_a_click():
    # silence, a click at 0.3 s that decays within ~20 ms, then a scrape (noise) 0.6-0.9 s
    rate = 16000
    n = np.arange(rate)
    rng = np.random.default_rng(5)
    click = np.where(n >= 0.3 * rate, 0.5 * np.exp(-(n - 0.3 * rate) / (0.004 * rate)), 0.0)
    click = click * np.sin(2 * np.pi * 3000 * n / rate)
    scrape = np.where((n >= 0.6 * rate) & (n < 0.9 * rate), rng.normal(0, 0.05, rate), 0.0)
    audio = click + scrape + rng.normal(0, 1e-4, rate)
    held = {}
    for hold in (4, 8):
        config = FeatureConfig(extra_features=('audio_power_rel_db', 'audio_peak_rel_db',
                                               'audio_hold_db'), audio_hold_frames=hold)
        extractor = StreamingFeatureExtractor(config=config, audio_rate=rate)
        frames = stream(extractor=extractor, audio=audio, audio_rate=rate,
                        ft_t=T0 + np.arange(101) / 100, force=np.zeros((101, 3)),
                        torque=np.zeros((101, 3)), audio_chunks=[333] * 60,
                        ft_chunks=[1] * 101)
        t = frames.t - T0
        peak = frames.x[:, config.feature_names.index('audio_peak_rel_db')]
        held[hold] = frames.x[:, config.feature_names.index('audio_hold_db')]
        # the click is loud (its peak far above the floor) but does not hold: a 32 ms frame
        # holds it for up to 4 hops, so 4 frames can all hold it for a few frames, 8 cannot
        clicking = (t > 0.3) & (t < 0.4)
        assert peak[clicking].max() > 40
        assert (held[hold][clicking] > 10).sum() <= (3 if hold == 4 else 0)
        # the scrape holds: once it has lasted hold frames (+ the frame length) it stays high
        scraping = (t > 0.6 + 0.032 + 0.01 * hold) & (t < 0.9)
        assert scraping.sum() > 15 and held[hold][scraping].min() > 30
        # and it is the minimum of the power above the floor over the newest hold frames
        rel = frames.x[:, config.feature_names.index('audio_power_rel_db')]
        assert held[hold].tolist() == [rel[max(0, i - hold + 1):i + 1].min()
                                       for i in range(rel.size)]
    # a longer hold is never higher: its minimum is over more frames
    assert np.all(held[8] <= held[4])
    # the scrape has held 4 frames 40 ms before it has held 8
    t4 = t[np.argmax((held[4] > 30) & (t > 0.5))]
    t8 = t[np.argmax((held[8] > 30) & (t > 0.5))]
    assert t8 - t4 == pytest.approx(0.04, abs=0.0015)


def test_silence_streams_finite_features():
    extractor = StreamingFeatureExtractor(config=FeatureConfig(
        extra_features=('audio_power_rel_db', 'force_delta', 'torque_delta')), audio_rate=16000)
    frames = stream(extractor=extractor, audio=np.zeros(16000, dtype=np.int16),
                    audio_rate=16000, ft_t=T0 + np.arange(100) / 100, force=np.zeros((100, 3)),
                    torque=np.zeros((100, 3)), audio_chunks=[160] * 100, ft_chunks=[1] * 100)
    assert len(frames) > 90 and np.all(np.isfinite(frames.x)) and np.all(frames.x == 0)


def test_bad_input_is_rejected_with_a_clear_error_and_changes_nothing():
    extractor = StreamingFeatureExtractor(config=FeatureConfig(), audio_rate=16000)
    extractor.push_wrench(t=[T0], force=[[0, 0, 1]], torque=[[0, 0, 0]])
    with pytest.raises(InputError, match='NaN or Inf'):
        extractor.push_wrench(t=[T0 + 0.01], force=[[np.nan, 0, 1]], torque=[[0, 0, 0]])
    with pytest.raises(InputError, match='NaN or Inf'):
        extractor.push_audio(np.array([0.1, np.inf]), stamp=T0)
    with pytest.raises(InputError, match='1-D'):
        extractor.push_audio(np.zeros((10, 2), dtype=np.int16), stamp=T0)
    with pytest.raises(InputError, match='int16 or float'):
        extractor.push_audio(np.zeros(10, dtype=np.int32), stamp=T0)
    with pytest.raises(InputError, match='shapes'):
        extractor.push_wrench(t=[T0 + 0.01], force=[[0, 1]], torque=[[0, 0, 0]])
    with pytest.raises(InputError, match='repeats or precedes'):
        extractor.push_wrench(t=[T0], force=[[0, 0, 1]], torque=[[0, 0, 0]])
    with pytest.raises(TimeJumpError, match='backwards'):
        extractor.push_wrench(t=[T0 - 5], force=[[0, 0, 1]], torque=[[0, 0, 0]])
    # the stream goes on from where it was
    extractor.push_wrench(t=[T0 + 0.01], force=[[0, 0, 1]], torque=[[0, 0, 0]])
    assert extractor.ft.last_input_t == T0 + 0.01


def test_wrench_gap_restarts_the_window_and_marks_frames_invalid():
    config = FeatureConfig(ft_window=16)
    audio, ft_t, force, torque = make_signals(seed=4, seconds=3.0, audio_rate=16000,
                                              ft_rate=100)
    keep = (ft_t < T0 + 1.0) | (ft_t > T0 + 1.2)     # a 200 ms dropout
    extractor = StreamingFeatureExtractor(config=config, audio_rate=16000)
    frames = stream(extractor=extractor, audio=audio, audio_rate=16000, ft_t=ft_t[keep],
                    force=force[keep], torque=torque[keep], audio_chunks=[160] * 400,
                    ft_chunks=[1] * 400)
    in_gap = (frames.t > T0 + 1.06) & (frames.t < T0 + 1.2)
    warming = (frames.t > T0 + 1.2) & (frames.t < T0 + 1.2 + 15 / 100)
    assert not frames.valid[in_gap].any() and not frames.valid[warming].any()
    assert frames.valid[frames.t > T0 + 1.4].all()
    assert extractor.ft.restarts == 1


def test_one_khz_wrench_is_block_averaged_to_the_feature_rate():
    config = FeatureConfig()
    audio, ft_t, force, torque = make_signals(seed=5, seconds=1.5, audio_rate=16000,
                                              ft_rate=100, ft_offset=0.0093)
    # 1 kHz input whose 10-sample block means are the 100 Hz signal
    fast_t = (ft_t[:, None] - 0.009 + 0.001 * np.arange(10)[None, :]).ravel()
    wiggle = np.tile(np.linspace(-1, 1, 10), ft_t.size)[:, None]
    fast_force = np.repeat(force, 10, axis=0) + wiggle
    fast_torque = np.repeat(torque, 10, axis=0) - 0.1 * wiggle
    slow = batch_features(config=config, audio=audio, audio_rate=16000, audio_t0=T0,
                          ft_t=ft_t, force=force, torque=torque)
    extractor = StreamingFeatureExtractor(config=config, audio_rate=16000, ft_input_rate=1000)
    fast = stream(extractor=extractor, audio=audio, audio_rate=16000, ft_t=fast_t,
                  force=fast_force, torque=fast_torque, audio_chunks=[320] * 100,
                  ft_chunks=[7] * 2000)
    np.testing.assert_allclose(fast.x, slow.x, atol=1e-9)


def test_buffers_stay_bounded_over_a_long_stream():
    config = FeatureConfig()
    extractor = StreamingFeatureExtractor(config=config, audio_rate=16000, history_s=2.0)
    rng = np.random.default_rng(6)
    n_audio = 0
    for k in range(600):        # 60 s in 100 ms steps
        chunk = (rng.normal(0, 0.01, 1600) * 32767).astype(np.int16)
        n_audio += chunk.size
        extractor.push_audio(chunk, stamp=T0 + (n_audio - 1) / 16000)
        t = T0 + 0.1 * k + np.arange(10) / 100
        extractor.push_wrench(t=t, force=rng.normal(size=(10, 3)),
                              torque=rng.normal(size=(10, 3)))
        assert extractor.audio._buf.size <= extractor.audio.frame_length + 1600
        assert extractor._ft_t.size <= extractor.history_frames
        assert extractor.pending <= 20


def test_audio_stamps_with_jitter_and_a_dropout():
    extractor = StreamingFeatureExtractor(config=FeatureConfig(), audio_rate=16000)
    rng = np.random.default_rng(7)
    n = 0
    for _ in range(100):
        n += 160
        extractor.push_audio(np.zeros(160, dtype=np.int16),
                             stamp=T0 + (n - 1) / 16000 + rng.uniform(0, 0.003))
    # the anchor is the least-delayed chunk: times are late by at most the smallest jitter
    assert extractor.audio.latest_time - (T0 + (n - 1) / 16000) < 0.0005
    n += 16000   # one second of audio lost
    extractor.push_audio(np.zeros(160, dtype=np.int16), stamp=T0 + (n - 1) / 16000)
    assert extractor.audio.restarts == 1
    with pytest.raises(TimeJumpError):
        extractor.push_audio(np.zeros(160, dtype=np.int16), stamp=T0)


def test_config_validation_names_the_field():
    with pytest.raises(ConfigError, match='ft_window'):
        FeatureConfig(ft_window=2)
    with pytest.raises(ConfigError, match='audio_hop_s'):
        FeatureConfig(audio_hop_s=0.1, audio_frame_s=0.05)
    with pytest.raises(ConfigError, match='extra_features'):
        FeatureConfig(extra_features=('nope',))
    with pytest.raises(ConfigError, match=r'wrench rate 20000 Hz is outside \[50, 10000\]'):
        StreamingFeatureExtractor(config=FeatureConfig(), audio_rate=16000, ft_input_rate=20000)
    assert FeatureConfig.from_dict(FeatureConfig().to_dict()) == FeatureConfig()
    # hold_frames is written only when it is not the default (older model hashes stay)
    assert 'hold_frames' not in FeatureConfig().to_dict()
    held = FeatureConfig(hold_frames=6)
    assert FeatureConfig.from_dict(held.to_dict()) == held
    with pytest.raises(ConfigError, match='hold_frames'):
        FeatureConfig(hold_frames=0)
    # so is audio_hold_frames (the shipped models' configuration hashes stay the same)
    assert 'audio_hold_frames' not in FeatureConfig.shipped().to_dict()
    audio_held = FeatureConfig(audio_hold_frames=5, extra_features=('audio_hold_db',))
    assert audio_held.to_dict()['audio_hold_frames'] == 5
    assert FeatureConfig.from_dict(audio_held.to_dict()) == audio_held
    for bad in (0, 2.0, True):
        with pytest.raises(ConfigError, match='audio_hold_frames'):
            FeatureConfig(audio_hold_frames=bad)
    with pytest.raises(ConfigError, match='audio_hold_db'):
        FeatureConfig(audio=False, extra_features=('audio_hold_db',))
    with pytest.raises(ConfigError, match='unknown'):
        FeatureConfig.from_dict({'bogus': 1})


def test_a_config_saved_before_baseline_window_existed_loads_with_the_same_features():
    # the first-round model files carry no baseline_window (nor rise_frames, change_max_frames):
    # they must load, and compute the same features as before (the fields only affect the
    # *_change, audio_rise_db and *_change_max features)
    old = FeatureConfig(ft_window=64, ft_detrend='mean',
                        extra_features=('force_delta', 'torque_delta')).to_dict()
    del old['baseline_window'], old['rise_frames'], old['change_max_frames']
    config = FeatureConfig.from_dict(old)
    assert config.baseline_window == 15 and config.rise_frames == 2
    assert config.change_max_frames == 15
    assert config.feature_names[-2:] == ('force_delta', 'torque_delta')
    assert ForceTorqueStream(config=config, input_rate=100.0).history == 64
