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

"""A configuration without the torque columns (``FeatureConfig.torque`` false): the force alone."""

from dataclasses import replace

from contact_detector.errors import ConfigError
from contact_detector.features.batch import batch_features
from contact_detector.features.config import FeatureConfig, PAPER_FEATURES, TORQUE_FEATURES
from contact_detector.features.streaming import StreamingFeatureExtractor
import numpy as np
import pytest

SHIPPED = FeatureConfig.shipped()
FORCE_ONLY = replace(SHIPPED, torque=False, extra_features=tuple(
    n for n in SHIPPED.extra_features if n not in TORQUE_FEATURES))
AUDIO_RATE, FT_RATE, T0 = 16000.0, 100.0, 1_700_000_000.0


def _signals(*, torque_scale: float = 1.0, seed: int = 4) -> tuple:
    """3 s of a held object the table takes 3 N of at 2 s, with a click then; audio and F/T."""
    rng = np.random.default_rng(seed)
    n = int(3.0 * FT_RATE)
    t = T0 + np.arange(n) / FT_RATE
    force = rng.normal(scale=0.05, size=(n, 3))
    force[:, 2] -= 5.0
    force[t - T0 >= 2.0, 2] += 3.0
    torque = torque_scale * (rng.normal(scale=0.005, size=(n, 3)) + 0.1 * force[:, [1, 0, 2]])
    audio = rng.normal(scale=300.0, size=int(3.0 * AUDIO_RATE))
    click = int(2.0 * AUDIO_RATE)
    audio[click:click + 200] += 8000.0 * np.hanning(200)
    return t, force, torque, np.round(audio).astype(np.int16)


def _stream(config: FeatureConfig, t, force, torque, audio):
    """Push the signals as a live node gets them: 10 ms of audio, then each wrench sample."""
    extractor = StreamingFeatureExtractor(config=config, audio_rate=AUDIO_RATE)
    rows = []
    for i in range(t.size):
        rows.append(extractor.push_wrench_one(t=float(t[i]), values=[*force[i], *torque[i]]))
        chunk = audio[i * 160:(i + 1) * 160]
        rows.append(extractor.push_audio(chunk, stamp=float(t[i])))
    rows.append(extractor.flush())
    keep = [r for r in rows if len(r)]
    return (np.concatenate([r.t for r in keep]), np.concatenate([r.x for r in keep]),
            np.concatenate([r.valid for r in keep]))


def test_the_vector_has_no_torque_column_and_refuses_torque_features():
    assert FORCE_ONLY.feature_names[:4] == ('audio_power', 'force_centroid', 'force_spread',
                                            'force_flux')
    assert not set(FORCE_ONLY.feature_names) & set(TORQUE_FEATURES)
    assert set(PAPER_FEATURES) - set(FORCE_ONLY.feature_names) == {
        'torque_centroid', 'torque_spread', 'torque_flux'}
    ft_only = replace(FORCE_ONLY, audio=False, extra_features=('force_shift',))
    assert ft_only.feature_names == ('force_centroid', 'force_spread', 'force_flux',
                                     'force_shift')
    for name in ('torque_shift', 'ft_change_angle', 'ft_carried_lever'):
        with pytest.raises(ConfigError, match=f'torque is false.*{name}'):
            replace(FORCE_ONLY, extra_features=(name,))
    with pytest.raises(ConfigError, match='torque must be true or false'):
        replace(FORCE_ONLY, torque='no')


def test_the_field_is_written_only_when_false_so_older_models_keep_their_hash():
    assert 'torque' not in SHIPPED.to_dict()
    assert FORCE_ONLY.to_dict()['torque'] is False
    assert FeatureConfig.from_dict(FORCE_ONLY.to_dict()) == FORCE_ONLY
    assert FeatureConfig.from_dict(SHIPPED.to_dict()) == SHIPPED


def test_the_force_columns_are_the_shipped_ones_and_do_not_read_the_torque():
    t, force, torque, audio = _signals()
    full_t, full_x, full_valid = _stream(SHIPPED, t, force, torque, audio)
    t_f, x_f, valid_f = _stream(FORCE_ONLY, t, force, torque, audio)
    assert np.array_equal(full_t, t_f) and np.array_equal(full_valid, valid_f)
    assert valid_f.sum() > 200
    columns = [SHIPPED.feature_names.index(n) for n in FORCE_ONLY.feature_names]
    assert np.array_equal(full_x[:, columns], x_f)
    # a sensor mounted with other lever arms gives the same frames
    _, x_lever, _ = _stream(FORCE_ONLY, t, force, 7.0 * torque, audio)
    assert np.array_equal(x_f, x_lever)
    _, x_full_lever, _ = _stream(SHIPPED, t, force, 7.0 * torque, audio)
    assert not np.array_equal(full_x, x_full_lever)


def test_streaming_rows_match_the_batch_reference():
    t, force, torque, audio = _signals(seed=5)
    stream_t, stream_x, stream_valid = _stream(FORCE_ONLY, t, force, torque, audio)
    batch = batch_features(config=FORCE_ONLY, audio=audio, audio_rate=AUDIO_RATE,
                           audio_t0=T0 - 160 / AUDIO_RATE, ft_t=t, force=force, torque=torque)
    assert batch.names == FORCE_ONLY.feature_names
    both = stream_valid[:len(batch.t)] & batch.valid[:len(stream_t)]
    n = min(len(batch.t), len(stream_t))
    assert np.allclose(stream_t[:n], batch.t[:n]) and both[:n].sum() > 200
    np.testing.assert_allclose(stream_x[:n][both[:n]], batch.x[:n][both[:n]], rtol=1e-9,
                               atol=1e-9)
