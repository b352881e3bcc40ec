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

"""Model bundle: save/load round trips, the model card, and every refusal of load_bundle."""

import hashlib
import json
from pathlib import Path
import pickle
from typing import Callable

from contact_detector.errors import ConfigError, ModelError
from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.model import (DecisionRule, default_model_path, load_bundle, ModelBundle,
                                    runtime_versions, save_bundle)
from contact_detector.model.card import card_paths
from contact_detector.model.shipped import find_model
from contact_detector.model.storage import JOBLIB_PROTOCOL
import joblib
import numpy as np
import pytest
import sklearn
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier
from sklearn.preprocessing import StandardScaler

CONFIG = FeatureConfig(extra_features=('force_delta',))


def _forest(n_features: int, *, seed: int = 0, n_classes: int = 2) -> RandomForestClassifier:
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(1500, n_features))
    y = (x[:, 0] + rng.normal(scale=0.5, size=1500) > 0.7).astype(int)
    if n_classes == 3:
        y = y + (x[:, 1] > 1.0)
    return RandomForestClassifier(n_estimators=4, max_features='sqrt',
                                  random_state=seed).fit(x, y)


@pytest.fixture(scope='module')
def forest() -> RandomForestClassifier:
    return _forest(CONFIG.n_features)


def _bundle(forest: RandomForestClassifier, **overrides: object) -> ModelBundle:
    fields = {
        'forest': forest, 'feature_config': CONFIG, 'feature_names': CONFIG.feature_names,
        'feature_schema_version': FEATURE_SCHEMA_VERSION,
        'label_window': {'mode': 'onset', 'start_s': 0.0, 'end_s': 0.1},
        'decision_rule': DecisionRule(threshold=0.6, confirm_frames=2, refractory_s=0.5),
        'versions': runtime_versions(),
        'training': {'n_frames': 1500, 'trials': ('a', 'b'), 'n_estimators_auc':
                     {str(n): 0.9 + n / 100 for n in range(1, 5)}},
        'metrics': {'roc_auc': np.float64(0.97), 'undefined': float('nan')},
        'created': '2026-03-01T12:00:00+00:00',
    }
    fields.update(overrides)
    return ModelBundle(**fields)


def _rewrite(path: Path, edit: Callable[[dict], None]) -> None:
    """Change a joblib model's payload and write a matching card, as a consistent pair."""
    payload = joblib.load(path)
    edit(payload)
    joblib.dump(payload, path, protocol=JOBLIB_PROTOCOL)
    card_json, _ = card_paths(path)
    card = json.loads(card_json.read_text())
    card.update(payload['metadata'])
    card['sha256'] = hashlib.sha256(path.read_bytes()).hexdigest()
    card_json.write_text(json.dumps(card))


@pytest.fixture
def saved(tmp_path: Path, forest: RandomForestClassifier) -> Path:
    return save_bundle(bundle=_bundle(forest), path=tmp_path / 'model.joblib')


# ---------------------------------------------------------------------------- round trips

@pytest.mark.parametrize('fmt', ['joblib', 'skops'])
@pytest.mark.parametrize('trees', ['random forest', 'extremely randomized'])
def test_round_trip(tmp_path: Path, forest: RandomForestClassifier, fmt: str,
                    trees: str) -> None:
    if fmt == 'skops':
        pytest.importorskip('skops.io')
    if trees != 'random forest':   # train --splitter random; skops must trust its types too
        x = np.random.default_rng(2).normal(size=(1500, CONFIG.n_features))
        forest = ExtraTreesClassifier(n_estimators=4, max_features='sqrt', random_state=0).fit(
            x, (x[:, 0] > 0.7).astype(int))
    bundle = _bundle(forest)
    path = save_bundle(bundle=bundle, path=tmp_path / 'sub' / f'm.{fmt}', fmt=fmt)
    loaded = load_bundle(path=path, expected_config=CONFIG)
    for name in ('feature_config', 'feature_names', 'feature_schema_version', 'label_window',
                 'decision_rule', 'versions', 'training', 'metrics', 'created'):
        assert getattr(loaded, name) == getattr(bundle, name), name
    assert loaded.metrics == {'roc_auc': 0.97, 'undefined': None}
    assert loaded.training['trials'] == ['a', 'b']
    assert loaded.model_id == bundle.model_id
    assert loaded.model_id.startswith('rf4-paper7+force_delta-')
    x = np.random.default_rng(1).normal(size=(300, CONFIG.n_features))
    np.testing.assert_array_equal(loaded.forest.predict_proba(x), forest.predict_proba(x))
    np.testing.assert_array_equal(loaded.compile(codegen_depth=0).predict_proba(x),
                                  forest.predict_proba(x)[:, 1])


def test_joblib_bytes_are_deterministic(tmp_path: Path, forest: RandomForestClassifier) -> None:
    first = save_bundle(bundle=_bundle(forest), path=tmp_path / 'a.joblib')
    second = save_bundle(bundle=_bundle(forest), path=tmp_path / 'b.joblib')
    assert first.read_bytes() == second.read_bytes()


def test_model_card(saved: Path, forest: RandomForestClassifier) -> None:
    card_json, card_md = card_paths(saved)
    assert card_json.name == 'model.card.json' and card_md.name == 'model.card.md'
    card = json.loads(card_json.read_text())
    assert card['sha256'] == hashlib.sha256(saved.read_bytes()).hexdigest()
    assert card['model_file'] == 'model.joblib' and card['format'] == 'joblib'
    assert card['size_bytes'] == saved.stat().st_size
    assert card['n_estimators'] == 4
    assert list(card['feature_importances']) == list(CONFIG.feature_names)
    assert sum(card['feature_importances'].values()) == pytest.approx(1.0)
    assert card['feature_importances']['audio_power'] == pytest.approx(
        forest.feature_importances_[0])
    assert card['feature_config'] == CONFIG.to_dict()
    assert card['decision_rule'] == {'threshold': 0.6, 'confirm_frames': 2, 'refractory_s': 0.5,
                                     'average_frames': 1, 'sustain_frames': 0,
                                     'sustain_threshold': 0.5, 'evidence_threshold': 0.0,
                                     'evidence_drift': 0.5}
    assert card['versions']['scikit-learn'] == sklearn.__version__
    assert card['created'] == '2026-03-01T12:00:00+00:00'
    assert len(card['forest']['tree_node_counts']) == 4
    assert 'forest' not in json.dumps(card['feature_config'])  # no pickled objects leak in
    text = card_md.read_text()
    assert card['model_id'] in text and card['sha256'] in text
    for name in CONFIG.feature_names:
        assert f'| {name} |' in text


# ---------------------------------------------------------------------------- refusals

def test_tampered_file_is_refused_before_unpickling(saved: Path, tmp_path: Path) -> None:
    marker = tmp_path / 'pwned'

    class Exploit:

        def __reduce__(self) -> tuple:
            return (open, (str(marker), 'w'))

    evil = pickle.dumps(Exploit())
    # The payload is live: loading it by hand does create the marker.
    probe = tmp_path / 'probe.joblib'
    probe.write_bytes(evil)
    joblib.load(probe).close()
    assert marker.exists()
    marker.unlink()
    saved.write_bytes(evil)  # the card still holds the genuine file's hash
    with pytest.raises(ModelError, match='sha256 .* does not match its card') as info:
        load_bundle(path=saved)
    assert 'NOT loaded' in str(info.value)
    assert not marker.exists()


def test_corrupted_byte_is_refused(saved: Path) -> None:
    data = bytearray(saved.read_bytes())
    data[len(data) // 2] ^= 0x01
    saved.write_bytes(bytes(data))
    with pytest.raises(ModelError, match='does not match its card'):
        load_bundle(path=saved)


def test_unreadable_file_with_matching_card_is_a_model_error(saved: Path) -> None:
    _rewrite(saved, lambda payload: None)
    saved.write_bytes(b'not a pickle at all')
    card_json, _ = card_paths(saved)
    card = json.loads(card_json.read_text())
    card['sha256'] = hashlib.sha256(saved.read_bytes()).hexdigest()
    card_json.write_text(json.dumps(card))
    with pytest.raises(ModelError, match='cannot read joblib model file') as info:
        load_bundle(path=saved)
    assert info.value.__cause__ is not None


def test_missing_card_is_refused(saved: Path) -> None:
    card_paths(saved)[0].unlink()
    with pytest.raises(ModelError, match='model card .* is missing'):
        load_bundle(path=saved)


def test_missing_file_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match='does not exist.*contact-detector train'):
        load_bundle(path=tmp_path / 'nothing.joblib')
    with pytest.raises(ModelError, match=r'\.joblib or \.skops'):
        load_bundle(path=tmp_path / 'model.pkl')


def test_wrong_feature_names_are_refused(saved: Path) -> None:
    def edit(payload: dict) -> None:
        payload['metadata']['feature_names'][0] = 'audio_energy'
    _rewrite(saved, edit)
    with pytest.raises(ModelError, match='names features .*audio_energy.*contact-detector '
                                         'train'):
        load_bundle(path=saved)


def test_wrong_schema_version_is_refused(saved: Path) -> None:
    def edit(payload: dict) -> None:
        payload['metadata']['feature_schema_version'] = FEATURE_SCHEMA_VERSION + 1
    _rewrite(saved, edit)
    with pytest.raises(ModelError, match=f'schema version {FEATURE_SCHEMA_VERSION + 1}.*'
                                         f'schema version {FEATURE_SCHEMA_VERSION}'):
        load_bundle(path=saved)


def test_config_mismatch_names_the_fields(saved: Path) -> None:
    expected = FeatureConfig(extra_features=('force_delta',), ft_window=64, ft_detrend='mean')
    with pytest.raises(ModelError) as info:
        load_bundle(path=saved, expected_config=expected)
    message = str(info.value)
    assert 'ft_window (model 32, expected 64)' in message
    assert "ft_detrend (model 'none', expected 'mean')" in message
    assert 'audio_hop_s' not in message and 'extra_features' not in message


def test_sklearn_version_mismatch_is_refused(saved: Path) -> None:
    def edit(payload: dict) -> None:
        payload['metadata']['versions']['scikit-learn'] = '0.20.3'
    _rewrite(saved, edit)
    with pytest.raises(ModelError) as info:
        load_bundle(path=saved)
    assert 'scikit-learn 0.20.3' in str(info.value)
    assert f'scikit-learn {sklearn.__version__} is installed' in str(info.value)


def test_forest_that_does_not_fit_is_refused(saved: Path) -> None:
    def wrong_width(payload: dict) -> None:
        payload['forest'] = _forest(CONFIG.n_features + 1)
    _rewrite(saved, wrong_width)
    with pytest.raises(ModelError, match='expects 9 features but the bundle names 8'):
        load_bundle(path=saved)

    def three_classes(payload: dict) -> None:
        payload['forest'] = _forest(CONFIG.n_features, n_classes=3)
    _rewrite(saved, three_classes)
    with pytest.raises(ModelError, match=r'classes \[0, 1\]'):
        load_bundle(path=saved)

    def not_a_forest(payload: dict) -> None:
        payload['forest'] = StandardScaler()
    _rewrite(saved, not_a_forest)
    with pytest.raises(ModelError, match='not a RandomForestClassifier'):
        load_bundle(path=saved)


def test_card_that_disagrees_with_the_file_is_refused(saved: Path) -> None:
    card_json, _ = card_paths(saved)
    card = json.loads(card_json.read_text())
    card['decision_rule']['threshold'] = 0.9  # hand edit of the card only
    card_json.write_text(json.dumps(card))
    with pytest.raises(ModelError, match=r"disagrees with model file .*\['decision_rule'\]"):
        load_bundle(path=saved)


def test_skops_refuses_types_outside_the_allow_list(tmp_path: Path,
                                                    forest: RandomForestClassifier) -> None:
    skops_io = pytest.importorskip('skops.io')
    path = save_bundle(bundle=_bundle(forest), path=tmp_path / 'm.skops', fmt='skops')
    payload = skops_io.load(path, trusted=skops_io.get_untrusted_types(file=path))
    payload['extra'] = StandardScaler()  # trusted by skops itself, not by us
    skops_io.dump(payload, path)
    card_json, _ = card_paths(path)
    card = json.loads(card_json.read_text())
    card['sha256'] = hashlib.sha256(path.read_bytes()).hexdigest()
    card_json.write_text(json.dumps(card))
    with pytest.raises(ModelError, match='outside the allow-list.*StandardScaler'):
        load_bundle(path=path)
    loaded = load_bundle(path=path,
                         trusted_skops_types=['sklearn.preprocessing._data.StandardScaler'])
    assert loaded.model_id == _bundle(forest).model_id


def test_card_of_other_format_is_refused(tmp_path: Path, forest: RandomForestClassifier) -> None:
    pytest.importorskip('skops.io')
    path = save_bundle(bundle=_bundle(forest), path=tmp_path / 'm.skops', fmt='skops')
    renamed = path.rename(tmp_path / 'm.joblib')
    with pytest.raises(ModelError, match="describes a 'skops' file"):
        load_bundle(path=renamed)


# ---------------------------------------------------------------------------- construction

def test_save_argument_errors(tmp_path: Path, forest: RandomForestClassifier) -> None:
    bundle = _bundle(forest)
    with pytest.raises(ConfigError, match='unknown model format'):
        save_bundle(bundle=bundle, path=tmp_path / 'm.pkl', fmt='pickle')
    with pytest.raises(ConfigError, match='must end in .skops'):
        save_bundle(bundle=bundle, path=tmp_path / 'm.joblib', fmt='skops')
    save_bundle(bundle=bundle, path=tmp_path / 'm.joblib')
    with pytest.raises(ConfigError, match='owns the card'):  # checked before skops is needed
        save_bundle(bundle=bundle, path=tmp_path / 'm.skops', fmt='skops')


def test_bundle_validation(forest: RandomForestClassifier) -> None:
    with pytest.raises(ModelError, match='feature_names'):
        _bundle(forest, feature_names=CONFIG.feature_names[::-1])
    with pytest.raises(ModelError, match='expects 8 features but the bundle names 7'):
        _bundle(forest, feature_config=FeatureConfig(),
                feature_names=FeatureConfig().feature_names)
    with pytest.raises(ModelError, match='ISO 8601'):
        _bundle(forest, created='yesterday')
    with pytest.raises(ModelError, match='metrics.bad'):
        _bundle(forest, metrics={'bad': object()})
    with pytest.raises(ModelError, match='not fitted'):
        _bundle(RandomForestClassifier())


def test_decision_rule() -> None:
    rule = DecisionRule(threshold=1, confirm_frames=np.int64(3))
    assert rule.threshold == 1.0 and isinstance(rule.threshold, float)
    assert rule.confirm_frames == 3 and type(rule.confirm_frames) is int
    assert DecisionRule.from_dict(rule.to_dict()) == rule
    assert DecisionRule.from_dict({}) == DecisionRule()
    for bad in ({'threshold': 1.5}, {'threshold': float('nan')}, {'threshold': True},
                {'confirm_frames': 0}, {'confirm_frames': 1.5}, {'refractory_s': -0.1},
                {'refractory_s': float('inf')}, {'average_frames': 0}, {'sustain_frames': -1},
                {'sustain_threshold': 1.2}):
        with pytest.raises(ConfigError, match=next(iter(bad))):
            DecisionRule(**bad)
    with pytest.raises(ConfigError, match='unknown DecisionRule keys'):
        DecisionRule.from_dict({'threshold': 0.5, 'hysteresis': 0.1})
    # Bundles written before the averaging and slow-path fields load with the plain rule.
    old = DecisionRule.from_dict({'threshold': 0.7, 'confirm_frames': 2, 'refractory_s': 1.0})
    assert (old.average_frames, old.sustain_frames) == (1, 0)


def test_find_model(tmp_path: Path) -> None:
    first, second = tmp_path / 'a', tmp_path / 'b'
    second.mkdir()
    (second / 'contact_forest.npz').write_bytes(b'x')
    assert find_model(dirs=[first, second]) == second / 'contact_forest.npz'
    first.mkdir()
    (first / 'contact_forest.npz').write_bytes(b'x')
    assert find_model(dirs=[first, second]) == first / 'contact_forest.npz'
    with pytest.raises(ModelError, match='searched .*contact-detector train'):
        find_model(dirs=[tmp_path / 'none'])


def test_default_model_path_finds_a_file_or_says_what_to_do() -> None:
    try:
        path = default_model_path()
    except ModelError as err:
        assert 'contact_forest.npz' in str(err) and 'contact-detector train' in str(err)
    else:
        assert path.is_file() and path.name == 'contact_forest.npz'
