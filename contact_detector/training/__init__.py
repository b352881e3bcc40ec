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
The training layer: the paper's training protocol, the model-selection sweeps, the recipe.

``protocol`` (labels, splits, forests by validation AUC), ``sweep`` (feature settings x label
windows x decision rules scored on held-out trials), ``recipe`` (the shipped model's defaults
and the data steps of ``contact-detector train``). It sits above evaluation: candidates are
scored with :mod:`contact_detector.evaluation.metrics`.
"""
