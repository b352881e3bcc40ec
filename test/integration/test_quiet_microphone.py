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

"""A quiet microphone does not change what discovery finds: 200 Hz ROS 1 bags, no flags."""

import dataclasses
import json
from pathlib import Path

from contact_detector.io.discovery import discover_streams
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest
from test_discovery import detect_found_and_by_hand

pytestmark = pytest.mark.slow   # writes and reads many bags, runs detect


def _rows(path: Path) -> list:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_quiet_200_hz_ros1_bags_decide_without_flags_as_with_them(tmp_path, capsys):
    """A gain 46 dB too low: samples of a few LSB, often 0, and no rate anywhere in the bag."""
    folder = tmp_path / 'robot'
    for index in range(3):
        trial = simulate_trial(seed=41, index=index, ft_rate=200.0)
        quiet = np.round(trial.audio.astype(float) / 200.0).astype(np.int16)
        trial = dataclasses.replace(trial, audio=quiet)
        write_trial_bag(trial=trial, path=folder / f'place_{index}', storage='ros1')
    bags = sorted(folder.iterdir())
    assert np.abs(quiet).max() < 60 and np.mean(quiet == 0) > 0.3
    for bag in bags:
        found = discover_streams(bag)
        assert abs(found.wrench_rate - 200.0) < 0.5 and found.wrench_rate_source == 'stamps'
        assert (found.audio_rate, found.audio_rate_source) == (16000.0, 'estimated')
    by_flags, by_hand = detect_found_and_by_hand(folder, tmp_path, capsys)
    rows = _rows(by_flags)
    assert len(rows) > 300 and rows == _rows(by_hand)
    assert {row['bag'] for row in rows} == {bag.name for bag in bags}
