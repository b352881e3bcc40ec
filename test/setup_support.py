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
setup.py's arguments as setuptools gets them (setup() replaced by a recorder, nothing built).

Used by test_package.py and test_launch.py to check what a build installs.
"""

import os
from pathlib import Path
import runpy

import setuptools

ROOT = Path(__file__).resolve().parents[1]


def setup_kwargs() -> dict:
    """Run setup.py in the repository with ``setuptools.setup`` recording its arguments."""
    recorded: dict = {}
    real, cwd = setuptools.setup, os.getcwd()
    setuptools.setup = lambda **kwargs: recorded.update(kwargs)
    try:
        os.chdir(ROOT)
        runpy.run_path(str(ROOT / 'setup.py'), run_name='__main__')
    finally:
        setuptools.setup = real
        os.chdir(cwd)
    return recorded


def installed_files() -> dict:
    """Return install path (relative to the prefix) -> source file, from ``data_files``."""
    files = {}
    for directory, sources in setup_kwargs()['data_files']:
        for source in sources:
            files[f'{directory}/{Path(source).name}'] = ROOT / source
    return files


def console_scripts() -> dict:
    """Return executable name -> ``module:function`` of the console scripts."""
    entries = setup_kwargs()['entry_points']['console_scripts']
    return dict((part.strip() for part in entry.split('=', 1)) for entry in entries)
