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
Short soak (the CI version of benchmarks/bench_soak.py): memory stays flat.

Simulated trials played in turn as one continuous stream at full speed, ``tracemalloc`` sampled
every 30 simulated seconds after a full collection:

* through :class:`ContactDetector` for 2 simulated minutes: the traced memory may not grow
  by more than 0.5 MB from minute 1 to the end (measured: flat to within a few KiB);
* through the real node (callbacks called directly, outputs published) for 1.5 simulated
  minutes: growth below 2 MB from minute 1 to the end, and below 0.1 MB outside the lines
  that keep the last 100 000 processing latencies per callback kind (bounded: ~0.17 MB per
  simulated minute until full after ~20 minutes, 3.3 MB in all; see docs/reliability.md).

The runner is :mod:`contact_detector.ros.soak`; the full soak (30+ minutes, RSS and
tracemalloc per minute) is ``python benchmarks/bench_soak.py``.
"""

import linecache

from contact_detector.ros.soak import make_pool, run_soak
import node_support
import pytest


@pytest.fixture(scope='module')
def bundle(tmp_path_factory):
    # The small test model: memory does not depend on the forest, the run time does.
    return node_support.load_test_model(tmp_path_factory.mktemp('model'))


@pytest.fixture(scope='module')
def pool():
    return make_pool(n=6)


def growth_after_minute_1(result) -> float:
    after = [s.traced_mb for s in result.samples if s.minute >= 1.0]
    return max(after) - after[0]


def test_detector_memory_is_flat(bundle, pool):
    result = run_soak(bundle=bundle, minutes=2.0, mode='detector', pool=pool, sample_s=30.0)
    assert result.samples[-1].minute == pytest.approx(2.0)
    assert result.counts['frames'] > 11000 and result.counts['releases'] >= 5
    growth = growth_after_minute_1(result)
    assert growth < 0.5, (growth, result.growth_sites)


def test_node_memory_is_bounded(bundle, pool):
    result = run_soak(bundle=bundle, minutes=1.5, mode='node', pool=pool, sample_s=30.0)
    assert result.counts['callback_errors'] == 0 and result.counts['frames'] > 8500
    growth = growth_after_minute_1(result)
    assert growth < 2.0, (growth, result.growth_sites)
    # All of it is the bounded latency history (node.py lines that keep latencies).
    other = sum(size for path, line, size, _ in result.growth
                if size > 0 and 'latency' not in linecache.getline(path, line))
    assert other < 0.1 * 2 ** 20, result.growth_sites
