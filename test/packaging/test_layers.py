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
The package's layers only point down (docs/architecture.md, "Layers").

Every ``import`` of the package, at module level or inside a function, is read from the
source with :mod:`ast`. A subpackage may import from itself and from the layers below it,
never from a layer above it nor from another subpackage of its own layer. Only ``ros/`` imports
rclpy, the ament index and ROS message, service and action packages.
"""

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PACKAGE = REPO / 'contact_detector'

#: The layers, bottom first. ``errors`` (and the package's ``__init__``) sit below them all.
LAYERS = (
    ('errors',),
    ('io',),
    ('features', 'sim'),
    ('model',),
    ('detection',),
    ('evaluation',),
    ('training',),
    ('ros',),
    ('cli',),
)
RANK = {name: rank for rank, names in enumerate(LAYERS) for name in names}
#: ROS modules, imported only in ``ros/``: the core and the commands run without them.
ROS_MODULES = ('rclpy', 'ament_index_python', 'rcl_interfaces', 'std_msgs', 'std_srvs',
               'geometry_msgs', 'sensor_msgs', 'diagnostic_msgs', 'trajectory_msgs',
               'control_msgs', 'audio_common_msgs', 'lifecycle_msgs', 'rosgraph_msgs',
               'builtin_interfaces', 'rosidl_runtime_py', 'launch', 'launch_ros')
#: Name endings of ROS interface packages (messages, services, actions) not listed above.
ROS_PACKAGE_SUFFIXES = ('_msgs', '_srvs', '_interfaces', '_actions')
#: Modules of ``cli/`` that are not commands: the dispatcher and the options commands share.
CLI_SUPPORT = ('__init__', 'main', 'common', 'model_options')


def _imports(path: Path) -> list:
    """Return ``(line, module)`` of every absolute import in ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.append((node.lineno, node.module))
            if node.module == 'contact_detector':  # from contact_detector import io
                found += [(node.lineno, f'contact_detector.{alias.name}')
                          for alias in node.names]
    return found


def _layer(path: Path) -> str:
    """Return the subpackage of a module of the package ('errors' for the top modules)."""
    parts = path.relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 else 'errors'


def _package_modules() -> list:
    return sorted(PACKAGE.rglob('*.py'))


def test_every_subpackage_has_a_layer() -> None:
    subpackages = {p.name for p in PACKAGE.iterdir() if (p / '__init__.py').is_file()}
    assert subpackages <= set(RANK), f'no layer for {sorted(subpackages - set(RANK))}'


def test_no_module_imports_from_a_layer_above_or_beside_it() -> None:
    wrong = []
    for path in _package_modules():
        source = _layer(path)
        for line, module in _imports(path):
            parts = module.split('.')
            if parts[0] != 'contact_detector' or len(parts) < 2:
                continue
            target = parts[1] if parts[1] in RANK and parts[1] != 'errors' else 'errors'
            if target == source:
                continue
            if RANK[target] >= RANK[source]:
                wrong.append(f'{path.relative_to(REPO)}:{line} ({source}) imports {module} '
                             f'({target})')
    assert not wrong, 'imports that do not point down:\n' + '\n'.join(wrong)


def _is_ros(module: str) -> bool:
    """Return whether ``module`` is rclpy, the ament index or a ROS interface package."""
    top = module.split('.')[0]
    return top in ROS_MODULES or top.endswith(ROS_PACKAGE_SUFFIXES)


def _ros_imports(paths) -> list:
    """Return ``path:line imports module`` for every ROS import in ``paths``."""
    return [f'{path.relative_to(REPO) if path.is_relative_to(REPO) else path}:{line} '
            f'imports {module}'
            for path in paths for line, module in _imports(path) if _is_ros(module)]


def test_only_ros_imports_rclpy_and_ros_messages() -> None:
    outside = [path for path in _package_modules() if _layer(path) != 'ros']
    wrong = _ros_imports(outside)
    assert not wrong, 'ROS imports outside contact_detector/ros/:\n' + '\n'.join(wrong)


def test_the_check_sees_a_ros_import(tmp_path: Path) -> None:
    module = tmp_path / 'command.py'
    module.write_text('import numpy\nimport rosbags.rosbag2\n'
                      'def run():\n    import rclpy.executors\n'
                      '    from std_srvs.srv import SetBool\n'
                      '    from my_robot_msgs.msg import Grip\n')
    assert [m.split(' imports ')[1] for m in _ros_imports([module])] == [
        'rclpy.executors', 'std_srvs.srv', 'my_robot_msgs.msg']


@pytest.mark.parametrize('folder', ['cli', 'benchmarks'])
def test_commands_and_benchmarks_do_not_import_commands(folder: str) -> None:
    base = PACKAGE / 'cli' if folder == 'cli' else REPO / 'benchmarks'
    wrong = []
    for path in sorted(base.glob('*.py')):
        if folder == 'cli' and path.stem in CLI_SUPPORT:
            continue
        for line, module in _imports(path):
            parts = module.split('.')
            if parts[:2] == ['contact_detector', 'cli'] and (
                    folder == 'benchmarks' or len(parts) < 3 or parts[2] not in CLI_SUPPORT):
                wrong.append(f'{path.relative_to(REPO)}:{line} imports {module}')
    assert not wrong, 'imports of command modules:\n' + '\n'.join(wrong)


def test_the_check_sees_an_upward_import(tmp_path: Path) -> None:
    module = tmp_path / 'upward.py'
    module.write_text('def f():\n    from contact_detector.training.recipe import X\n'
                      'from contact_detector import cli\n')
    assert [m for _, m in _imports(module)] == [
        'contact_detector', 'contact_detector.cli', 'contact_detector.training.recipe']
