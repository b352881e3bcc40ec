# noqa: A005 (a subpackage of contact_detector: the standard library module stays reachable)
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
Input/output at the edges: message adapters, CDR readers, rosbag2 helpers.

The submodules are imported on their own (``from contact_detector.io.bags import find_bags``),
so that the node, which needs :mod:`~contact_detector.io.messages` and
:mod:`~contact_detector.io.cdr` only, does not import rosbags (:mod:`~contact_detector.io.bags`,
for the offline tools).
"""
