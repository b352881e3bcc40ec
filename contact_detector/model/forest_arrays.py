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
A fitted random forest as plain numpy arrays: the ``.npz`` model format, numpy only.

:class:`ForestArrays` holds the trees of a binary ``RandomForestClassifier`` exactly as
scikit-learn stores them (``tree_.children_left/right``, ``feature``, ``threshold``,
``value``), concatenated tree after tree, plus the feature importances. It validates every
array at construction, so a :class:`ForestArrays` always describes well-formed trees, and it
reads and writes the ``.npz`` model file with ``np.load(..., allow_pickle=False)``: loading a
model runs no pickle and needs no scikit-learn.

File layout (a zip of ``.npy`` members, written with fixed timestamps so that the same forest
gives the same bytes)::

    header               uint8 (n,)     UTF-8 JSON: {'npz_version': 1, 'metadata': {...},
                                        'forest_params': {...}}
    tree_offsets         int64 (T + 1,)  first node of each tree; [0, n_0, n_0 + n_1, ..., N]
    children_left        int64 (N,)      tree-local index of the left child, -1 at leaves
    children_right       int64 (N,)      tree-local index of the right child, -1 at leaves
    feature              int64 (N,)      feature tested by a split, -2 at leaves
    threshold            float64 (N,)    go left when float32(x[feature]) <= threshold;
                                         -2.0 at leaves
    value                float64 (N, 2)  class fractions [P(no contact), P(contact)] per node
    feature_importances  float64 (F,)    mean decrease in impurity per feature (sums to 1)

See ``docs/model.md`` for what loading checks.
"""

from dataclasses import dataclass, field
import functools
import hashlib
import io
import json
from pathlib import Path
from typing import Any, Dict, Mapping, Optional
import zipfile

from contact_detector.errors import ModelError
import numpy as np

#: Version of the npz layout above.
NPZ_VERSION = 1
#: scikit-learn's markers: ``TREE_LEAF`` for children, ``TREE_UNDEFINED`` for leaf features.
TREE_LEAF = -1
TREE_UNDEFINED = -2
#: Tolerance of a node's class fractions summing to 1 (scikit-learn >= 1.4 stores fractions).
PROBABILITY_SUM_TOLERANCE = 1e-9
#: Upper bound on the uncompressed size of an npz model file (bytes): refuses a header that
#: claims a huge array before anything is allocated.
MAX_NPZ_BYTES = 1 << 30
#: Upper bound on the JSON header (bytes).
MAX_HEADER_BYTES = 1 << 24

#: Member name -> (dtype, number of dimensions). Nothing else may be in the file.
NPZ_MEMBERS: Dict[str, tuple] = {
    'header': (np.dtype(np.uint8), 1),
    'tree_offsets': (np.dtype('<i8'), 1),
    'children_left': (np.dtype('<i8'), 1),
    'children_right': (np.dtype('<i8'), 1),
    'feature': (np.dtype('<i8'), 1),
    'threshold': (np.dtype('<f8'), 1),
    'value': (np.dtype('<f8'), 2),
    'feature_importances': (np.dtype('<f8'), 1),
}
_TREE_ARRAYS = ('children_left', 'children_right', 'feature', 'threshold', 'value')
#: Fixed zip member time, so the bytes depend on the content only.
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


def update_tree_digest(digest: Any, *, children_left: np.ndarray, children_right: np.ndarray,
                       feature: np.ndarray, threshold: np.ndarray, value: np.ndarray) -> None:
    """
    Feed one tree's arrays into ``digest`` (a hashlib object), in a fixed byte layout.

    The layout (``<i8`` children and features, ``<f8`` thresholds and values, ``value`` in
    node-major order) is the same for a scikit-learn tree (``value`` of shape (n, 1, 2)) and
    for :class:`ForestArrays` (shape (n, 2)), so a forest has one content hash in every
    format.
    """
    for array, dtype in ((children_left, '<i8'), (children_right, '<i8'), (feature, '<i8'),
                         (threshold, '<f8'), (value, '<f8')):
        digest.update(np.ascontiguousarray(array, dtype=dtype).tobytes())


def _plain_params(params: Mapping[str, Any]) -> dict:
    """Forest hyper-parameters as JSON scalars (anything else as its repr)."""
    out = {}
    for name, value in sorted(params.items()):
        if name == 'estimator' or '__' in name:
            continue
        out[name] = value if value is None or isinstance(value, (bool, int, float, str)) \
            else repr(value)
    return out


@dataclass(frozen=True, eq=False)
class ForestArrays:
    """
    A binary random forest as validated, read-only arrays (see the module docstring).

    Attributes
    ----------
    tree_offsets : np.ndarray of int64, shape (n_trees + 1,)
        Tree ``k`` owns nodes ``tree_offsets[k]:tree_offsets[k + 1]``; its root is the first.
    children_left, children_right : np.ndarray of int64, shape (n_nodes,)
        Tree-local child indices, both ``-1`` at leaves. A child's index is larger than its
        parent's, and every node but the root is the child of exactly one node.
    feature : np.ndarray of int64, shape (n_nodes,)
        Feature index ``0 <= f < n_features`` at splits, ``-2`` at leaves.
    threshold : np.ndarray of float64, shape (n_nodes,)
        Finite split threshold, ``-2.0`` at leaves.
    value : np.ndarray of float64, shape (n_nodes, 2)
        Class fractions of each node, in [0, 1], each row summing to 1 within 1e-9.
    n_features : int
        Length of the feature vector.
    feature_importances : np.ndarray of float64, shape (n_features,)
        Mean decrease in impurity, non-negative, summing to 1 (or all 0 for single-leaf trees).
    params : dict
        The forest's hyper-parameters (plain JSON; for the model card only).

    Raises
    ------
    ModelError
        At construction, naming the first array that breaks a rule above.

    """

    tree_offsets: np.ndarray
    children_left: np.ndarray
    children_right: np.ndarray
    feature: np.ndarray
    threshold: np.ndarray
    value: np.ndarray
    n_features: int
    feature_importances: np.ndarray
    params: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        """Validate every array; store read-only copies."""
        n_features = self.n_features
        if isinstance(n_features, bool) or not isinstance(n_features, (int, np.integer)) \
                or n_features < 1:
            raise ModelError(f'forest: n_features must be an int >= 1, got {n_features!r}')
        object.__setattr__(self, 'n_features', int(n_features))
        for name, (dtype, ndim) in NPZ_MEMBERS.items():
            if name == 'header':
                continue
            array = getattr(self, name)
            if not isinstance(array, np.ndarray) or array.dtype != dtype or array.ndim != ndim:
                got = (f'{array.dtype} with {array.ndim} dimension(s)'
                       if isinstance(array, np.ndarray) else type(array).__name__)
                raise ModelError(f'forest: {name} must be a {ndim}-D {dtype} array, got {got}')
            array = np.array(array, dtype=dtype, order='C', copy=True)
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        if not isinstance(self.params, Mapping):
            raise ModelError(f'forest: params must be a dict, got {type(self.params).__name__}')
        object.__setattr__(self, 'params', _plain_params(self.params))
        problem = self._problem()
        if problem:
            raise ModelError(f'forest: {problem}')

    def _problem(self) -> Optional[str]:
        """Describe the first structural problem, or None."""
        offsets = self.tree_offsets
        n_nodes = self.children_left.shape[0]
        if offsets.shape[0] < 2:
            return 'tree_offsets must list at least one tree'
        if offsets[0] != 0 or offsets[-1] != n_nodes or np.any(np.diff(offsets) < 1):
            return (f'tree_offsets must start at 0, increase strictly and end at the node count '
                    f'{n_nodes}')
        for name in ('children_right', 'feature', 'threshold'):
            if getattr(self, name).shape != (n_nodes,):
                return f'{name} has shape {getattr(self, name).shape}, expected ({n_nodes},)'
        if self.value.shape != (n_nodes, 2):
            return (f'value has shape {self.value.shape}, expected ({n_nodes}, 2) (class '
                    'fractions of the classes [0, 1])')
        if self.feature_importances.shape != (self.n_features,):
            return (f'feature_importances has shape {self.feature_importances.shape}, expected '
                    f'({self.n_features},)')
        left, right = self.children_left, self.children_right
        leaf = left == TREE_LEAF
        split = ~leaf
        if np.any(leaf != (right == TREE_LEAF)):
            return 'a node has exactly one child (children must both be -1 or both be nodes)'
        tree = np.repeat(np.arange(offsets.shape[0] - 1), np.diff(offsets))
        local = np.arange(n_nodes) - offsets[tree]
        size = (offsets[1:] - offsets[:-1])[tree]
        for name, child in (('children_left', left), ('children_right', right)):
            if np.any((child[split] <= local[split]) | (child[split] >= size[split])):
                return (f'{name} out of range: a child must lie in its own tree after its '
                        'parent (or be -1 at a leaf)')
        parents = np.bincount(np.concatenate([left[split] + offsets[tree[split]],
                                              right[split] + offsets[tree[split]]]),
                              minlength=n_nodes)
        roots = offsets[:-1]
        not_root = np.ones(n_nodes, dtype=bool)
        not_root[roots] = False
        if np.any(parents[roots] != 0) or np.any(parents[not_root] != 1):
            return 'the nodes do not form trees (every node but a root needs exactly one parent)'
        if np.any(left[split] == right[split]):
            return 'a split has the same node as both children'
        feature = self.feature
        if np.any((feature[split] < 0) | (feature[split] >= self.n_features)):
            return f'feature index out of range [0, {self.n_features}) at a split'
        if np.any(feature[leaf] != TREE_UNDEFINED) or np.any(self.threshold[leaf]
                                                             != TREE_UNDEFINED):
            return "leaves must have feature -2 and threshold -2.0 (scikit-learn's markers)"
        if not np.all(np.isfinite(self.threshold)):
            return 'a threshold is not finite'
        value = self.value
        if not np.all(np.isfinite(value)) or np.any((value < 0.0) | (value > 1.0)) \
                or np.any(np.abs(value.sum(axis=1) - 1.0) > PROBABILITY_SUM_TOLERANCE):
            return ('value rows must be class fractions in [0, 1] summing to 1 (forests of '
                    'scikit-learn < 1.4 stored counts; retrain them)')
        importances = self.feature_importances
        if not np.all(np.isfinite(importances)) or np.any(importances < 0.0) \
                or not (abs(float(importances.sum()) - 1.0) <= 1e-6
                        or not np.any(importances)):
            return 'feature_importances must be finite, >= 0 and sum to 1'
        return None

    # ------------------------------------------------------------------ properties

    @property
    def n_trees(self) -> int:
        """Return the number of trees."""
        return int(self.tree_offsets.shape[0] - 1)

    @property
    def n_estimators(self) -> int:
        """Return the number of trees (scikit-learn's name)."""
        return self.n_trees

    @property
    def n_nodes(self) -> int:
        """Return the number of nodes of all trees."""
        return int(self.children_left.shape[0])

    def tree_node_counts(self) -> list:
        """Nodes per tree."""
        return np.diff(self.tree_offsets).astype(int).tolist()

    def tree_leaf_counts(self) -> list:
        """Leaves per tree."""
        leaf = (self.children_left == TREE_LEAF).astype(np.int64)
        return np.add.reduceat(leaf, self.tree_offsets[:-1]).astype(int).tolist()

    def tree_max_depths(self) -> list:
        """Depth of each tree (a single leaf has depth 0)."""
        depth = np.zeros(self.n_nodes, dtype=np.int64)
        offsets = self.tree_offsets
        tree = np.repeat(np.arange(self.n_trees), np.diff(offsets))
        split = np.flatnonzero(self.children_left != TREE_LEAF)
        # Children follow their parent, so one pass in index order sets every depth.
        for node in split.tolist():
            base = offsets[tree[node]]
            d = depth[node] + 1
            depth[self.children_left[node] + base] = d
            depth[self.children_right[node] + base] = d
        return np.maximum.reduceat(depth, offsets[:-1]).astype(int).tolist()

    @functools.cached_property
    def content_sha256(self) -> str:
        """SHA-256 of the trees (structure, thresholds, values), equal to scikit-learn's."""
        digest = hashlib.sha256()
        for start, stop in zip(self.tree_offsets[:-1].tolist(), self.tree_offsets[1:].tolist()):
            update_tree_digest(digest, **{name: getattr(self, name)[start:stop]
                                          for name in _TREE_ARRAYS})
        return digest.hexdigest()

    def flat(self) -> Dict[str, np.ndarray]:
        """
        Return the trees as one array set with global indices (for :class:`CompiledForest`).

        Returns
        -------
        dict
            ``feature``, ``threshold``, ``left``, ``right`` (global child index, -1 at
            leaves), ``p_contact`` (``value[:, 1]``) and ``roots`` (``tree_offsets[:-1]``).

        """
        tree = np.repeat(np.arange(self.n_trees), np.diff(self.tree_offsets))
        base = self.tree_offsets[tree]
        leaf = self.children_left == TREE_LEAF
        return {'feature': self.feature.astype(np.intp),
                'threshold': self.threshold.copy(),
                'left': np.where(leaf, -1, self.children_left + base).astype(np.intp),
                'right': np.where(leaf, -1, self.children_right + base).astype(np.intp),
                'p_contact': self.value[:, 1].copy(),
                'roots': self.tree_offsets[:-1].astype(np.intp)}

    # ------------------------------------------------------------------ conversion

    @classmethod
    def from_sklearn(cls, forest: Any) -> 'ForestArrays':
        """
        Copy the trees of a fitted binary scikit-learn forest (scikit-learn >= 1.4).

        A ``RandomForestClassifier`` or an ``ExtraTreesClassifier``: their trees hold the same
        arrays.

        Raises
        ------
        ModelError
            Not a fitted single-output forest with classes ``[0, 1]``, or trees whose arrays
            break the rules of this class.

        """
        estimators = getattr(forest, 'estimators_', None)
        classes = getattr(forest, 'classes_', None)
        if not estimators or classes is None:
            raise ModelError(f'expected a fitted scikit-learn forest, got {type(forest)!r}')
        if getattr(forest, 'n_outputs_', 1) != 1 or np.asarray(classes).tolist() != [0, 1]:
            raise ModelError('the forest must be a single-output binary classifier with classes '
                             f'[0, 1] (1 = contact), got classes {np.asarray(classes).tolist()}')
        parts: Dict[str, list] = {name: [] for name in _TREE_ARRAYS}
        offsets = [0]
        for estimator in estimators:
            tree = estimator.tree_
            if tree.value.shape[1:] != (1, 2):
                raise ModelError(f'unexpected tree value shape {tree.value.shape}; expected '
                                 '(n_nodes, 1, 2) for a binary classifier')
            parts['children_left'].append(np.asarray(tree.children_left, dtype='<i8'))
            parts['children_right'].append(np.asarray(tree.children_right, dtype='<i8'))
            parts['feature'].append(np.asarray(tree.feature, dtype='<i8'))
            parts['threshold'].append(np.asarray(tree.threshold, dtype='<f8'))
            parts['value'].append(np.asarray(tree.value[:, 0, :], dtype='<f8'))
            offsets.append(offsets[-1] + int(tree.node_count))
        params = forest.get_params() if hasattr(forest, 'get_params') else {}
        return cls(tree_offsets=np.asarray(offsets, dtype='<i8'),
                   **{name: np.concatenate(chunks) for name, chunks in parts.items()},
                   n_features=int(forest.n_features_in_),
                   feature_importances=np.asarray(forest.feature_importances_, dtype='<f8'),
                   params=params)

    # ------------------------------------------------------------------ npz file

    def write_npz(self, *, path: Path, metadata: Mapping[str, Any]) -> None:
        """
        Write the npz model file (deterministic bytes: fixed zip times, sorted JSON).

        Parameters
        ----------
        path : Path
            Output file.
        metadata : dict
            Plain-JSON bundle metadata, stored in the header.

        """
        header = json.dumps({'npz_version': NPZ_VERSION, 'metadata': metadata,
                             'forest_params': self.params}, sort_keys=True,
                            allow_nan=False).encode('utf-8')
        members = {'header': np.frombuffer(header, dtype=np.uint8)}
        members.update({name: getattr(self, name) for name in NPZ_MEMBERS if name != 'header'})
        with zipfile.ZipFile(path, 'w', compression=zipfile.ZIP_DEFLATED,
                             compresslevel=6) as archive:
            for name, array in members.items():
                buffer = io.BytesIO()
                np.lib.format.write_array(buffer, np.ascontiguousarray(array),
                                          version=(1, 0), allow_pickle=False)
                info = zipfile.ZipInfo(name + '.npy', date_time=_ZIP_TIME)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                archive.writestr(info, buffer.getvalue())

    @classmethod
    def read_npz(cls, *, path: Path) -> tuple:
        """
        Read and validate an npz model file, with numpy only and no pickle.

        Returns
        -------
        (ForestArrays, dict)
            The forest (``n_features`` from the metadata's ``feature_names``) and the header's
            ``metadata``.

        Raises
        ------
        ModelError
            For anything but a well-formed file of this layout: not a zip, members missing or
            extra, a dtype or shape other than the layout's (object arrays included), an array
            whose header does not match its stored size, a bad JSON header, or trees that
            break the rules of :class:`ForestArrays`.

        """
        try:
            arrays = _read_members(Path(path))
        except ModelError:
            raise
        except Exception as err:  # any failure of zip/npy parsing means a corrupt file
            raise ModelError(f'cannot read npz model file {path}: {type(err).__name__}: '
                             f'{err}') from err
        try:
            header = json.loads(arrays.pop('header').tobytes().decode('utf-8'))
        except (UnicodeDecodeError, ValueError) as err:
            raise ModelError(f'npz model file {path}: the header is not UTF-8 JSON') from err
        if not isinstance(header, dict) or header.get('npz_version') != NPZ_VERSION \
                or not isinstance(header.get('metadata'), dict) \
                or not isinstance(header.get('forest_params'), dict):
            raise ModelError(f'npz model file {path}: the header is not a version '
                             f'{NPZ_VERSION} contact_detector header')
        names = header['metadata'].get('feature_names')
        if not isinstance(names, list) or not names:
            raise ModelError(f'npz model file {path}: the header names no features')
        try:
            forest = cls(n_features=len(names), params=header['forest_params'], **arrays)
        except ModelError as err:
            raise ModelError(f'npz model file {path}: {err}') from err
        return forest, header['metadata']


def _read_members(path: Path) -> Dict[str, np.ndarray]:
    """Check the zip directory and every npy header, then load with ``allow_pickle=False``."""
    with zipfile.ZipFile(path) as archive:
        infos = archive.infolist()
        names = [info.filename for info in infos]
        expected = sorted(name + '.npy' for name in NPZ_MEMBERS)
        if sorted(names) != expected:
            raise ModelError(f'npz model file {path} must hold exactly {expected} '
                             f'(missing {sorted(set(expected) - set(names))}, unexpected '
                             f'{sorted(set(names) - set(expected))})')
        if sum(info.file_size for info in infos) > MAX_NPZ_BYTES:
            raise ModelError(f'npz model file {path} is larger than {MAX_NPZ_BYTES} bytes '
                             'uncompressed')
        # Headers first (a few bytes each): a claimed shape must match the stored bytes
        # before numpy allocates anything for it.
        for info in infos:
            name = info.filename[:-len('.npy')]
            dtype, ndim = NPZ_MEMBERS[name]
            with archive.open(info) as stream:
                if np.lib.format.read_magic(stream) != (1, 0):
                    raise ModelError(f'npz model file {path}: {name} is not an npy 1.0 array')
                shape, fortran, stored = np.lib.format.read_array_header_1_0(stream)
                data_bytes = info.file_size - stream.tell()
            if stored != dtype or fortran or len(shape) != ndim:
                raise ModelError(f'npz model file {path}: {name} is a {len(shape)}-D {stored} '
                                 f'array, expected a {ndim}-D {dtype} array')
            count = int(np.prod(shape, dtype=np.int64))
            if count * dtype.itemsize != data_bytes:
                raise ModelError(f'npz model file {path}: {name} claims shape {shape} '
                                 f'({count * dtype.itemsize} bytes) but holds {data_bytes}')
            if name == 'header' and data_bytes > MAX_HEADER_BYTES:
                raise ModelError(f'npz model file {path}: the header is too large')
    with np.load(path, allow_pickle=False) as npz:
        return {name: npz[name] for name in NPZ_MEMBERS}


def boundary_frames(forest: ForestArrays, *, n_rows: int = 4096, seed: int = 0) -> np.ndarray:
    """
    Frames whose features sit on either side of the forest's split thresholds.

    Each feature of each row is drawn from ``{lo(t), hi(t)}`` over the thresholds ``t`` of that
    feature, where ``lo(t)`` is the largest float32 ``<= t`` (goes left) and ``hi(t)`` the
    smallest float32 ``> t`` (goes right): the values where a comparison done differently
    (float64 input, ``<`` for ``<=``) would change a path. Used by ``save_bundle`` to compare
    the arrays with scikit-learn where they are easiest to get wrong.

    Returns
    -------
    np.ndarray of float32, shape (n_rows, n_features)
        Features never split on are 0.

    """
    rng = np.random.default_rng(seed)
    x = np.zeros((n_rows, forest.n_features), dtype=np.float32)
    split = forest.children_left != TREE_LEAF
    for f in range(forest.n_features):
        t = forest.threshold[split & (forest.feature == f)]
        if t.size == 0:
            continue
        with np.errstate(over='ignore'):
            lo = t.astype(np.float32)
        lo = np.where(lo.astype(np.float64) > t, np.nextafter(lo, np.float32(-np.inf)), lo)
        hi = np.nextafter(lo, np.float32(np.inf))
        values = np.concatenate([lo, hi])
        x[:, f] = rng.choice(values[np.isfinite(values)], size=n_rows)
    return x
