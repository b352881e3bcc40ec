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

"""Which frames a forest is trained on: the label window and the frames left out around it."""

from contact_detector.errors import ConfigError
from contact_detector.training.protocol import LabelWindow, stack_weights
import numpy as np
import pytest


def test_frames_after_the_window_are_left_out_of_training_only_for_ignore_s():
    t = np.arange(400) / 100.0
    window = LabelWindow(start_s=0.0, end_s=0.3, ignore_s=0.2)
    kept = window.trained(t=t, onsets=[1.0, 2.5])
    dropped = t[~kept]
    # 0.3-0.5 s after each onset: the object rests on the table, neither label is taught
    assert dropped.tolist() == (np.r_[130:150, 280:300] / 100.0).tolist()
    assert LabelWindow(start_s=0.0, end_s=0.3).trained(t=t, onsets=[1.0]).all()


def test_with_ignore_lead_the_frames_before_the_window_are_left_out_not_taught_no_contact():
    t = np.arange(400) / 100.0
    window = LabelWindow(start_s=0.03, end_s=0.3, ignore_lead=True)
    kept = window.trained(t=t, onsets=[1.0, 2.5])
    # the first 30 ms of each contact: 3 frames of 10 ms, neither label is taught
    assert t[~kept].tolist() == (np.r_[100:103, 250:253] / 100.0).tolist()
    # without it they are trained on, as no contact
    assert LabelWindow(start_s=0.03, end_s=0.3).trained(t=t, onsets=[1.0, 2.5]).all()
    both = LabelWindow(start_s=0.03, end_s=0.3, ignore_s=0.2, ignore_lead=True)
    assert (~both.trained(t=t, onsets=[1.0])).sum() == 3 + 20


def test_ignore_lead_is_in_the_model_file_only_when_set():
    window = LabelWindow(start_s=0.03, end_s=0.3, ignore_lead=True)
    assert window.to_dict() == {'start_s': 0.03, 'end_s': 0.3, 'ignore_lead': True}
    assert LabelWindow(**window.to_dict()) == window
    assert 'ignore_lead' not in LabelWindow(start_s=0.03, end_s=0.3).to_dict()


@pytest.mark.parametrize('bad', [1, 'yes', None])
def test_an_ignore_lead_that_is_not_a_bool_is_refused(bad):
    with pytest.raises(ConfigError, match='ignore_lead'):
        LabelWindow(start_s=0.03, end_s=0.3, ignore_lead=bad)


def test_ignore_lead_with_a_window_from_the_onset_is_refused_not_a_silent_no_op():
    with pytest.raises(ConfigError, match='give a label start > 0'):
        LabelWindow(start_s=0.0, end_s=0.3, ignore_lead=True)


def test_model_files_without_ignore_s_keep_their_label_window():
    assert LabelWindow(start_s=0.0, end_s=0.3).to_dict() == {'start_s': 0.0, 'end_s': 0.3}
    window = LabelWindow(start_s=0.0, end_s=0.3, ignore_s=0.2)
    assert LabelWindow(**window.to_dict()) == window


@pytest.mark.parametrize('bad', [-0.1, float('nan'), float('inf'), True])
def test_a_bad_ignore_s_is_refused(bad):
    with pytest.raises(ConfigError, match='ignore_s'):
        LabelWindow(start_s=0.0, end_s=0.3, ignore_s=bad)


def test_frames_near_an_exogenous_event_before_the_onset_weigh_event_weight():
    t = np.arange(500) / 100.0
    window = LabelWindow(start_s=0.0, end_s=0.3, event_weight=4.0)
    # a knock at 1.0 s, a brush at 3.7 s that runs into the contact at 4.0 s
    w = window.weights(t=t, onsets=[4.0], exogenous=[1.0, 3.7])
    heavy = t[w == 4.0]
    assert heavy.tolist() == (np.r_[98:180, 368:400] / 100.0).tolist()
    assert set(w.tolist()) == {1.0, 4.0}
    # the contact's own frames are never weighted, nor is anything without events
    assert (w[t >= 4.0] == 1.0).all()
    assert window.weights(t=t, onsets=[4.0], exogenous=[]) is None
    assert window.weights(t=t, onsets=[0.5], exogenous=[1.0]) is None
    assert LabelWindow(start_s=0.0, end_s=0.3).weights(t=t, onsets=[4.0], exogenous=[1.0]) is None


def test_the_event_weight_is_in_the_model_file_only_when_it_is_not_1():
    window = LabelWindow(start_s=0.0, end_s=0.3, event_weight=3.0)
    assert window.to_dict() == {'start_s': 0.0, 'end_s': 0.3, 'event_weight': 3.0}
    assert LabelWindow(**window.to_dict()) == window


@pytest.mark.parametrize('bad', [0.5, 0.0, float('nan'), float('inf'), True])
def test_a_bad_event_weight_is_refused(bad):
    with pytest.raises(ConfigError, match='event_weight'):
        LabelWindow(start_s=0.0, end_s=0.3, event_weight=bad)


def test_trials_without_events_weigh_1_beside_trials_with_them():
    assert stack_weights([None, None], sizes=[3, 2]) is None
    stacked = stack_weights([None, np.array([4.0, 1.0])], sizes=[3, 2])
    assert stacked.tolist() == [1.0, 1.0, 1.0, 4.0, 1.0]
