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

"""Feature core: paper eqs. 1-4, streamed per audio frame (no ROS imports)."""

from contact_detector.features.config import (EXTRA_FEATURES, FEATURE_SCHEMA_VERSION,
                                              FeatureConfig, PAPER_FEATURES)
from contact_detector.features.frames import FeatureFrames, TimeJumpError
from contact_detector.features.streaming import StreamingFeatureExtractor

__all__ = ['EXTRA_FEATURES', 'FEATURE_SCHEMA_VERSION', 'FeatureConfig', 'FeatureFrames',
           'PAPER_FEATURES', 'StreamingFeatureExtractor', 'TimeJumpError']
