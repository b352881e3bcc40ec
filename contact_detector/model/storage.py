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
Saving and loading model bundles, with the checks that refuse a model that does not fit.

A bundle is saved as three files side by side::

    contact_forest.npz         the model file: the trees as plain arrays (or legacy
                               ``.joblib`` / ``.skops``)
    contact_forest.card.json   the model card: all metadata + SHA-256 of the model file
    contact_forest.card.md     the same card rendered for humans

The ``.npz`` file (:mod:`contact_detector.model.forest_arrays`) holds the trees as numpy
arrays and the metadata as JSON; it is read with ``np.load(..., allow_pickle=False)``, so
loading it needs neither scikit-learn nor pickle. The legacy formats hold ``{'payload_version':
1, 'forest': <RandomForestClassifier>, 'metadata': {...}}`` and are read through scikit-learn
(imported only then). The card (:mod:`contact_detector.model.card`) repeats the metadata and
adds the hash, so :func:`load_bundle` checks a file **before** parsing it and refuses an
incompatible model without touching it. See ``docs/model.md``.
"""

import dataclasses
import json
import os
from pathlib import Path
import pickle
from typing import Any, Mapping, Optional, Sequence
import warnings
import zipfile

from contact_detector.errors import ConfigError, ModelError
from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.model.bundle import (forest_problem, import_sklearn, ModelBundle, RETRAIN,
                                           sklearn_version)
from contact_detector.model.card import (build_card, card_paths, CARD_VERSION, file_sha256,
                                         render_card_markdown)
from contact_detector.model.compiled_forest import CompiledForest
from contact_detector.model.forest_arrays import boundary_frames, ForestArrays
from contact_detector.model.rule import DecisionRule
import numpy as np

#: Version of the payload dict inside legacy (joblib/skops) model files.
PAYLOAD_VERSION = 1
FORMATS = {'.npz': 'npz', '.joblib': 'joblib', '.skops': 'skops'}
#: Formats whose forest is a pickled/serialised scikit-learn object (loaded through sklearn).
SKLEARN_FORMATS = ('joblib', 'skops')
#: Rows of the training frames on which save_bundle also checks the single-frame path.
SAVE_CHECK_SINGLE_ROWS = 2000
#: Pickle protocol of joblib files, fixed so that the same forest gives the same bytes.
JOBLIB_PROTOCOL = 4
#: zlib level of joblib files: ~4x smaller than raw for deep trees, deterministic.
JOBLIB_COMPRESS = ('zlib', 3)

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
    # extremely randomized trees (train --splitter random)
    'sklearn.ensemble._forest.ExtraTreesClassifier',
    'sklearn.tree._classes.ExtraTreeClassifier',
    'sklearn.tree._tree.Tree',
})


def _major_minor(version: str) -> str:
    """'1.9.1' -> '1.9'."""
    return '.'.join(str(version).split('.')[:2])


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
                             f'{sklearn_version()} predict_proba on {len(x)} frames; the model '
                             'was not saved (is this forest from scikit-learn >= 1.4?)')


def _check_metadata(*, meta: Mapping[str, Any], source: str,
                    expected_config: Optional[FeatureConfig], fmt: str) -> FeatureConfig:
    """Check a card's or payload's metadata against the running code; return its config."""
    if not isinstance(meta, Mapping):
        raise ModelError(f'{source}: the metadata is not a JSON object; {RETRAIN}')
    missing = [key for key in _METADATA_KEYS if key not in meta]
    if missing:
        raise ModelError(f'{source} lacks {missing}; it was not written by save_bundle; '
                         f'{RETRAIN}')
    schema = meta['feature_schema_version']
    if schema != FEATURE_SCHEMA_VERSION:
        raise ModelError(f'{source} was trained on feature schema version {schema}, but this '
                         f'contact_detector computes schema version {FEATURE_SCHEMA_VERSION} '
                         f'(the features changed meaning); {RETRAIN}')
    if not isinstance(meta['versions'], Mapping) or not isinstance(meta['feature_names'], list):
        raise ModelError(f'{source}: versions must be an object and feature_names a list; '
                         f'{RETRAIN}')
    if fmt in SKLEARN_FORMATS:
        # A pickled forest is only read by the scikit-learn that wrote it; npz has no such tie.
        saved = str(meta['versions'].get('scikit-learn', 'unknown'))
        installed = sklearn_version()
        if _major_minor(saved) != _major_minor(installed):
            raise ModelError(f'{source} was saved with scikit-learn {saved} but scikit-learn '
                             f'{installed} is installed; {fmt} forests are only loaded by the '
                             f'same major.minor version. Convert it once with `contact-detector '
                             f'convert-model` under scikit-learn {_major_minor(saved)}.x (the '
                             f'npz format needs no scikit-learn), or {RETRAIN}')
    try:
        config = FeatureConfig.from_dict(meta['feature_config'])
    except (ConfigError, TypeError, ValueError, AttributeError) as err:
        raise ModelError(f'{source} has a feature configuration this contact_detector cannot '
                         f'use ({err}); {RETRAIN}') from err
    names = tuple(meta['feature_names'])
    if names != config.feature_names:
        raise ModelError(f'{source} names features {list(names)} but its feature configuration '
                         f'produces {list(config.feature_names)}; the model does not match the '
                         f'feature code; {RETRAIN}')
    if expected_config is not None and config != expected_config:
        diffs = [f'{f.name} (model {getattr(config, f.name)!r}, expected '
                 f'{getattr(expected_config, f.name)!r})'
                 for f in dataclasses.fields(FeatureConfig)
                 if getattr(config, f.name) != getattr(expected_config, f.name)]
        raise ModelError(f'{source} was trained with a different feature configuration: '
                         f'{"; ".join(diffs)}. Use the model\'s configuration for the features, '
                         f'or {RETRAIN} with the expected one')
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
    import_sklearn()
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
                         f'({err}); {RETRAIN}') from err
    except Exception as err:  # any unpickling failure means a bad model file
        raise ModelError(f'cannot read {fmt} model file {path}: {type(err).__name__}: {err}; '
                         f'the file is corrupt or not a contact_detector model; '
                         f'{RETRAIN}') from err


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
       inputs (a fitted ``RandomForestClassifier`` or ``ExtraTreesClassifier`` with classes
       ``[0, 1]`` for joblib/skops).

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
                         f'the file or its card is corrupt; {RETRAIN}') from err


def _load_bundle(*, path: Path, expected_config: Optional[FeatureConfig], verify_hash: bool,
                 trusted_skops_types: Sequence[str]) -> ModelBundle:
    """:func:`load_bundle` without the final wrapping of unexpected errors."""
    fmt = FORMATS.get(path.suffix)
    if fmt is None:
        raise ModelError(f'model file {path} must end in .npz, .joblib or .skops')
    if not path.is_file():
        raise ModelError(f'model file {path} does not exist; pass an existing model or '
                         f'{RETRAIN}')
    card_json, _ = card_paths(path)
    if not card_json.is_file():
        raise ModelError(f'model card {card_json} is missing; a model file is only loaded '
                         'together with the card save_bundle writes beside it (it holds the '
                         'SHA-256 checked before loading). Copy the card along with the model, '
                         f'or {RETRAIN}')
    try:
        card = json.loads(card_json.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise ModelError(f'model card {card_json} cannot be read: {err}') from err
    if not isinstance(card, dict) or card.get('card_version') != CARD_VERSION \
            or not isinstance(card.get('sha256'), str):
        raise ModelError(f'model card {card_json} is not a version {CARD_VERSION} card with a '
                         f'sha256; {RETRAIN}')
    if card.get('format') != fmt:
        raise ModelError(f'model card {card_json} describes a {card.get("format")!r} file but '
                         f'{path.name} is loaded as {fmt} (by its suffix)')
    if verify_hash:
        actual = file_sha256(path)
        if actual != card['sha256']:
            raise ModelError(f'model file {path} has sha256 {actual}, which does not match its '
                             f'card {card_json} ({card["sha256"]}): the file is corrupt or was '
                             'modified, and it was NOT loaded. Restore the file that goes with '
                             f'the card, or {RETRAIN}')
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
                             f'contact_detector bundle; {RETRAIN}')
        forest, meta = payload['forest'], payload['metadata']
    differing = [key for key in _METADATA_KEYS if meta.get(key) != card.get(key)]
    if differing:
        raise ModelError(f'model card {card_json} disagrees with model file {path.name} in '
                         f'{differing}; the card must be the one save_bundle wrote with this '
                         'file. Re-save the bundle to regenerate the card')
    problem = forest_problem(forest, len(config.feature_names))
    if problem:
        raise ModelError(f'model file {path}: {problem}; {RETRAIN}')
    try:
        return ModelBundle(forest=forest, feature_config=config,
                           feature_names=tuple(meta['feature_names']),
                           feature_schema_version=meta['feature_schema_version'],
                           label_window=meta['label_window'],
                           decision_rule=DecisionRule.from_dict(meta['decision_rule']),
                           versions=meta['versions'], training=meta['training'],
                           metrics=meta['metrics'], created=meta['created'])
    except (ConfigError, TypeError) as err:
        raise ModelError(f'model file {path} has invalid metadata: {err}; {RETRAIN}') from err
