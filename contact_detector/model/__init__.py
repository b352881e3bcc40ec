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
The model layer: the bundle and its rule, save/load with checks, the card, the forest.

``bundle`` (:class:`ModelBundle`), ``rule`` (:class:`DecisionRule`), ``storage``
(:func:`save_bundle`, :func:`load_bundle`), ``card`` (the model card), ``shipped`` (where the
shipped models are, without ROS), ``forest_arrays`` and ``compiled_forest`` (the trees).
"""

from contact_detector.model.bundle import ModelBundle, runtime_versions
from contact_detector.model.compiled_forest import CompiledForest
from contact_detector.model.forest_arrays import ForestArrays
from contact_detector.model.rule import DecisionRule
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle, save_bundle

__all__ = [
    'CompiledForest',
    'DecisionRule',
    'ForestArrays',
    'ModelBundle',
    'default_ft_model_path',
    'default_model_path',
    'load_bundle',
    'runtime_versions',
    'save_bundle',
]
