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

"""CompiledForest reproduces RandomForestClassifier.predict_proba bit for bit."""

from contact_detector.errors import InputError, ModelError
from contact_detector.model.compiled_forest import check_same_as_sklearn, CompiledForest
from contact_detector.training.protocol import make_forest
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest
from sklearn.ensemble import RandomForestClassifier, RandomForestRegressor

N_FEATURES = 7


def _data(*, n: int, seed: int) -> tuple:
    """Features with continuous, quantised and duplicated columns; noisy labels."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, N_FEATURES))
    x[:, 1] = np.round(x[:, 1] * 4) / 4          # ties: thresholds halfway between levels
    x[:, 2] = rng.integers(0, 3, size=n)          # few distinct values
    x[:, 3] = x[:, 3] * 1e6                       # large magnitudes
    x[:, 4] = x[:, 4] * 1e-6                      # tiny magnitudes
    x[n // 2:, 5] = x[: n - n // 2, 5]            # duplicated values across rows
    y = (x[:, 0] + 0.3 * x[:, 1] + rng.normal(scale=0.8, size=n) > 0.8).astype(int)
    # Identical rows with conflicting labels leave fractional, unsplittable leaves.
    if n >= 800:
        x[-200:] = x[-400:-200]
    return x, y


def _bits(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)


@pytest.fixture(scope='module')
def forests() -> dict:
    x, y = _data(n=6000, seed=1)
    out = {}
    for n_trees in (1, 10):
        out[n_trees] = RandomForestClassifier(n_estimators=n_trees, max_features='sqrt',
                                              random_state=n_trees).fit(x, y)
    out['weighted'] = RandomForestClassifier(n_estimators=4, max_features='sqrt',
                                             class_weight='balanced', max_samples=0.5,
                                             random_state=3).fit(x, y)
    # train --splitter random: random thresholds, not halfway between two training values
    out['extra'] = make_forest(n_estimators=5, seed=4, jobs=1, splitter='random').fit(x, y)
    return out


@pytest.fixture(scope='module')
def compiled(forests: dict) -> dict:
    return {key: CompiledForest.from_sklearn(forest) for key, forest in forests.items()}


def _edge_rows(forest: RandomForestClassifier, *, seed: int) -> np.ndarray:
    """Rows that put one feature exactly at, or one float32 step around, split thresholds."""
    rng = np.random.default_rng(seed)
    rows = []
    per_tree = max(150, 1500 // len(forest.estimators_))
    for estimator in forest.estimators_:
        tree = estimator.tree_
        split = np.flatnonzero(tree.children_left >= 0)
        for node in rng.choice(split, size=min(split.size, per_tree), replace=False):
            feature, threshold = tree.feature[node], tree.threshold[node]
            t32 = np.float32(threshold)
            candidates = (threshold,                                   # float64 exactly at it
                          float(t32),                                  # rounded to float32
                          float(np.nextafter(t32, np.float32(np.inf))),
                          float(np.nextafter(t32, np.float32(-np.inf))),
                          np.nextafter(threshold, np.inf),              # rounds to float32 too
                          np.nextafter(threshold, -np.inf))
            for value in candidates:
                row = rng.normal(size=N_FEATURES)
                row[feature] = value
                rows.append(row)
    return np.array(rows)


@pytest.mark.parametrize('key', [1, 10, 'weighted', 'extra'])
def test_batch_and_single_equal_sklearn_on_thousands_of_frames(forests: dict, compiled: dict,
                                                               key: object) -> None:
    x, _ = _data(n=3000, seed=7)
    assert check_same_as_sklearn(forest=forests[key], compiled=compiled[key], x=x)
    expected = forests[key].predict_proba(x)[:, 1]
    assert np.unique(expected).size > 5  # non-trivial probabilities, not just 0 and 1
    np.testing.assert_array_equal(_bits(compiled[key].predict_proba(x)), _bits(expected))


@pytest.mark.parametrize('key', [1, 10, 'extra'])
def test_values_at_thresholds_and_float32_rounding_edges(forests: dict, compiled: dict,
                                                         key: object) -> None:
    rows = _edge_rows(forests[key], seed=key if isinstance(key, int) else 5)
    assert rows.shape[0] > 1000
    expected = forests[key].predict_proba(rows)[:, 1]
    np.testing.assert_array_equal(_bits(compiled[key].predict_proba(rows)), _bits(expected))
    single = np.array([compiled[key].predict_one(row) for row in rows])
    np.testing.assert_array_equal(_bits(single), _bits(expected))
    # These rows discriminate: walking without the float32 cast reaches other leaves.
    tree = forests[key].estimators_[0].tree_
    assert np.any(_leaves_without_cast(tree, rows) != tree.apply(rows.astype(np.float32)))


def _leaves_without_cast(tree: object, rows: np.ndarray) -> np.ndarray:
    """Leaf of each row when comparing float64 features (the mistake the cast avoids)."""
    node = np.zeros(rows.shape[0], dtype=np.intp)
    for _ in range(tree.max_depth):
        split = tree.children_left[node] >= 0
        go_left = rows[np.arange(rows.shape[0]), tree.feature[node]] <= tree.threshold[node]
        child = np.where(go_left, tree.children_left[node], tree.children_right[node])
        node = np.where(split, child, node)
    return node


def test_codegen_depths_give_identical_results(forests: dict) -> None:
    x, _ = _data(n=1500, seed=11)
    x = np.vstack([x, _edge_rows(forests[10], seed=3)[:1500]])
    expected = _bits(forests[10].predict_proba(x)[:, 1])
    # 0: tuples only; 3: generated code on top, tuples below; default: all generated.
    for depth in (0, 3):
        other = CompiledForest.from_sklearn(forests[10], codegen_depth=depth)
        single = np.array([other.predict_one(row) for row in x])
        np.testing.assert_array_equal(_bits(single), expected)
        np.testing.assert_array_equal(_bits(other.predict_proba(x)), expected)


@pytest.mark.parametrize('n_rows', [0, 1, 31, 32, 33, 500, 33000])
def test_batch_sizes_across_small_batch_and_chunk_limits(forests: dict, compiled: dict,
                                                         n_rows: int) -> None:
    x, _ = _data(n=max(n_rows, 10), seed=n_rows)
    x = x[:n_rows]
    out = compiled[1].predict_proba(x)
    assert out.shape == (n_rows,) and out.dtype == np.float64
    if n_rows:
        np.testing.assert_array_equal(_bits(out), _bits(forests[1].predict_proba(x)[:, 1]))


def test_single_frame_equals_batch_row(compiled: dict) -> None:
    x, _ = _data(n=800, seed=5)
    batch = compiled[10].predict_proba(x)
    single = np.array([compiled[10].predict_one(row) for row in x])
    np.testing.assert_array_equal(_bits(single), _bits(batch))
    assert isinstance(compiled[10].predict_one(x[0]), float)


def test_input_dtypes_are_cast_like_sklearn(forests: dict, compiled: dict) -> None:
    x, _ = _data(n=400, seed=9)
    for variant in (x.astype(np.float32), np.round(x * 10).astype(np.int64),
                    (x > 0), x.tolist()):
        expected = forests[10].predict_proba(np.asarray(variant))[:, 1]
        np.testing.assert_array_equal(_bits(compiled[10].predict_proba(variant)),
                                      _bits(expected))
        row = variant[3]
        assert compiled[10].predict_one(row) == expected[3]
    # Huge but float32-finite values are legal and follow the same path as in sklearn.
    big = np.full((1, N_FEATURES), 3.0e38)
    assert compiled[10].predict_one(big[0]) == forests[10].predict_proba(big)[0, 1]


@settings(max_examples=150, deadline=None)
@given(st.lists(st.floats(min_value=-3.0e38, max_value=3.0e38, allow_nan=False,
                          allow_subnormal=True, width=64),
                min_size=N_FEATURES, max_size=N_FEATURES))
def test_property_random_frames(row: list) -> None:
    forest, fast = _PROPERTY_FOREST
    expected = forest.predict_proba(np.array([row]))[0, 1]
    assert fast.predict_one(row) == expected
    assert _bits(fast.predict_proba([row]))[0] == _bits(np.array([expected]))[0]


def _property_forest() -> tuple:
    x, y = _data(n=2000, seed=21)
    forest = RandomForestClassifier(n_estimators=5, random_state=0).fit(x, y)
    return forest, CompiledForest.from_sklearn(forest, codegen_depth=4)


_PROPERTY_FOREST = _property_forest()


@pytest.mark.parametrize('bad', [
    np.zeros(N_FEATURES + 1),
    np.zeros(N_FEATURES - 1),
    np.zeros((1, N_FEATURES)),
    np.array([0.0] * (N_FEATURES - 1) + [np.nan]),
    np.array([0.0] * (N_FEATURES - 1) + [np.inf]),
    np.array([0.0] * (N_FEATURES - 1) + [1e39]),          # overflows float32
    np.array(['1.0'] * N_FEATURES),
    np.zeros(N_FEATURES, dtype=complex),
])
def test_predict_one_rejects_bad_input(compiled: dict, bad: np.ndarray) -> None:
    with np.errstate(over='ignore'), pytest.raises(InputError):
        compiled[1].predict_one(bad)


@pytest.mark.parametrize('bad', [
    np.zeros(N_FEATURES),
    np.zeros((3, N_FEATURES + 1)),
    np.zeros((2, 3, N_FEATURES)),
    np.vstack([np.zeros(N_FEATURES), np.full(N_FEATURES, np.nan)]),
    np.vstack([np.zeros((40, N_FEATURES)), np.full((1, N_FEATURES), -np.inf)]),
    np.full((2, N_FEATURES), 1e39),
    np.full((2, N_FEATURES), 'a'),
])
def test_predict_proba_rejects_bad_input(compiled: dict, bad: np.ndarray) -> None:
    with pytest.raises(InputError):
        compiled[1].predict_proba(bad)


def test_from_sklearn_rejects_other_models() -> None:
    x, y = _data(n=300, seed=2)
    with pytest.raises(ModelError, match='fitted'):
        CompiledForest.from_sklearn(RandomForestClassifier())
    with pytest.raises(ModelError, match='fitted'):
        CompiledForest.from_sklearn(RandomForestRegressor(n_estimators=2).fit(x, y))
    three = RandomForestClassifier(n_estimators=2).fit(x, y + (x[:, 0] > 1))
    with pytest.raises(ModelError, match=r'classes \[0, 1\]'):
        CompiledForest.from_sklearn(three)
    shifted = RandomForestClassifier(n_estimators=2).fit(x, y + 1)
    with pytest.raises(ModelError, match=r'classes \[0, 1\]'):
        CompiledForest.from_sklearn(shifted)
    with pytest.raises(ModelError, match='codegen_depth'):
        CompiledForest.from_sklearn(RandomForestClassifier(n_estimators=1).fit(x, y),
                                    codegen_depth=200)


def test_from_sklearn_reuses_compiled_forests_by_content() -> None:
    x, y = _data(n=500, seed=4)
    forest = RandomForestClassifier(n_estimators=3, random_state=0).fit(x, y)
    first = CompiledForest.from_sklearn(forest)
    assert CompiledForest.from_sklearn(forest) is first
    assert CompiledForest.from_sklearn(forest, codegen_depth=2) is not first
    # Refitting the same object in place changes the content, so a new one is built.
    forest.fit(x, 1 - y)
    second = CompiledForest.from_sklearn(forest)
    assert second is not first
    assert check_same_as_sklearn(forest=forest, compiled=second, x=x[:200])
