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
The node on Ubuntu 24.04's library versions: the shipped model, a live trial, one release.

``tools/ubuntu2404_env.sh`` (run by ``tools/test.sh`` before pytest) makes ``.venv-noble`` with
exactly the apt versions of a stock Ubuntu 24.04 ROS 2 Jazzy install (numpy 1.26.4, scipy
1.11.4, scikit-learn 1.4.1.post1, joblib 1.3.2), rclpy from the ros-jazzy wheels, no rosbags,
and contact_detector installed without dependencies. In that environment the node starts with
its default parameters and the shipped model, a publisher plays a simulated trial live (from
the simulator's arrays: no bag is written or read), and a listener records the outputs: the
node releases once, just after the contact.
"""

import json
import os
from pathlib import Path
import subprocess

import node_support
import pytest

pytestmark = pytest.mark.rclpy

TEST_DIR = Path(__file__).resolve().parents[1]  # test/: the helper scripts
REPO = TEST_DIR.parent
NOBLE_PYTHON = Path(os.environ.get('CONTACT_DETECTOR_NOBLE_VENV', REPO / '.venv-noble')) \
    / 'bin' / 'python'
NOBLE_VERSIONS = {'numpy': '1.26.4', 'scipy': '1.11.4', 'scikit-learn': '1.4.1.post1',
                  'joblib': '1.3.2'}
#: Largest accepted delay from the true onset to the release message, s.
LATENCY_BUDGET_S = 0.3

needs_noble = pytest.mark.skipif(not NOBLE_PYTHON.is_file(),
                                 reason='no .venv-noble: run tools/ubuntu2404_env.sh '
                                        '(tools/test.sh does)')


def _noble(args, log: Path) -> subprocess.Popen:
    return subprocess.Popen([str(NOBLE_PYTHON), *args], cwd=REPO, env=dict(os.environ),
                            stdout=open(log, 'w'), stderr=subprocess.STDOUT)


@needs_noble
def test_the_environment_has_exactly_ubuntu_2404s_versions_and_no_rosbags() -> None:
    code = """
import importlib.metadata as md, importlib.util, json, sys
import contact_detector.ros.node  # noqa: F401
print(json.dumps({'versions': {n: md.version(n) for n in %r},
                  'rosbags': importlib.util.find_spec('rosbags') is not None,
                  'imported': sorted(m for m in ('sklearn', 'joblib', 'rosbags', 'matplotlib')
                                     if m in sys.modules)}))
""" % (list(NOBLE_VERSIONS),)
    done = subprocess.run([str(NOBLE_PYTHON), '-c', code], cwd=REPO, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout)
    assert found == {'versions': NOBLE_VERSIONS, 'rosbags': False, 'imported': []}


@needs_noble
def test_node_detects_a_live_trial_with_the_shipped_model(tmp_path: Path) -> None:
    params = REPO / 'params' / 'contact_detector.yaml'
    run = node_support.run_live_trial(
        start=_noble, tmp_path=tmp_path,
        node_args=['-m', 'contact_detector.ros.node', '--ros-args', '--params-file', str(params)])
    logs = run['logs']
    assert run['pub_code'] == 0, logs['pub']
    assert run['listen_code'] == 0, logs['listen']
    assert run['node_code'] == 0, logs['node']
    assert 'contact_forest' in logs['node'] and 'FATAL' not in logs['node'], logs['node']
    pub, got = run['pub'], run['got']
    releases = [t for t, value in got['release'] if value]
    assert len(releases) == 1, (releases, pub['onset_wall'], logs['node'])
    delay = releases[0] - pub['onset_wall']
    assert 0.0 < delay <= LATENCY_BUDGET_S, (delay, logs['node'])
    assert len(got['contact']) > 100, len(got['contact'])
