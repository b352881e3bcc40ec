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

"""ament_flake8 with its own configuration and plugins, as `colcon test` runs it on ROS."""

from pathlib import Path

from ament_flake8.main import main_with_errors
import pytest


@pytest.fixture(autouse=True)
def _package_root(monkeypatch):
    # ament's linters check the current directory: the package root, wherever pytest started.
    monkeypatch.chdir(Path(__file__).resolve().parents[1])


@pytest.mark.slow
@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    rc, errors = main_with_errors(argv=[])
    assert rc == 0, \
        'Found %d code style errors / warnings:\n' % len(errors) + \
        '\n'.join(errors)
