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
A random forest flattened for fast, bit-exact inference without scikit-learn's overhead.

scikit-learn's ``RandomForestClassifier.predict_proba`` costs 0.7-1 ms per call
whatever the batch size (input validation, a thread pool, one array per tree). The live node
classifies one audio frame at a time, so :class:`CompiledForest` evaluates the same trees
directly:

* :meth:`CompiledForest.predict_one` (the live path) runs one generated Python function per
  tree: nested ``if x3 <= 0.25:`` statements, one compare-and-jump per level on local
  variables and constants, ``return <leaf probability>`` at the leaves. Levels below
  ``codegen_depth`` (Python refuses more than 100 levels of indentation) are walked over
  nested tuples instead, about twice as slow per level.
* :meth:`CompiledForest.predict_proba` (batches) advances all rows of all trees one level per
  numpy step; batches of at most 32 rows use the per-row path.

Exactness. Both paths return the same float64 values as ``forest.predict_proba(x)[:, 1]``
bit for bit, because they repeat scikit-learn's arithmetic (version 1.9):

1. ``x`` is cast to float32 (``validate_data(dtype=np.float32)``); each node compares the
   float32 value, widened exactly to float64, with the float64 threshold:
   ``x[f] <= threshold`` goes left (``Tree._apply_dense``).
2. A tree's P(contact) is ``tree_.value[leaf, 0, 1]``: since scikit-learn 1.4 classification
   trees store the weighted class fractions of each node in ``value``, and
   ``DecisionTreeClassifier.predict_proba`` returns them without further arithmetic.
3. The forest sums the per-tree probabilities in estimator order into a float64 zero
   (``_accumulate_prediction`` with ``n_jobs=None``), then divides by the number of trees:
   ``p = (((0.0 + p_0) + p_1) + ... + p_{T-1}) / T``. Python floats and numpy float64 both
   use IEEE-754 binary64 with round-to-nearest, so the same sequence of operations gives
   the same bits.

With ``n_jobs > 1`` scikit-learn adds the trees in whatever order its threads finish, so
scikit-learn itself is then only reproducible to the last bit when the order happens to
match; models are trained and compared with ``n_jobs=None``.
"""

from collections import OrderedDict
import math
import threading
from typing import Any, Callable, List, Sequence, Tuple

from contact_detector.errors import InputError, ModelError
from contact_detector.model.forest_arrays import ForestArrays
import numpy as np

#: Levels of each tree compiled to Python code. Python's tokenizer refuses more than 100 levels
#: of indentation, hence the cap. Compiling costs about 8 us per node (~1.5 s for 8 trees of
#: 20k nodes); deep levels still matter because they are where the cache misses are.
MAX_CODEGEN_DEPTH = 96
DEFAULT_CODEGEN_DEPTH = MAX_CODEGEN_DEPTH

#: Rows per chunk of the batch path (bounds its temporary arrays to a few MB).
_BATCH_CHUNK = 32768
#: Batches up to this size go through the per-row path (numpy overhead dominates below).
_SMALL_BATCH = 32
#: The batch path drops finished (tree, row) slots every this many levels.
_COMPACT_EVERY = 4

#: Compiled forests kept by :meth:`CompiledForest.from_sklearn`, keyed by content hash.
_CACHE_SIZE = 4
_cache: 'OrderedDict[tuple, CompiledForest]' = OrderedDict()
_cache_lock = threading.Lock()

_Node = Tuple[int, float, Any, Any]


def _walk(x: List[float], node: _Node) -> float:
    """
    Walk one (sub)tree stored as nested tuples and return its leaf's P(contact).

    Parameters
    ----------
    x : list of float
        The frame's features, already rounded to float32 and widened to Python floats.
    node : tuple
        ``(feature, threshold, left, right)`` for a split; ``(-1, p_contact, None, None)``
        for a leaf.

    """
    f, t, left, right = node
    while f >= 0:
        f, t, left, right = left if x[f] <= t else right
    return t


class CompiledForest:
    """
    A fitted binary random forest in flat arrays, evaluated without scikit-learn.

    Build it with :meth:`from_sklearn`. Instances are immutable after construction and safe
    to share between threads.

    Attributes
    ----------
    n_features : int
        Length of the feature vector the forest expects.
    n_trees : int
        Number of trees.
    codegen_depth : int
        Tree levels evaluated by generated code in :meth:`predict_one`.

    """

    def __init__(self, *, feature: np.ndarray, threshold: np.ndarray, left: np.ndarray,
                 right: np.ndarray, p_contact: np.ndarray, roots: np.ndarray,
                 n_features: int, codegen_depth: int = DEFAULT_CODEGEN_DEPTH) -> None:
        """
        Build from flat node arrays; prefer :meth:`from_sklearn`.

        Parameters
        ----------
        feature : np.ndarray of int, shape (n_nodes,)
            Feature index tested by each split node; ignored for leaves.
        threshold : np.ndarray of float64, shape (n_nodes,)
            Split threshold; a frame goes left when ``float32(x[feature]) <= threshold``.
        left, right : np.ndarray of int, shape (n_nodes,)
            Global indices of the children; ``-1`` in ``left`` marks a leaf.
        p_contact : np.ndarray of float64, shape (n_nodes,)
            Probability of class 1 at each node (used at leaves).
        roots : np.ndarray of int, shape (n_trees,)
            Index of each tree's root, in estimator order.
        n_features : int
            Feature vector length.
        codegen_depth : int
            Levels per tree compiled to Python code, 0 ... :data:`MAX_CODEGEN_DEPTH`.

        """
        if isinstance(codegen_depth, bool) or not isinstance(codegen_depth, int) \
                or not 0 <= codegen_depth <= MAX_CODEGEN_DEPTH:
            raise ModelError(f'codegen_depth must be an int in [0, {MAX_CODEGEN_DEPTH}], '
                             f'got {codegen_depth!r}')
        self.n_features = int(n_features)
        self.n_trees = int(len(roots))
        self.codegen_depth = codegen_depth
        n_nodes = len(left)
        feature = np.asarray(feature, dtype=np.intp)
        left = np.asarray(left, dtype=np.intp)
        right = np.asarray(right, dtype=np.intp)
        threshold = np.asarray(threshold, dtype=np.float64)
        p_contact = np.asarray(p_contact, dtype=np.float64)
        roots = np.asarray(roots, dtype=np.intp)
        if self.n_trees < 1 or self.n_features < 1 or not (
                feature.shape == threshold.shape == right.shape == p_contact.shape
                == (n_nodes,)):
            raise ModelError('CompiledForest needs at least one tree and one feature and node '
                             'arrays of equal length')
        is_leaf = left < 0
        split = ~is_leaf
        if (np.any((roots < 0) | (roots >= n_nodes))
                or np.any((left[split] <= np.flatnonzero(split)) | (left[split] >= n_nodes))
                or np.any((right[split] <= np.flatnonzero(split)) | (right[split] >= n_nodes))
                or np.any((feature[split] < 0) | (feature[split] >= self.n_features))
                or not np.all(np.isfinite(threshold[split]))
                or not np.all(np.isfinite(p_contact[is_leaf]))):
            raise ModelError('CompiledForest: malformed tree arrays (children must follow their '
                             'parent, features must be in range, thresholds and leaf values '
                             'finite)')
        # Batch arrays: leaves point at themselves so finished rows can stay in the loop.
        own = np.arange(n_nodes, dtype=np.intp)
        self._children = np.empty(2 * n_nodes, dtype=np.intp)
        self._children[0::2] = np.where(is_leaf, own, left)
        self._children[1::2] = np.where(is_leaf, own, right)
        self._feature = np.where(is_leaf, 0, feature)
        self._threshold = np.where(is_leaf, 0.0, threshold)
        self._is_split = split
        self._p_contact = np.where(is_leaf, p_contact, 0.0)
        self._roots = roots
        for array in (self._children, self._feature, self._threshold, self._is_split,
                      self._p_contact, self._roots):
            array.flags.writeable = False
        self._tree_fns = tuple(
            self._build_tree_fn(root=int(root), feature=feature, threshold=threshold,
                                left=left, right=right, p_contact=p_contact, tree_index=k)
            for k, root in enumerate(roots))

    @classmethod
    def from_sklearn(cls, forest: Any, *,
                     codegen_depth: int = DEFAULT_CODEGEN_DEPTH) -> 'CompiledForest':
        """
        Flatten a fitted ``RandomForestClassifier`` with classes ``[0, 1]``.

        Parameters
        ----------
        forest : sklearn.ensemble.RandomForestClassifier
            Fitted, single output, ``classes_ == [0, 1]`` (1 = contact).
        codegen_depth : int
            Levels of each tree compiled to Python code for :meth:`predict_one`
            (0 = walk every level over tuples; no code generated).

        Returns
        -------
        CompiledForest
            Building one costs about 1.5 s for 8 trees of 20k nodes (mostly Python's
            compiler), so the last few are cached by content hash (~15 ms): detectors built
            again and again for the same model (one per bag, one per decision rule) share one
            instance, and a forest that was refitted in place gets a new one.

        Raises
        ------
        ModelError
            If ``forest`` is not such a forest.

        """
        return cls.from_arrays(ForestArrays.from_sklearn(forest), codegen_depth=codegen_depth)

    @classmethod
    def from_arrays(cls, forest: ForestArrays, *,
                    codegen_depth: int = DEFAULT_CODEGEN_DEPTH) -> 'CompiledForest':
        """
        Compile a :class:`ForestArrays` (the npz model format; no scikit-learn involved).

        Shares :meth:`from_sklearn`'s cache: a forest and its arrays have the same content hash
        and give the same (bit-identical) instance.
        """
        if not isinstance(forest, ForestArrays):
            raise ModelError(f'expected ForestArrays, got {type(forest).__name__}')
        key = (forest.content_sha256, forest.n_features, codegen_depth)
        with _cache_lock:
            if key in _cache:
                _cache.move_to_end(key)
                return _cache[key]
        compiled = cls(**forest.flat(), n_features=forest.n_features,
                       codegen_depth=codegen_depth)
        with _cache_lock:
            _cache[key] = compiled
            while len(_cache) > _CACHE_SIZE:
                _cache.popitem(last=False)
        return compiled

    # ------------------------------------------------------------------ build helpers

    def _build_tree_fn(self, *, root: int, feature: np.ndarray, threshold: np.ndarray,
                       left: np.ndarray, right: np.ndarray, p_contact: np.ndarray,
                       tree_index: int) -> Callable[[List[float]], float]:
        """Return ``fn(x) -> P(contact)`` for one tree: generated code on top, tuples below."""
        feat_l = feature.tolist()
        thr_l = threshold.tolist()
        left_l = left.tolist()
        right_l = right.tolist()
        p_l = p_contact.tolist()
        tuples = {}

        def as_tuples(top: int) -> _Node:
            # Children have larger indices than their parent, so a reverse sweep over the
            # subtree's index range builds every child before its parent (no recursion).
            order = []
            stack = [top]
            while stack:
                node = stack.pop()
                order.append(node)
                if left_l[node] >= 0:
                    stack.append(right_l[node])
                    stack.append(left_l[node])
            for node in sorted(order, reverse=True):
                if left_l[node] < 0:
                    tuples[node] = (-1, p_l[node], None, None)
                else:
                    tuples[node] = (feat_l[node], thr_l[node], tuples.pop(left_l[node]),
                                    tuples.pop(right_l[node]))
            return tuples.pop(top)

        if self.codegen_depth == 0:
            root_tuple = as_tuples(root)
            return lambda x: _walk(x, root_tuple)

        names = ', '.join(f'x{k}' for k in range(self.n_features))
        lines = ['def tree(x):', f' {names}, = x']
        subtrees = []
        # Depth-first emission; ('else', indent) entries emit the else line between branches.
        stack: list = [(root, 0)]
        while stack:
            node, depth = stack.pop()
            indent = ' ' * (depth + 1) if node != 'else' else ' ' * depth
            if node == 'else':
                lines.append(indent + 'else:')
            elif left_l[node] < 0:
                lines.append(f'{indent}return {p_l[node]!r}')
            elif depth >= self.codegen_depth:
                subtrees.append(as_tuples(node))
                lines.append(f'{indent}return _walk(x, _S[{len(subtrees) - 1}])')
            else:
                lines.append(f'{indent}if x{feat_l[node]} <= {thr_l[node]!r}:')
                stack.append((right_l[node], depth + 1))
                stack.append(('else', depth + 1))
                stack.append((left_l[node], depth + 1))
        # The source holds only integer indices and float reprs produced here (thresholds and
        # leaf values were checked finite), so compiling it cannot run foreign code.
        namespace = {'__builtins__': {}, '_walk': _walk, '_S': tuple(subtrees)}
        code = compile('\n'.join(lines) + '\n', f'<contact_detector tree {tree_index}>', 'exec')
        exec(code, namespace)
        return namespace['tree']

    # ------------------------------------------------------------------ inference

    def predict_one(self, x: Any) -> float:
        """
        P(contact) of one frame: the live path.

        Parameters
        ----------
        x : array_like, shape (n_features,)
            One feature vector (any real dtype; cast to float32 like scikit-learn).

        Returns
        -------
        float
            Bit-identical to ``forest.predict_proba(x[None, :])[0, 1]``.

        Raises
        ------
        InputError
            Wrong shape, non-numeric dtype, or a value that is NaN/Inf after the float32 cast.

        """
        arr = x if type(x) is np.ndarray else np.asarray(x)
        if arr.shape != (self.n_features,) or arr.dtype.kind not in 'biuf':
            raise InputError(f'predict_one expects a real vector of shape ({self.n_features},), '
                             f'got shape {arr.shape} dtype {arr.dtype}')
        # Cast as sklearn's check_array does: astype for arrays, asarray(dtype) for sequences.
        xs = (arr.astype(np.float32) if arr is x else np.asarray(x, dtype=np.float32)).tolist()
        # A sum of finite float32 values cannot overflow float64: one test covers all values.
        if not math.isfinite(sum(xs)):
            raise InputError(f'predict_one: non-finite feature value (after float32 cast) in '
                             f'{arr.tolist()}')
        return self._predict_row(xs)

    def _predict_row(self, xs: List[float]) -> float:
        """P(contact) of one validated row given as Python floats (float32 values)."""
        total = 0.0
        for tree_fn in self._tree_fns:
            total += tree_fn(xs)
        return total / self.n_trees

    def predict_proba(self, x: Any) -> np.ndarray:
        """
        P(contact) of a batch of frames.

        Parameters
        ----------
        x : array_like, shape (n_frames, n_features)
            Feature matrix (any real dtype; cast to float32 like scikit-learn). ``n_frames``
            may be 0.

        Returns
        -------
        np.ndarray of float64, shape (n_frames,)
            Bit-identical to ``forest.predict_proba(x)[:, 1]``.

        Raises
        ------
        InputError
            Wrong shape, non-numeric dtype, or NaN/Inf after the float32 cast.

        """
        arr = np.asarray(x)
        if arr.ndim != 2 or arr.shape[1] != self.n_features or arr.dtype.kind not in 'biuf':
            raise InputError(f'predict_proba expects a real matrix of shape (n, '
                             f'{self.n_features}), got shape {arr.shape} dtype {arr.dtype}')
        with np.errstate(over='ignore'):
            x32 = np.ascontiguousarray(arr.astype(np.float32, copy=False) if arr is x
                                       else np.asarray(x, dtype=np.float32))
        finite = np.isfinite(x32).all(axis=1)
        if not finite.all():
            bad = np.flatnonzero(~finite)
            raise InputError(f'predict_proba: {bad.size} row(s) with non-finite values (after '
                             f'float32 cast), first at row {int(bad[0])}')
        out = np.empty(x32.shape[0], dtype=np.float64)
        for start in range(0, x32.shape[0], _BATCH_CHUNK):
            chunk = x32[start:start + _BATCH_CHUNK]
            out[start:start + chunk.shape[0]] = self._predict_chunk(chunk)
        return out

    def _predict_chunk(self, x32: np.ndarray) -> np.ndarray:
        """Batch path on finite float32 rows; see :meth:`predict_proba`."""
        n_rows, n_feat = x32.shape
        n_trees = self.n_trees
        if n_rows <= _SMALL_BATCH:
            # numpy's per-call overhead (~60 levels x 10 calls) exceeds the per-row path here.
            return np.array([self._predict_row(row) for row in x32.tolist()], dtype=np.float64)
        flat_x = x32.ravel()
        # One slot per (tree, row), tree-major, so the per-tree sums below run in tree order.
        slot = np.arange(n_trees * n_rows, dtype=np.intp)
        current = np.repeat(self._roots, n_rows)
        base = np.tile(np.arange(n_rows, dtype=np.intp) * n_feat, n_trees)
        final = np.empty(n_trees * n_rows, dtype=np.intp)
        level = 0
        while current.size:
            # float32 widened exactly to float64 against the float64 threshold, as
            # Tree._apply_dense; NaN was rejected, so '>' is exactly 'not <='.
            go_right = flat_x[base + self._feature[current]] > self._threshold[current]
            current = self._children[2 * current + go_right]
            level += 1
            # Leaves loop to themselves, so finished slots are only dropped now and then.
            if level % _COMPACT_EVERY == 0 or current.size <= _SMALL_BATCH:
                split = self._is_split[current]
                done = ~split
                final[slot[done]] = current[done]
                current = current[split]
                base = base[split]
                slot = slot[split]
        leaf_p = self._p_contact[final].reshape(n_trees, n_rows)
        total = np.zeros(n_rows, dtype=np.float64)
        for k in range(n_trees):
            total += leaf_p[k]
        total /= n_trees
        return total


def check_same_as_sklearn(*, forest: Any, compiled: CompiledForest,
                          x: Sequence[Sequence[float]]) -> bool:
    """
    Return whether ``compiled`` reproduces ``forest.predict_proba(x)[:, 1]`` bit for bit.

    Used by tests and the benchmark; cheap enough to run once after loading a model.

    Parameters
    ----------
    forest : sklearn.ensemble.RandomForestClassifier
        The source forest.
    compiled : CompiledForest
        Built from ``forest``.
    x : array_like, shape (n_frames, n_features)
        Frames to compare on.

    Returns
    -------
    bool
        True when the batch path and the single-frame path both equal scikit-learn exactly.

    """
    arr = np.asarray(x)
    expected = forest.predict_proba(arr)[:, 1]
    batch = compiled.predict_proba(arr)
    single = np.array([compiled.predict_one(row) for row in arr], dtype=np.float64)
    return bool(np.array_equal(expected.view(np.uint64), batch.view(np.uint64))
                and np.array_equal(expected.view(np.uint64), single.view(np.uint64)))
