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
The npz model format: round trip, the save-time check, the loader's refusals and fuzzing.

The npz file is the shipped model format: it loads with numpy alone (no scikit-learn, no
pickle). Every corrupted file or card must give a ModelError naming the problem: never another
exception, never a model that differs from the one the card describes.
"""

import hashlib
import io
import json
from pathlib import Path
import subprocess
import sys
from typing import Callable, Dict
import zipfile

from contact_detector.cli import convert_model
from contact_detector.errors import ConfigError, ModelError
from contact_detector.evaluation.metrics import frame_report
from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.model.bundle import ModelBundle, runtime_versions
from contact_detector.model.card import card_paths
from contact_detector.model.forest_arrays import ForestArrays, NPZ_MEMBERS
from contact_detector.model.rule import DecisionRule
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle, save_bundle
import numpy as np
import pytest
from sklearn.ensemble import RandomForestClassifier

REPO = Path(__file__).resolve().parents[3]
CONFIG = FeatureConfig(extra_features=('force_delta',))


def _data(n: int = 1500, seed: int = 0) -> tuple:
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, CONFIG.n_features))
    y = (x[:, 0] + rng.normal(scale=0.5, size=n) > 0.7).astype(int)
    return x, y


@pytest.fixture(scope='module')
def fitted() -> tuple:
    x, y = _data()
    forest = RandomForestClassifier(n_estimators=4, max_features='sqrt', random_state=0)
    return forest.fit(x, y), x


def _bundle(forest, **overrides) -> ModelBundle:
    fields = {'forest': forest, 'feature_config': CONFIG, 'feature_names': CONFIG.feature_names,
              'feature_schema_version': FEATURE_SCHEMA_VERSION,
              'label_window': {'mode': 'onset', 'start_s': 0.0, 'end_s': 0.1},
              'decision_rule': DecisionRule(threshold=0.6, confirm_frames=2),
              'versions': runtime_versions(), 'training': {'frames': 1500},
              'metrics': {'auc': 0.9}, 'created': '2026-03-01T12:00:00+00:00'}
    fields.update(overrides)
    return ModelBundle(**fields)


@pytest.fixture
def saved(tmp_path: Path, fitted: tuple) -> Path:
    forest, x = fitted
    return save_bundle(bundle=_bundle(forest), path=tmp_path / 'm.npz', check_frames=x)


def _bits(values: np.ndarray) -> np.ndarray:
    return np.asarray(values, dtype=np.float64).view(np.uint64)


# ---------------------------------------------------------------------------- round trip

def test_npz_round_trip_is_bit_identical_to_sklearn(saved: Path, fitted: tuple) -> None:
    forest, x = fitted
    loaded = load_bundle(path=saved, expected_config=CONFIG)
    assert isinstance(loaded.forest, ForestArrays) and loaded.sklearn_forest is None
    assert loaded.model_id == _bundle(forest).model_id
    assert loaded.metadata() == _bundle(forest).metadata()
    assert loaded.feature_importances() == pytest.approx(
        dict(zip(CONFIG.feature_names, forest.feature_importances_)), abs=0)
    probe = np.random.default_rng(5).normal(size=(3000, CONFIG.n_features))
    for frames in (x, probe):
        expected = forest.predict_proba(frames)[:, 1]
        compiled = loaded.compile()
        assert np.array_equal(_bits(compiled.predict_proba(frames)), _bits(expected))
        single = np.array([compiled.predict_one(row) for row in frames[:300]])
        assert np.array_equal(_bits(single), _bits(expected[:300]))
    card = json.loads(card_paths(saved)[0].read_text())
    assert card['format'] == 'npz' and card['model_file'] == 'm.npz'
    assert card['forest']['tree_node_counts'] == [e.tree_.node_count for e in forest.estimators_]
    assert card['forest']['tree_max_depths'] == [e.tree_.max_depth for e in forest.estimators_]
    assert card['forest']['tree_leaf_counts'] == [e.tree_.n_leaves for e in forest.estimators_]
    assert card['forest']['params']['n_estimators'] == 4
    assert 'numpy only' in card_paths(saved)[1].read_text()


def test_npz_bytes_are_deterministic_and_resaving_keeps_them(tmp_path: Path,
                                                             fitted: tuple) -> None:
    forest, _ = fitted
    first = save_bundle(bundle=_bundle(forest), path=tmp_path / 'a.npz')
    second = save_bundle(bundle=_bundle(forest), path=tmp_path / 'b.npz')
    assert first.read_bytes() == second.read_bytes()
    # A bundle loaded from npz (no scikit-learn forest) saves as npz to the same bytes ...
    again = save_bundle(bundle=load_bundle(path=first), path=tmp_path / 'c.npz')
    assert again.read_bytes() == first.read_bytes()
    # ... but not as joblib, which would need the scikit-learn object.
    with pytest.raises(ModelError, match='can only be saved as npz'):
        save_bundle(bundle=load_bundle(path=first), path=tmp_path / 'd.joblib')


def test_save_refuses_a_forest_whose_arrays_differ_from_sklearn(tmp_path: Path,
                                                                fitted: tuple) -> None:
    class OffByOneBit(RandomForestClassifier):
        """A forest whose predict_proba is one ulp off from its own trees."""

        def predict_proba(self, x):
            p = super().predict_proba(x)
            return np.nextafter(p, 2.0)

    x, y = _data()
    odd = OffByOneBit(n_estimators=2, random_state=0).fit(x, y)
    path = tmp_path / 'odd.npz'
    with pytest.raises(ModelError, match='differ from scikit-learn'):
        save_bundle(bundle=_bundle(odd), path=path, check_frames=x)
    assert not path.exists() and not card_paths(path)[0].exists()
    with pytest.raises(ModelError, match='check_frames must have shape'):
        save_bundle(bundle=_bundle(fitted[0]), path=path, check_frames=x[:, :3])
    with pytest.raises(ConfigError, match='must end in'):
        save_bundle(bundle=_bundle(fitted[0]), path=tmp_path / 'm.pkl')


# ---------------------------------------------------------------------------- corruption

def _members(path: Path) -> Dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as npz:
        return {name: npz[name].copy() for name in npz.files}


def _write_members(path: Path, members: Dict[str, object], *, allow_pickle: bool = False,
                   update_forest_hash: bool = False) -> None:
    """Write ``members`` as an npz at ``path`` and give the card the new SHA-256."""
    with zipfile.ZipFile(path, 'w', compression=zipfile.ZIP_DEFLATED) as archive:
        for name, array in members.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, np.asanyarray(array), allow_pickle=allow_pickle)
            archive.writestr(name + '.npy', buffer.getvalue())
    _fix_card(path)


def _fix_card(path: Path, **fields) -> None:
    card_json, _ = card_paths(path)
    card = json.loads(card_json.read_text())
    card['sha256'] = hashlib.sha256(path.read_bytes()).hexdigest()
    card.update(fields)
    card_json.write_text(json.dumps(card))


def _edited(edit: Callable[[Dict[str, np.ndarray]], None]) -> Callable[[Path], None]:
    def corrupt(path: Path) -> None:
        members = _members(path)
        edit(members)
        _write_members(path, members)
    return corrupt


def _set(name: str, index, value) -> Callable[[Dict[str, np.ndarray]], None]:
    def edit(members: Dict[str, np.ndarray]) -> None:
        members[name][index] = value
    return edit


def _first_split(members: Dict[str, np.ndarray]) -> int:
    return int(np.flatnonzero(members['children_left'] >= 0)[0])


def _child_before_parent(members):
    node = int(np.flatnonzero(members['children_left'] >= 0)[1])
    members['children_left'][node] = node - 1


def _shared_child(members):
    node = _first_split(members)
    members['children_right'][node] = members['children_left'][node]


def _header(text: bytes) -> Callable[[Dict[str, np.ndarray]], None]:
    def edit(members):
        members['header'] = np.frombuffer(text, dtype=np.uint8)
    return edit


def _header_json(change: Callable[[dict], None]):
    def edit(members):
        header = json.loads(members['header'].tobytes())
        change(header)
        members['header'] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    return edit


#: name -> (corruption of the npz members, part of the expected message)
ARRAY_CORRUPTIONS = {
    'left child out of range': (_set('children_left', 0, 10 ** 6), 'children_left out of range'),
    'right child negative': (lambda m: m['children_right'].__setitem__(_first_split(m), -5),
                             'children_right out of range'),
    'split with one child': (lambda m: m['children_right'].__setitem__(_first_split(m), -1),
                             'exactly one child'),
    'child before parent': (_child_before_parent, 'children_left out of range'),
    'shared child': (_shared_child, 'do not form trees'),
    'feature out of range': (lambda m: m['feature'].__setitem__(_first_split(m), 99),
                             'feature index out of range'),
    'negative feature': (lambda m: m['feature'].__setitem__(_first_split(m), -1),
                         'feature index out of range'),
    'nan threshold': (lambda m: m['threshold'].__setitem__(_first_split(m), np.nan),
                      'threshold is not finite'),
    'inf threshold': (lambda m: m['threshold'].__setitem__(_first_split(m), np.inf),
                      'threshold is not finite'),
    'leaf with a feature': (lambda m: m['feature'].__setitem__(
        int(np.flatnonzero(m['children_left'] < 0)[0]), 0), 'leaves must have feature -2'),
    'probabilities not summing to 1': (_set('value', (0, 1), 0.9), 'class fractions'),
    'negative probability': (lambda m: m['value'].__setitem__(
        (0, slice(None)), [1.5, -0.5]), 'class fractions'),
    'offsets not increasing': (_set('tree_offsets', 1, 0), 'tree_offsets'),
    'offsets past the end': (_set('tree_offsets', -1, 10 ** 6), 'tree_offsets'),
    'wrong value shape': (lambda m: m.__setitem__('value', m['value'][:, :1].copy()),
                          'value has shape'),
    'value of three classes': (lambda m: m.__setitem__('value', np.hstack(
        [m['value'], np.zeros((len(m['value']), 1))])), 'value has shape'),
    'short threshold': (lambda m: m.__setitem__('threshold', m['threshold'][:-1].copy()),
                        'threshold has shape'),
    'importances of another width': (lambda m: m.__setitem__(
        'feature_importances', np.full(3, 1 / 3)), 'feature_importances has shape'),
    'negative importance': (_set('feature_importances', 0, -1.0), 'feature_importances must'),
    'int32 children': (lambda m: m.__setitem__('children_left',
                                               m['children_left'].astype(np.int32)),
                       'expected a 1-D int64 array'),
    'float32 thresholds': (lambda m: m.__setitem__('threshold',
                                                   m['threshold'].astype(np.float32)),
                           'expected a 1-D float64 array'),
    '2-D children': (lambda m: m.__setitem__('children_left', m['children_left'][:, None]),
                     'expected a 1-D int64 array'),
    'missing member': (lambda m: m.pop('feature_importances'), 'missing'),
    'extra member': (lambda m: m.__setitem__('extra', np.zeros(3)), 'unexpected'),
    'header not JSON': (_header(b'\xff\x00not json'), 'header is not UTF-8 JSON'),
    'header of another version': (_header_json(lambda h: h.__setitem__('npz_version', 2)),
                                  'not a version 1 contact_detector header'),
    'header without feature names': (_header_json(
        lambda h: h['metadata'].__setitem__('feature_names', [])), 'names no features'),
    'header metadata differs from the card': (_header_json(
        lambda h: h['metadata'].__setitem__('created', '2020-01-01T00:00:00')),
        "disagrees with model file m.npz in ['created']"),
}


@pytest.mark.parametrize('name', sorted(ARRAY_CORRUPTIONS))
def test_corrupted_arrays_are_refused(saved: Path, name: str) -> None:
    corrupt, message = ARRAY_CORRUPTIONS[name]
    _edited(corrupt)(saved)
    with pytest.raises(ModelError, match=message.replace('[', r'\[').replace(']', r'\]')):
        load_bundle(path=saved)


def test_a_valid_but_different_forest_is_refused_by_the_card_hash(saved: Path) -> None:
    # Consistent trees (a leaf value changed within the rules), and the file's SHA-256 updated
    # in the card: the forest content hash in the card still catches it.
    def edit(members):
        leaf = int(np.flatnonzero(members['children_left'] < 0)[0])
        members['value'][leaf] = members['value'][leaf][::-1]
    _edited(edit)(saved)
    with pytest.raises(ModelError, match='content hash'):
        load_bundle(path=saved)


def test_pickled_object_arrays_are_refused_without_unpickling(saved: Path,
                                                              tmp_path: Path) -> None:
    marker = tmp_path / 'pickle_ran'
    members = _members(saved)
    members['threshold'] = np.array([_Trap(str(marker))] * len(members['threshold']),
                                    dtype=object)
    _write_members(saved, members, allow_pickle=True)
    with pytest.raises(ModelError, match='threshold is a 1-D object array'):
        load_bundle(path=saved)
    assert not marker.exists()


class _Trap:
    """Unpickling this object creates a file (it must never happen)."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __reduce__(self):
        return (Path.touch, (Path(self.path),))


def test_npy_header_that_claims_a_huge_array_is_refused_before_allocating(saved: Path) -> None:
    members = _members(saved)
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, members['threshold'])
    raw = buffer.getvalue()
    n = len(members['threshold'])
    header = raw.replace(f'({n},)'.encode(), f'({n * 10 ** 6},)'.encode().ljust(
        len(f'({n},)'), b' '), 1)
    assert header != raw
    with zipfile.ZipFile(saved, 'w') as archive:
        for name, array in members.items():
            if name == 'threshold':
                archive.writestr('threshold.npy', header)
                continue
            one = io.BytesIO()
            np.lib.format.write_array(one, array)
            archive.writestr(name + '.npy', one.getvalue())
    _fix_card(saved)
    with pytest.raises(ModelError, match='claims shape'):
        load_bundle(path=saved)


def test_truncated_files_are_refused(saved: Path) -> None:
    data = saved.read_bytes()
    for length in sorted({0, 1, 4, 30, 100, len(data) // 3, len(data) // 2, len(data) - 22,
                          len(data) - 1}):
        saved.write_bytes(data[:length])
        with pytest.raises(ModelError, match='sha256'):       # the card's hash catches it
            load_bundle(path=saved)
        with pytest.raises(ModelError):                       # and so does the parser
            load_bundle(path=saved, verify_hash=False)
        _fix_card(saved)
        with pytest.raises(ModelError):
            load_bundle(path=saved)
        saved.write_bytes(data)
        _fix_card(saved)
    assert load_bundle(path=saved).n_estimators == 4


@pytest.mark.slow
def test_flipped_bytes_never_give_a_wrong_model(saved: Path) -> None:
    """Every byte flip is refused, or loads the very forest and metadata the card describes."""
    data = saved.read_bytes()
    reference = load_bundle(path=saved)
    rng = np.random.default_rng(0)
    positions = sorted(set(rng.integers(0, len(data), size=150).tolist())
                       | set(range(0, 64)) | set(range(len(data) - 100, len(data))))
    loaded_ok = 0
    for position in positions:
        corrupted = bytearray(data)
        corrupted[position] ^= 1 << int(rng.integers(0, 8))
        saved.write_bytes(bytes(corrupted))
        _fix_card(saved)                  # so the file itself is parsed, not just hash-checked
        try:
            bundle = load_bundle(path=saved)
        except ModelError:
            continue
        loaded_ok += 1
        assert bundle.forest_sha256 == reference.forest_sha256, position
        assert bundle.metadata() == reference.metadata(), position
    assert loaded_ok < len(positions) // 2   # most flips are refused (CRC, headers, arrays)


CARD_CORRUPTIONS = {
    'not JSON': lambda card_json: card_json.write_text('{"card_version": 1,'),
    'a list': lambda card_json: card_json.write_text('[]'),
    'versions not an object': lambda card_json: _edit_card(card_json, versions=[1, 2]),
    'feature names not a list': lambda card_json: _edit_card(card_json, feature_names='abc'),
    'feature config garbage': lambda card_json: _edit_card(card_json, feature_config=[3]),
    'decision rule garbage': lambda card_json: _edit_card(card_json, decision_rule='x'),
    'schema version': lambda card_json: _edit_card(card_json, feature_schema_version=-1),
    'format joblib': lambda card_json: _edit_card(card_json, format='joblib'),
    'no sha256': lambda card_json: _edit_card(card_json, sha256=None),
}


def _edit_card(card_json: Path, **fields) -> None:
    card = json.loads(card_json.read_text())
    card.update(fields)
    card_json.write_text(json.dumps(card))


@pytest.mark.parametrize('name', sorted(CARD_CORRUPTIONS))
def test_corrupted_cards_are_refused(saved: Path, name: str) -> None:
    CARD_CORRUPTIONS[name](card_paths(saved)[0])
    with pytest.raises(ModelError):
        load_bundle(path=saved)


def test_forest_arrays_validate_at_construction(saved: Path) -> None:
    forest, _ = ForestArrays.read_npz(path=saved)
    good = {name: getattr(forest, name) for name in NPZ_MEMBERS if name != 'header'}
    assert ForestArrays(n_features=forest.n_features, **good).content_sha256 \
        == forest.content_sha256
    with pytest.raises(ModelError, match='n_features'):
        ForestArrays(n_features=0, **good)
    with pytest.raises(ModelError, match='threshold must be a 1-D float64 array, got list'):
        ForestArrays(n_features=forest.n_features, **{**good, 'threshold': [0.0]})
    assert not forest.threshold.flags.writeable


# ---------------------------------------------------------------------------- shipped model

@pytest.mark.slow
def test_shipped_model_is_npz_and_loads_without_sklearn_joblib_rosbags_matplotlib(
        tmp_path: Path) -> None:
    """Node import, model load and one live-path detection with those packages made absent."""
    code = f"""
import sys
for name in ('sklearn', 'joblib', 'skops', 'rosbags', 'matplotlib'):
    sys.modules[name] = None   # any import of them now fails
import numpy as np
import contact_detector.ros.node  # noqa: F401
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim.trial import simulate_trial
sys.path.insert(0, {str(REPO / 'test')!r})
import node_support
path = default_model_path()
assert path.name == 'contact_forest.npz', path
bundle = load_bundle(path=path)
trial = simulate_trial(seed=22, index=3, hits='none', audio_rate=16000)
detector = ContactDetector(bundle=bundle, settings=DetectorSettings(audio_rate=16000,
                                                                    wrench_rate=trial.ft_rate))
releases = []
for e in node_support.trial_events(trial):
    if e.kind == 'audio':
        out = detector.on_audio(trial.audio[e.lo:e.hi], stamp=e.t)
        releases += [float(t) for t in out.releases]
    else:
        detector.on_wrench(t=trial.wrench_t[e.lo:e.hi], force=trial.force[e.lo:e.hi],
                           torque=trial.torque[e.lo:e.hi])
print(len(releases), releases[0] - trial.onset_t if releases else None)
"""
    done = subprocess.run([sys.executable, '-c', code], cwd=REPO, capture_output=True,
                          text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    count, delay = done.stdout.split()
    assert count == '1' and 0.0 <= float(delay) < 0.3, done.stdout


@pytest.mark.slow
def test_run_time_commands_import_no_sklearn_or_joblib() -> None:
    code = ("import sys\nfor n in ('sklearn', 'joblib', 'skops'):\n    sys.modules[n] = None\n"
            'import contact_detector.cli.demo, contact_detector.cli.detect  # noqa: E401\n'
            'import contact_detector.cli.evaluate, contact_detector.ros.node  # noqa: E401\n'
            'from contact_detector.cli.main import main\n'
            'sys.exit(main(["train", "--help"]))\n')
    done = subprocess.run([sys.executable, '-c', code], cwd=REPO, capture_output=True,
                          text=True, timeout=120)
    # Even train's --help works: scikit-learn is imported only when training starts.
    assert done.returncode == 0, done.stderr
    assert 'contact_forest.npz' in done.stdout


@pytest.mark.slow
def test_detect_and_evaluate_run_without_sklearn(tmp_path: Path) -> None:
    bags = tmp_path / 'bags'
    subprocess.run([sys.executable, '-m', 'contact_detector.cli.main', 'simulate', str(bags),
                    '--trials', '2', '--seed', '22', '--quiet'], cwd=REPO, check=True,
                   capture_output=True, timeout=180)
    block = ("import sys\nfor n in ('sklearn', 'joblib', 'skops'):\n    sys.modules[n] = None\n"
             'from contact_detector.cli.main import main\n')
    detect = block + f'sys.exit(main(["detect", {str(bags)!r}, "--out", ' \
                     f'{str(tmp_path / "d.jsonl")!r}]))'
    evaluate = block + f'sys.exit(main(["evaluate", {str(bags)!r}, "--detector", "forest", ' \
                       f'"--report", {str(tmp_path / "report")!r}]))'
    for code in (detect, evaluate):
        done = subprocess.run([sys.executable, '-c', code], cwd=REPO, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, done.stderr
    rows = [json.loads(line) for line in (tmp_path / 'd.jsonl').read_text().splitlines()]
    assert sum(1 for row in rows if row.get('event') == 'release') == 2
    metrics = json.loads((tmp_path / 'report' / 'metrics.json').read_text())
    assert metrics['forest']['frames']['accuracy'] > 0.9


def test_legacy_joblib_needs_sklearn_and_says_how_to_convert(tmp_path: Path,
                                                             fitted: tuple) -> None:
    path = save_bundle(bundle=_bundle(fitted[0]), path=tmp_path / 'old.joblib')
    code = ('import sys\nsys.modules["sklearn"] = None\n'
            'from contact_detector.model.storage import load_bundle\n'
            f'load_bundle(path={str(path)!r})\n')
    done = subprocess.run([sys.executable, '-c', code], cwd=REPO, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 1
    assert 'ModelError' in done.stderr and 'convert-model' in done.stderr


# ---------------------------------------------------------------------------- convert-model

@pytest.mark.parametrize('fmt', ['joblib', 'skops'])
def test_convert_model(tmp_path: Path, fitted: tuple, fmt: str, capsys) -> None:
    if fmt == 'skops':
        pytest.importorskip('skops.io')
    forest, x = fitted
    old = save_bundle(bundle=_bundle(forest), path=tmp_path / f'old.{fmt}')
    new = tmp_path / 'new' / 'model.npz'
    assert convert_model.main([str(old), str(new), '--check-rows', '5000']) == 0
    assert 'bit for bit' in capsys.readouterr().out
    converted = load_bundle(path=new)
    assert converted.model_id == load_bundle(path=old).model_id
    assert np.array_equal(_bits(converted.compile().predict_proba(x)),
                          _bits(forest.predict_proba(x)[:, 1]))
    with pytest.raises(SystemExit):
        convert_model.main([str(old), str(tmp_path / 'x.joblib')])
    assert convert_model.main([str(tmp_path / 'missing.joblib'), str(tmp_path / 'y.npz')]) == 1
    assert 'does not exist' in capsys.readouterr().err


@pytest.mark.slow
def test_convert_model_command_is_registered(tmp_path: Path, fitted: tuple) -> None:
    old = save_bundle(bundle=_bundle(fitted[0]), path=tmp_path / 'old.joblib')
    done = subprocess.run([str(Path(sys.executable).parent / 'contact-detector'),
                           'convert-model', str(old), str(tmp_path / 'new.npz')],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / 'new.card.json').is_file()


def test_default_model_is_the_npz() -> None:
    assert default_model_path().name == 'contact_forest.npz'
    assert not list((REPO / 'models').glob('*.joblib'))


# ---------------------------------------------------------------------------- frame report

@pytest.mark.slow
def test_frame_report_equals_sklearns_classification_report() -> None:
    from sklearn.metrics import classification_report
    rng = np.random.default_rng(0)
    names = ['not contact', 'contact']
    for _ in range(60):
        n = int(rng.integers(20, 3000))
        y_true = (rng.random(n) < rng.random() ** 2).astype(int)
        y_pred = np.where(rng.random(n) < 0.5 + rng.random() / 2, y_true, 1 - y_true)
        text, report = frame_report(y_true=y_true, y_pred=y_pred)
        expected = classification_report(y_true, y_pred, labels=[0, 1], target_names=names,
                                         zero_division=0, output_dict=True)
        assert report == expected
        if report['accuracy'] > 0:
            assert text == classification_report(y_true, y_pred, labels=[0, 1],
                                                 target_names=names, zero_division=0)
