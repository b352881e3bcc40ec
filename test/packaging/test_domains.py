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

"""tools/test.sh's two pytest workers: each in a DDS domain of its own, set once."""

import os
from pathlib import Path
import subprocess
import sys

TEST_DIR = Path(__file__).resolve().parents[1]


def _domain(**env: str) -> str:
    # a fresh process that imports the suite's conftest, as a worker or a pytest it starts does
    code = (f'import os, sys; sys.path.insert(0, {str(TEST_DIR)!r}); import conftest; '
            'print(os.environ["ROS_DOMAIN_ID"])')
    base = {k: v for k, v in os.environ.items()
            if k not in ('PYTEST_XDIST_WORKER', 'CONTACT_DETECTOR_TEST_WORKER')}
    return subprocess.run([sys.executable, '-c', code], env={**base, **env},
                          capture_output=True, text=True, check=True).stdout.strip()


def test_each_worker_gets_a_domain_of_its_own_once():
    assert _domain(ROS_DOMAIN_ID='86') == '86'   # no worker: the run's own domain
    first = _domain(ROS_DOMAIN_ID='86', PYTEST_XDIST_WORKER='gw0')
    second = _domain(ROS_DOMAIN_ID='86', PYTEST_XDIST_WORKER='gw1')
    assert (first, second) == ('186', '187')
    # a pytest the worker starts (colcon test) inherits the worker's domain and keeps it
    assert _domain(ROS_DOMAIN_ID='187', PYTEST_XDIST_WORKER='gw1',
                   CONTACT_DETECTOR_TEST_WORKER='gw1') == '187'
    # Fast DDS takes domains 0-232
    assert _domain(ROS_DOMAIN_ID='150', PYTEST_XDIST_WORKER='gw0') == '17'
