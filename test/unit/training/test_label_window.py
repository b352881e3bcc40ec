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

"""Which frames a forest is trained on: the label window and the frames left out after it."""

from contact_detector.errors import ConfigError
from contact_detector.training.protocol import LabelWindow
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


def test_model_files_without_ignore_s_keep_their_label_window():
    assert LabelWindow(start_s=0.0, end_s=0.3).to_dict() == {'start_s': 0.0, 'end_s': 0.3}
    window = LabelWindow(start_s=0.0, end_s=0.3, ignore_s=0.2)
    assert LabelWindow(**window.to_dict()) == window


@pytest.mark.parametrize('bad', [-0.1, float('nan'), float('inf'), True])
def test_a_bad_ignore_s_is_refused(bad):
    with pytest.raises(ConfigError, match='ignore_s'):
        LabelWindow(start_s=0.0, end_s=0.3, ignore_s=bad)
