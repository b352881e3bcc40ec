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
