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

"""A force reading that jumps back and forth is noise; a load that moves is not."""

from contact_detector.errors import InputError
from contact_detector.features.config import FeatureConfig
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.features.noise import jump_statistics, NOISE_WINDOW
import numpy as np
import pytest
from wrench_support import held_load

RATE = 100.0
T0 = 1_700_000_000.0
CONFIG = FeatureConfig(audio=False, ft_window=64)


def _reference(force: np.ndarray, window: int) -> tuple:
    # the definition, one window at a time
    jumps, turns = [], []
    for k in range(window, force.shape[0]):
        change = [force[i] - force[i - 1] for i in range(k - window + 1, k + 1)]
        jumps.append(np.median([np.linalg.norm(c) for c in change]))
        turns.append(np.mean([float(np.dot(a, b) < 0) for a, b in zip(change, change[1:])]))
    return np.array(jumps), np.array(turns)


def test_statistics_match_their_definition_and_tell_noise_from_a_moving_load():
    rng = np.random.default_rng(1)
    noise = rng.normal(0.0, 20.0, (400, 3))
    jump, turns = jump_statistics(force=noise)
    assert jump.shape == turns.shape == (400 - NOISE_WINDOW,)
    ref_jump, ref_turns = _reference(noise, NOISE_WINDOW)
    np.testing.assert_allclose(jump, ref_jump, rtol=1e-12)
    np.testing.assert_array_equal(turns, ref_turns)
    # white noise: the median jump is about 2.18 sigma, about 81 % of the changes reverse
    assert np.median(jump) == pytest.approx(2.18 * 20.0, rel=0.1)
    assert np.mean(turns) == pytest.approx(0.81, abs=0.05)
    # a load moving at 2 N per sample (a fast contact) never reverses
    ramp = np.outer(np.arange(50.0), [0.0, 0.0, 2.0])
    jump, turns = jump_statistics(force=ramp)
    np.testing.assert_allclose(jump, 2.0)
    assert not turns.any()
    # too few samples for a window: nothing
    assert jump_statistics(force=noise[:NOISE_WINDOW])[0].size == 0


def _stream(**kw) -> ForceTorqueStream:
    return ForceTorqueStream(config=CONFIG, input_rate=RATE, **kw)


def _noisy_reading(sigma: float, *, start: int = 300, samples: int = 20) -> tuple:
    # a held 5 N with white noise of sigma N per force axis on samples [start, start + samples)
    t, force, torque = held_load(seconds=5.0, rate=RATE, t0=T0, seed=2)
    force[start:start + samples] += np.random.default_rng(3).normal(0.0, sigma, (samples, 3))
    return t, force, torque


def test_a_noise_burst_is_counted_once_and_holds_for_the_features_look_back():
    t, force, torque = _noisy_reading(20.0)
    stream = _stream()
    stream.push(t=t, force=force, torque=torque)
    # a window is noisy while most of its changes are: up to NOISE_WINDOW samples after
    assert stream.noise_bursts == 1 and 5 <= stream.noisy <= 20 + NOISE_WINDOW
    assert stream.noise_level >= 15.0
    # the hold covers every frame whose features saw a noisy sample, and ends after that
    hold = stream.history / RATE
    assert t[319] + hold <= stream.noise_until <= t[319 + NOISE_WINDOW] + hold + 1e-9
    # the same samples one at a time (a live node): the same count and hold
    one = _stream()
    for i in range(t.size):
        one.push_one(t=float(t[i]), values=np.concatenate([force[i], torque[i]]))
    assert (one.noisy, one.noise_bursts, one.noise_until) == (
        stream.noisy, stream.noise_bursts, stream.noise_until)


def test_the_check_leaves_the_features_as_they_are():
    # what training relies on when it turns the check off: the same frames either way
    t, force, torque = _noisy_reading(20.0)
    checked = _stream()
    on_t, on_x = checked.push(t=t, force=force, torque=torque)
    off_t, off_x = _stream(noise_jump_n=0.0).push(t=t, force=force, torque=torque)
    assert checked.noise_bursts == 1 and on_x.shape[0] > 100
    np.testing.assert_array_equal(on_t, off_t)
    np.testing.assert_array_equal(on_x, off_x)


@pytest.mark.parametrize('case', ['sensor noise', 'quiet 2 N noise', 'contact', 'off'])
def test_readings_that_are_not_noise_are_never_flagged(case):
    t, force, torque = held_load(seconds=5.0, rate=RATE, t0=T0, seed=2)
    kw = {}
    if case == 'quiet 2 N noise':
        t, force, torque = _noisy_reading(2.0, samples=100)
    elif case == 'contact':
        # the table takes 5 N off in 30 ms, and the arm rings at 20 Hz with 8 N for 0.2 s
        force[300:303, 2] += np.linspace(0, 5.0, 3)
        force[303:, 2] += 5.0
        ring = np.arange(20)
        force[300:320, 2] += 8.0 * np.exp(-ring / 8.0) * np.sin(2 * np.pi * 20.0 * ring / RATE)
    elif case == 'off':
        t, force, torque = _noisy_reading(20.0)
        kw = {'noise_jump_n': 0.0}
    stream = _stream(**kw)
    stream.push(t=t, force=force, torque=torque)
    assert (stream.noisy, stream.noise_bursts) == (0, 0)
    assert stream.noise_until == -np.inf


def test_a_gap_starts_the_jumps_again_and_a_reset_forgets_the_hold():
    # three samples jumping by 20 N before a 0.2 s gap and three after: joined they would fill
    # a window with reversing jumps, but a change across a gap is no jump of the reading
    t, force, torque = held_load(seconds=5.0, rate=RATE, t0=T0, seed=2)
    t[200:] += 0.2
    for lo in (197, 200):
        force[lo:lo + 3, 0] += [20.0, -20.0, 20.0]
    stream = _stream()
    stream.push(t=t, force=force, torque=torque)
    assert stream.restarts == 1 and stream.noisy == 0
    # without the gap the same samples are noise
    joined = _stream()
    joined.push(t=T0 + np.arange(t.size) / RATE, force=force, torque=torque)
    assert joined.noise_bursts == 1
    joined.reset()
    assert joined.noise_until == -np.inf


@pytest.mark.parametrize('bad', [-1.0, float('nan'), float('inf'), True, '15'])
def test_a_bad_threshold_is_refused(bad):
    with pytest.raises(InputError, match='noise_jump_n'):
        _stream(noise_jump_n=bad)
