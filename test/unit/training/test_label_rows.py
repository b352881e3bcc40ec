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

"""Which bag each row of a labels CSV names, and what reports call each bag."""

from contact_detector.errors import BagError
from contact_detector.io.bags import recording_names
from contact_detector.training.protocol import match_labels
import pytest


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
