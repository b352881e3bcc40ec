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
Launch the contact detector node with its params file, remappings and a namespace.

Examples::

    ros2 launch contact_detector contact_detector.launch.py                # generic robot
    ros2 launch contact_detector contact_detector.launch.py robot:=hsr     # Toyota HSR
    ros2 launch contact_detector contact_detector.launch.py namespace:=left_arm \
        wrist_wrench:=/left/ft_sensor/wrench audio:=/mic/audio managed:=true

``ros2 launch contact_detector contact_detector.launch.py --show-args`` lists the arguments.
The parameters come from ``params/contact_detector.yaml``, then the robot preset's file
(``robot:=hsr``: ``params/hsr.yaml``), then ``params_file`` if given (later files win).
An empty topic argument keeps the robot preset's remapping (or none). ``managed:=true`` starts
the lifecycle node; with ``autostart:=true`` (default) this file configures and activates it.
See docs/node.md.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, EmitEvent, OpaqueFunction, RegisterEventHandler
from launch.events import matches_action
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import LifecycleNode, Node
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from lifecycle_msgs.msg import Transition

PACKAGE = 'contact_detector'
#: Executable run for managed:=false / managed:=true (console scripts of setup.py).
EXECUTABLES = {'false': 'contact_detector_node', 'true': 'contact_detector_lifecycle_node'}
#: The params file every robot starts from (share/contact_detector/params/).
BASE_PARAMS = 'contact_detector.yaml'
#: Robot presets: an extra params file (loaded after BASE_PARAMS) and input remappings.
ROBOTS = {
    'generic': {'params': None, 'remap': {}},
    'hsr': {'params': 'hsr.yaml',
            'remap': {'wrist_wrench': '/hsrb/wrist_wrench/raw', 'audio': '/audio'}},
}
#: The node's topics that a launch argument of the same name remaps.
TOPICS = ('wrist_wrench', 'audio', 'audio_info', 'contact', 'contact_probability', 'release')


def _arguments() -> list:
    arguments = [
        DeclareLaunchArgument('robot', default_value='generic', choices=list(ROBOTS),
                              description='Robot preset: params file and input remappings.'),
        DeclareLaunchArgument('namespace', default_value='',
                              description='Namespace of the node (its relative topics too).'),
        DeclareLaunchArgument('node_name', default_value=PACKAGE, description='Node name.'),
        DeclareLaunchArgument('params_file', default_value='',
                              description='Extra params file loaded last; empty = none.'),
        DeclareLaunchArgument('model_path', default_value='',
                              description='model.path; empty = the params files (shipped '
                                          'model by default).'),
        DeclareLaunchArgument('managed', default_value='false', choices=list(EXECUTABLES),
                              description='Run the lifecycle (managed) node.'),
        DeclareLaunchArgument('autostart', default_value='true', choices=['true', 'false'],
                              description='managed:=true: configure and activate at start.'),
        DeclareLaunchArgument('use_sim_time', default_value='false',
                              choices=['true', 'false'],
                              description='Use /clock (bag replay with --clock).'),
        DeclareLaunchArgument('log_level', default_value='info',
                              description='Log level of the node.'),
    ]
    arguments += [DeclareLaunchArgument(topic, default_value='',
                                        description=f'Remap {topic} to this topic; empty = '
                                                    "the robot preset's or none.")
                  for topic in TOPICS]
    return arguments


def _launch_setup(context, *args, **kwargs) -> list:
    def arg(name: str) -> str:
        return LaunchConfiguration(name).perform(context)

    robot = ROBOTS[arg('robot')]
    share = get_package_share_directory(PACKAGE)
    parameters = [os.path.join(share, 'params', BASE_PARAMS)]
    if robot['params']:
        parameters.append(os.path.join(share, 'params', robot['params']))
    if arg('params_file'):
        parameters.append(arg('params_file'))
    overrides = {'use_sim_time': arg('use_sim_time') == 'true'}
    if arg('model_path'):
        overrides['model.path'] = arg('model_path')
    parameters.append(overrides)
    remap = dict(robot['remap'])
    remap.update({topic: arg(topic) for topic in TOPICS if arg(topic)})
    common = {'package': PACKAGE, 'name': arg('node_name'), 'namespace': arg('namespace'),
              'parameters': parameters, 'remappings': list(remap.items()), 'output': 'screen',
              'ros_arguments': ['--log-level', arg('log_level')]}
    managed = arg('managed')
    if managed == 'false':
        return [Node(executable=EXECUTABLES[managed], **common)]
    node = LifecycleNode(executable=EXECUTABLES[managed], **common)
    actions = [node]
    if arg('autostart') == 'true':
        actions += [
            RegisterEventHandler(OnStateTransition(
                target_lifecycle_node=node, goal_state='inactive',
                entities=[EmitEvent(event=ChangeState(
                    lifecycle_node_matcher=matches_action(node),
                    transition_id=Transition.TRANSITION_ACTIVATE))])),
            EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(node),
                                        transition_id=Transition.TRANSITION_CONFIGURE)),
        ]
    return actions


def generate_launch_description() -> LaunchDescription:
    """Return the launch description (``ros2 launch`` calls this)."""
    return LaunchDescription(_arguments() + [OpaqueFunction(function=_launch_setup)])
