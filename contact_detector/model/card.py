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
The model card: everything about a saved model beside it, as JSON and as Markdown.

A model file ``contact_forest.npz`` has ``contact_forest.card.json`` (the bundle's metadata,
the file's SHA-256, tree sizes, feature importances) and ``contact_forest.card.md`` (the same
for humans) beside it. :func:`~contact_detector.model.storage.load_bundle` checks the card
before it parses the file. See ``docs/model.md``.
"""

import functools
import hashlib
import json
from pathlib import Path
from typing import Any, Mapping

from contact_detector.model.bundle import ModelBundle, plain_json
from contact_detector.model.forest_arrays import ForestArrays

#: Version of the card layout.
CARD_VERSION = 1


def file_sha256(path: Path) -> str:
    """Return the SHA-256 of the file ``path`` as hex."""
    digest = hashlib.sha256()
    with open(path, 'rb') as stream:
        for block in iter(functools.partial(stream.read, 1 << 20), b''):
            digest.update(block)
    return digest.hexdigest()


def card_paths(path: Path) -> tuple:
    """Return ``(card_json, card_md)`` beside the model file ``path``."""
    path = Path(path)
    return (path.with_name(path.stem + '.card.json'), path.with_name(path.stem + '.card.md'))


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
            'sha256': file_sha256(Path(model_path)),
            'size_bytes': Path(model_path).stat().st_size,
            'model_id': bundle.model_id,
            'forest_sha256': bundle.forest_sha256,
            'n_estimators': bundle.n_estimators,
            'feature_importances': bundle.feature_importances(),
            'forest': _forest_summary(bundle.trees)}
    card.update(bundle.metadata())
    return plain_json(card, 'card')


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
