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

"""Which bag each row of a labels CSV names, what reports call each bag, and bad rows."""

import re
import warnings

from contact_detector.errors import BagError
from contact_detector.evaluation.metrics import LATE_S
from contact_detector.io.bags import jazzy_typestore, recording_names, TRUTH_TOPIC
from contact_detector.training.protocol import labels_for, match_labels, read_labels_csv
from contact_detector.training.recipe import training_sources
import pytest
from rosbags.rosbag2 import Writer


@pytest.fixture
def days(tmp_path):
    bags = [tmp_path / 'rec' / day / name for day in ('day1', 'day2')
            for name in ('place_0.bag', 'place_1.bag')]
    bags.append(tmp_path / 'rec' / 'day2' / 'only_here.bag')
    return tmp_path, bags


def test_reports_name_a_bag_by_as_much_of_its_path_as_tells_it_apart(days):
    _root, bags = days
    assert sorted(recording_names(bags).values()) == [
        'day1/place_0.bag', 'day1/place_1.bag', 'day2/place_0.bag', 'day2/place_1.bag',
        'only_here.bag']


def test_rows_name_bags_by_path_from_the_csv_or_by_a_unique_ending(days, monkeypatch):
    root, bags = days
    csv = root / 'labels.csv'
    rows = {'rec/day1/place_0.bag': 1.0,          # relative to the CSV's folder
            str(bags[1]): 2.0,                     # absolute
            'day2/place_0.bag': 3.0,               # the end of one bag's path
            'only_here.bag': 4.0,                  # a name no other bag has
            'day3/place_0.bag': 5.0}               # no such bag among these: left out
    assert match_labels(rows=rows, bags=bags, csv_path=csv) == {
        bags[0]: 1.0, bags[1]: 2.0, bags[2]: 3.0, bags[4]: 4.0}
    # relative to the working directory
    (root / 'rec').mkdir()
    monkeypatch.chdir(root / 'rec')
    assert match_labels(rows={'day2/place_1.bag': 6.0}, bags=bags,
                        csv_path=root / 'elsewhere' / 'labels.csv') == {bags[3]: 6.0}


def test_a_row_that_could_name_several_bags_or_a_bag_named_twice_is_an_error(days):
    root, bags = days
    with pytest.raises(BagError, match="'place_0.bag' could be any of 2 bags"):
        match_labels(rows={'place_0.bag': 1.0}, bags=bags, csv_path=root / 'labels.csv')
    with pytest.raises(BagError, match='both name'):
        match_labels(rows={'only_here.bag': 1.0, 'day2/only_here.bag': 2.0}, bags=bags,
                     csv_path=root / 'labels.csv')


def test_each_csv_of_several_names_the_bags_relative_to_its_own_folder(days):
    root, bags = days
    # one CSV per session, beside its bags, naming them as `label` does: by their own names
    first = root / 'rec' / 'day1' / 'labels.csv'
    second = root / 'rec' / 'day2' / 'labels.csv'
    first.parent.mkdir(parents=True)
    second.parent.mkdir(parents=True)
    _csv(first, 'place_0.bag,10.0,10.1', 'place_1.bag,11.0,11.1')
    _csv(second, 'place_0.bag,20.0,20.1', 'place_1.bag,,,no contact', 'only_here.bag,22.0,22.1')
    with pytest.warns(UserWarning, match='place_1.bag has no onset'):
        labels = labels_for(csv_paths=[first, second], bags=bags)
    assert labels.onsets == {bags[0]: [10.0], bags[1]: [11.0], bags[2]: [20.0], bags[4]: [22.0]}
    assert labels.left_out == [bags[3]] and labels.own_truth == []
    # a bag two CSVs name is an error naming both, not a silent choice of one
    both = _csv(root / 'labels.csv', 'rec/day2/only_here.bag,30.0,30.1')
    with pytest.raises(BagError, match=re.escape(f'{second} and {both} both name {bags[4]}')), \
            pytest.warns(UserWarning, match='place_1.bag has no onset'):
        labels_for(csv_paths=[first, second, both], bags=bags)
    with pytest.raises(BagError, match='no labels CSV given'):
        labels_for(csv_paths=[], bags=bags)


# --- labels that cannot be right (docs: contact-detector label, evaluate --labels) -----------


def _csv(path, *rows):
    path.write_text('\n'.join(['bag,onset_start,onset_end', *rows]) + '\n')
    return path


@pytest.mark.parametrize('content', [None, b'\xf4\x80garbage,\xff\n', 'directory'])
def test_a_labels_file_that_does_not_read_is_a_bag_error_naming_it(tmp_path, content):
    csv = tmp_path / 'labels.csv'
    if content == 'directory':
        csv.mkdir()
    elif content is not None:
        csv.write_bytes(content)
    # the error evaluate and train print as one line (a FileNotFoundError or a
    # UnicodeDecodeError would be a traceback)
    for read in (lambda: read_labels_csv(csv),
                 lambda: labels_for(csv_paths=[csv], bags=[tmp_path / 'trial_0000'])):
        with pytest.raises(BagError, match=f'cannot read labels {re.escape(str(csv))}: '):
            read()


@pytest.mark.parametrize('onset', ['nan', 'NaN', 'inf', '-inf', 'Infinity'])
def test_an_onset_that_is_no_finite_time_is_refused_naming_its_line(tmp_path, onset):
    csv = _csv(tmp_path / 'labels.csv', 'a,10.0,10.1', f'b,{onset},{onset}')
    with pytest.raises(BagError, match=re.escape(f'{csv}:3: onset_start {onset!r}')):
        read_labels_csv(csv)
    # as the first line too, where a header may stand
    csv.write_text(f'b,{onset},{onset}\n')
    with pytest.raises(BagError, match=re.escape(f'{csv}:1: ')):
        read_labels_csv(csv)


@pytest.mark.parametrize('gap', [0.0, 0.001, LATE_S - 0.01])
def test_rows_of_one_bag_closer_than_the_late_window_are_refused_naming_both(tmp_path, gap):
    # one contact written twice (or twice near enough): its release would score two misses
    csv = _csv(tmp_path / 'labels.csv', f'a,{10.0 + gap!r},10.1', 'b,10.0,10.1', 'a,10.0,10.1')
    with pytest.raises(BagError, match=re.escape(f'{csv}:2 and line 4: ') + '.* of a are'):
        read_labels_csv(csv)
    with pytest.raises(BagError, match=re.escape(f'{csv}:2 and line 4: ')):
        labels_for(csv_paths=[csv], bags=[tmp_path / 'a', tmp_path / 'b'])


def test_rows_of_one_bag_far_enough_apart_are_several_contacts(tmp_path):
    csv = _csv(tmp_path / 'labels.csv', 'a,13.0,13.1', 'a,10.0,10.1', f'a,{10.0 + LATE_S!r},1',
               'b,10.0,10.1')
    assert read_labels_csv(csv) == {'a': [13.0, 10.0, 10.0 + LATE_S], 'b': [10.0]}
    # bags that are no bags here: nothing to compare the onsets with, no warning
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        labels = labels_for(csv_paths=[csv], bags=[tmp_path / 'a', tmp_path / 'b'])
    assert labels.onsets == {tmp_path / 'a': [13.0, 10.0, 10.0 + LATE_S],
                             tmp_path / 'b': [10.0]}


def _bag(path, *seconds):
    """Write a rosbag2 of /contact_truth messages logged at ``seconds``; return its path."""
    store = jazzy_typestore()
    kind = 'std_msgs/msg/Bool'
    with Writer(path, version=9) as writer:
        topic = writer.add_connection(TRUTH_TOPIC, kind, typestore=store)
        for t in seconds:
            writer.write(topic, int(t * 1e9), store.serialize_cdr(
                store.types[kind](data=False), kind))
    return path


def test_an_onset_outside_the_recording_is_kept_with_a_warning_naming_its_line(tmp_path):
    bags = [_bag(tmp_path / 'a', 1000.0, 1010.0), _bag(tmp_path / 'b', 2000.0, 2010.0)]
    # seconds from the start of the recording instead of bag time: a usual slip
    csv = _csv(tmp_path / 'labels.csv', 'a,1005.0,1005.1', 'b,5.0,5.1')
    with pytest.warns(UserWarning, match=re.escape(f'{csv}:3: 5.0 (recorded 2000.000 to ')):
        labels = labels_for(csv_paths=[csv], bags=bags)
    # a warning, not an error: stamps on another clock than the receive times may be right
    assert labels.onsets == {bags[0]: [1005.0], bags[1]: [5.0]}
    _csv(csv, 'a,1005.0,1005.1', 'b,2010.0,2010.1')
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        onsets = labels_for(csv_paths=[csv], bags=bags).onsets
    assert onsets == {bags[0]: [1005.0], bags[1]: [2010.0]}


def test_the_card_names_every_labels_csv_by_as_much_of_its_path_as_tells_them_apart(tmp_path):
    user = [tmp_path / 'day1' / 'a', tmp_path / 'day2' / 'a', tmp_path / 'day2' / 'b']
    csvs = [tmp_path / 'day1' / 'labels.csv', tmp_path / 'day2' / 'labels.csv']
    sources = training_sources(user=user, csv_onsets={user[0]: [1.0], user[1]: [2.0, 3.0]},
                               labels_paths=csvs, sim=None, sim_dir=None, kept=False,
                               manifest={})
    assert sources['recordings']['contacts'] == 4
    assert sources['recordings']['labels'].startswith(
        'day1/labels.csv, day2/labels.csv (--labels) for 2, the /contact_truth topic')
