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

"""The README's main job: ``contact-detector demo`` end to end (one trial, real processes)."""

import os
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.rclpy


def test_demo_runs_the_node_live_and_passes(tmp_path):
    env = dict(os.environ)   # conftest.py keeps DDS on loopback with this run's domain
    result = subprocess.run(
        [sys.executable, '-m', 'contact_detector.cli.main', 'demo', '--trials', '1',
         '--out', str(tmp_path)], cwd=ROOT, env=env, capture_output=True, text=True,
        timeout=240)
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert 'trial_' in result.stdout and 'detected' in result.stdout, output
    assert '1/1 contacts detected, 0 premature, 0 missed' in result.stdout, output
    assert (tmp_path / 'demo_trial.png').stat().st_size > 10_000
    assert (tmp_path / 'node.log').exists() and (tmp_path / 'manifest.json').exists()
