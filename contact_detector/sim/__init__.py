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
Simulator of the placing task: synthetic wrist F/T + microphone trials written as rosbag2.

:mod:`.trial` synthesises (numpy only), :mod:`.bag_writer` writes bags and the manifest,
:mod:`.conditions` documents every randomised parameter range.
"""

from contact_detector.sim.conditions import CONDITION_SETS, resolve_conditions
from contact_detector.sim.trial import Impact, simulate_trial, simulate_trials, Trial

__all__ = [
    'CONDITION_SETS',
    'Impact',
    'resolve_conditions',
    'simulate_trial',
    'simulate_trials',
    'Trial',
]
