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
launch/contact_detector.launch.py against what the package installs (no launch needed).

The launch file is read with ast: every params file and executable it names must be installed
by setup.py (data_files, console_scripts), and the topics it remaps must be the node's. ROS's
``launch`` has no wheel, so the launch file itself runs only where it is installed (a ROS
install); that test is skipped here.
"""

import ast
import importlib.util
from pathlib import Path

from contact_detector.ros.params import PARAMS_BY_NAME
import pytest
import setup_support
import yaml

ROOT = Path(__file__).resolve().parents[2]
LAUNCH = ROOT / 'launch' / 'contact_detector.launch.py'
SHARE = 'share/contact_detector'


def module_constants(path: Path) -> dict:
    """Module-level NAME = <literal> assignments of a file."""
    constants = {}
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                and isinstance(node.targets[0], ast.Name):
            try:
                constants[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                pass
    return constants


def test_launch_file_is_installed():
    files = setup_support.installed_files()
    assert files[f'{SHARE}/launch/contact_detector.launch.py'] == LAUNCH


def test_every_params_file_it_names_is_installed():
    tree = ast.parse(LAUNCH.read_text())
    named = {node.value for node in ast.walk(tree)
             if isinstance(node, ast.Constant) and isinstance(node.value, str)
             and node.value.endswith('.yaml')}
    assert named == {'contact_detector.yaml', 'hsr.yaml'}
    files = setup_support.installed_files()
    for name in named:
        assert files.get(f'{SHARE}/params/{name}') == ROOT / 'params' / name, name
    # They are looked up in share/contact_detector/params (the folder data_files fills).
    assert "os.path.join(share, 'params'," in LAUNCH.read_text()


def test_every_executable_it_runs_is_a_console_script():
    constants = module_constants(LAUNCH)
    assert constants['PACKAGE'] == setup_support.setup_kwargs()['name']
    executables = set(constants['EXECUTABLES'].values())
    assert executables == {'contact_detector_node', 'contact_detector_lifecycle_node'}
    scripts = setup_support.console_scripts()
    for name in executables:
        module, function = scripts[name].split(':')
        spec = importlib.util.find_spec(module)
        assert spec is not None, scripts[name]
        defined = {node.name for node in ast.parse(Path(spec.origin).read_text()).body
                   if isinstance(node, ast.FunctionDef)}
        assert function in defined, scripts[name]
    # No other executable: every executable= argument is EXECUTABLES[...].
    calls = [kw.value for node in ast.walk(ast.parse(LAUNCH.read_text()))
             if isinstance(node, ast.Call) for kw in node.keywords if kw.arg == 'executable']
    assert calls and all(isinstance(v, ast.Subscript) and v.value.id == 'EXECUTABLES'
                         for v in calls)


def test_remappable_topics_are_the_nodes():
    # That they are the running node's topics: test_node_topics.py.
    constants = module_constants(LAUNCH)
    assert set(constants['TOPICS']) == {
        'wrist_wrench', 'audio', 'audio_info', 'contact', 'contact_probability', 'release'}
    for robot in constants['ROBOTS'].values():
        assert set(robot['remap']) <= set(constants['TOPICS'])
    hsr = constants['ROBOTS']['hsr']
    assert hsr['remap'] == {'wrist_wrench': '/hsrb/wrist_wrench/raw', 'audio': '/audio'}


def flat(tree: dict, prefix: str = '') -> dict:
    values = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            values.update(flat(value, f'{prefix}{key}.'))
        else:
            values[f'{prefix}{key}'] = value
    return values


def test_hsr_preset_sets_known_parameters():
    values = flat(yaml.safe_load((ROOT / 'params' / 'hsr.yaml').read_text())
                  ['/**']['ros__parameters'])
    assert values['gripper.enabled'] is True
    assert values['gripper.topic'] == '/gripper_controller/joint_trajectory'
    for name, value in values.items():
        assert name in PARAMS_BY_NAME, name
        assert type(value) is type(PARAMS_BY_NAME[name].default), name


@pytest.mark.skipif(importlib.util.find_spec('launch_ros') is None,
                    reason='launch and launch_ros have no wheel; they come with a ROS install')
def test_launch_description_builds():
    from launch.actions import DeclareLaunchArgument
    import runpy

    description = runpy.run_path(str(LAUNCH))['generate_launch_description']()
    arguments = {entity.name for entity in description.entities
                 if isinstance(entity, DeclareLaunchArgument)}
    assert set(module_constants(LAUNCH)['TOPICS']) <= arguments
    assert {'robot', 'namespace', 'params_file', 'managed'} <= arguments
