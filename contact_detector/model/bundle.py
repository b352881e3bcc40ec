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
The model bundle: a trained forest plus everything needed to use it correctly.

A bundle is saved as three files side by side::

    contact_forest.npz         the model file: the trees as plain arrays (or legacy
                               ``.joblib`` / ``.skops``)
    contact_forest.card.json   the model card: all metadata + SHA-256 of the model file
    contact_forest.card.md     the same card rendered for humans

The ``.npz`` file (:mod:`contact_detector.model.forest_arrays`) holds the trees as numpy
arrays and the metadata as JSON; it is read with ``np.load(..., allow_pickle=False)``, so
loading it needs neither scikit-learn nor pickle. The legacy formats hold ``{'payload_version':
1, 'forest': <RandomForestClassifier>, 'metadata': {...}}`` and are read through scikit-learn
(imported only then). ``metadata`` is plain JSON (feature config, feature names, schema
version, label window, decision rule, versions, training summary, metrics, creation time).
The card repeats ``metadata`` and adds the hash, so :func:`load_bundle` checks a file
**before** parsing it and refuses an incompatible model without touching it. See
``docs/model.md``.
"""

import dataclasses
from dataclasses import dataclass, field
from datetime import datetime
import functools
import hashlib
import importlib.metadata
import json
import math
import os
from pathlib import Path
import pickle
import platform
import sys
from typing import Any, Dict, Mapping, Optional, Sequence
import warnings
import zipfile

import contact_detector
from contact_detector.errors import ConfigError, ModelError
from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.model.compiled_forest import CompiledForest, DEFAULT_CODEGEN_DEPTH
from contact_detector.model.forest_arrays import boundary_frames, ForestArrays
import numpy as np

#: Version of the payload dict inside model files and of the card layout.
PAYLOAD_VERSION = 1
CARD_VERSION = 1
#: File name of the shipped model (in ``<share>/contact_detector/models/``).
DEFAULT_MODEL_NAME = 'contact_forest.npz'
#: File name of the shipped F/T-only model (robots without a microphone), beside it.
FT_ONLY_MODEL_NAME = 'contact_forest_ft.npz'
FORMATS = {'.npz': 'npz', '.joblib': 'joblib', '.skops': 'skops'}
#: Formats whose forest is a pickled/serialised scikit-learn object (loaded through sklearn).
SKLEARN_FORMATS = ('joblib', 'skops')
#: Rows of the training frames on which save_bundle also checks the single-frame path.
SAVE_CHECK_SINGLE_ROWS = 2000
#: Pickle protocol of joblib files, fixed so that the same forest gives the same bytes.
JOBLIB_PROTOCOL = 4
#: zlib level of joblib files: ~4x smaller than raw for deep trees, deterministic.
JOBLIB_COMPRESS = ('zlib', 3)

_RETRAIN = 'retrain with `contact-detector train`'
_METADATA_KEYS = ('feature_config', 'feature_names', 'feature_schema_version', 'label_window',
                  'decision_rule', 'versions', 'training', 'metrics', 'created')

#: Types a skops model file may contain (fully qualified names). Anything else is refused.
SKOPS_ALLOWED_TYPES = frozenset({
    'builtins.dict', 'builtins.list', 'builtins.tuple', 'builtins.str', 'builtins.int',
    'builtins.float', 'builtins.bool', 'builtins.NoneType',
    'numpy.ndarray', 'numpy.dtype', 'numpy.int64', 'numpy.int32', 'numpy.intp',
    'numpy.float64', 'numpy.float32', 'numpy.bool_', 'numpy.bool',
    'numpy.random.mtrand.RandomState', 'numpy.random._mt19937.MT19937',
    'sklearn.ensemble._forest.RandomForestClassifier',
    'sklearn.tree._classes.DecisionTreeClassifier',
    'sklearn.tree._tree.Tree',
})


# ---------------------------------------------------------------------------- decision rule

@dataclass(frozen=True)
class DecisionRule:
    """
    How per-frame probabilities become contact events (applied by the detection layer).

    Attributes
    ----------
    threshold : float
        Contact when P(contact) >= ``threshold``, in [0, 1].
    confirm_frames : int
        Consecutive frames at or above the threshold needed to report a contact, >= 1.
    refractory_s : float
        Seconds after a reported contact during which no new one is reported, >= 0.
    average_frames : int
        Frames averaged before the comparison with ``threshold``, >= 1.
    sustain_frames, sustain_threshold : int, float
        Slow path: contact when the mean P(contact) of the newest ``sustain_frames`` frames is
        ``>= sustain_threshold`` (0 frames = off).
    evidence_threshold, evidence_drift : float
        Evidence path (a CUSUM): ``S_i = max(0, S_{i-1} + p_i - evidence_drift)`` over
        consecutive valid frames, contact when ``S_i >= evidence_threshold`` (0 = off). A
        forest that is only 0.6-0.9 sure for a few frames accumulates evidence, while frames
        below ``evidence_drift`` take it away again.

    """

    threshold: float = 0.5
    confirm_frames: int = 1
    refractory_s: float = 1.0
    average_frames: int = 1
    sustain_frames: int = 0
    sustain_threshold: float = 0.5
    evidence_threshold: float = 0.0
    evidence_drift: float = 0.5

    def __post_init__(self) -> None:
        """Validate and normalise; raise :class:`ConfigError` naming the bad field."""
        for name, low, high in (('threshold', 0.0, 1.0), ('refractory_s', 0.0, math.inf),
                                ('sustain_threshold', 0.0, 1.0),
                                ('evidence_threshold', 0.0, 1000.0),
                                ('evidence_drift', 0.0, 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or not low <= value <= high:
                raise ConfigError(f'DecisionRule.{name} must be a finite number in '
                                  f'[{low}, {high}], got {value!r}')
            object.__setattr__(self, name, float(value))
        for name, low in (('confirm_frames', 1), ('average_frames', 1), ('sustain_frames', 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                    or value < low:
                raise ConfigError(f'DecisionRule.{name} must be an int >= {low}, got {value!r}')
            object.__setattr__(self, name, int(value))

    def describe(self) -> str:
        """Return the rule as one line for logs and diagnostics."""
        text = (f'threshold={self.threshold:.3f} confirm_frames={self.confirm_frames} '
                f'refractory_s={self.refractory_s:.3f}')
        if self.average_frames > 1:
            text += f' average_frames={self.average_frames}'
        if self.sustain_frames > 0:
            text += (f' sustain_frames={self.sustain_frames} '
                     f'sustain_threshold={self.sustain_threshold:.3f}')
        if self.evidence_threshold > 0:
            text += (f' evidence_threshold={self.evidence_threshold:.3f} '
                     f'evidence_drift={self.evidence_drift:.3f}')
        return text

    def short(self) -> str:
        """Return the rule as a table label, e.g. ``p>=0.85 x1 or mean10>=0.4``."""
        text = f'p>={self.threshold:g} x{self.confirm_frames}'
        if self.average_frames > 1:
            text = f'mean{self.average_frames} ' + text
        if self.sustain_frames > 0:
            text += f' or mean{self.sustain_frames}>={self.sustain_threshold:g}'
        if self.evidence_threshold > 0:
            text += f' or sum(p-{self.evidence_drift:g})>={self.evidence_threshold:g}'
        return text

    def to_dict(self) -> dict:
        """Plain-JSON form, stored in bundles and cards."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> 'DecisionRule':
        """Inverse of :meth:`to_dict`; unknown keys are a :class:`ConfigError`."""
        if not isinstance(data, Mapping):
            raise ConfigError(f'DecisionRule must be a mapping, got {type(data).__name__}')
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ConfigError(f'unknown DecisionRule keys: {unknown} (known: {sorted(known)})')
        return cls(**dict(data))


# ---------------------------------------------------------------------------- helpers

def _sklearn_version() -> str:
    """Installed scikit-learn version (without importing it), or ``'not installed'``."""
    try:
        return importlib.metadata.version('scikit-learn')
    except importlib.metadata.PackageNotFoundError:
        return 'not installed'


def _import_sklearn() -> Any:
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
            'scikit-learn': _sklearn_version(),
            'numpy': np.__version__,
            'python': platform.python_version()}


def _plain(value: Any, where: str) -> Any:
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
            out[key] = _plain(item, f'{where}.{key}')
        return out
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(item, f'{where}[{i}]') for i, item in enumerate(value)]
    raise ModelError(f'{where}: {type(value).__name__} cannot be stored in a model card '
                     '(use str, int, float, bool, None, lists and dicts)')


def _major_minor(version: str) -> str:
    """'1.9.1' -> '1.9'."""
    return '.'.join(str(version).split('.')[:2])


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, 'rb') as stream:
        for block in iter(functools.partial(stream.read, 1 << 20), b''):
            digest.update(block)
    return digest.hexdigest()


def card_paths(path: Path) -> tuple:
    """Return ``(card_json, card_md)`` beside the model file ``path``."""
    path = Path(path)
    return (path.with_name(path.stem + '.card.json'), path.with_name(path.stem + '.card.md'))


def _forest_problem(forest: Any, n_features: int) -> Optional[str]:
    """Describe what is wrong with ``forest`` as the bundle's classifier, or None."""
    if isinstance(forest, ForestArrays):
        if forest.n_features != n_features:
            return (f'the forest expects {forest.n_features} features but the bundle names '
                    f'{n_features}')
        return None
    if 'sklearn' not in sys.modules:  # not a scikit-learn object either
        return (f'the classifier is a {type(forest).__name__}, not a RandomForestClassifier '
                'or ForestArrays')
    from sklearn.ensemble import RandomForestClassifier
    if not isinstance(forest, RandomForestClassifier):
        return f'the classifier is a {type(forest).__name__}, not a RandomForestClassifier'
    if not getattr(forest, 'estimators_', None):
        return 'the RandomForestClassifier is not fitted'
    classes = np.asarray(forest.classes_).tolist()
    if forest.n_outputs_ != 1 or classes != [0, 1]:
        return f'the forest must have classes [0, 1] (1 = contact), it has {classes}'
    if forest.n_features_in_ != n_features:
        return (f'the forest expects {forest.n_features_in_} features but the bundle names '
                f'{n_features}')
    return None


# ---------------------------------------------------------------------------- the bundle

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
            setattr(self, name, _plain(value, name))
        try:
            datetime.fromisoformat(self.created)
        except (TypeError, ValueError) as err:
            raise ModelError(f'ModelBundle.created must be an ISO 8601 time string, got '
                             f'{self.created!r}') from err
        problem = _forest_problem(self.forest, len(self.feature_names))
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
        share the id. An F/T-only model's set starts with ``ft6`` (the paper's six F/T columns).
        """
        base = 'ft6' if self.feature_config.ft_only else 'paper7'
        feature_set = '+'.join((base,) + tuple(self.feature_config.extra_features))
        return f'rf{self.n_estimators}-{feature_set}-{self.forest_sha256[:10]}'

    def metadata(self) -> dict:
        """Everything except the forest, as plain JSON (stored in the file and the card)."""
        return {
            'feature_config': self.feature_config.to_dict(),
            'feature_names': list(self.feature_names),
            'feature_schema_version': self.feature_schema_version,
            'label_window': _plain(self.label_window, 'label_window'),
            'decision_rule': self.decision_rule.to_dict(),
            'versions': _plain(self.versions, 'versions'),
            'training': _plain(self.training, 'training'),
            'metrics': _plain(self.metrics, 'metrics'),
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


# ---------------------------------------------------------------------------- the card

def _forest_summary(trees: ForestArrays) -> dict:
    return {'params': dict(trees.params),
            'tree_node_counts': trees.tree_node_counts(),
            'tree_max_depths': trees.tree_max_depths(),
            'tree_leaf_counts': trees.tree_leaf_counts()}


def build_card(*, bundle: ModelBundle, model_path: Path, fmt: str) -> dict:
    """
    Return the model card of ``bundle`` saved at ``model_path`` (which must exist).

    Returns
    -------
    dict
        ``card_version``, ``model_file``, ``format``, ``sha256``, ``size_bytes``,
        ``model_id``, ``forest_sha256``, ``n_estimators``, ``feature_importances`` (name ->
        importance), ``forest`` (parameters and tree sizes) and every key of
        :meth:`ModelBundle.metadata`.

    """
    card = {'card_version': CARD_VERSION,
            'model_file': Path(model_path).name,
            'format': fmt,
            'sha256': _sha256(Path(model_path)),
            'size_bytes': Path(model_path).stat().st_size,
            'model_id': bundle.model_id,
            'forest_sha256': bundle.forest_sha256,
            'n_estimators': bundle.n_estimators,
            'feature_importances': bundle.feature_importances(),
            'forest': _forest_summary(bundle.trees)}
    card.update(bundle.metadata())
    return _plain(card, 'card')


def _md_value(value: Any) -> str:
    if isinstance(value, float):
        return f'{value:.6g}'
    if isinstance(value, (dict, list)):
        return '`' + json.dumps(value, sort_keys=True) + '`'
    return f'`{value}`' if isinstance(value, str) else str(value)


def _md_table(rows: Mapping[str, Any], header: tuple = ('key', 'value')) -> list:
    lines = [f'| {header[0]} | {header[1]} |', '|---|---|']
    lines += [f'| {key} | {_md_value(value)} |' for key, value in rows.items()]
    return lines + ['']


_LOAD_CHECKS = {
    'npz': ('Loading needs numpy only (no scikit-learn, no pickle): it checks the SHA-256 above, '
            'the feature schema version, the feature names and configuration, then every '
            'array of the file (dtypes, shapes, child and feature indices, tree structure, '
            'finite thresholds, class fractions) and the forest content hash '
            '(see docs/model.md).'),
    'joblib': ('Loading checks the SHA-256 above before unpickling, then the feature schema '
               'version, the feature names and configuration, and the scikit-learn version '
               '(see docs/model.md). Convert it to the npz format with `contact-detector '
               'convert-model`.'),
}
_LOAD_CHECKS['skops'] = _LOAD_CHECKS['joblib']


def render_card_markdown(card: Mapping[str, Any]) -> str:
    """Render a card dict (see :func:`build_card`) as Markdown."""
    importances = sorted(card['feature_importances'].items(), key=lambda kv: -kv[1])
    forest = card['forest']
    lines = [f'# Model card: {card["model_id"]}', '',
             f'Model file `{card["model_file"]}` ({card["format"]}, {card["size_bytes"]} bytes), '
             f'created {card["created"]}.', '',
             f'- SHA-256 of the model file: `{card["sha256"]}`',
             f'- Forest content hash: `{card["forest_sha256"]}`',
             f'- Trees: {card["n_estimators"]}, nodes per tree {forest["tree_node_counts"]}, '
             f'depths {forest["tree_max_depths"]}',
             f'- Feature schema version: {card["feature_schema_version"]}', '',
             _LOAD_CHECKS.get(card['format'], _LOAD_CHECKS['joblib']), '',
             '## Features and importances', '',
             '| feature | importance |', '|---|---|']
    lines += [f'| {name} | {value:.4f} |' for name, value in importances]
    lines += ['', '## Feature configuration', '']
    lines += _md_table(card['feature_config'])
    lines += ['## Labels and decision rule', '']
    lines += _md_table({'label_window': card['label_window'], **card['decision_rule']})
    for title, key in (('Metrics', 'metrics'), ('Training data', 'training'),
                       ('Versions', 'versions')):
        lines += [f'## {title}', '']
        lines += _md_table(card[key]) if card[key] else ['(none)', '']
    lines += ['## Forest parameters', '']
    lines += _md_table(forest['params'])
    return '\n'.join(lines)


# ---------------------------------------------------------------------------- save / load

def _replace_atomically(*, data_writer: Any, path: Path) -> None:
    """Write with ``data_writer(tmp_path)`` then rename over ``path``."""
    tmp = path.with_name(f'.{path.name}.tmp')
    try:
        data_writer(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def save_bundle(*, bundle: ModelBundle, path: Path, fmt: Optional[str] = None,
                check_frames: Optional[np.ndarray] = None) -> Path:
    """
    Save ``bundle`` as a model file plus its card (``.card.json`` and ``.card.md``).

    Parameters
    ----------
    bundle : ModelBundle
        The bundle to save.
    path : Path
        Model file path; its suffix names the format (``.npz``, ``.joblib`` or ``.skops``).
        Parent directories are created.
    fmt : str, optional
        ``'npz'`` (arrays, loads with numpy alone; see :mod:`~contact_detector.model.
        forest_arrays`), ``'joblib'`` (pickle protocol 4, zlib level 3) or ``'skops'``;
        None = from the suffix. All three give the same bytes for the same bundle.
    check_frames : np.ndarray, shape (n_frames, n_features), optional
        npz only: frames (e.g. the training frames) on which the written file's forest must
        give ``forest.predict_proba(x)[:, 1]`` of the bundle's scikit-learn forest bit for
        bit, besides :func:`~contact_detector.model.forest_arrays.boundary_frames`.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ConfigError
        Unknown ``fmt`` or a suffix that does not match it.
    ModelError
        The bundle cannot be written; or, for npz, the file read back is not the same forest
        (content hash, metadata, or probabilities differing from scikit-learn's in any bit).
        Nothing is written then.

    """
    path = Path(path)
    if fmt is None:
        fmt = FORMATS.get(path.suffix)
        if fmt is None:
            raise ConfigError(f'a model file must end in one of {sorted(FORMATS)}, got '
                              f'{path.name!r}')
    if fmt not in FORMATS.values():
        raise ConfigError(f'unknown model format {fmt!r}; use one of {sorted(FORMATS.values())}')
    if FORMATS.get(path.suffix) != fmt:
        raise ConfigError(f'a {fmt} model file must end in .{fmt}, got {path.name!r}')
    if not isinstance(bundle, ModelBundle):
        raise ModelError(f'save_bundle needs a ModelBundle, got {type(bundle).__name__}')
    card_json, card_md = card_paths(path)
    others = [path.with_suffix(suffix) for suffix in FORMATS if suffix != path.suffix]
    clash = [other.name for other in others if other.exists()]
    if clash:
        raise ConfigError(f'{clash[0]} already sits beside {path.name} and owns the card '
                          f'{card_json.name}; save the {fmt} file under another name')
    if fmt == 'npz':
        def writer(tmp: Path) -> None:
            bundle.trees.write_npz(path=tmp, metadata=bundle.metadata())
            _check_written_npz(bundle=bundle, path=tmp, check_frames=check_frames)
    else:
        payload = {'payload_version': PAYLOAD_VERSION, 'forest': _sklearn_forest_of(bundle),
                   'metadata': bundle.metadata()}
        if fmt == 'joblib':
            import joblib

            def writer(tmp: Path) -> None:
                joblib.dump(payload, tmp, compress=JOBLIB_COMPRESS, protocol=JOBLIB_PROTOCOL)
        else:
            skops_io = _import_skops()

            def writer(tmp: Path) -> None:
                skops_io.dump(payload, tmp, compression=zipfile.ZIP_DEFLATED, compresslevel=3)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _replace_atomically(data_writer=writer, path=path)
        card = build_card(bundle=bundle, model_path=path, fmt=fmt)
        _replace_atomically(
            data_writer=lambda tmp: tmp.write_text(json.dumps(card, indent=2) + '\n'),
            path=card_json)
        _replace_atomically(data_writer=lambda tmp: tmp.write_text(render_card_markdown(card)),
                            path=card_md)
    except (OSError, TypeError, ValueError, pickle.PicklingError) as err:
        raise ModelError(f'cannot save model to {path}: {err}') from err
    return path


def _sklearn_forest_of(bundle: ModelBundle) -> Any:
    """Return the scikit-learn forest the legacy formats store, or raise ModelError."""
    if bundle.sklearn_forest is None:
        raise ModelError('this bundle holds its forest as arrays (it was loaded from an npz '
                         'file); it can only be saved as npz')
    return bundle.sklearn_forest


def _bits(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)


def _check_written_npz(*, bundle: ModelBundle, path: Path,
                       check_frames: Optional[np.ndarray]) -> None:
    """Read ``path`` back and compare it with the bundle; raise ModelError on any difference."""
    loaded, meta = ForestArrays.read_npz(path=path)
    if loaded.content_sha256 != bundle.forest_sha256 or meta != bundle.metadata():
        raise ModelError('the npz file read back differs from the bundle (trees or metadata); '
                         'it was not saved')
    forest = bundle.sklearn_forest
    if forest is None:
        return  # the bundle's forest already is these arrays (content hash compared above)
    compiled = CompiledForest.from_arrays(loaded)
    frames = [boundary_frames(loaded)]
    if check_frames is not None:
        frames.append(np.asarray(check_frames))
    for x in frames:
        if x.ndim != 2 or x.shape[1] != loaded.n_features:
            raise ModelError(f'check_frames must have shape (n, {loaded.n_features}), got '
                             f'{x.shape}')
        expected = forest.predict_proba(x)[:, 1]
        single = x[np.linspace(0, len(x) - 1, min(len(x), SAVE_CHECK_SINGLE_ROWS)).astype(int)] \
            if len(x) else x
        one = np.array([compiled.predict_one(row) for row in single], dtype=np.float64)
        expected_one = forest.predict_proba(single)[:, 1] if len(single) else one
        if not (np.array_equal(_bits(compiled.predict_proba(x)), _bits(expected))
                and np.array_equal(_bits(one), _bits(expected_one))):
            raise ModelError(f"the npz forest's probabilities differ from scikit-learn "
                             f'{_sklearn_version()} predict_proba on {len(x)} frames; the model '
                             'was not saved (is this forest from scikit-learn >= 1.4?)')


def _check_metadata(*, meta: Mapping[str, Any], source: str,
                    expected_config: Optional[FeatureConfig], fmt: str) -> FeatureConfig:
    """Check a card's or payload's metadata against the running code; return its config."""
    if not isinstance(meta, Mapping):
        raise ModelError(f'{source}: the metadata is not a JSON object; {_RETRAIN}')
    missing = [key for key in _METADATA_KEYS if key not in meta]
    if missing:
        raise ModelError(f'{source} lacks {missing}; it was not written by save_bundle; '
                         f'{_RETRAIN}')
    schema = meta['feature_schema_version']
    if schema != FEATURE_SCHEMA_VERSION:
        raise ModelError(f'{source} was trained on feature schema version {schema}, but this '
                         f'contact_detector computes schema version {FEATURE_SCHEMA_VERSION} '
                         f'(the features changed meaning); {_RETRAIN}')
    if not isinstance(meta['versions'], Mapping) or not isinstance(meta['feature_names'], list):
        raise ModelError(f'{source}: versions must be an object and feature_names a list; '
                         f'{_RETRAIN}')
    if fmt in SKLEARN_FORMATS:
        # A pickled forest is only read by the scikit-learn that wrote it; npz has no such tie.
        saved = str(meta['versions'].get('scikit-learn', 'unknown'))
        installed = _sklearn_version()
        if _major_minor(saved) != _major_minor(installed):
            raise ModelError(f'{source} was saved with scikit-learn {saved} but scikit-learn '
                             f'{installed} is installed; {fmt} forests are only loaded by the '
                             f'same major.minor version. Convert it once with `contact-detector '
                             f'convert-model` under scikit-learn {_major_minor(saved)}.x (the '
                             f'npz format needs no scikit-learn), or {_RETRAIN}')
    try:
        config = FeatureConfig.from_dict(meta['feature_config'])
    except (ConfigError, TypeError, ValueError, AttributeError) as err:
        raise ModelError(f'{source} has a feature configuration this contact_detector cannot '
                         f'use ({err}); {_RETRAIN}') from err
    names = tuple(meta['feature_names'])
    if names != config.feature_names:
        raise ModelError(f'{source} names features {list(names)} but its feature configuration '
                         f'produces {list(config.feature_names)}; the model does not match the '
                         f'feature code; {_RETRAIN}')
    if expected_config is not None and config != expected_config:
        diffs = [f'{f.name} (model {getattr(config, f.name)!r}, expected '
                 f'{getattr(expected_config, f.name)!r})'
                 for f in dataclasses.fields(FeatureConfig)
                 if getattr(config, f.name) != getattr(expected_config, f.name)]
        raise ModelError(f'{source} was trained with a different feature configuration: '
                         f'{"; ".join(diffs)}. Use the model\'s configuration for the features, '
                         f'or {_RETRAIN} with the expected one')
    return config


def _skops_types(path: Path) -> set:
    """All ``module.Class`` names in a skops file's schema."""
    with zipfile.ZipFile(path) as archive:
        schema = json.loads(archive.read('schema.json'))
    found = set()
    stack = [schema]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            if isinstance(item.get('__class__'), str) and isinstance(item.get('__module__'), str):
                found.add(f'{item["__module__"]}.{item["__class__"]}')
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)
    return found


def _import_skops() -> Any:
    try:
        import skops.io
    except ImportError as err:
        raise ModelError('the skops format needs the skops package: pip install skops (the '
                         '"safe" extra of contact_detector), or use the joblib format') from err
    return skops.io


def _read_payload(*, path: Path, fmt: str, trusted_skops_types: Sequence[str]) -> Any:
    """Deserialise a (hash-checked) legacy model file; wrap every failure in ModelError."""
    _import_sklearn()
    from sklearn.exceptions import InconsistentVersionWarning
    skops_io = _import_skops() if fmt == 'skops' else None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter('error', InconsistentVersionWarning)
            if fmt == 'joblib':
                import joblib
                return joblib.load(path)
            allowed = SKOPS_ALLOWED_TYPES | set(trusted_skops_types)
            untrusted = set(skops_io.get_untrusted_types(file=path))
            refused = sorted((untrusted | _skops_types(path)) - allowed)
            if refused:
                raise ModelError(f'skops model file {path} contains types outside the '
                                 f'allow-list: {refused}; it was not loaded. If you trust '
                                 'the file, pass them in trusted_skops_types')
            return skops_io.load(path, trusted=sorted(untrusted))
    except ModelError:
        raise
    except InconsistentVersionWarning as err:
        raise ModelError(f'model file {path} was pickled by another scikit-learn version '
                         f'({err}); {_RETRAIN}') from err
    except Exception as err:  # any unpickling failure means a bad model file
        raise ModelError(f'cannot read {fmt} model file {path}: {type(err).__name__}: {err}; '
                         f'the file is corrupt or not a contact_detector model; '
                         f'{_RETRAIN}') from err


def load_bundle(*, path: Path, expected_config: Optional[FeatureConfig] = None,
                verify_hash: bool = True, trusted_skops_types: Sequence[str] = ()
                ) -> ModelBundle:
    """
    Load a model file saved by :func:`save_bundle`, refusing anything that does not fit.

    Order of checks (each failure is a :class:`ModelError` saying what to do; no other
    exception escapes):

    1. the model file and its ``<stem>.card.json`` exist; the suffix names the format;
    2. the file's SHA-256 equals the card's (skipped if ``verify_hash`` is False), *before*
       the file is parsed (unpickling a joblib file runs code);
    3. from the card, still before parsing: feature schema version equals
       :data:`FEATURE_SCHEMA_VERSION`, feature names equal the card's
       ``feature_config.feature_names``, the config equals ``expected_config`` (differing
       fields named); for joblib/skops only, scikit-learn major.minor equals the running one;
    4. npz: the zip holds exactly the layout's members with their dtypes and dimensions and
       sizes matching their headers, read by ``np.load(allow_pickle=False)``; the arrays form
       valid trees (:class:`~contact_detector.model.forest_arrays.ForestArrays`); the content
       hash equals the card's ``forest_sha256``.
       skops: every type in the file is in :data:`SKOPS_ALLOWED_TYPES` or
       ``trusted_skops_types``;
    5. the file's own metadata equals the card's; the forest has ``len(feature_names)``
       inputs (a fitted ``RandomForestClassifier`` with classes ``[0, 1]`` for joblib/skops).

    Only joblib and skops import scikit-learn (and joblib/skops); npz needs numpy alone.

    Parameters
    ----------
    path : Path
        ``.npz``, ``.joblib`` or ``.skops`` model file.
    expected_config : FeatureConfig, optional
        The configuration the caller will compute features with.
    verify_hash : bool
        Compare the file's SHA-256 with the card (default). Only turn off for a file whose
        provenance you know and whose card you cannot regenerate.
    trusted_skops_types : sequence of str
        Extra fully qualified type names accepted in a skops file.

    Returns
    -------
    ModelBundle

    """
    path = Path(path)
    try:
        return _load_bundle(path=path, expected_config=expected_config, verify_hash=verify_hash,
                            trusted_skops_types=trusted_skops_types)
    except ModelError:
        raise
    except Exception as err:  # a malformed card or file: never anything but ModelError
        raise ModelError(f'model {path} cannot be loaded: {type(err).__name__}: {err}; '
                         f'the file or its card is corrupt; {_RETRAIN}') from err


def _load_bundle(*, path: Path, expected_config: Optional[FeatureConfig], verify_hash: bool,
                 trusted_skops_types: Sequence[str]) -> ModelBundle:
    """:func:`load_bundle` without the final wrapping of unexpected errors."""
    fmt = FORMATS.get(path.suffix)
    if fmt is None:
        raise ModelError(f'model file {path} must end in .npz, .joblib or .skops')
    if not path.is_file():
        raise ModelError(f'model file {path} does not exist; pass an existing model or '
                         f'{_RETRAIN}')
    card_json, _ = card_paths(path)
    if not card_json.is_file():
        raise ModelError(f'model card {card_json} is missing; a model file is only loaded '
                         'together with the card save_bundle writes beside it (it holds the '
                         'SHA-256 checked before loading). Copy the card along with the model, '
                         f'or {_RETRAIN}')
    try:
        card = json.loads(card_json.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise ModelError(f'model card {card_json} cannot be read: {err}') from err
    if not isinstance(card, dict) or card.get('card_version') != CARD_VERSION \
            or not isinstance(card.get('sha256'), str):
        raise ModelError(f'model card {card_json} is not a version {CARD_VERSION} card with a '
                         f'sha256; {_RETRAIN}')
    if card.get('format') != fmt:
        raise ModelError(f'model card {card_json} describes a {card.get("format")!r} file but '
                         f'{path.name} is loaded as {fmt} (by its suffix)')
    if verify_hash:
        actual = _sha256(path)
        if actual != card['sha256']:
            raise ModelError(f'model file {path} has sha256 {actual}, which does not match its '
                             f'card {card_json} ({card["sha256"]}): the file is corrupt or was '
                             'modified, and it was NOT loaded. Restore the file that goes with '
                             f'the card, or {_RETRAIN}')
    card_source = f'model {path.name} (per its card)'
    config = _check_metadata(meta=card, source=card_source, expected_config=expected_config,
                             fmt=fmt)

    if fmt == 'npz':
        forest, meta = ForestArrays.read_npz(path=path)
        if forest.content_sha256 != card.get('forest_sha256'):
            raise ModelError(f'model file {path}: its trees have content hash '
                             f'{forest.content_sha256}, the card says '
                             f'{card.get("forest_sha256")}; re-save the bundle to regenerate '
                             'the card')
    else:
        payload = _read_payload(path=path, fmt=fmt, trusted_skops_types=trusted_skops_types)
        if not isinstance(payload, dict) or payload.get('payload_version') != PAYLOAD_VERSION \
                or not isinstance(payload.get('metadata'), dict) or 'forest' not in payload:
            raise ModelError(f'model file {path} does not hold a version {PAYLOAD_VERSION} '
                             f'contact_detector bundle; {_RETRAIN}')
        forest, meta = payload['forest'], payload['metadata']
    differing = [key for key in _METADATA_KEYS if meta.get(key) != card.get(key)]
    if differing:
        raise ModelError(f'model card {card_json} disagrees with model file {path.name} in '
                         f'{differing}; the card must be the one save_bundle wrote with this '
                         'file. Re-save the bundle to regenerate the card')
    problem = _forest_problem(forest, len(config.feature_names))
    if problem:
        raise ModelError(f'model file {path}: {problem}; {_RETRAIN}')
    try:
        return ModelBundle(forest=forest, feature_config=config,
                           feature_names=tuple(meta['feature_names']),
                           feature_schema_version=meta['feature_schema_version'],
                           label_window=meta['label_window'],
                           decision_rule=DecisionRule.from_dict(meta['decision_rule']),
                           versions=meta['versions'], training=meta['training'],
                           metrics=meta['metrics'], created=meta['created'])
    except (ConfigError, TypeError) as err:
        raise ModelError(f'model file {path} has invalid metadata: {err}; {_RETRAIN}') from err


# ---------------------------------------------------------------------------- shipped model

def _model_dirs() -> list:
    """Directories searched for the shipped model, in order."""
    dirs = []
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:
        pass
    else:
        try:
            dirs.append(Path(get_package_share_directory('contact_detector')) / 'models')
        except (LookupError, OSError, ValueError):
            pass  # not installed in a sourced ROS workspace
    dirs.append(Path(sys.prefix) / 'share' / 'contact_detector' / 'models')
    dirs.append(Path(__file__).resolve().parents[2] / 'models')
    return dirs


def find_model(*, name: str = DEFAULT_MODEL_NAME, dirs: Sequence[Path]) -> Path:
    """
    Return the first ``<dir>/<name>`` that exists.

    Raises
    ------
    ModelError
        If none exists; the message lists the directories searched.

    """
    for directory in dirs:
        candidate = Path(directory) / name
        if candidate.is_file():
            return candidate
    searched = ', '.join(str(d) for d in dirs)
    raise ModelError(f'no {name} found (searched {searched}); pass a model path, or '
                     f'{_RETRAIN} and save it as models/{name}')


def default_model_path() -> Path:
    """
    Path of the shipped model ``models/contact_forest.npz``.

    Searched in the ament share directory of ``contact_detector`` (if ament_index_python is
    importable and the package is installed), then ``<sys.prefix>/share/contact_detector/
    models/``, then the source checkout's ``models/``.

    Raises
    ------
    ModelError
        If no shipped model exists.

    """
    return find_model(dirs=_model_dirs())


def default_ft_model_path() -> Path:
    """
    Path of the shipped F/T-only model ``models/contact_forest_ft.npz``.

    Searched where :func:`default_model_path` searches.

    Raises
    ------
    ModelError
        If no shipped F/T-only model exists.

    """
    return find_model(name=FT_ONLY_MODEL_NAME, dirs=_model_dirs())
