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
The F/T sensor's zero (``wrench.bias``, ``~/zero_sensor``) in the detector.

The toy F/T-only model of test_carried.py says contact when the force change lasted and points
against the carried load. A sensor that was never zeroed reads the carried load plus its
offset, whose direction has nothing to do with gravity, so the table taking weight off no
longer points against it and nothing releases. Given the offset as the bias, the detector
releases as on a zeroed sensor; the zero measured with the empty hand is that offset, and a
new zero restarts the stream state instead of passing a step to the features.
"""

from dataclasses import replace

from bundle_support import unloading_bundle
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.factory import build_detector_factory
from contact_detector.detection.fallback import AudioFallback
from contact_detector.detection.offline import run_detector
from contact_detector.errors import ConfigError
from contact_detector.features.config import CARRIED_FEATURES, FeatureConfig, SHIFT_FEATURES
from contact_detector.io.sensor_stream import WrenchEvent
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.storage import save_bundle
import numpy as np
import pytest

CONFIG = FeatureConfig(audio=False, ft_window=64, ft_detrend='mean', delta_window=1,
                       extra_features=SHIFT_FEATURES + CARRIED_FEATURES)
RATE = 100.0
T0 = 1_700_000_000.0
STEP_S = 4.0
#: A sensor never zeroed: 20 N sideways and 1 N m, against a 5 N object.
OFFSET = (20.0, 0.0, 0.0, 0.0, 1.0, 0.0)


@pytest.fixture(scope='module')
def bundle() -> ModelBundle:
    return _bundle(CONFIG)


def _bundle(config: FeatureConfig) -> ModelBundle:
    return unloading_bundle(config=config, created='2026-11-29T00:00:00+00:00')


def _events(*, offset=(0.0,) * 6, seed: int = 1) -> list:
    """Return a held 5 N along -z, 3 N of it taken by the table at 4 s, read ``+ offset``."""
    rng = np.random.default_rng(seed)
    n = int(6.0 * RATE)
    t = T0 + np.arange(n) / RATE
    force = rng.normal(scale=0.02, size=(n, 3)) + np.asarray(offset[:3])
    torque = rng.normal(scale=0.002, size=(n, 3)) + np.asarray(offset[3:])
    force[:, 2] -= 5.0
    force[t - T0 >= STEP_S, 2] += 3.0
    return [WrenchEvent(t=t[i:i + 1], force=force[i:i + 1], torque=torque[i:i + 1],
                        now=float(t[i]) + 0.002) for i in range(n)]


def _detector(bundle, **settings) -> ContactDetector:
    return ContactDetector(bundle=bundle, settings=DetectorSettings(
        audio_rate=16000.0, wrench_rate=RATE, **settings))


@pytest.mark.parametrize('in_blocks', [True, False])
def test_the_bias_undoes_the_offset_of_a_sensor_never_zeroed(bundle, in_blocks):
    zeroed = run_detector(_events(), detector=_detector(bundle), in_blocks=in_blocks)
    assert len(zeroed.releases) == 1
    offset = run_detector(_events(offset=OFFSET), detector=_detector(bundle),
                          in_blocks=in_blocks)
    assert offset.releases == []            # the failure the bias is for
    biased = run_detector(_events(offset=OFFSET),
                          detector=_detector(bundle, wrench_bias=OFFSET), in_blocks=in_blocks)
    assert biased.releases == pytest.approx(zeroed.releases, abs=1e-9)
    assert biased.carried.force_n == pytest.approx(5.0, abs=0.02)
    assert np.allclose(biased.p, zeroed.p, atol=1e-6)


def _feed(detector, *, seconds: float, start: float, offset=OFFSET, move_n: float = 0.0):
    """Feed an empty hand on a sensor reading ``offset``; ``move_n`` N added halfway."""
    n = int(seconds * RATE)
    for k in range(n):
        values = list(offset)
        values[2] += move_n if k >= n // 2 else 0.0
        t = start + k / RATE
        detector.on_wrench_one(t=t, values=values, now=t)
    return start + n / RATE


def test_the_zero_measured_with_the_empty_hand_is_the_offset(bundle):
    detector = _detector(bundle)
    t = _feed(detector, seconds=1.0, start=T0)
    assert detector.zero_measurement is None
    detector.measure_zero()
    _feed(detector, seconds=1.0, start=t)
    zero = detector.zero_measurement
    assert zero.steady and zero.samples == CONFIG.carried_window
    assert zero.load == pytest.approx(OFFSET)
    assert detector.bias == (0.0,) * 6          # measured, not applied: the caller decides
    detector.set_bias(tuple(zero.load))
    assert detector.bias == pytest.approx(OFFSET)
    # measured again with the bias applied: the corrected signal reads nothing
    detector.measure_zero()
    _feed(detector, seconds=1.0, start=t + 1.0)
    assert detector.zero_measurement is not zero
    assert detector.zero_measurement.load == pytest.approx([0.0] * 6, abs=1e-9)


def test_a_hand_that_moves_while_it_is_zeroed_is_reported(bundle):
    detector = _detector(bundle)
    detector.measure_zero()
    _feed(detector, seconds=0.5, start=T0, move_n=2.0)     # the 50 samples measured
    zero = detector.zero_measurement
    assert not zero.steady and zero.status == 'moved'
    assert zero.moved[0] == pytest.approx(2.0, abs=1e-9)


def test_a_new_zero_restarts_the_stream_and_never_releases_by_itself(bundle):
    # The hand holds 5 N on a sensor reading 20 N off; zeroing now (wrongly, while it holds
    # the object) is a step of 20 N in every sample. Without the reset that step would reach
    # the windows as a load change; with it, nothing releases and the carried load is measured
    # again, in the new zero.
    detector = _detector(bundle)
    events = _events(offset=OFFSET)[:300]        # before the table
    run_detector(events, detector=detector, in_blocks=False)
    assert detector.carried_load.force_n == pytest.approx(np.hypot(20.0, 5.0), abs=0.05)
    detector.set_bias((0.0, 0.0, -5.0) + OFFSET[3:])     # a step of 20 N, 5 N
    assert detector.carried_load is None and detector.armed
    after = run_detector(_events(offset=OFFSET)[300:380], detector=detector, in_blocks=False)
    assert after.releases == []
    assert detector.carried_load.load[:3] == pytest.approx([20.0, 0.0, 0.0], abs=0.05)


def test_an_unchanged_bias_keeps_the_stream_state(bundle):
    detector = _detector(bundle, wrench_bias=OFFSET)
    run_detector(_events(offset=OFFSET)[:100], detector=detector, in_blocks=False)
    carried = detector.carried_load
    detector.set_bias(list(OFFSET))
    assert detector.carried_load is carried


@pytest.mark.parametrize('bias', [(1.0,) * 5, (float('nan'),) + (0.0,) * 5, 'zero',
                                  [0.0] * 6, (True,) + (0.0,) * 5])
def test_a_bad_bias_in_the_settings_is_a_config_error(bias):
    with pytest.raises(ConfigError, match='wrench_bias'):
        DetectorSettings(wrench_bias=bias)


@pytest.mark.parametrize('bias', [(1.0,) * 5, (float('inf'),) + (0.0,) * 5, None])
def test_a_bad_bias_at_run_time_is_a_config_error_and_changes_nothing(bundle, bias):
    detector = _detector(bundle, wrench_bias=OFFSET)
    with pytest.raises(ConfigError, match='bias'):
        detector.set_bias(bias)
    assert detector.bias == OFFSET


def test_the_audio_fallback_gives_both_models_the_zero(bundle):
    primary = ContactDetector(bundle=_bundle(replace(CONFIG, audio=True)),
                              settings=DetectorSettings(audio_rate=16000.0, wrench_rate=RATE))
    detector = AudioFallback(primary=primary, fallback=_detector(bundle), timeout_s=0.5)
    detector.measure_zero()
    _feed(detector, seconds=1.0, start=T0)
    assert detector.zero_measurement is primary.zero_measurement
    detector.set_bias(tuple(detector.zero_measurement.load))
    assert detector.primary.bias == detector.fallback.bias == pytest.approx(OFFSET)
    assert detector.active is detector.primary


def test_offline_params_give_the_bias(bundle, tmp_path):
    model = tmp_path / 'toy.npz'
    save_bundle(bundle=bundle, path=model)
    params = tmp_path / 'robot.yaml'
    params.write_text('contact_detector:\n  ros__parameters:\n    wrench:\n'
                      '      bias: [20, 0, 0, 0, 1, 0]\n')
    make, _ = build_detector_factory(model=model, params_file=params, audio_rate=None)
    detector = make(has_audio=False)
    assert detector.bias == OFFSET
    run = run_detector(_events(offset=OFFSET), detector=detector)
    assert len(run.releases) == 1
    params.write_text('contact_detector:\n  ros__parameters:\n    wrench:\n'
                      '      bias: [20, 0, 0]\n')
    with pytest.raises(ConfigError, match='wrench.bias must be a list of 6 numbers'):
        build_detector_factory(model=model, params_file=params, audio_rate=None)
