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
Inference speed of the contact forest: CompiledForest vs scikit-learn, and model load times.

Trains a forest like the shipped one (``--trees`` deep, unpruned trees, ``max_features='sqrt'``)
on synthetic frames, checks that CompiledForest is bit-identical to scikit-learn on the test
frames, then reports medians over ``--repeats`` runs:

* ``CompiledForest.predict_one`` per frame (the live path), also the median and p99 of
  individually timed calls (these include ~0.1 us of timer overhead);
* ``CompiledForest.predict_proba`` on a batch, per frame;
* ``RandomForestClassifier.predict_proba`` on one frame (one call) and on the batch, per frame;
* ``load_bundle`` time and file size for the npz, joblib and skops formats, and the time to
  build the CompiledForest.

Usage::

    python benchmarks/bench_inference.py [--frames 100000] [--repeats 7]
"""

import argparse
import os
from pathlib import Path
import statistics
import sys
import tempfile
import time
from typing import Callable, List, Optional, Sequence

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from contact_detector.features.config import (  # noqa: E402
    FEATURE_SCHEMA_VERSION, FeatureConfig)
from contact_detector.model import (  # noqa: E402
    CompiledForest, load_bundle, ModelBundle, runtime_versions, save_bundle)
from contact_detector.model.compiled_forest import check_same_as_sklearn  # noqa: E402
import numpy as np  # noqa: E402
from sklearn.ensemble import RandomForestClassifier  # noqa: E402


def synthetic_frames(*, n: int, n_features: int, seed: int) -> tuple:
    """Imbalanced frames (~15 % contact) with one strong and several weak, noisy features."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, n_features))
    score = 1.0 * x[:, 0] + 0.3 * x[:, 1:].sum(axis=1) / np.sqrt(max(n_features - 1, 1))
    y = (score + rng.normal(scale=0.8, size=n) > 1.1).astype(int)
    return x, y


def median_of(*, repeats: int, run: Callable[[], float]) -> float:
    """Median of ``run()`` over ``repeats`` calls (each returns a time)."""
    return statistics.median(run() for _ in range(repeats))


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog='bench_inference', description=__doc__.split('\n')[1])
    parser.add_argument('--frames', type=int, default=100_000, help='training frames')
    parser.add_argument('--repeats', type=int, default=7, help='timed runs per figure')
    parser.add_argument('--trees', type=int, default=8)
    parser.add_argument('--features', type=int, default=7, choices=range(7, 11),
                        help='7 = the paper set; 8-10 add the extra features')
    parser.add_argument('--test-frames', type=int, default=2000,
                        help='distinct frames per predict_one run')
    parser.add_argument('--batch', type=int, default=10_000, help='frames per batch call')
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args(argv)
    load_before = os.getloadavg()[0]

    extras = ('audio_power_rel_db', 'force_delta', 'torque_delta')[:args.features - 7]
    config = FeatureConfig(extra_features=extras)
    x, y = synthetic_frames(n=args.frames, n_features=args.features, seed=args.seed)
    t0 = time.perf_counter()
    forest = RandomForestClassifier(n_estimators=args.trees, max_features='sqrt',
                                    random_state=args.seed).fit(x, y)
    fit_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    compiled = CompiledForest.from_sklearn(forest)
    build_s = time.perf_counter() - t0
    x_test, _ = synthetic_frames(n=max(args.test_frames, args.batch), n_features=args.features,
                                 seed=args.seed + 1)
    rows = list(x_test[:args.test_frames])
    batch = x_test[:args.batch]
    exact = check_same_as_sklearn(forest=forest, compiled=compiled, x=x_test[:args.test_frames])

    def time_predict_one() -> float:
        start = time.perf_counter()
        for row in rows:
            compiled.predict_one(row)
        return (time.perf_counter() - start) / len(rows)

    def time_batch() -> float:
        start = time.perf_counter()
        compiled.predict_proba(batch)
        return (time.perf_counter() - start) / len(batch)

    single = batch[:1]

    def time_sklearn_single() -> float:
        calls = 50
        start = time.perf_counter()
        for _ in range(calls):
            forest.predict_proba(single)
        return (time.perf_counter() - start) / calls

    def time_sklearn_batch() -> float:
        start = time.perf_counter()
        forest.predict_proba(batch)
        return (time.perf_counter() - start) / len(batch)

    one_s = median_of(repeats=args.repeats, run=time_predict_one)
    batch_s = median_of(repeats=args.repeats, run=time_batch)
    sk_single_s = median_of(repeats=args.repeats, run=time_sklearn_single)
    sk_batch_s = median_of(repeats=args.repeats, run=time_sklearn_batch)
    calls: List[float] = []
    for row in rows:
        start = time.perf_counter()
        compiled.predict_one(row)
        calls.append(time.perf_counter() - start)
    p50_s, p99_s = (float(v) for v in np.percentile(calls, [50, 99]))

    bundle = ModelBundle(forest=forest, feature_config=config,
                         feature_names=config.feature_names,
                         feature_schema_version=FEATURE_SCHEMA_VERSION,
                         label_window={'mode': 'onset', 'start_s': 0.0, 'end_s': 0.1},
                         versions=runtime_versions(), created='2026-01-01T00:00:00+00:00')
    formats = {}
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in ('npz', 'joblib', 'skops'):
            path = Path(tmp) / f'model_{fmt}.{fmt}'
            start = time.perf_counter()
            save_bundle(bundle=bundle, path=path, fmt=fmt)
            save_s = time.perf_counter() - start

            def time_load(path: Path = path) -> float:
                start = time.perf_counter()
                load_bundle(path=path)
                return time.perf_counter() - start

            formats[fmt] = (path.stat().st_size, save_s,
                            median_of(repeats=args.repeats, run=time_load))

    nodes = [e.tree_.node_count for e in forest.estimators_]
    depths = [e.tree_.max_depth for e in forest.estimators_]
    print(f'Forest: {args.trees} trees on {args.frames} x {args.features} synthetic frames '
          f'(fit {fit_s:.1f} s), {min(nodes)}-{max(nodes)} nodes and depth '
          f'{min(depths)}-{max(depths)} per tree; seed {args.seed}; medians of '
          f'{args.repeats} runs; Python {sys.version.split()[0]}; {os.cpu_count()} CPUs, load '
          f'average {load_before:.1f} before and {os.getloadavg()[0]:.1f} after (other '
          f'processes slow every figure).')
    print(f'CompiledForest bit-identical to sklearn on {len(rows)} frames (batch and single): '
          f'{"yes" if exact else "NO"}. Build time {build_s:.2f} s.\n')
    print('| path | us per frame |')
    print('|---|---|')
    print(f'| CompiledForest.predict_one ({len(rows)} distinct frames) | {one_s * 1e6:.2f} |')
    print(f'| CompiledForest.predict_one, median of single timed calls | {p50_s * 1e6:.2f} |')
    print(f'| CompiledForest.predict_one, p99 of single timed calls | {p99_s * 1e6:.2f} |')
    print(f'| CompiledForest.predict_proba, batch of {len(batch)} | {batch_s * 1e6:.2f} |')
    print(f'| sklearn predict_proba, 1 frame per call | {sk_single_s * 1e6:.1f} |')
    print(f'| sklearn predict_proba, batch of {len(batch)} | {sk_batch_s * 1e6:.2f} |')
    print(f'\nsklearn single call / predict_one: {sk_single_s / one_s:.0f}x; '
          f'sklearn batch / CompiledForest batch: {sk_batch_s / batch_s:.2f}x\n')
    print('| format | file size (MB) | save (s) | load_bundle (ms) |')
    print('|---|---|---|---|')
    for fmt, (size, save_s, load_s) in formats.items():
        print(f'| {fmt} | {size / 1e6:.2f} | {save_s:.2f} | {load_s * 1e3:.0f} |')
    return 0 if exact else 1


if __name__ == '__main__':
    sys.exit(main())
