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
The load path in the detector: a slow, held load transfer the forest does not catch.

The toy F/T-only forest of ``test_carried.py`` says contact only when the force change over its
sliding baseline lasted above 1 N against the carried load. The table taking 3 N over 1.5 s
(a soft layer) never moves the load that fast, so the forest never fires; the load path, the
force held 2 N from the load carried after the start, does. The detector computes that distance
beside the model's columns and gives the forest only its own.
"""

from dataclasses import replace

from bundle_support import lasting_change_bundle, toy_bundle
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector
from contact_detector.errors import ConfigError, ModelError
from contact_detector.features.config import CARRIED_FEATURES, FeatureConfig, SHIFT_FEATURES
from contact_detector.model.bundle import ModelBundle
import numpy as np
import pytest
from wrench_support import held_load, sample_messages

CONFIG = FeatureConfig(audio=False, ft_window=64, ft_detrend='mean', delta_window=1,
                       extra_features=SHIFT_FEATURES + CARRIED_FEATURES)
RATE = 100.0
T0 = 1_700_000_000.0
START_S = 3.0
LOAD = {'load_threshold': 2.0, 'load_frames': 20, 'load_support': 0.0, 'load_support_frames': 25}


def _bundle(config: FeatureConfig) -> ModelBundle:
    return lasting_change_bundle(config=config, n=4000, created='2026-11-28T00:00:00+00:00')


@pytest.fixture(scope='module')
def bundle() -> ModelBundle:
    return _bundle(CONFIG)


def _events(*, ramp_s: float = 1.5, knock: bool = False, push: bool = False,
            noise: bool = False, tared: bool = False) -> list:
    """
    Return wrench messages: 5 N held along -z, the table taking 3 N over ``ramp_s`` from 3 s.

    ``knock``: a 30 ms, 10 N knock along -z at 3 s instead; ``push``: a hand pushing the object
    sideways (3 N along x over ``ramp_s``) instead of the table; ``noise``: white noise of 5 N
    per axis on the reading for 0.8 s from 3 s (a loose connector) instead; ``tared``: the
    sensor was zeroed with the object in the hand, so it reads no carried load.
    """
    t, force, torque = held_load(seconds=6.0, rate=RATE, t0=T0, seed=1)
    if knock:
        force[(t - T0 >= START_S) & (t - T0 < START_S + 0.03), 2] -= 10.0
    elif push:
        force[:, 0] += 3.0 * np.clip((t - T0 - START_S) / ramp_s, 0.0, 1.0)
    elif noise:
        burst = (t - T0 >= START_S) & (t - T0 < START_S + 0.8)
        force[burst] += np.random.default_rng(7).normal(scale=5.0, size=(int(burst.sum()), 3))
    else:
        force[:, 2] += 3.0 * np.clip((t - T0 - START_S) / ramp_s, 0.0, 1.0)
    if tared:
        force[:, 2] += 5.0
    return sample_messages(t=t, force=force, torque=torque)


def _run(bundle, events, *, in_blocks=True, **load):
    rule = replace(bundle.decision_rule, **load)
    detector = ContactDetector(bundle=bundle, settings=DetectorSettings(
        audio_rate=16000.0, wrench_rate=RATE, rule=rule))
    return run_detector(events, detector=detector, in_blocks=in_blocks)


@pytest.mark.parametrize('in_blocks', [True, False])
def test_the_load_path_releases_a_slow_transfer_the_forest_misses(bundle, in_blocks):
    assert _run(bundle, _events(), in_blocks=in_blocks).releases == []
    run = _run(bundle, _events(), in_blocks=in_blocks, **LOAD)
    # 2 N of the 3 N are off at 1.0 s into the ramp; held for 20 frames (0.2 s) after that
    assert run.releases == [pytest.approx(T0 + START_S + 1.0 + 0.2, abs=0.03)]


def test_the_forest_still_reads_only_the_model_columns(bundle):
    # the same P(contact) per frame with and without the load path's column computed
    plain, loaded = _run(bundle, _events()), _run(bundle, _events(), **LOAD)
    assert np.array_equal(plain.t, loaded.t) and np.array_equal(plain.p, loaded.p)


def test_the_load_path_ignores_a_knock_and_needs_the_forest_behind_it(bundle):
    # a 10 N knock for 30 ms is far from the carried load but not for 20 frames
    assert _run(bundle, _events(knock=True), **LOAD).releases == []
    # with backing asked for, the forest's 0 over the slow ramp holds the release back
    assert _run(bundle, _events(), **{**LOAD, 'load_support': 0.5}).releases == []


def test_a_model_without_the_carried_load_refuses_the_load_path():
    config = replace(CONFIG, extra_features=SHIFT_FEATURES)
    bundle = _bundle(config)
    rule = replace(bundle.decision_rule, **LOAD)
    with pytest.raises(ConfigError, match='carried'):
        ContactDetector(bundle=bundle, settings=DetectorSettings(wrench_rate=RATE, rule=rule))
    detector = ContactDetector(bundle=bundle, settings=DetectorSettings(wrench_rate=RATE))
    with pytest.raises(ConfigError, match='release.load_threshold'):
        detector.set_rule(rule)
    assert detector.rule == bundle.decision_rule          # the refused rule did not apply
    with pytest.raises(ModelError, match='load path'):
        replace(bundle, decision_rule=rule)


@pytest.mark.parametrize('in_blocks', [True, False])
def test_the_fast_load_path_reads_the_same_distance_sooner(bundle, in_blocks):
    # 1 N of the 3 N is off at 0.5 s into the ramp; held for 3 frames after that, long before
    # the load path's 2 N held for 0.2 s
    fast = {'load2_threshold': 1.0, 'load2_frames': 3, 'load2_support': 0.0,
            'load2_support_frames': 5}
    run = _run(bundle, _events(), in_blocks=in_blocks, **LOAD, **fast)
    assert run.releases == [pytest.approx(T0 + START_S + 0.5 + 0.03, abs=0.03)]
    # the fast path alone is a load path too: it needs the carried-load column
    alone = _run(bundle, _events(), in_blocks=in_blocks, **fast)
    assert alone.releases == run.releases
    # and holds a 30 ms knock back when it must be held for 5 frames
    assert _run(bundle, _events(knock=True), **{**fast, 'load2_frames': 5}).releases == []


@pytest.mark.parametrize('in_blocks', [True, False])
def test_the_direction_gate_tells_the_table_from_a_sideways_push(bundle, in_blocks):
    # a long, unbacked hold: 1 N from the carried load for 0.1 s
    hold = {'load2_threshold': 1.0, 'load2_frames': 10, 'load2_support': 0.0,
            'load2_support_frames': 1}
    gated = {**hold, 'load2_direction': -0.4}
    # the table takes the load off against the carried load: the gate lets it through
    table = _run(bundle, _events(), in_blocks=in_blocks, **hold)
    assert table.releases == [pytest.approx(T0 + START_S + 0.5 + 0.1, abs=0.03)]
    assert _run(bundle, _events(), in_blocks=in_blocks, **gated).releases == table.releases
    # a push across the carried load moves the force as far, and only the ungated hold fires
    assert len(_run(bundle, _events(push=True), in_blocks=in_blocks, **hold).releases) == 1
    assert _run(bundle, _events(push=True), in_blocks=in_blocks, **gated).releases == []
    # a tared sensor measured no carried load: the gate has no direction to judge there
    pushed = _events(push=True, tared=True)
    ungated = _run(bundle, pushed, in_blocks=in_blocks, **hold).releases
    assert len(ungated) == 1
    assert _run(bundle, pushed, in_blocks=in_blocks, **gated).releases == ungated


@pytest.fixture(scope='module')
def vetoing_bundle() -> ModelBundle:
    """Return a toy forest that says contact only for a 1 kN lasting change: only holds release."""
    rng = np.random.default_rng(0)
    x = np.abs(rng.normal(size=(2000, CONFIG.n_features)))
    x[:10, CONFIG.feature_names.index('force_shift_min')] = 1000.0
    y = (np.arange(2000) < 10).astype(int)
    return toy_bundle(config=CONFIG, x=x, y=y, created='2026-11-29T00:00:00+00:00')


@pytest.mark.parametrize('in_blocks', [True, False])
def test_a_steady_hold_keeps_noise_on_the_reading_out_and_the_table_in(vetoing_bundle,
                                                                       in_blocks):
    bundle = vetoing_bundle
    # the shipped F/T-only model's gated hold: 2 N for 40 frames, no backing, gated at -0.4
    hold = {'load2_threshold': 2.0, 'load2_frames': 40, 'load2_support': 0.0,
            'load2_support_frames': 1, 'load2_direction': -0.4}
    steady = {**hold, 'load2_steady': 0.5}
    # 0.8 s of white noise: its distance from the carried load stays above 2 N for 40 frames,
    # and on a tared sensor the gate has no direction to judge
    noisy = _events(noise=True, tared=True)
    assert len(_run(bundle, noisy, in_blocks=in_blocks, **hold).releases) == 1
    assert _run(bundle, noisy, in_blocks=in_blocks, **steady).releases == []
    # the table's slow 3 N changes the distance by 0.2 N in 10 frames: the same release
    table = _run(bundle, _events(), in_blocks=in_blocks, **hold).releases
    assert table == [pytest.approx(T0 + START_S + 1.0 + 0.4, abs=0.03)]
    assert _run(bundle, _events(), in_blocks=in_blocks, **steady).releases == table
