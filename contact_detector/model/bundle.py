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
The model bundle: a trained forest plus the contract it was trained under.

:class:`ModelBundle` holds the trees, the feature configuration and names, the label window,
the decision rule and the training summary. Saving and loading (with the checks) are in
:mod:`contact_detector.model.storage`, the card beside a model file in
:mod:`contact_detector.model.card`, the shipped models' location in
:mod:`contact_detector.model.shipped`. See ``docs/model.md``.
"""

from dataclasses import dataclass, field
from datetime import datetime
import functools
import importlib.metadata
import math
import platform
import sys
from typing import Any, Dict, Mapping, Optional

import contact_detector
from contact_detector.errors import ModelError
from contact_detector.features.config import FeatureConfig
from contact_detector.model.compiled_forest import CompiledForest, DEFAULT_CODEGEN_DEPTH
from contact_detector.model.forest_arrays import ForestArrays
from contact_detector.model.rule import DecisionRule
import numpy as np

#: How every model error message ends: what to do about it.
RETRAIN = 'retrain with `contact-detector train`'


def sklearn_version() -> str:
    """Installed scikit-learn version (without importing it), or ``'not installed'``."""
    try:
        return importlib.metadata.version('scikit-learn')
    except importlib.metadata.PackageNotFoundError:
        return 'not installed'


def import_sklearn() -> Any:
    """Import scikit-learn for the legacy formats, or say how to get it."""
    try:
        import sklearn
        import sklearn.ensemble  # noqa: F401
    except ImportError as err:
        raise ModelError('this model format holds a scikit-learn object and needs scikit-learn '
                         '(pip install "contact_detector[train]"); or convert the model once '
                         'with `contact-detector convert-model OLD NEW.npz` where scikit-learn '
                         'is installed') from err
    return sklearn


def runtime_versions() -> Dict[str, str]:
    """Versions recorded in a new bundle: contact_detector, scikit-learn, numpy, python."""
    return {'contact_detector': contact_detector.__version__,
            'scikit-learn': sklearn_version(),
            'numpy': np.__version__,
            'python': platform.python_version()}


def plain_json(value: Any, where: str) -> Any:
    """Return ``value`` as plain JSON types; non-finite floats become None."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, Mapping):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise ModelError(f'{where}: keys must be strings, got {key!r}')
            out[key] = plain_json(item, f'{where}.{key}')
        return out
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain_json(item, f'{where}[{i}]') for i, item in enumerate(value)]
    raise ModelError(f'{where}: {type(value).__name__} cannot be stored in a model card '
                     '(use str, int, float, bool, None, lists and dicts)')


def forest_problem(forest: Any, n_features: int) -> Optional[str]:
    """Describe what is wrong with ``forest`` as the bundle's classifier, or None."""
    if isinstance(forest, ForestArrays):
        if forest.n_features != n_features:
            return (f'the forest expects {forest.n_features} features but the bundle names '
                    f'{n_features}')
        return None
    if 'sklearn' not in sys.modules:  # not a scikit-learn object either
        return (f'the classifier is a {type(forest).__name__}, not a RandomForestClassifier, '
                'ExtraTreesClassifier or ForestArrays')
    # both hold the same tree arrays (training's ``splitter``: 'best' or 'random')
    from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier
    if not isinstance(forest, (RandomForestClassifier, ExtraTreesClassifier)):
        return (f'the classifier is a {type(forest).__name__}, not a RandomForestClassifier '
                'or ExtraTreesClassifier')
    if not getattr(forest, 'estimators_', None):
        return f'the {type(forest).__name__} is not fitted'
    classes = np.asarray(forest.classes_).tolist()
    if forest.n_outputs_ != 1 or classes != [0, 1]:
        return f'the forest must have classes [0, 1] (1 = contact), it has {classes}'
    if forest.n_features_in_ != n_features:
        return (f'the forest expects {forest.n_features_in_} features but the bundle names '
                f'{n_features}')
    return None


@dataclass(kw_only=True, eq=False)
class ModelBundle:
    """
    A trained contact classifier with the contract it was trained under.

    Attributes
    ----------
    forest : ForestArrays or sklearn.ensemble.RandomForestClassifier
        The trees as arrays (npz models), or a fitted scikit-learn forest (training, legacy
        models) with classes ``[0, 1]`` (1 = contact); ``len(feature_names)`` inputs.
        :attr:`trees` gives the arrays in both cases.
    feature_config : FeatureConfig
        The feature configuration the training data was computed with.
    feature_names : tuple of str
        Column names; must equal ``feature_config.feature_names``.
    feature_schema_version : int
        :data:`~contact_detector.features.config.FEATURE_SCHEMA_VERSION` at training time.
    label_window : dict
        How frames were labelled, e.g. ``{'mode': 'onset', 'start_s': 0.0, 'end_s': 0.1}``.
    decision_rule : DecisionRule
        Threshold and event logic chosen on validation data.
    versions : dict
        Library versions at training time (see :func:`runtime_versions`).
    training : dict
        Summary of the training data (counts, sources, split, n_estimators search, ...).
    metrics : dict
        Validation / test metrics.
    created : str
        ISO 8601 creation time, passed in by the caller (the library never reads the clock).

    Notes
    -----
    Dict fields are normalised to plain JSON types (tuples become lists, numpy scalars Python
    numbers, NaN/Inf None), exactly as they are stored. Bundles compare by identity.

    """

    forest: Any
    feature_config: FeatureConfig
    feature_names: tuple
    feature_schema_version: int
    label_window: dict
    decision_rule: DecisionRule = field(default_factory=DecisionRule)
    versions: dict
    training: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    created: str

    def __post_init__(self) -> None:
        """Validate the bundle's consistency; raise :class:`ModelError` saying what is wrong."""
        if not isinstance(self.feature_config, FeatureConfig):
            raise ModelError('ModelBundle.feature_config must be a FeatureConfig, got '
                             f'{type(self.feature_config).__name__}')
        if not isinstance(self.decision_rule, DecisionRule):
            raise ModelError('ModelBundle.decision_rule must be a DecisionRule, got '
                             f'{type(self.decision_rule).__name__}')
        if self.decision_rule.uses_load and not self.feature_config.measures_carried:
            raise ModelError('ModelBundle.decision_rule has a load path on (load_threshold '
                             f'{self.decision_rule.load_threshold:g} N, load2_threshold '
                             f'{self.decision_rule.load2_threshold:g} N), which needs the '
                             'carried load, but the feature config has no carried-load feature')
        self.feature_names = tuple(self.feature_names)
        if self.feature_names != self.feature_config.feature_names:
            raise ModelError(f'ModelBundle.feature_names {list(self.feature_names)} differ from '
                             'the names the feature config produces, '
                             f'{list(self.feature_config.feature_names)}')
        version = self.feature_schema_version
        if isinstance(version, bool) or not isinstance(version, (int, np.integer)):
            raise ModelError(f'ModelBundle.feature_schema_version must be an int, got {version!r}')
        self.feature_schema_version = int(version)
        for name in ('label_window', 'versions', 'training', 'metrics'):
            value = getattr(self, name)
            if not isinstance(value, Mapping):
                raise ModelError(f'ModelBundle.{name} must be a dict, got {type(value).__name__}')
            setattr(self, name, plain_json(value, name))
        try:
            datetime.fromisoformat(self.created)
        except (TypeError, ValueError) as err:
            raise ModelError(f'ModelBundle.created must be an ISO 8601 time string, got '
                             f'{self.created!r}') from err
        problem = forest_problem(self.forest, len(self.feature_names))
        if problem:
            raise ModelError(f'invalid ModelBundle: {problem}')

    @functools.cached_property
    def trees(self) -> ForestArrays:
        """Return the forest as :class:`ForestArrays` (converted once from scikit-learn's)."""
        if isinstance(self.forest, ForestArrays):
            return self.forest
        return ForestArrays.from_sklearn(self.forest)

    @property
    def sklearn_forest(self) -> Any:
        """Return the scikit-learn forest, or None for a bundle loaded from an npz file."""
        return None if isinstance(self.forest, ForestArrays) else self.forest

    @property
    def n_estimators(self) -> int:
        """Return the number of trees."""
        return self.trees.n_trees

    @property
    def forest_sha256(self) -> str:
        """SHA-256 of the trees' structure and leaf values, independent of the file format."""
        return self.trees.content_sha256

    @property
    def model_id(self) -> str:
        """
        Short identifier for logs and diagnostics: ``rf<trees>-<feature set>-<hash>``.

        E.g. ``rf8-paper7-3fa2c1d09b``, or ``rf8-paper7+force_delta-...`` with extra features.
        The hash is :attr:`forest_sha256`, so the npz, joblib and skops files of one forest
        share the id. An F/T-only model's set starts with ``ft6`` (the paper's six F/T columns);
        without the torque columns (``FeatureConfig.torque`` false) ``paper4`` and ``ft3``.
        Extremely randomized trees (``training['splitter']`` ``'random'``, ``train --splitter
        random``) are ``et<trees>``.
        """
        config = self.feature_config
        paper = len(config.feature_names) - len(config.extra_features)
        base = f'ft{paper}' if config.ft_only else f'paper{paper}'
        feature_set = '+'.join((base,) + tuple(self.feature_config.extra_features))
        kind = 'et' if self.training.get('splitter') == 'random' else 'rf'
        return f'{kind}{self.n_estimators}-{feature_set}-{self.forest_sha256[:10]}'

    def metadata(self) -> dict:
        """Everything except the forest, as plain JSON (stored in the file and the card)."""
        return {
            'feature_config': self.feature_config.to_dict(),
            'feature_names': list(self.feature_names),
            'feature_schema_version': self.feature_schema_version,
            'label_window': plain_json(self.label_window, 'label_window'),
            'decision_rule': self.decision_rule.to_dict(),
            'versions': plain_json(self.versions, 'versions'),
            'training': plain_json(self.training, 'training'),
            'metrics': plain_json(self.metrics, 'metrics'),
            'created': self.created,
        }

    def feature_importances(self) -> Dict[str, float]:
        """Mean decrease in impurity per feature name (sums to 1), as in the paper's Fig. 7."""
        return {name: float(value)
                for name, value in zip(self.feature_names, self.trees.feature_importances)}

    def compile(self, *,  # noqa: A003 (a method: the builtin stays reachable)
                codegen_depth: int = DEFAULT_CODEGEN_DEPTH) -> CompiledForest:
        """Return a :class:`CompiledForest` of the forest (about 1.5 s for 8 x 20k nodes)."""
        return CompiledForest.from_arrays(self.trees, codegen_depth=codegen_depth)
