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
Where the shipped models are found without ROS.

``models/contact_forest.npz`` (and the F/T-only ``contact_forest_ft.npz``) are installed to
``<prefix>/share/contact_detector/models/`` by ``setup.py``'s data files (pip, colcon) and sit
in ``models/`` of a source checkout. This module finds them from the package's own location,
so the offline tools need no ROS; the node also asks the ament index first
(:mod:`contact_detector.ros.model_search`).
"""

from pathlib import Path
import sys
from typing import Sequence

import contact_detector
from contact_detector.errors import ModelError
from contact_detector.model.bundle import RETRAIN

#: File name of the shipped model (in ``<share>/contact_detector/models/``).
DEFAULT_MODEL_NAME = 'contact_forest.npz'
#: File name of the shipped F/T-only model (robots without a microphone), beside it.
FT_ONLY_MODEL_NAME = 'contact_forest_ft.npz'


def model_dirs() -> list:
    """
    Directories searched for the shipped models without ROS, in order.

    ``<prefix>/share/contact_detector/models`` of the installation that holds this package
    (``<prefix>/lib/pythonX.Y/site-packages/contact_detector``), then that of the running
    interpreter (``sys.prefix``), then the source checkout's ``models/``.
    """
    package = Path(contact_detector.__file__).resolve().parent
    dirs = []
    if package.parent.name in ('site-packages', 'dist-packages'):
        dirs.append(package.parents[3] / 'share' / 'contact_detector' / 'models')
    dirs.append(Path(sys.prefix) / 'share' / 'contact_detector' / 'models')
    dirs.append(package.parent / 'models')
    return list(dict.fromkeys(dirs))


def find_model(*, name: str = DEFAULT_MODEL_NAME, dirs: Sequence[Path]) -> Path:
    """
    Return the first ``<dir>/<name>`` that exists.

    Raises
    ------
    ModelError
        If none exists; the message lists the directories searched.

    """
    for directory in dirs:
        candidate = Path(directory) / name
        if candidate.is_file():
            return candidate
    searched = ', '.join(str(d) for d in dirs)
    raise ModelError(f'no {name} found (searched {searched}); pass a model path, or '
                     f'{RETRAIN} and save it as models/{name}')


def default_model_path() -> Path:
    """
    Path of the shipped model ``models/contact_forest.npz``, found without ROS.

    Searched in :func:`model_dirs`.

    Raises
    ------
    ModelError
        If no shipped model exists.

    """
    return find_model(dirs=model_dirs())


def default_ft_model_path() -> Path:
    """
    Path of the shipped F/T-only model ``models/contact_forest_ft.npz``, found without ROS.

    Searched in :func:`model_dirs`.

    Raises
    ------
    ModelError
        If no shipped F/T-only model exists.

    """
    return find_model(name=FT_ONLY_MODEL_NAME, dirs=model_dirs())
