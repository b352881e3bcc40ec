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

from contact_detector.errors import ConfigError
from contact_detector.io.sensor_stream import AudioEvent, TruthEvent, WrenchEvent
from contact_detector.training.augmentation import (augment_events, draw, lag_wrench,
                                                    trial_seed, WrenchAugmentation)
from contact_detector.training.recipe import DEFAULT_FEATURES
from contact_detector.training.sweep import trial_frames
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


def test_an_unzeroed_sensor_adds_one_constant_offset_and_a_tared_one_none():
    events = _placing()
    aug = WrenchAugmentation(tare_probability=0.0, torque_scale=(1.0, 1.0),
                             offset_probability=1.0, offset_force_n=10.0, offset_torque_nm=0.5)
    _t0, f0, tq0 = _wrench(events)
    offsets = []
    for name in ('a', 'b', 'c'):
        _t1, f1, tq1 = _wrench(augment_events(events, augmentation=aug,
                                              seed=trial_seed(seed=2, name=name)))
        b_f, b_t = f1 - f0, tq1 - tq0
        # one constant per trial, within the size per axis
        np.testing.assert_allclose(b_f, b_f[:1].repeat(len(b_f), axis=0), atol=1e-12)
        np.testing.assert_allclose(b_t, b_t[:1].repeat(len(b_t), axis=0), atol=1e-12)
        assert np.all(np.abs(b_f[0]) <= 10.0) and np.all(np.abs(b_t[0]) <= 0.5)
        offsets.append(b_f[0])
    assert len({tuple(o) for o in offsets}) == 3
    # a sensor tared at rest has no offset left: it reads the load change alone
    tared = WrenchAugmentation(tare_probability=1.0, torque_scale=(1.0, 1.0),
                               offset_probability=1.0)
    _t, f, _tq = _wrench(augment_events(events, augmentation=tared,
                                        seed=trial_seed(seed=2, name='a')))
    assert np.abs(f[20:60].mean(axis=0)).max() < 0.02
    # the scale and the tare of a trial are those it drew before offsets existed
    for name in ('a', 'b', 'c'):
        seed = trial_seed(seed=3, name=name)
        old = draw(augmentation=WrenchAugmentation(), seed=seed)
        new = draw(augmentation=WrenchAugmentation(offset_probability=0.7,
                                                   contact_offset_m=0.1), seed=seed)
        assert (new.torque_scale, new.tared) == (old.torque_scale, old.tared)


def test_a_contact_offset_moves_the_torque_of_every_load_change_only():
    events = _placing()
    aug = WrenchAugmentation(tare_probability=0.0, torque_scale=(1.0, 1.0),
                             contact_offset_m=0.08)
    t0, f0, tq0 = _wrench(events)
    seed = trial_seed(seed=4, name='a')
    d = draw(augmentation=aug, seed=seed).contact_offset
    assert 0.0 < np.linalg.norm(d) <= 0.08
    t1, f1, tq1 = _wrench(augment_events(events, augmentation=aug, seed=seed))
    np.testing.assert_array_equal(f1, f0)
    rest = f0[(t0 >= t0[0] + 0.2) & (t0 < t0[0] + 0.6)].mean(axis=0)
    np.testing.assert_allclose(tq1, tq0 + np.cross(d, f0 - rest), atol=1e-12)
    # at rest nothing moves; after the table takes half the weight the torque of that change
    # is that of a table pushing at LEVER + d
    at_rest = t0 < 2.4
    assert np.abs(tq1[at_rest] - tq0[at_rest]).max() < 0.01
    late = t0 > 3.0
    change = f0[late].mean(axis=0) - rest
    np.testing.assert_allclose(tq1[late].mean(axis=0) - tq0[:100].mean(axis=0),
                               np.cross(LEVER + d, change), atol=2e-3)


def test_offset_settings_are_checked_and_written_to_the_card_only_when_used():
    with pytest.raises(ConfigError, match='offset_probability'):
        WrenchAugmentation(offset_probability=1.5)
    with pytest.raises(ConfigError, match='offset sizes'):
        WrenchAugmentation(contact_offset_m=-0.1)
    assert set(WrenchAugmentation().to_dict()) == {'tare_probability', 'tare_window_s',
                                                   'torque_scale'}
    card = WrenchAugmentation(offset_probability=0.5, contact_offset_m=0.05).to_dict()
    assert card['offset_probability'] == 0.5 and card['contact_offset_m'] == 0.05
    assert card['offset_force_n'] == 10.0 and card['offset_torque_nm'] == 0.5


def test_a_gain_multiplies_the_whole_wrench_of_a_trial():
    events = _placing()
    aug = WrenchAugmentation(tare_probability=0.0, torque_scale=(1.0, 1.0), gain=(0.2, 1.5))
    _t0, f0, tq0 = _wrench(events)
    gains = set()
    for name in ('a', 'b', 'c'):
        seed = trial_seed(seed=5, name=name)
        g = draw(augmentation=aug, seed=seed).gain
        assert 0.2 <= g <= 1.5
        _t1, f1, tq1 = _wrench(augment_events(events, augmentation=aug, seed=seed))
        np.testing.assert_allclose(f1, g * f0)
        np.testing.assert_allclose(tq1, g * tq0)
        gains.add(g)
    assert len(gains) == 3
    assert 'gain' not in WrenchAugmentation().to_dict()
    assert aug.to_dict()['gain'] == [0.2, 1.5]
    with pytest.raises(ConfigError, match='gain'):
        WrenchAugmentation(gain=(0.0, 1.0))


def test_a_lag_stretches_the_load_transfer_and_leaves_the_carried_load():
    events = _placing(seconds=6.0)
    t, f0, _tq0 = _wrench(events)
    aug = WrenchAugmentation(tare_probability=0.0, torque_scale=(1.0, 1.0), lag_s=(0.05, 0.3))
    seed = trial_seed(seed=2, name='a')
    tau = draw(augmentation=aug, seed=seed).lag_s
    assert 0.05 <= tau <= 0.3
    _t1, f1, tq1 = _wrench(augment_events(events, augmentation=aug, seed=seed))
    load = np.linalg.norm(f0, axis=1)
    lagged = np.linalg.norm(f1, axis=1)
    holding = t < 2.4
    np.testing.assert_allclose(lagged[holding].mean(), load[holding].mean(), rtol=1e-3)
    # The raw transfer (8 N -> 4 N in 15 ms) is done 50 ms after the onset; lagged, a step
    # arrives as 1 - exp(-t / tau): at one tau after the transfer, 63 % of it.
    done = np.abs(t - (2.5 + 0.015 + tau)) <= 0.5 / RATE
    moved = (load[holding].mean() - lagged[done].mean()) / 4.0
    assert 0.55 < moved < 0.72
    late = t > 2.5 + 0.015 + 8 * 0.3
    np.testing.assert_allclose(lagged[late].mean(), load[late].mean(), atol=0.05)
    # One filter for force and torque, so the torque lags the same way.
    np.testing.assert_allclose(tq1, np.cross(LEVER, f1), atol=0.01)
    assert aug.to_dict()['lag_s'] == [0.05, 0.3]
    assert 'lag_s' not in WrenchAugmentation().to_dict()
    assert draw(augmentation=WrenchAugmentation(), seed=seed).lag_s == 0.0
    with pytest.raises(ConfigError, match='lag_s'):
        WrenchAugmentation(lag_s=(0.0, 0.3))


def test_a_lag_follows_the_stamps_across_a_gap():
    w = [WrenchEvent(t=np.array([0.0, 0.01, 0.02]), force=np.zeros((3, 3)),
                     torque=np.zeros((3, 3)), now=0.02),
         WrenchEvent(t=np.array([1.02]), force=np.ones((1, 3)), torque=np.ones((1, 3)),
                     now=1.02)]
    out = lag_wrench(w, tau_s=0.1)
    # 1 s without a sample is ten time constants: the output has all but caught up.
    np.testing.assert_allclose(out[1].force, 1.0 - np.exp(-10.0), rtol=1e-12)
    np.testing.assert_array_equal(out[0].force, 0.0)
    assert [e.t.tolist() for e in out] == [e.t.tolist() for e in w]
