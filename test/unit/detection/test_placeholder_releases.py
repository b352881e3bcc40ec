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
A driver's zero-wrench placeholders never release, and the offline tools say they were there.

The toy model of test_carried.py releases when a lasting change unloads the hand. A driver
that publishes six zeros for 0.3 s while the hand holds 5 N is that change, as the
F/T itself would be if the load really went (values a hair above zero); the placeholders are
left out, counted, and reported by ``Run.input_problem``.
"""

from bundle_support import unloading_bundle
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector
from contact_detector.features.config import CARRIED_FEATURES, FeatureConfig, SHIFT_FEATURES
import pytest
from wrench_support import held_load, sample_messages

CONFIG = FeatureConfig(audio=False, ft_window=64, ft_detrend='mean', delta_window=1,
                       extra_features=SHIFT_FEATURES + CARRIED_FEATURES)
RATE = 100.0
T0 = 1_700_000_000.0


@pytest.fixture(scope='module')
def bundle():
    return unloading_bundle(config=CONFIG, created='2026-11-29T00:00:00+00:00')


def _events(*, gone: float) -> list:
    """Return 5 s of a held 5 N along -z; from 3 s to 3.3 s every value reads ``gone``."""
    t, force, torque = held_load(seconds=5.0, rate=RATE, t0=T0, seed=4)
    force[300:330] = gone           # samples, not stamps: 30 of them
    torque[300:330] = gone
    return sample_messages(t=t, force=force, torque=torque)


@pytest.mark.parametrize('in_blocks', [True, False])
def test_zero_placeholders_do_not_release_and_are_reported(bundle, in_blocks):
    def detector():
        return ContactDetector(bundle=bundle, settings=DetectorSettings(wrench_rate=RATE))
    # the load really gone for 0.3 s (a hair above zero): the model's contact
    real = run_detector(_events(gone=1e-6), detector=detector(), in_blocks=in_blocks)
    assert len(real.releases) == 1 and real.counts['wrench_placeholders'] == 0
    assert real.input_problem() is None
    placeholders = run_detector(_events(gone=0.0), detector=detector(), in_blocks=in_blocks)
    assert placeholders.releases == []
    assert placeholders.counts['wrench_placeholders'] == 30
    assert placeholders.counts['wrench_dropped'] == 0          # no hold-off: not corrupt
    assert placeholders.input_problem() == (
        '30 F/T samples with a force or torque of exactly (0, 0, 0) after a load were left '
        "out (a driver's placeholder for a missing reading)")
