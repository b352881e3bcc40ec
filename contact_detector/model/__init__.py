"""The model layer: model bundles (save/load with checks) and the compiled forest."""

from contact_detector.model.bundle import (
    DecisionRule,
    default_model_path,
    load_bundle,
    ModelBundle,
    runtime_versions,
    save_bundle,
)
from contact_detector.model.compiled_forest import CompiledForest

__all__ = [
    'CompiledForest',
    'DecisionRule',
    'ModelBundle',
    'default_model_path',
    'load_bundle',
    'runtime_versions',
    'save_bundle',
]
