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
Interference on the F/T never releases the shipped models; the contact after it still does.

White noise of 20 N per force axis for 0.2 s, 1 s before the contact, releases both shipped
models early with the noise check off (the forest takes the noise for a contact:
docs/reliability.md); with it on, the burst is counted, the offline report names it, and
the one release is the contact.
"""

import dataclasses

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector
from contact_detector.errors import ConfigError
from contact_detector.io.sensor_stream import AudioEvent, WrenchEvent
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim.messages import message_events
from contact_detector.sim.trial import simulate_trials
import numpy as np
import pytest

# a trial the shipped models release within 0.5 s of the contact without a fault, and early
# with the noise below and the check off (the second of benchmarks/sensor_faults.py's 24)
TRIAL = {'n': 1, 'seed': 8600, 'conditions': ('wide',), 'start_index': 1}


@pytest.fixture(scope='module')
def noisy_trial():
    trial = next(simulate_trials(**TRIAL))
    force = trial.force.copy()
    j = int(np.searchsorted(trial.wrench_t, trial.onset_t - 1.0))
    force[j:j + 20] += np.random.default_rng(1).normal(0.0, 20.0, (20, 3))
    return trial, dataclasses.replace(trial, force=force)


def _events(trial) -> list:
    # the trial's messages as a node receives them (each at its log time)
    return [AudioEvent(samples=trial.audio[e.lo:e.hi], stamp=e.t, now=e.t) if e.kind == 'audio'
            else WrenchEvent(t=trial.wrench_t[e.lo:e.hi], force=trial.force[e.lo:e.hi],
                             torque=trial.torque[e.lo:e.hi], now=e.t)
            for e in message_events(trial=trial)]


def _releases(trial, *, path, noise_jump_n: float):
    detector = ContactDetector(bundle=load_bundle(path=path), settings=DetectorSettings(
        audio_rate=trial.audio_rate, wrench_rate=trial.ft_rate, noise_jump_n=noise_jump_n))
    return run_detector(_events(trial), detector=detector)


@pytest.mark.parametrize('model', ['multimodal', 'ft-only'])
def test_interference_does_not_release_and_the_contact_does(noisy_trial, model):
    clean, noisy = noisy_trial
    path = default_model_path() if model == 'multimodal' else default_ft_model_path()
    before = _releases(clean, path=path, noise_jump_n=15.0)
    assert len(before.releases) == 1
    assert 0.0 < before.releases[0] - clean.onset_t <= 0.5
    assert before.counts['wrench_noise'] == 0 and before.input_problem() is None
    unchecked = _releases(noisy, path=path, noise_jump_n=0.0)
    assert unchecked.releases[0] < clean.onset_t            # what the check is for
    checked = _releases(noisy, path=path, noise_jump_n=15.0)
    assert len(checked.releases) == 1
    assert 0.0 < checked.releases[0] - clean.onset_t <= 0.5
    assert checked.counts['wrench_noise'] >= 5
    assert 'F/T samples were noise' in checked.input_problem()


@pytest.mark.parametrize('bad', [-1.0, float('nan'), float('inf')])
def test_a_bad_noise_threshold_is_a_config_error(bad):
    with pytest.raises(ConfigError, match='noise_jump_n'):
        DetectorSettings(noise_jump_n=bad)
