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
        'test': ['pytest>=7', 'hypothesis>=6.80', 'flake8>=6', 'flake8-quotes>=3.3',
                 'pydocstyle>=6.3', 'psutil>=5.9'],
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
