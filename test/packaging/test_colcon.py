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
colcon build and colcon test of the package, as on a ROS install (tools/colcon_check.sh).

colcon, colcon-ros and ament_package come from PyPI (setup.py extra "colcon"). The build is
checked for what it installs; colcon test runs the linters, the package checks and the core
tests (the feature core, release rule, model and message readers: the whole suite runs
outside colcon anyway, and all of it under colcon would add minutes to CI), and colcon
test-result must report no failure. ``tools/colcon_check.sh`` alone runs every test that does
not start rclpy.
"""

import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[2]
UNDER_COLCON = ['test/test_flake8.py', 'test/test_pep257.py', 'test/test_copyright.py',
                'test/packaging/test_package.py', 'test/packaging/test_launch.py',
                'test/unit/features/test_features.py', 'test/unit/detection/test_release.py',
                'test/unit/io/test_cdr.py', 'test/unit/io/test_messages.py',
                'test/unit/model/test_compiled_forest.py', 'test/unit/model/test_bundle.py']

pytestmark = [pytest.mark.colcon, pytest.mark.slow]


@pytest.mark.skipif(shutil.which('colcon', path=str(Path(sys.executable).parent)) is None,
                    reason='colcon is not installed in this venv (tools/setup.sh installs it)')
def test_colcon_build_and_test(tmp_path):
    env = dict(os.environ, COLCON_PYTEST_ARGS=' '.join(
        ['-q', '-p', 'no:cacheprovider', '-m', "'not rclpy and not colcon'"] + UNDER_COLCON))
    done = subprocess.run([str(ROOT / 'tools' / 'colcon_check.sh'), str(tmp_path / 'ws')],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=1200)
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-6000:]
    assert 'sourced install/setup.bash: contact_detector from' in output
    summary = re.search(r'Summary: (\d+) tests, (\d+) errors, (\d+) failures', output)
    assert summary, output[-3000:]
    tests, errors, failures = map(int, summary.groups())
    assert tests > 100 and errors == 0 and failures == 0
    results = list((tmp_path / 'ws' / 'build' / 'contact_detector').rglob('pytest.xml'))
    assert results, 'colcon test wrote no JUnit result'
