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
ament_copyright as `colcon test` runs it on ROS; without it, the same rule checked here.

There is no PyPI wheel of ament_copyright, so outside a ROS install the test applies
``tools/lint_fix.py``'s port of its rule (Apache-2.0 only): every C/C++/CMake/Python source
under ``.`` and ``test`` (not the package's setup.py) starts, after any shebang or coding line,
with a comment block holding ``Copyright <year> <holder>`` and the Apache-2.0 notice; the
repository root holds LICENSE (the Apache-2.0 text) and CONTRIBUTING.md (ament's apache2 text).
"""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

try:
    from ament_copyright.main import main
except ImportError:  # no ament_copyright wheel: pip installs check the same rule below
    main = None


def load_lint_fix():
    """Import tools/lint_fix.py (not a package) by path."""
    spec = importlib.util.spec_from_file_location('lint_fix', ROOT / 'tools' / 'lint_fix.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(autouse=True)
def _package_root(monkeypatch):
    # ament's linters check the current directory: the package root, wherever pytest started.
    monkeypatch.chdir(ROOT)


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    if main is not None:
        rc = main(argv=['.', 'test'])
        assert rc == 0, 'Found errors'
    else:
        errors = load_lint_fix().copyright_report([Path('.'), Path('test')])
        assert not errors, 'Found errors:\n' + '\n'.join(errors)
