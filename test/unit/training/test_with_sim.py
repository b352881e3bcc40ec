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

"""The simulated trials ``train --with-sim N`` adds: the shipped model's proportions."""

import json

from contact_detector.errors import BagError
from contact_detector.sim.bag_writer import simulator_fingerprint
from contact_detector.training.recipe import sim_parts, simulated_trials
import pytest


def counts(n: int) -> dict:
    return {name: (p['trials'], p['seed'], p['start_index'], p['events'], p['hits'])
            for name, p in sim_parts(n=n, seed=7, ft_rate=125.0, audio_rate=16000).items()}


def test_with_sim_600_is_the_shipped_training_sets_480_plus_120():
    assert counts(600) == {'family': (480, 7, 0, 'family', None),
                           'mixed': (120, 8, 480, 'everywhere', 'mixed')}


@pytest.mark.parametrize(('n', 'mixed'), [(1, 0), (2, 0), (3, 1), (7, 1), (8, 2), (24, 5),
                                          (60, 12), (61, 12), (62, 12), (63, 13)])
def test_a_fifth_rounded_to_the_nearest_trial_has_every_event_in_every_family(n, mixed):
    parts = counts(n)
    assert parts.get('mixed', (0,))[0] == mixed
    assert parts['family'][0] + mixed == n
    # the trial indices follow on, so no two simulated trials share a name
    if mixed:
        assert parts['mixed'][2] == parts['family'][0]


def test_a_refused_sim_dir_gets_no_new_trials(tmp_path):
    # a mixed part made with other events: refused before the family part is simulated
    settings = sim_parts(n=8, seed=0, ft_rate=125.0, audio_rate=16000)['mixed']
    (tmp_path / 'mixed').mkdir()
    (tmp_path / 'mixed' / 'manifest.json').write_text(json.dumps(
        {'settings': {**settings, 'events': 'family', 'hits': None}, 'trials': []}))
    with pytest.raises(BagError, match='holds other simulated trials'):
        simulated_trials(sim_dir=tmp_path, n=8, seed=0, ft_rate=125.0, audio_rate=16000)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['mixed']


def test_a_part_whose_bags_are_gone_is_refused(tmp_path):
    # its manifest says the right trials, but the bags it lists are not there
    settings = sim_parts(n=8, seed=0, ft_rate=125.0, audio_rate=16000)['mixed']
    (tmp_path / 'mixed').mkdir()
    (tmp_path / 'mixed' / 'manifest.json').write_text(json.dumps(
        {'simulator': simulator_fingerprint(), 'settings': settings,
         'trials': [{'bag': f'trial_{i:04d}'} for i in range(6, 8)]}))
    with pytest.raises(BagError, match=r'holds other simulated trials \(other bags\)'):
        simulated_trials(sim_dir=tmp_path, n=8, seed=0, ft_rate=125.0, audio_rate=16000)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['mixed']
