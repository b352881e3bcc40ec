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

"""The node's YAML parameter file, read without ROS (for the offline tools' ``--params``)."""

from pathlib import Path

from contact_detector.errors import ConfigError


def read_node_params(path: Path) -> dict:
    """
    Return the node's parameters from a ROS 2 YAML parameter file, flattened ('a.b': v).

    Raises
    ------
    ConfigError
        If the file cannot be read or has no ``ros__parameters`` section.

    """
    import yaml
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as err:
        raise ConfigError(f'cannot read parameter file {path}: {err}') from err
    section = None
    for value in (data or {}).values():
        if isinstance(value, dict) and 'ros__parameters' in value:
            section = value['ros__parameters']
            break
    if section is None:
        raise ConfigError(f'{path} has no "<node>: ros__parameters:" section')
    flat = {}

    def walk(prefix, node):
        for key, value in node.items():
            name = f'{prefix}.{key}' if prefix else key
            if isinstance(value, dict):
                walk(name, value)
            else:
                flat[name] = value
    walk('', section)
    return flat
