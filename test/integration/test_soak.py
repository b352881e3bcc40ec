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
  minutes, its history of processing latencies shortened to 1000 per callback kind (full
  within the first minute; the default 100 000 fills after ~20 simulated minutes, 3.3 MB in
  all, see docs/reliability.md): growth below 0.025 MB from minute 1 to the end (measured
  0.004 MB; 0.095 MB with the default history, which grows meanwhile).

The runner is :mod:`contact_detector.ros.soak`; the full soak (30+ minutes, RSS and
tracemalloc per minute) is ``python benchmarks/bench_soak.py``.
"""

from contact_detector.ros import node as node_module
from contact_detector.ros.soak import make_pool, run_soak
import node_support
import pytest

# The node mode starts rclpy; both runs take minutes.
pytestmark = [pytest.mark.rclpy, pytest.mark.slow]


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


def test_node_memory_is_bounded(bundle, pool, monkeypatch):
    # The node keeps the last LATENCY_HISTORY processing latencies per callback kind, a
    # bounded history (full after ~20 simulated minutes at its default length). With a short
    # one, full within the first minute, nothing may grow after it.
    monkeypatch.setattr(node_module, 'LATENCY_HISTORY', 1000)
    result = run_soak(bundle=bundle, minutes=1.5, mode='node', pool=pool, sample_s=30.0)
    assert result.counts['callback_errors'] == 0 and result.counts['frames'] > 8500
    growth = growth_after_minute_1(result)
    # Measured 0.004 MB; with the default history (still filling) 0.095 MB.
    assert growth < 0.025, (growth, result.growth_sites)
