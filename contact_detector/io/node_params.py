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

import fnmatch
from pathlib import Path
from typing import Any, Dict, List

from contact_detector.errors import ConfigError

#: The node's name: the sections of a parameter file that apply to it are ``/**``, ``**``
#: and those whose last name component matches it (``contact_detector``,
#: ``/robot/contact_detector``, ``/**/contact_*``); the executable's name is accepted too.
NODE_NAMES = ('contact_detector', 'contact_detector_node')


def _applies(key: str) -> bool:
    # ROS 2 matches a section's key against the node's fully qualified name; offline the
    # namespace is unknown, so only the last component is compared
    if key.strip('/') in ('**', '*'):
        return True
    last = key.rstrip('/').rsplit('/', 1)[-1]
    return any(fnmatch.fnmatchcase(name, last) for name in NODE_NAMES)


def read_node_params(path: Path) -> Dict[str, Any]:
    """
    Return the node's parameters from a ROS 2 YAML parameter file, flattened ('a.b': v).

    A file with one ``<node>: ros__parameters:`` section is read whatever the node is called
    there. A file with several (a robot's bring-up file) is read as the node would: the
    sections for every node (``/**``) and for the contact detector, merged in file order.

    Parameters
    ----------
    path : Path
        The YAML file.

    Returns
    -------
    dict
        Dotted parameter name -> value, as written (not checked; see
        :func:`contact_detector.detection.parameters.read_param_file`).

    Raises
    ------
    ConfigError
        If the file cannot be read or decoded, is not a mapping of node sections, or has no
        ``ros__parameters`` section for the node.

    """
    import yaml
    try:
        data = yaml.safe_load(Path(path).read_text(encoding='utf-8'))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        raise ConfigError(f'cannot read parameter file {path}: {err}') from err
    if not isinstance(data, dict):
        raise ConfigError(f'{path} is not a ROS 2 parameter file: its top level must map '
                          'node names to "ros__parameters:" sections')
    sections = [(str(key), value['ros__parameters']) for key, value in data.items()
                if isinstance(value, dict) and 'ros__parameters' in value]
    if len(sections) > 1:
        sections = [(key, section) for key, section in sections if _applies(key)]
    if not sections:
        raise ConfigError(f'{path} has no "<node>: ros__parameters:" section for the contact '
                          f'detector (sections: {", ".join(map(str, data)) or "none"})')
    flat: Dict[str, Any] = {}

    def walk(prefix: str, node: Any, trail: List[str]) -> None:
        if not isinstance(node, dict):
            raise ConfigError(f'{path}: {" / ".join(trail)}: ros__parameters must be a '
                              f'mapping of parameter names to values, got {node!r}')
        for key, value in node.items():
            name = f'{prefix}.{key}' if prefix else str(key)
            if isinstance(value, dict):
                walk(name, value, trail + [str(key)])
            else:
                flat[name] = value
    for key, section in sections:
        if section is not None:         # an empty section sets nothing
            walk('', section, [key])
    return flat
