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
package.xml against the code: every import declared with its rosdep key; license; URLs.

``rosdep install --from-paths src`` installs what package.xml declares and nothing else, so an
import without its key fails on a robot, not here (where the venv has everything). No rclpy.
"""

import ast
from pathlib import Path
import re
import sys
import xml.etree.ElementTree as ET

import setup_support

ROOT = Path(__file__).resolve().parents[2]

#: Top-level import name -> rosdep key (Jazzy, Ubuntu 24.04). The python keys are those of
#: rosdistro's rosdep/python.yaml; the others are ROS packages of Jazzy.
IMPORT_KEYS = {
    'rclpy': 'rclpy',
    'rcl_interfaces': 'rcl_interfaces',
    'lifecycle_msgs': 'lifecycle_msgs',
    'std_msgs': 'std_msgs',
    'std_srvs': 'std_srvs',
    'geometry_msgs': 'geometry_msgs',
    'trajectory_msgs': 'trajectory_msgs',
    'diagnostic_msgs': 'diagnostic_msgs',
    'rosgraph_msgs': 'rosgraph_msgs',
    'builtin_interfaces': 'builtin_interfaces',
    'ament_index_python': 'ament_index_python',
    'launch': 'launch',
    'launch_ros': 'launch_ros',
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'sklearn': 'python3-sklearn',
    'joblib': 'python3-joblib',
    'matplotlib': 'python3-matplotlib',
    'tqdm': 'python3-tqdm',
    'yaml': 'python3-yaml',
    'rosbags': 'python3-rosbags-pip',
    'soundfile': 'python3-soundfile',
    'psutil': 'python3-psutil',
    'pytest': 'python3-pytest',
    'hypothesis': 'python3-hypothesis',
    'setuptools': 'python3-setuptools',
    'ament_copyright': 'ament_copyright',
    'ament_flake8': 'ament_flake8',
    'ament_pep257': 'ament_pep257',
}
#: Imports with no rosdep key: optional, imported where they are used, and said so in
#: package.xml.
OPTIONAL = {'skops': 'pip install skops (setup.py extra "safe")'}
#: Tools the tests run (python -m NAME) or configure (setup.cfg), by rosdep key.
TOOL_KEYS = {'flake8': 'python3-flake8', 'pydocstyle': 'pydocstyle',
             'flake8-quotes': 'python3-flake8-quotes',
             'flake8-blind-except': 'python3-flake8-blind-except',
             'flake8-class-newline': 'python3-flake8-class-newline',
             'flake8-deprecated': 'python3-flake8-deprecated'}


def package_xml() -> ET.Element:
    return ET.parse(ROOT / 'package.xml').getroot()


def declared(*tags: str) -> set:
    return {e.text.strip() for tag in tags for e in package_xml().iter(tag)}


def top_level_imports(paths) -> dict:
    """Absolute imports that are neither the standard library nor local: name -> files."""
    local = {'contact_detector'}
    local |= {p.stem for folder in ('test', 'benchmarks') for p in (ROOT / folder).rglob('*.py')}
    found: dict = {}
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split('.')[0]
                if top not in sys.stdlib_module_names and top not in local:
                    found.setdefault(top, set()).add(str(path.relative_to(ROOT)))
    return found


def test_every_package_import_is_an_exec_depend():
    imports = top_level_imports(sorted((ROOT / 'contact_detector').rglob('*.py')))
    assert {'rclpy', 'numpy', 'rcl_interfaces'} <= set(imports)     # the scan works
    unknown = {name: files for name, files in imports.items()
               if name not in IMPORT_KEYS and name not in OPTIONAL}
    assert not unknown, ('imports without a rosdep key in IMPORT_KEYS (add it there and to '
                         f'package.xml): {unknown}')
    runtime = declared('exec_depend', 'depend')
    missing = {IMPORT_KEYS[name]: sorted(files) for name, files in imports.items()
               if name in IMPORT_KEYS and IMPORT_KEYS[name] not in runtime}
    assert not missing, f'package.xml lacks <exec_depend> for {missing}'
    xml_text = (ROOT / 'package.xml').read_text()
    for name in set(imports) & set(OPTIONAL):
        assert name in xml_text, f'package.xml does not say how to get optional {name}'


def test_every_test_import_and_tool_is_declared():
    tests = sorted((ROOT / 'test').rglob('*.py'))
    imports = top_level_imports(tests)
    unknown = sorted(set(imports) - set(IMPORT_KEYS) - set(OPTIONAL))
    assert not unknown, f'test imports without a rosdep key in IMPORT_KEYS: {unknown}'
    available = declared('exec_depend', 'depend', 'test_depend')
    missing = sorted({IMPORT_KEYS[name] for name in imports if name in IMPORT_KEYS}
                     - available)
    assert not missing, f'package.xml lacks <test_depend> for {missing}'
    # ament_flake8 and ament_pep257 (test_flake8.py, test_pep257.py) run flake8 with these
    # plugins and pydocstyle as libraries: each needs its key.
    assert {'ament_flake8', 'ament_pep257'} <= set(imports)
    missing = sorted(set(TOOL_KEYS.values()) - available)
    assert not missing, f'package.xml lacks <test_depend> for the tools {missing}'


def test_no_stale_python_dependency():
    used = set(IMPORT_KEYS.values()) | set(TOOL_KEYS.values())
    python_keys = {key for key in declared('exec_depend', 'depend', 'test_depend')
                   if key.startswith('python3-') or key == 'pydocstyle'}
    assert python_keys <= used, f'declared but not in the tables: {python_keys - used}'


def test_license_file_matches_package_xml_and_setup():
    root = package_xml()
    license_tag = root.find('license')
    assert license_tag.text.strip() == 'Apache-2.0'
    assert license_tag.get('file') == 'LICENSE'
    text = (ROOT / 'LICENSE').read_text()
    assert text.split()[:4] == ['Apache', 'License', 'Version', '2.0,']
    assert 'TERMS AND CONDITIONS FOR USE, REPRODUCTION, AND DISTRIBUTION' in text
    assert 'END OF TERMS AND CONDITIONS' in text and len(text) > 10000   # the full text
    keywords = setup_support.setup_kwargs()
    assert keywords['license'] == 'Apache-2.0'
    assert keywords['name'] == root.findtext('name')
    assert keywords['version'] == root.findtext('version')


def test_urls_and_format():
    root = package_xml()
    assert root.get('format') == '3'
    urls = {e.get('type'): e.text.strip() for e in root.iter('url')}
    assert set(urls) == {'website', 'bugtracker', 'repository'}
    assert all(re.fullmatch(r'https://\S+', url) for url in urls.values())
    assert urls['bugtracker'] == urls['repository'] + '/issues'


def test_package_files_are_installed():
    files = setup_support.installed_files()
    for name in ('CHANGELOG.rst', 'LICENSE', 'package.xml', 'README.md'):
        assert files[f'share/contact_detector/{name}'] == ROOT / name
    assert all(source.is_file() for source in files.values())
    assert files['share/ament_index/resource_index/packages/contact_detector'].is_file()
