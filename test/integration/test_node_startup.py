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
The node as a user starts it: integers for float parameters, quiet until the first input.

Real rclpy, in-process; the node's log lines are read from /rosout, as ``ros2 launch`` and
``rqt_console`` see them.
"""

import dataclasses
import math
import time

from contact_detector.ros.node import ContactDetectorNode
from contact_detector.ros.params import NodeConfig, PARAMS
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
import node_support
import pytest
from rcl_interfaces.msg import Log
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Int16MultiArray

pytestmark = pytest.mark.rclpy

FLOAT_PARAMS = [spec for spec in PARAMS if isinstance(spec.default, float)]


def as_int(value: float) -> int:
    """Return an integer inside the parameter's range near its default (0.05 -> 1)."""
    return int(math.ceil(value))


def float_fields(config: NodeConfig) -> dict:
    return {f.name: getattr(config, f.name) for f in dataclasses.fields(config)
            if f.type in (float, 'float')}


# --- integers for float parameters ---------------------------------------------------------------

def test_integers_for_every_float_parameter(context, model):
    overrides = [Parameter('model.path', value=str(model))]
    ints = {spec.name: as_int(spec.default) for spec in FLOAT_PARAMS}
    ints['release.refractory_s'] = 2          # overrides the model's rule
    overrides += [Parameter(name, value=value) for name, value in ints.items()]
    assert all(p.type_ == Parameter.Type.INTEGER for p in overrides[1:])
    node = ContactDetectorNode(context=context, parameter_overrides=overrides)
    try:
        values = float_fields(node.config)
        assert len(values) == 15          # every float field of NodeConfig
        assert node.config.release_overrides == {'refractory_s': 2.0}
        assert type(node.detector.rule.refractory_s) is float
        assert all(type(v) is float for v in values.values()), values
        assert node.config.audio_sample_rate == 16000.0
        assert node.config.executor_poll_s == 1.0 and node.config.gripper_position == 2.0
        assert type(node.detector.settings.audio_rate) is float
        assert node.detector.rule.threshold == node.bundle.decision_rule.threshold  # -1: model's
        # At run time too; a string is still refused and the value kept.
        assert node.set_parameters([Parameter('max_input_delay_s', value=1)])[0].successful
        assert type(node.config.max_input_delay_s) is float
        assert node.detector.settings.max_input_delay_s == 1.0
        refused = node.set_parameters([Parameter('max_input_delay_s', value='0.3')])[0]
        assert not refused.successful and 'must be a float' in refused.reason
        assert node.config.max_input_delay_s == 1.0
        assert not node.set_parameters([Parameter('warmup_s', value=-3)])[0].successful
    finally:
        node.destroy_node()


def test_integers_from_the_command_line_and_a_params_file(model, tmp_path):
    params = tmp_path / 'ints.yaml'
    params.write_text('/**:\n  ros__parameters:\n    wrench:\n      rate: 100\n'
                      '    warmup_s: 1\n')
    ctx = Context()
    rclpy.init(context=ctx, args=['--ros-args', '--params-file', str(params),
                                  '-p', f'model.path:={model}',
                                  '-p', 'audio.sample_rate:=44100'])
    try:
        node = ContactDetectorNode(context=ctx)
        assert (node.config.audio_sample_rate, node.config.wrench_rate,
                node.config.warmup_s) == (44100.0, 100.0, 1.0)
        assert all(type(v) is float for v in float_fields(node.config).values())
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


def test_hsr_preset_params_file_on_top_of_the_default(model):
    # What the launch file's robot:=hsr passes: both files, the preset last.
    params = node_support.REPO / 'params'
    ctx = Context()
    rclpy.init(context=ctx, args=['--ros-args',
                                  '--params-file', str(params / 'contact_detector.yaml'),
                                  '--params-file', str(params / 'hsr.yaml'),
                                  '-p', f'model.path:={model}'])
    try:
        node = ContactDetectorNode(context=ctx)
        assert node.config.gripper_enabled and node.gripper_pub is not None
        assert node.gripper_pub.topic_name == '/gripper_controller/joint_trajectory'
        assert node.config.audio_sample_rate == 16000.0       # from contact_detector.yaml
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


# --- waiting for input ---------------------------------------------------------------------------

class Watcher:
    """A helper node that records /diagnostics and the node's /rosout lines."""

    def __init__(self, context, node):
        self.node = node
        self.io = rclpy.create_node('watcher', context=context)
        self.diag, self.logs = [], []
        self.io.create_subscription(DiagnosticArray, '/diagnostics', self.diag.append, 100)
        logs_qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.io.create_subscription(Log, '/rosout', self._on_log, logs_qos)
        self.wrench_pub = self.io.create_publisher(WrenchStamped, 'wrist_wrench', 10)
        self.audio_pub = self.io.create_publisher(Int16MultiArray, 'audio', 10)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(node)
        self.executor.add_node(self.io)
        # The node's log lines are read from /rosout: wait until one of its lines arrives
        # (the graph may still list a node of the same name from an earlier test).
        end = time.monotonic() + 10.0
        while not any(log.msg == 'test: rosout ready' for log in self.logs):
            assert time.monotonic() < end, 'no /rosout from the node'
            node.get_logger().info('test: rosout ready')
            self.spin_for(0.05)
        self.logs[:] = [log for log in self.logs if log.msg != 'test: rosout ready']

    def _on_log(self, msg: Log) -> None:
        if msg.name == self.node.get_logger().name:
            self.logs.append(msg)

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def spin_until(self, predicate, timeout: float = 10.0) -> None:
        node_support.spin_until(self.executor, predicate, timeout=timeout)

    def lines(self, level: int, text: str) -> list:
        return [m.msg for m in self.logs if m.level == level and text in m.msg]

    def close(self) -> None:
        self.executor.shutdown()
        self.io.destroy_node()
        self.node.destroy_node()


def test_waiting_for_input_is_said_once_then_stale_input_warns(context, model):
    # A name of its own: rcl keeps one /rosout publisher per logger name and process.
    node = ContactDetectorNode('contact_detector_waiting', context=context, parameter_overrides=[
        Parameter('model.path', value=str(model)),
        Parameter('diagnostics.period_s', value=0.1), Parameter('log_throttle_s', value=0.5),
        Parameter('max_input_delay_s', value=0.2),
        Parameter('wrench.stamp_source', value='receive')])
    w = Watcher(context, node)
    try:
        # No sensor has started: one INFO line, /diagnostics says so, no warning at all
        # (it used to warn 'stale or missing input' every log_throttle_s).
        w.spin_until(lambda: len(w.diag) >= 10)
        w.spin_for(0.3)
        statuses = [d.status[0] for d in w.diag]
        assert {(s.level, s.message) for s in statuses} == {
            (DiagnosticStatus.WARN, 'waiting for input: audio, wrench')}
        assert len(w.lines(Log.INFO, 'waiting for input')) == 1
        assert [m.msg for m in w.logs if m.level >= Log.WARN] == []

        # The sensors start, then stop: now missing input is a fault, warned (throttled).
        w.spin_until(lambda: w.wrench_pub.get_subscription_count() > 0
                     and w.audio_pub.get_subscription_count() > 0)
        for _ in range(3):
            w.wrench_pub.publish(WrenchStamped())
            w.audio_pub.publish(Int16MultiArray(data=[0] * 160))
            w.spin_for(0.02)
        w.spin_until(lambda: node.audio.received == 3 and node.wrench.received == 3)
        n, start = len(w.diag), time.monotonic()
        w.spin_until(lambda: len(w.diag) >= n + 15)
        w.spin_for(0.2)
        span = time.monotonic() - start
        after = [d.status[0] for d in w.diag[n:]]
        stale = [s for s in after if s.message == 'stale or missing input: audio, wrench']
        assert len(stale) >= 10 and all(s.level == DiagnosticStatus.WARN for s in stale)
        assert not any(s.message.startswith('waiting') for s in after[1:])
        assert w.lines(Log.INFO, 'audio input started') and \
            w.lines(Log.INFO, 'wrench input started')
        warned = w.lines(Log.WARN, 'stale or missing input')
        # A status every 0.1 s, a warning at most every 0.5 s (log_throttle_s).
        assert 1 <= len(warned) <= span / 0.5 + 1
        assert len(warned) < len(stale) / 2
        assert len(w.lines(Log.INFO, 'waiting for input')) == 1
    finally:
        w.close()
