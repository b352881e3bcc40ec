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


"""The truth a simulator manifest gives a bag: found as discovery finds it, or a clear error."""

import json
import re

from contact_detector.errors import BagError
from contact_detector.evaluation.truth import conditions_of, truth_for
import pytest


def _manifest(folder, *trials):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / 'manifest.json').write_text(json.dumps({'trials': list(trials)}))
    return folder / 'manifest.json'


def test_an_entry_is_found_by_its_bag_or_its_name_as_discovery_finds_it(tmp_path):
    # io.bags.manifest_entry accepts "bag" or "name": an entry with "bag" alone is a trial's
    _manifest(tmp_path / 'day1', {'condition': 'no bag, no name', 'onset_t': 1.0},
              {'bag': 'trial_0000', 'condition': 'paper', 'onset_t': 6.5},
              {'name': 'trial_0001', 'condition': 'wide', 'onset_t': 7.5,
               'contact_end_t': 8.0, 'impacts': [{'t': 3.0, 'kind': 'hand', 'in_air': True}],
               'phases': [['rest', 0.0, 1.0], ['lift', 1.0, 2.0]]},
              {'name': 'trial_0002', 'bag': 'trial_0002.bag', 'onset_t': 9.5},
              {'name': 'trial_0001', 'onset_t': 99.0})    # a later entry of the same name
    _manifest(tmp_path / 'day2', {'name': 'trial_0000', 'onset_t': 16.5})
    bags = [tmp_path / 'day1' / 'trial_0000', tmp_path / 'day1' / 'trial_0001',
            tmp_path / 'day1' / 'trial_0002.bag', tmp_path / 'day2' / 'trial_0000',
            tmp_path / 'day2' / 'trial_0009', tmp_path / 'day3' / 'trial_0000']
    manifest = conditions_of(bags)
    assert set(manifest) == set(bags[:4])       # not in a manifest, or no manifest: none
    truths = {bag: truth_for(bag, [], manifest) for bag in bags[:4]}
    assert [(t.name, t.condition, t.onset_t) for t in truths.values()] == [
        ('trial_0000', 'paper', 6.5), ('trial_0001', 'wide', 7.5),
        ('trial_0002.bag', '', 9.5), ('trial_0000', '', 16.5)]
    assert truths[bags[1]].contact_end_t == 8.0
    assert truths[bags[1]].impacts == ((3.0, 'hand', True),)
    assert truths[bags[1]].phases == (('rest', 0.0), ('lift', 1.0))


@pytest.mark.parametrize('entry', [
    {'onset_t': 'soon'}, {'onset_t': None}, {}, {'onset_t': 'nan'}, {'onset_t': [6.5]},
    {'onset_t': 6.5, 'contact_end_t': 'later'},
    {'onset_t': 6.5, 'impacts': [{'t': 'x', 'kind': 'hand', 'in_air': True}]},
    {'onset_t': 6.5, 'impacts': [{'kind': 'hand', 'in_air': True}]},
    {'onset_t': 6.5, 'phases': [['rest', 'start']]},
    {'onset_t': 6.5, 'phases': [3]},
])
def test_an_entry_without_usable_times_is_a_bag_error_naming_manifest_and_trial(tmp_path, entry):
    file = _manifest(tmp_path, {'name': 'trial_0000', 'condition': 'paper', **entry})
    bag = tmp_path / 'trial_0000'
    with pytest.raises(BagError, match=re.escape(f'{file}: trial trial_0000: ')):
        truth_for(bag, [], conditions_of([bag]))


def test_a_manifest_that_does_not_read_is_a_bag_error_naming_it(tmp_path):
    (tmp_path / 'manifest.json').write_text('{"trials": [')
    with pytest.raises(BagError, match=re.escape(str(tmp_path / 'manifest.json'))):
        conditions_of([tmp_path / 'trial_0000'])
