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
The node's search for the shipped models: the ament index first, then the package's own places.

In a sourced ROS workspace the models live in the ament share directory of
``contact_detector``; elsewhere :func:`contact_detector.model.shipped.model_dirs` finds them
from the package's location (no ROS needed, which is what the offline tools use).
"""

from pathlib import Path

from contact_detector.model.shipped import find_model, FT_ONLY_MODEL_NAME, model_dirs


def node_model_dirs() -> list:
    """
    Directories the node searches for the shipped models, in order.

    ``<ament share of contact_detector>/models`` if ament_index_python is importable and the
    package is installed in a sourced workspace, then
    :func:`~contact_detector.model.shipped.model_dirs`.
    """
    dirs = []
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:
        pass
    else:
        try:
            dirs.append(Path(get_package_share_directory('contact_detector')) / 'models')
        except (LookupError, OSError, ValueError):
            pass  # not installed in a sourced ROS workspace
    return list(dict.fromkeys(dirs + model_dirs()))


def default_model_path() -> Path:
    """
    Path of the shipped model ``models/contact_forest.npz``, searched in :func:`node_model_dirs`.

    Raises
    ------
    ModelError
        If no shipped model exists.

    """
    return find_model(dirs=node_model_dirs())


def default_ft_model_path() -> Path:
    """
    Path of the shipped F/T-only model ``contact_forest_ft.npz``, searched like the full one.

    Raises
    ------
    ModelError
        If no shipped F/T-only model exists.

    """
    return find_model(name=FT_ONLY_MODEL_NAME, dirs=node_model_dirs())
