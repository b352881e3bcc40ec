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

"""Training-time wrench augmentation: other lever arms and tared sensors, drawn per trial."""

from contact_detector.cli.train import DEFAULT_FEATURES
from contact_detector.errors import ConfigError
from contact_detector.io.sensor_stream import AudioEvent, TruthEvent, WrenchEvent
from contact_detector.model.augmentation import (augment_events, draw, trial_seed,
                                                 WrenchAugmentation)
from contact_detector.model.sweep import trial_frames
import numpy as np
import pytest

RATE = 100.0
CARRIED = np.array([0.0, 0.0, -8.0])      # N: the object's weight in the sensor frame
LEVER = np.array([0.0, 0.12, 0.0])        # m: where the table pushes, from the sensor


def _placing(*, seconds: float = 4.0, onset: float = 2.5) -> list:
    """Events of a synthetic placing: rest holding the object, then the table takes half."""
    t = np.arange(int(seconds * RATE)) / RATE
    rng = np.random.default_rng(0)
    share = np.clip((t - onset) / 0.03, 0.0, 0.5)[:, None]
    force = CARRIED * (1.0 - share) + rng.normal(0, 0.02, (t.size, 3))
    torque = np.cross(LEVER, force) + rng.normal(0, 0.002, (t.size, 3))
    events = []
    chunk = 1024
    audio = rng.normal(0, 1e-3, int(seconds * 16000))
    for k in range(0, t.size, 10):
        events.append(WrenchEvent(t=t[k:k + 10], force=force[k:k + 10],
                                  torque=torque[k:k + 10], now=float(t[min(k + 9, t.size - 1)])))
    for i in range(chunk, audio.size + 1, chunk):
        events.append(AudioEvent(samples=audio[i - chunk:i], stamp=i / 16000.0, now=i / 16000.0))
    events.sort(key=lambda e: e.now)
    return events


def _wrench(events):
    w = [e for e in events if isinstance(e, WrenchEvent)]
    return (np.concatenate([e.t for e in w]), np.concatenate([e.force for e in w]),
            np.concatenate([e.torque for e in w]))


def test_lever_arm_scales_every_torque_and_leaves_force_and_audio_alone():
    events = _placing()
    aug = WrenchAugmentation(tare_probability=0.0, torque_scale=(0.2, 5.0))
    scales = []
    for name in ('a', 'b', 'c', 'd'):
        out = augment_events(events, augmentation=aug, seed=trial_seed(seed=1, name=name))
        t0, f0, tq0 = _wrench(events)
        t1, f1, tq1 = _wrench(out)
        s = draw(augmentation=aug, seed=trial_seed(seed=1, name=name)).torque_scale
        assert 0.2 <= s <= 5.0
        np.testing.assert_array_equal(t1, t0)
        np.testing.assert_array_equal(f1, f0)
        np.testing.assert_allclose(tq1, s * tq0)
        audio_in = [e for e in events if isinstance(e, AudioEvent)]
        audio_out = [e for e in out if isinstance(e, AudioEvent)]
        assert all(a is b for a, b in zip(audio_in, audio_out))
        scales.append(s)
    # Each trial its own lever arm, the same one in every run.
    assert len(set(scales)) == 4
    first, again = (_wrench(augment_events(events, augmentation=aug,
                                           seed=trial_seed(seed=1, name='a')))[2]
                    for _ in range(2))
    np.testing.assert_array_equal(first, again)


def test_a_tared_sensor_reads_zero_while_holding_and_the_contact_raises_force():
    events = _placing()
    aug = WrenchAugmentation(tare_probability=1.0, torque_scale=(1.0, 1.0))
    t, f, tq = _wrench(augment_events(events, augmentation=aug, seed=(0, 0)))
    holding = (t >= 0.2) & (t < 0.6)
    np.testing.assert_allclose(f[holding].mean(axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(tq[holding].mean(axis=0), 0.0, atol=1e-12)
    before, after = np.linalg.norm(f[t < 2.4], axis=1), np.linalg.norm(f[t > 2.7], axis=1)
    # Untared, the contact lowers |F| (8 N -> 4 N); tared, it raises it (0 -> 4 N).
    raw = np.linalg.norm(_wrench(events)[1], axis=1)
    assert raw[t > 2.7].mean() < raw[t < 2.4].mean() - 3.0
    assert after.mean() > before.mean() + 3.0


def test_vector_shift_features_do_not_see_the_tare_but_norm_features_do():
    events = _placing()
    raw = trial_frames(events=events, truth=None, config=DEFAULT_FEATURES, audio_rate=16000.0,
                       wrench_rate=RATE)
    tared = trial_frames(events=events, truth=None, config=DEFAULT_FEATURES,
                         audio_rate=16000.0, wrench_rate=RATE,
                         augmentation=WrenchAugmentation(tare_probability=1.0,
                                                         torque_scale=(1.0, 1.0)),
                         augment_seed=(0, 0))
    names = DEFAULT_FEATURES.feature_names
    np.testing.assert_array_equal(raw.t, tared.t)
    shift = names.index('force_shift')
    np.testing.assert_allclose(tared.x[:, shift], raw.x[:, shift], atol=1e-9)
    change = names.index('force_change')
    assert not np.allclose(tared.x[:, change], raw.x[:, change], atol=1e-3)


@pytest.mark.parametrize('kwargs', [
    {'tare_probability': 1.5}, {'tare_probability': -0.1},
    {'tare_window_s': (0.6, 0.2)}, {'torque_scale': (0.0, 2.0)},
    {'torque_scale': (3.0, 1.0)}, {'torque_scale': ('a', 2.0)}])
def test_bad_ranges_are_refused_at_construction(kwargs):
    with pytest.raises(ConfigError):
        WrenchAugmentation(**kwargs)


def test_truth_and_recordings_without_the_tare_window_pass_through():
    events = [TruthEvent(value=True, now=0.05),
              WrenchEvent(t=np.array([0.0, 0.01]), force=np.ones((2, 3)),
                          torque=np.ones((2, 3)), now=0.01)]
    out = augment_events(events, augmentation=WrenchAugmentation(tare_probability=1.0,
                                                                 torque_scale=(2.0, 2.0)),
                         seed=(3,))
    assert out[0] is events[0]
    np.testing.assert_array_equal(out[1].force, np.ones((2, 3)))   # no sample to tare on
    np.testing.assert_allclose(out[1].torque, 2.0 * np.ones((2, 3)))
