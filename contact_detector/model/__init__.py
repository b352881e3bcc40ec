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

"""The model layer: bundles (save/load with checks), forest arrays, the compiled forest."""

from contact_detector.model.bundle import (
    DecisionRule,
    default_ft_model_path,
    default_model_path,
    load_bundle,
    ModelBundle,
    runtime_versions,
    save_bundle,
)
from contact_detector.model.compiled_forest import CompiledForest
from contact_detector.model.forest_arrays import ForestArrays

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
