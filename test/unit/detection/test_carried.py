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
The carried-load features in the detector: a contact that unloads, a push across the load.

An F/T-only model whose forest says contact when the force change lasted and points against
the carried load (``force_shift_min > 1 N`` and ``force_carried_cos < -0.5``): the table taking
weight off releases, a person pushing the object sideways by as much does not, and an arming
measures the carried load again (another object in the hand).
"""

from dataclasses import replace

from bundle_support import unloading_bundle
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.fallback import AudioFallback
from contact_detector.detection.offline import run_detector
from contact_detector.features.config import CARRIED_FEATURES, FeatureConfig, SHIFT_FEATURES
from contact_detector.io.sensor_stream import WrenchEvent
from contact_detector.model.bundle import ModelBundle
import numpy as np
import pytest

CONFIG = FeatureConfig(audio=False, ft_window=64, ft_detrend='mean', delta_window=1,
                       extra_features=SHIFT_FEATURES + CARRIED_FEATURES)
RATE = 100.0
T0 = 1_700_000_000.0
STEP_S = 4.0


@pytest.fixture(scope='module')
def bundle() -> ModelBundle:
    return _bundle(CONFIG)


def _bundle(config: FeatureConfig) -> ModelBundle:
    return unloading_bundle(config=config, created='2026-11-24T00:00:00+00:00')


def _events(direction, *, weight_n: float = 5.0, seed: int = 1) -> list:
    """One wrench message per sample: a held weight along -z, 3 N along ``direction`` at 4 s."""
    rng = np.random.default_rng(seed)
    n = int(6.0 * RATE)
    t = T0 + np.arange(n) / RATE
    force = rng.normal(scale=0.02, size=(n, 3))
    torque = rng.normal(scale=0.002, size=(n, 3))
    force[:, 2] -= weight_n
    force[t - T0 >= STEP_S] += 3.0 * np.asarray(direction)
    return [WrenchEvent(t=t[i:i + 1], force=force[i:i + 1], torque=torque[i:i + 1],
                        now=float(t[i]) + 0.002) for i in range(n)]


def _detector(bundle) -> ContactDetector:
    return ContactDetector(bundle=bundle, settings=DetectorSettings(audio_rate=16000.0,
                                                                    wrench_rate=RATE))


@pytest.mark.parametrize('in_blocks', [True, False])
def test_an_unload_releases_and_a_push_across_the_load_does_not(bundle, in_blocks):
    unload = run_detector(_events([0, 0, 1.0]), detector=_detector(bundle), in_blocks=in_blocks)
    assert len(unload.releases) == 1
    assert T0 + STEP_S <= unload.releases[0] <= T0 + STEP_S + 0.3
    push = run_detector(_events([1.0, 0, 0]), detector=_detector(bundle), in_blocks=in_blocks)
    assert push.releases == []


def test_a_run_reports_the_carried_load_it_compared_with(bundle):
    # the first 0.5 s hold 5 N still: steady; a recording that starts during the grasp (the
    # 5 N arrive 0.25 s in) has moved, and says by how much
    still = run_detector(_events([0, 0, 1.0]), detector=_detector(bundle))
    assert still.carried.status == 'steady'
    assert still.carried.force_n == pytest.approx(5.0, abs=0.02)
    grasp = _events([0, 0, 1.0])
    for event in grasp[:25]:
        event.force[:, 2] += 5.0
    late = run_detector(grasp, detector=_detector(bundle))
    assert late.carried.status == 'moved'
    assert late.carried.moved[0] == pytest.approx(5.0, abs=0.05)


def test_arming_measures_the_carried_load_again(bundle):
    # the node started with an empty, tared hand (no carried load: the cosine is 0, nothing
    # releases); 1 s later the hand holds 5 N. Armed then, the carried load is those 5 N and
    # the table taking 3 N of them releases; not armed again, the start's empty hand stays
    # the reference (a wrench gap does not measure it again)
    for armed_again, releases in ((False, 0), (True, 1)):
        detector = _detector(bundle)
        for k in range(100):
            t = T0 - 2.0 + k / RATE
            detector.on_wrench_one(t=t, values=[0.0] * 6, now=t)
        assert detector.extractor.ft.carried == pytest.approx([0.0] * 6)
        if armed_again:
            detector.arm(True)
        run = run_detector(_events([0, 0, 1.0]), detector=detector, in_blocks=False)
        assert len(run.releases) == releases
        expected = [0.0, 0.0, -5.0] if armed_again else [0.0] * 3
        assert detector.extractor.ft.carried[:3] == pytest.approx(expected, abs=0.05)


def test_the_audio_fallback_measures_the_carried_load_again_in_both_models(bundle):
    # either model may be active at the contact, so an arming restarts both measurements
    primary = ContactDetector(bundle=_bundle(replace(CONFIG, audio=True)),
                              settings=DetectorSettings(audio_rate=16000.0, wrench_rate=RATE))
    detector = AudioFallback(primary=primary, fallback=_detector(bundle), timeout_s=0.5)
    both = (detector.primary, detector.fallback)
    for k in range(100):
        detector.on_wrench_one(t=T0 + k / RATE, values=[0.0, 0.0, -2.0, 0.0, 0.0, 0.0],
                               now=T0 + k / RATE)
    detector.arm(True)
    for k in range(100, 200):
        detector.on_wrench_one(t=T0 + k / RATE, values=[0.0, 0.0, -6.0, 0.0, 0.0, 0.0],
                               now=T0 + k / RATE)
    assert [d.extractor.ft.carried[2] for d in both] == [-6.0, -6.0]
    assert detector.carried_load is detector.primary.carried_load
    assert detector.carried_load.force_n == 6.0
