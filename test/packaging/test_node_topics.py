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

"""The launch file's remappable topics are the relative topic names the running node uses."""

import importlib.util

from contact_detector.io.messages import AUDIO_MSG_TYPES
from contact_detector.ros.node import ContactDetectorNode
import pytest
from rclpy.parameter import Parameter
from test_launch import LAUNCH, module_constants

pytestmark = pytest.mark.rclpy

NAMESPACE = '/robot_ns'


def relative_topics(node) -> set:
    """Topics of the node's subscriptions and publishers given as relative (remappable) names."""
    # In a namespace, a relative name resolves under it; absolute ones (/diagnostics,
    # /rosout, /parameter_events, the gripper's) do not.
    names = [e.topic_name for e in (*node.subscriptions, *node.publishers)]
    return {name[len(NAMESPACE) + 1:] for name in names if name.startswith(NAMESPACE + '/')}


def make_node(context, model, **params):
    values = {'model.path': str(model), 'gripper.enabled': True}
    values.update(params)
    return ContactDetectorNode(context=context, namespace=NAMESPACE, parameter_overrides=[
        Parameter(name, value=value) for name, value in values.items()])


def test_launch_topics_are_the_nodes_relative_topics(context, model):
    launch_topics = set(module_constants(LAUNCH)['TOPICS'])
    node = make_node(context, model)
    try:
        used = relative_topics(node)
        assert {sub.topic_name for sub in node.subscriptions} == {
            f'{NAMESPACE}/wrist_wrench', f'{NAMESPACE}/audio'}
    finally:
        node.destroy_node()
    assert used == {'wrist_wrench', 'audio', 'contact', 'contact_probability', 'release'}
    # audio_info is subscribed to only with the ros-drivers audio_common types.
    assert launch_topics - used == {'audio_info'}


def test_audio_info_is_subscribed_with_ros_drivers_audio(context, model):
    spec = next(s for s in AUDIO_MSG_TYPES.values() if s.info_topic)
    if importlib.util.find_spec(spec.package) is None:
        pytest.skip(f'{spec.package} ({spec.source}) is not installed here')
    node = make_node(context, model, **{'audio.msg_type': spec.name})
    try:
        assert 'audio_info' in relative_topics(node)
    finally:
        node.destroy_node()
