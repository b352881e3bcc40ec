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

"""``force_roughness`` and ``force_roughness_rel``: a rubbing load against a smooth one."""

from contact_detector.errors import ConfigError
from contact_detector.features.config import FeatureConfig
from contact_detector.features.force_torque import ForceTorqueStream
import numpy as np
import pytest

RATE = 100.0
CONFIG = FeatureConfig(audio=False, extra_features=('force_shift', 'force_roughness',
                                                    'force_roughness_rel'))
ROTATION = np.array([[0.0, -1.0, 0.0], [0.6, 0.0, 0.8], [-0.8, 0.0, 0.6]])


def _wrench(change: np.ndarray, *, gain: float = 1.0):
    """Carried 6 N along z (world), the change along z on top, seen by a rotated biased sensor."""
    n = change.size
    world = np.zeros((n, 3))
    world[:, 2] = -6.0 + change
    force = gain * world @ ROTATION.T + np.array([3.0, -1.0, 2.0])
    return np.arange(n) / RATE, force, np.zeros((n, 3))


def _features(change: np.ndarray, *, gain: float = 1.0) -> dict:
    t, force, torque = _wrench(change, gain=gain)
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    _, x = stream.push(t=t, force=force, torque=torque)
    names = stream.columns
    return {name: x[:, names.index(name)] for name in CONFIG.extra_features}


def _load_off(*, fluctuation: float, noise: float = 0.1, seed: int = 0) -> np.ndarray:
    """1.1 s at rest, then the first 0.3 s of taking 4 N off over 0.3 s; sensor noise, N."""
    n = 140
    rng = np.random.default_rng(seed)
    ramp = np.clip((np.arange(n) - 110) / 30.0, 0.0, 1.0) * 4.0
    return ramp * (1.0 + rng.standard_normal(n) * fluctuation) + rng.standard_normal(n) * noise


def test_a_steady_or_linearly_changing_force_is_not_rough():
    steady = _features(np.zeros(200))
    np.testing.assert_allclose(steady['force_roughness'], 0.0, atol=1e-9)
    np.testing.assert_allclose(steady['force_roughness_rel'], 0.0, atol=1e-9)
    # the newest frames' windows lie inside the ramp, past its knee: a straight line
    smooth = _features(_load_off(fluctuation=0.0, noise=0.0))
    assert np.all(smooth['force_roughness'][-5:] < 1e-9)


def test_a_force_that_fluctuates_as_it_slips_is_rougher_than_before_it():
    smooth = _features(_load_off(fluctuation=0.0))
    rubbing = _features(_load_off(fluctuation=0.35))
    # the newest frames: over 3 N off against the baseline, the ramp's knee out of the window
    last = slice(-5, None)
    assert np.all(rubbing['force_shift'][last] > 3.0)
    assert np.all(smooth['force_shift'][last] > 3.0)
    # white noise alone: as rough as 0.2 s before, within the spread of 20 samples
    assert np.all(np.abs(smooth['force_roughness_rel'][last] - 1.0) < 0.5)
    assert np.all(rubbing['force_roughness_rel'][last] > 3.0)


def test_the_ratio_does_not_depend_on_the_sensor_gain():
    one = _features(_load_off(fluctuation=0.35))
    three = _features(_load_off(fluctuation=0.35), gain=3.0)
    np.testing.assert_allclose(three['force_roughness'], 3.0 * one['force_roughness'],
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(three['force_roughness_rel'], one['force_roughness_rel'],
                               rtol=1e-9)


def test_the_window_is_validated_and_stored_only_when_it_differs():
    with pytest.raises(ConfigError, match='rough_window'):
        FeatureConfig(rough_window=0)
    assert 'rough_window' not in CONFIG.to_dict()
    wide = FeatureConfig(rough_window=40, extra_features=('force_roughness',))
    assert FeatureConfig.from_dict(wide.to_dict()) == wide
