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
The opt-in ``hot_path`` executor (private rclpy API) against the default public one.

``contact_detector.ros.executor`` uses rclpy internals; these tests pin the rclpy versions it
was checked with and check that it decides a trial exactly as rclpy's SingleThreadedExecutor
(the node's default) does. On a new rclpy, run them, and add the version to
``CHECKED_RCLPY_VERSIONS`` once they pass.
"""

import subprocess
import sys

from contact_detector.ros.executor import CHECKED_RCLPY_VERSIONS, rclpy_version
import node_support
import numpy as np
import pytest
# The node harness and its fixtures (a module-scoped trial, a harness per test).
from test_node import harness_factory, trial  # noqa: F401

pytestmark = pytest.mark.rclpy


def test_rclpy_is_a_version_the_hot_path_was_checked_with():
    version = rclpy_version()
    assert version in CHECKED_RCLPY_VERSIONS, (
        f'executor.type hot_path uses private rclpy API and was checked with rclpy '
        f'{CHECKED_RCLPY_VERSIONS}, not {version}: if the tests of this module pass, add it to '
        'contact_detector.ros.executor.CHECKED_RCLPY_VERSIONS')


def test_hot_path_decides_a_trial_as_the_public_executor(harness_factory, trial):  # noqa: F811
    events = node_support.trial_events(trial, t_from=trial.onset_t - 2.0,
                                       t_to=trial.onset_t + 1.0)
    outputs = {}
    for executor in ('single', 'hot_path'):
        h = harness_factory(executor=executor)
        h.feed(trial, events)
        h.flush_outputs()
        counts = h.node.detector_counts()
        outputs[executor] = ([m.data for m in h.contact], [m.data for m in h.prob],
                             [m.data for m in h.release], counts['frames'],
                             counts['callback_errors'], counts['audio_dropped'])
    single, hot = outputs['single'], outputs['hot_path']
    assert single[3] > 200 and single[4] == 0 and single[5] == 0
    assert single[2] == [True]          # the contact released once
    assert hot[3:] == single[3:]
    assert hot[0] == single[0] and hot[2] == single[2]
    np.testing.assert_array_equal(hot[1], single[1])


def test_default_executor_uses_public_rclpy_api_only(model):
    # In a fresh process: the node built and its executor made with default parameters never
    # imports the module that holds the private-API executor.
    code = (
        'import sys, rclpy\n'
        'from rclpy.executors import SingleThreadedExecutor\n'
        'from rclpy.parameter import Parameter\n'
        'from contact_detector.ros.node import ContactDetectorNode, make_executor\n'
        'rclpy.init()\n'
        f'node = ContactDetectorNode(parameter_overrides=[Parameter("model.path", '
        f'value={str(model)!r})])\n'
        'executor = make_executor(node)\n'
        'print(type(executor) is SingleThreadedExecutor, '
        '"contact_detector.ros.executor" in sys.modules)\n'
        'executor.shutdown()\n'
        'node.destroy_node()\n'
        'rclpy.try_shutdown()\n')
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-2:] == ['True', 'False'], out.stdout


def test_hot_path_is_opt_in_by_parameter(context, model):
    from contact_detector.ros.executor import HotPathExecutor
    from contact_detector.ros.node import ContactDetectorNode, make_executor
    from rclpy.parameter import Parameter

    node = ContactDetectorNode(context=context, parameter_overrides=[
        Parameter('model.path', value=str(model)),
        Parameter('executor.type', value='hot_path')])
    try:
        executor = make_executor(node)
        assert isinstance(executor, HotPathExecutor)
        executor.shutdown()
    finally:
        node.destroy_node()
