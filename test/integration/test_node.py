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
The live node in-process, with real rclpy: topics, services, parameters, bad input, time.

Every test gets its own rclpy context. Messages go through DDS (loopback, see conftest.py);
time is simulated (``use_sim_time``, the test publishes ``/clock`` like ``ros2 bag play
--clock``), so a trial is fed as fast as the node takes it and the node's per-frame output
can be compared with :class:`ContactDetector` run offline on the same arrays and stamps.
"""

from dataclasses import replace
import importlib.util
import os
from pathlib import Path
import struct
import subprocess
import sys

from contact_detector.detection.detector import ContactDetector
from contact_detector.errors import ConfigError, ModelError
from contact_detector.model.storage import load_bundle
from contact_detector.ros.executor import HotPathExecutor
from contact_detector.ros.node import ContactDetectorNode
from contact_detector.ros.params import PARAMS
from contact_detector.sim.trial import simulate_trial
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
import node_support
import numpy as np
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Bool, Float32, Float32MultiArray, Int16MultiArray
from std_srvs.srv import SetBool, Trigger
from trajectory_msgs.msg import JointTrajectory

pytestmark = pytest.mark.rclpy

TICK_S = 0.01              # /clock period of the simulated bag player
TRIAL = {'seed': 3, 'index': 21, 'hits': 'hand'}  # in-air hand hits 1.5 s and 1.1 s before onset


@pytest.fixture(scope='module')
def trial():
    return simulate_trial(**TRIAL)


stamp = node_support.stamp


def wrench_msg(t, force, torque) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.stamp = stamp(float(t))
    msg.header.frame_id = 'wrist_ft_sensor_frame'
    f, m = msg.wrench.force, msg.wrench.torque
    f.x, f.y, f.z = (float(v) for v in force)
    m.x, m.y, m.z = (float(v) for v in torque)
    return msg


class Harness:
    """The node under test plus a helper node that feeds it and records what it publishes."""

    def __init__(self, context, model, *, audio_type=Int16MultiArray, executor='single',
                 **params):
        values = {'model.path': str(model), 'use_sim_time': True,
                  'qos.reliability': 'reliable', 'qos.depth': 1000,
                  'diagnostics.period_s': 0.5}
        values.update(params)
        self.node = ContactDetectorNode(
            context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in values.items()])
        self.io = rclpy.create_node('test_io', context=context)
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.clock_pub = self.io.create_publisher(Clock, '/clock', 10)
        self.wrench_pub = self.io.create_publisher(WrenchStamped, 'wrist_wrench', reliable)
        self.audio_pub = self.io.create_publisher(audio_type, 'audio', reliable)
        self.contact, self.prob, self.release, self.diag, self.gripper = [], [], [], [], []
        for msg_type, topic, sink in ((Bool, 'contact', self.contact),
                                      (Float32, 'contact_probability', self.prob),
                                      (Bool, 'release', self.release),
                                      (DiagnosticArray, '/diagnostics', self.diag),
                                      (JointTrajectory, '/gripper_controller/joint_trajectory',
                                       self.gripper)):
            self.io.create_subscription(msg_type, topic, sink.append, reliable)
        self.arm = self.io.create_client(SetBool, 'contact_detector/arm')
        self.reset = self.io.create_client(Trigger, 'contact_detector/reset')
        if executor == 'hot_path':
            self.executor = HotPathExecutor(hot=self.node.subscriptions, poll_s=0.01,
                                            context=context)
        elif executor == 'lazy_wrench':
            self.executor = HotPathExecutor(hot=self.node.subscriptions, poll_s=0.01,
                                            lazy=[self.node.wrench_sub],
                                            wanted=self.node.wrench_wanted, lazy_max_s=30.0,
                                            context=context)
        else:
            self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.io)
        self.clock_t = None
        self.spin_until(lambda: all(p.get_subscription_count() > 0 for p in (
            self.clock_pub, self.wrench_pub, self.audio_pub)) and len(
            self.io.get_publishers_info_by_topic('/release')) > 0)

    def spin_until(self, predicate, timeout=10.0):
        node_support.spin_until(self.executor, predicate, timeout=timeout)

    def set_clock(self, t: float) -> None:
        self.clock_pub.publish(Clock(clock=stamp(t)))
        target = stamp(t)
        want = target.sec * 1_000_000_000 + target.nanosec
        self.spin_until(lambda: self.node.get_clock().now().nanoseconds == want)
        self.clock_t = t

    def send_wrench(self, msg) -> None:
        n = self.node.wrench.received
        self.wrench_pub.publish(msg)
        self.spin_until(lambda: self.node.wrench.received > n)

    def send_audio(self, msg) -> None:
        n = self.node.audio.received
        self.audio_pub.publish(msg)
        self.spin_until(lambda: self.node.audio.received > n)

    def feed(self, trial, events, *, offset=0.0, wrench_offset=0.0):
        """
        Feed events in order, /clock stepping in TICK_S; return the (receive time, event) list.

        ``offset`` shifts the clock and every stamp, ``wrench_offset`` the wrench stamps only.
        """
        fed = []
        for e in events:
            tick = offset + np.floor((e.t - trial.start_time) / TICK_S) * TICK_S \
                + trial.start_time
            if self.clock_t is None or tick > self.clock_t + 1e-9:
                self.set_clock(tick)
            if e.kind == 'audio':
                self.send_audio(Int16MultiArray(data=trial.audio[e.lo:e.hi].tolist()))
            else:
                j = e.lo
                self.send_wrench(wrench_msg(trial.wrench_t[j] + offset + wrench_offset,
                                            trial.force[j], trial.torque[j]))
            fed.append((self.clock_t, e))
        return fed

    def flush_outputs(self):
        """Spin until every published frame has arrived at the helper node."""
        frames = self.node.detector_counts()['contact_msgs']
        self.spin_until(lambda: len(self.contact) >= frames and len(self.prob) >= frames)
        for _ in range(20):
            self.executor.spin_once(timeout_sec=0.005)

    def call(self, client, request):
        assert client.wait_for_service(timeout_sec=5.0)
        future = client.call_async(request)
        self.spin_until(future.done)
        return future.result()

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.io.destroy_node()


@pytest.fixture
def harness_factory(context, model):
    made = []

    def make(**kwargs):
        made.append(Harness(context, model, **kwargs))
        return made[-1]
    yield make
    for h in made:
        h.close()


def offline_run(model, trial, fed, **settings):
    """Run the same arrays and stamps through ContactDetector directly (no ROS)."""
    bundle = load_bundle(path=model)
    from contact_detector.detection.detector import DetectorSettings
    det = ContactDetector(bundle=bundle, settings=DetectorSettings(
        audio_rate=trial.audio_rate, wrench_rate=trial.ft_rate, **settings))
    p, contact, releases = [], [], []
    for now, e in fed:
        if e.kind == 'audio':
            d = det.on_audio(trial.audio[e.lo:e.hi], stamp=now, now=now)
        else:
            d = det.on_wrench(t=trial.wrench_t[e.lo:e.hi], force=trial.force[e.lo:e.hi],
                              torque=trial.torque[e.lo:e.hi], now=now)
        p.extend(d.p)
        contact.extend(d.contact)
        releases.extend(d.releases)
    return np.array(p), np.array(contact, dtype=bool), releases


def capture_log(node) -> dict:
    """Return {'info': [...], 'warning': [...]}, filled with the node's log lines from now on."""
    logged = {'info': [], 'warning': []}
    logger = node.get_logger()
    # one wrapper per severity: rclpy refuses two severities from one call site
    info, warning = logger.info, logger.warning
    logger.info = lambda text, *a, **k: (logged['info'].append(text), info(text, *a, **k))
    logger.warning = lambda text, *a, **k: (logged['warning'].append(text),
                                            warning(text, *a, **k))
    return logged


def diag_values(harness):
    status = harness.diag[-1].status[0]
    return status, {kv.key: kv.value for kv in status.values}


# --- a trial end to end --------------------------------------------------------------------------

def test_trial_frames_and_single_release(harness_factory, model, trial):
    h = harness_factory(**{'gripper.enabled': True})
    events = node_support.trial_events(trial, t_from=trial.onset_t - 2.5,
                                       t_to=trial.onset_t + 1.5)
    fed = h.feed(trial, events)
    h.flush_outputs()
    p, contact, releases = offline_run(model, trial, fed)
    counts = h.node.detector_counts()
    # One Bool and one Float32 per audio frame, equal to the offline detector's decisions.
    assert counts['frames'] == len(p) == len(h.contact) == len(h.prob) > 300
    np.testing.assert_array_equal([m.data for m in h.contact], contact)
    np.testing.assert_array_equal([m.data for m in h.prob], p.astype(np.float32))
    # Exactly one release, after the true onset; in-air hits (before it) released nothing.
    assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.3
    assert [m.data for m in h.release] == [True]
    assert counts['releases'] == 1 and not h.node.detector.armed
    assert h.gripper[0].joint_names == ['hand_motor_joint']
    assert h.gripper[0].points[0].positions[0] == pytest.approx(1.2)
    status, values = diag_values(h)
    assert values['model_id'] == load_bundle(path=model).model_id
    assert float(values['latency_p99_ms']) > 0
    assert values['audio_dropped'] == '0' and values['callback_errors'] == '0'
    assert float(values['wrench_age_s']) < 0.1


@pytest.mark.parametrize('executor', ['single', 'hot_path'])
def test_arm_and_reset_services(harness_factory, trial, executor):
    h = harness_factory(executor=executor, **{'release.armed_on_start': False})
    span = {'t_from': trial.onset_t - 1.5, 't_to': trial.onset_t + 0.5}
    h.feed(trial, node_support.trial_events(trial, **span))
    h.flush_outputs()
    counts = h.node.detector_counts()
    assert counts['events'] >= 1 and counts['releases'] == 0 and h.release == []

    assert h.call(h.arm, SetBool.Request(data=True)).success
    assert h.node.detector.armed
    reply = h.call(h.reset, Trigger.Request())
    assert reply.success and 'armed' in reply.message
    assert h.node.detector.extractor.pending == 0
    # The same contact replayed 100 s later (a second trial run): now armed, one release.
    h.feed(trial, node_support.trial_events(trial, **span), offset=100.0)
    h.flush_outputs()
    assert [m.data for m in h.release] == [True]
    assert h.node.detector_counts()['releases'] == 1 and not h.node.detector.armed
    assert h.call(h.arm, SetBool.Request(data=False)).message == 'release disarmed'


def test_lazy_wrench_is_taken_with_the_next_audio(harness_factory, model, trial):
    h = harness_factory(executor='lazy_wrench')
    events = node_support.trial_events(trial, t_from=trial.onset_t - 1.0,
                                       t_to=trial.onset_t + 0.5)
    first = next(e for e in events if e.kind == 'wrench')
    events = events[events.index(first):]
    h.set_clock(first.t)
    # A wrench message alone does not wake the executor (no audio frame waits for F/T).
    h.wrench_pub.publish(wrench_msg(trial.wrench_t[first.lo], trial.force[first.lo],
                                    trial.torque[first.lo]))
    for _ in range(5):
        h.executor.spin_once(timeout_sec=0.01)
    assert h.node.wrench.received == 0
    # Each audio chunk is published after the wrench messages before it, without waiting
    # for them: the executor takes the queued wrench when the chunk (or a frame waiting for
    # F/T) wakes it, and the decisions are the per-message ones, whatever the order.
    fed, pending = [], [first]
    for e in events[1:]:
        if e.kind == 'wrench':
            h.wrench_pub.publish(wrench_msg(trial.wrench_t[e.lo], trial.force[e.lo],
                                            trial.torque[e.lo]))
            pending.append(e)
            continue
        tick = np.floor((e.t - trial.start_time) / TICK_S) * TICK_S + trial.start_time
        if tick > h.clock_t + 1e-9:
            h.set_clock(tick)
        n = h.node.audio.received
        h.audio_pub.publish(Int16MultiArray(data=trial.audio[e.lo:e.hi].tolist()))
        h.spin_until(lambda: h.node.audio.received > n)
        fed += [(h.clock_t, w) for w in pending] + [(h.clock_t, e)]
        pending = []
    h.flush_outputs()
    assert h.node.wrench.received >= len([f for f in fed if f[1].kind == 'wrench']) - 2
    p, contact, _ = offline_run(model, trial, fed)
    counts = h.node.detector_counts()
    assert counts['frames'] == len(p) == len(h.prob) > 100 and counts['wrench_dropped'] == 0
    np.testing.assert_array_equal([m.data for m in h.contact], contact)
    np.testing.assert_array_equal([m.data for m in h.prob], p.astype(np.float32))


# --- parameters ----------------------------------------------------------------------------------

@pytest.mark.parametrize('params, match', [
    ({'audio.sample_rate': 100.0}, 'audio.sample_rate'),
    ({'audio.sample_rate': '44100'}, 'audio.sample_rate must be a float'),
    ({'audio.msg_type': 'sensor_msgs/msg/Image'}, 'audio.msg_type'),
    ({'audio.channels': 2, 'audio.channel': 2}, 'audio.channel=2'),
    ({'audio.stamp_source': 'header'}, 'audio.stamp_source'),
    ({'qos.reliability': 'sometimes'}, 'qos.reliability'),
    ({'release.threshold': 1.5}, 'release.threshold'),
    ({'wrench.rate': 20000.0}, 'outside'),
    ({'wrench.bias': [1.0, 2.0, 3.0]}, 'wrench.bias must be a list of 6 numbers'),
    ({'wrench.bias': [0.0] * 5 + [1e9]}, 'wrench.bias.*outside'),
])
def test_invalid_parameters_refused_at_start(context, model, params, match):
    overrides = [Parameter('model.path', value=str(model))]
    overrides += [Parameter(k, value=v) for k, v in params.items()]
    with pytest.raises(ConfigError, match=match):
        ContactDetectorNode(context=context, parameter_overrides=overrides)


def test_params_file_documents_every_parameter(model):
    import yaml
    path = Path(__file__).resolve().parents[2] / 'params' / 'contact_detector.yaml'
    tree = yaml.safe_load(path.read_text())['/**']['ros__parameters']

    def flat(node, prefix=''):
        for key, value in node.items():
            if isinstance(value, dict):
                yield from flat(value, f'{prefix}{key}.')
            else:
                yield f'{prefix}{key}', value
    values = dict(flat(tree))
    assert list(values) == [spec.name for spec in PARAMS]
    for spec in PARAMS:
        value = values[spec.name]
        if isinstance(spec.default, tuple):         # an array: a YAML list
            value = tuple(value) if isinstance(value, list) else value
        assert type(value) is type(spec.default), spec.name
        assert value == spec.default, spec.name
    # rclpy reads the file: the node starts with it (model path overridden after it).
    ctx = Context()
    rclpy.init(context=ctx, args=['--ros-args', '--params-file', str(path),
                                  '-p', f'model.path:={model}', '-p', 'release.threshold:=0.7'])
    try:
        node = ContactDetectorNode(context=ctx)
        assert node.config.release_overrides == {'threshold': 0.7}
        assert node.detector.rule.threshold == 0.7
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)


def test_parameters_at_run_time(harness_factory):
    h = harness_factory()
    node = h.node
    base = node.bundle.decision_rule

    def set_(name, value):
        return node.set_parameters([Parameter(name, value=value)])[0]

    refused = set_('release.threshold', 1.5)
    assert not refused.successful and 'release.threshold' in refused.reason
    assert not set_('release.confirm_frames', -2).successful
    assert not set_('audio.sample_rate', 44100.0).successful        # read-only
    assert not set_('qos.reliability', 'best_effort').successful    # read-only
    assert not set_('gripper.joint', ' ').successful
    assert node.detector.rule == base

    assert set_('release.threshold', 0.8).successful
    assert set_('release.confirm_frames', 3).successful
    assert (node.detector.rule.threshold, node.detector.rule.confirm_frames) == (0.8, 3)
    assert node.detector.logic.rule == node.detector.rule
    assert set_('release.threshold', -1.0).successful               # back to the model's
    assert node.detector.rule.threshold == base.threshold
    assert set_('max_input_delay_s', 0.25).successful
    assert node.detector.settings.max_input_delay_s == 0.25
    assert set_('diagnostics.period_s', 2.0).successful
    assert node.get_parameter('release.confirm_frames').value == 3
    # The averaged threshold and the slow path, on top of the model's rule and back.
    assert not set_('release.sustain_threshold', 1.5).successful
    assert set_('release.sustain_frames', 10).successful
    assert set_('release.sustain_threshold', 0.4).successful
    assert set_('release.average_frames', 2).successful
    rule = node.detector.rule
    assert (rule.sustain_frames, rule.sustain_threshold, rule.average_frames) == (10, 0.4, 2)
    assert node.detector.logic.rule == rule and rule.confirm_frames == 3
    assert 'sustain_frames=10' in rule.describe()
    assert set_('release.sustain_frames', -1).successful
    assert set_('release.average_frames', 0).successful
    assert (node.detector.rule.sustain_frames, node.detector.rule.average_frames) == (
        base.sustain_frames, base.average_frames)
    # The load path on the shipped model (it measures the carried load), and off again.
    assert not set_('release.load_support', 2.0).successful
    assert set_('release.load_threshold', 2.0).successful
    assert set_('release.load_frames', 15).successful
    rule = node.detector.rule
    assert rule.uses_load and (rule.load_threshold, rule.load_frames) == (2.0, 15)
    assert node.detector.logic.rule == rule
    assert set_('release.load2_threshold', 5.0).successful
    assert set_('release.load2_frames', 3).successful
    rule = node.detector.rule
    assert (rule.load2_threshold, rule.load2_frames) == (5.0, 3)
    assert 'load>=5N x3' in rule.short() and node.detector.logic.rule == rule
    # its direction gate: a cosine in [-1, 1]; below -1 hands it back to the model
    assert not set_('release.load2_direction', 1.5).successful
    assert set_('release.load2_direction', -0.4).successful
    rule = node.detector.rule
    assert rule.load2_direction == -0.4 and rule.uses_direction
    assert rule.short().endswith('cos<=-0.4') and node.detector.logic.rule == rule
    assert set_('release.load2_direction', -2.0).successful
    assert node.detector.rule.load2_direction == base.load2_direction
    assert set_('release.load_threshold', 0.0).successful
    assert set_('release.load2_threshold', 0.0).successful
    assert not node.detector.rule.uses_load
    # the sensor's zero: an integer array is taken, a wrong length refused
    assert not set_('wrench.bias', [1.0, 2.0]).successful
    assert node.detector.bias == (0.0,) * 6
    assert set_('wrench.bias', [1, 0, -2, 0, 0, 3]).successful
    assert node.detector.bias == (1.0, 0.0, -2.0, 0.0, 0.0, 3.0)


def test_the_load_path_needs_a_model_that_measures_the_carried_load(context, tmp_path):
    # the small test model has the paper's features only: no carried load to hold the force
    # against, so the load path is refused at start and at run time, with the reason
    plain = node_support.model_path(tmp_path, allow_shipped=False)
    with pytest.raises(ConfigError, match='carried'):
        ContactDetectorNode(context=context, parameter_overrides=[
            Parameter('model.path', value=str(plain)),
            Parameter('release.load_threshold', value=2.0)])
    node = ContactDetectorNode(context=context, parameter_overrides=[
        Parameter('model.path', value=str(plain))])
    try:
        for name in ('release.load_threshold', 'release.load2_threshold'):
            result = node.set_parameters([Parameter(name, value=2.0)])[0]
            assert not result.successful and 'carried' in result.reason
        assert not node.detector.rule.uses_load
    finally:
        node.destroy_node()


def test_stream_rate_change_rebuilds_the_detector(harness_factory, trial):
    # What an audio_info / AudioStamped announcing another rate does (audio_common is not
    # installed here, so the rebuild is driven directly).
    h = harness_factory(**{'release.armed_on_start': False})
    h.feed(trial, node_support.trial_events(trial, t_from=trial.start_time + 1.0,
                                            t_to=trial.start_time + 1.5))
    frames = h.node.detector_counts()['frames']
    h.node.detector.arm(True)
    h.node._set_audio_rate(48000.0)
    assert h.node.detector.settings.audio_rate == 48000.0 and h.node.detector.armed
    counts = h.node.detector_counts()
    assert counts['frames'] == frames and counts['detector_rebuilds'] == 1
    h.node._set_audio_rate(50.0)                     # unsupported: the stream is refused
    assert 'audio at 50 Hz' in h.node.audio_refused
    h.send_audio(Int16MultiArray(data=[0] * 160))
    assert h.node.detector_counts()['audio_refused'] == 1


def test_wrench_at_another_rate_than_configured_is_reported(harness_factory, trial):
    """200 Hz wrench into a node set to 100 Hz: one WARN line, and WARN on /diagnostics."""
    h = harness_factory()
    t0 = trial.start_time
    h.set_clock(t0 + 1.0)
    logged = []
    logger = h.node.get_logger()
    original = logger.warning
    logger.warning = lambda text, *a, **k: (logged.append(text), original(text, *a, **k))
    for k in range(100):                        # 0.5 s of 200 Hz samples
        h.send_wrench(wrench_msg(t0 + 0.5 + k / 200.0, trial.force[0], trial.torque[0]))
    for _ in range(2):
        h.node.diagnostics()
    status, values = diag_values_of(h.node.diagnostics())
    assert status.level == DiagnosticStatus.WARN
    assert 'wrench arrives at 200 Hz but wrench.rate is 100 Hz' in status.message
    assert float(values['wrench_measured_rate_hz']) == pytest.approx(200.0, rel=1e-3)
    assert sum('wrench arrives at' in text for text in logged) == 1     # one line, not a flood


def test_carried_load_is_logged_and_a_load_that_moved_is_reported(harness_factory, trial):
    """The carried load of each measurement in one log line; armed while it moved: WARN."""
    h = harness_factory(**{'release.armed_on_start': False})
    logged = capture_log(h.node)
    t0 = trial.start_time
    # the start's measurement: the hand holds the object still
    h.feed(trial, node_support.trial_events(trial, t_to=t0 + 1.0))
    held = float(np.linalg.norm(np.median(trial.force[:50], axis=0)))
    assert [line for line in logged['info'] if line.startswith('carried load')] == [
        f'carried load measured over 50 F/T samples: |F| {held:.2f} N, '
        f'|T| {float(np.linalg.norm(np.median(trial.torque[:50], axis=0))):.3f} N m']
    h.node.diagnostics()
    status, values = diag_values_of(h.node.diagnostics())
    assert values['carried_load'] == 'steady'
    assert float(values['carried_force_n']) == pytest.approx(held, abs=0.01)
    # armed while the hand still takes 4 N more (a grasp, a lift): WARN until armed again
    assert h.call(h.arm, SetBool.Request(data=True)).success
    grasp = trial.force.copy()
    grasp[trial.wrench_t >= t0 + 1.25, 2] -= 4.0
    h.feed(replace(trial, force=grasp),
           node_support.trial_events(trial, t_from=t0 + 1.0, t_to=t0 + 2.0))
    moved = [line for line in logged['warning'] if line.startswith('carried load')]
    assert len(moved) == 1 and 'moved by 4.0' in moved[0] and '~/arm' in moved[0]
    status, values = diag_values_of(h.node.diagnostics())
    assert values['carried_load'] == 'moved'
    assert status.level == DiagnosticStatus.WARN and 'carried load moved' in status.message
    # disarmed, it compares with nothing that could release: the status is no longer WARN
    assert h.call(h.arm, SetBool.Request(data=False)).success
    status, values = diag_values_of(h.node.diagnostics())
    assert status.level == DiagnosticStatus.OK


def test_zero_sensor_sets_the_bias_from_what_the_hand_reads(harness_factory, trial):
    """~/zero_sensor: the next 50 samples' median becomes wrench.bias; a moving hand: WARN."""
    h = harness_factory(**{'release.armed_on_start': False})
    logged = capture_log(h.node)
    zero = h.io.create_client(Trigger, 'contact_detector/zero_sensor')
    t0 = trial.start_time
    h.feed(trial, node_support.trial_events(trial, t_to=t0 + 0.8))
    reply = h.call(zero, Trigger.Request())
    assert reply.success and 'over the next 0.50 s (50 samples at the 100 Hz' in reply.message
    h.feed(trial, node_support.trial_events(trial, t_from=t0 + 0.8, t_to=t0 + 1.6))
    # what the sensor read over the 50 samples after the call (100 Hz: the feature rate)
    after = np.flatnonzero(trial.wrench_t >= t0 + 0.8)[:50]
    read = np.median(np.hstack([trial.force[after], trial.torque[after]]), axis=0)
    bias = h.node.get_parameter('wrench.bias').value
    assert list(bias) == pytest.approx(read, abs=1e-5)
    assert h.node.detector.bias == pytest.approx(read, abs=1e-5)
    zeroed = [line for line in logged['info'] if line.startswith('F/T sensor zeroed')]
    assert len(zeroed) == 1 and 'wrench.bias: [' in zeroed[0]
    status, values = diag_values_of(h.node.diagnostics())
    assert [float(v) for v in values['wrench_bias'].split()] == pytest.approx(read, abs=1e-4)
    # the carried load is measured again in the new zero: about nothing
    h.feed(trial, node_support.trial_events(trial, t_from=t0 + 1.6, t_to=t0 + 2.4))
    assert h.node.detector.carried_load.force_n < 0.5
    # a hand that moves while it is zeroed: nothing changes, and the log says so
    assert h.call(zero, Trigger.Request()).success
    moving = trial.force.copy()
    moving[trial.wrench_t >= t0 + 2.65, 2] -= 3.0
    h.feed(replace(trial, force=moving),
           node_support.trial_events(trial, t_from=t0 + 2.4, t_to=t0 + 3.2))
    refused = [line for line in logged['warning'] if line.startswith('F/T zero not changed')]
    assert len(refused) == 1 and 'moved by 3.0' in refused[0] and '~/zero_sensor' in refused[0]
    assert list(h.node.get_parameter('wrench.bias').value) == list(bias)
    assert h.node.detector_counts()['releases'] == 0


def diag_values_of(array):
    status = array.status[0]
    return status, {kv.key: kv.value for kv in status.values}


@pytest.mark.skipif(importlib.util.find_spec('audio_common_msgs') is not None,
                    reason='checks the error for a missing audio_common_msgs; it is installed')
def test_missing_audio_common_package(context, model):
    for msg_type in ('audio_common_msgs/msg/AudioData', 'audio_common_msgs/msg/AudioStamped'):
        overrides = [Parameter('model.path', value=str(model)),
                     Parameter('audio.msg_type', value=msg_type)]
        with pytest.raises(ConfigError, match="package 'audio_common_msgs'.*not installed"):
            ContactDetectorNode(context=context, parameter_overrides=overrides)


def test_main_exits_non_zero_with_a_clear_message(tmp_path):
    env = dict(os.environ)
    repo = Path(__file__).resolve().parents[2]
    cmd = [sys.executable, '-m', 'contact_detector.ros.node', '--ros-args',
           '-p', f'model.path:={tmp_path / "missing.npz"}']
    done = subprocess.run(cmd, env=env, cwd=repo, capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert 'cannot start' in done.stderr and 'missing.npz does not exist' in done.stderr


def test_bad_model_is_a_model_error(context, tmp_path):
    bad = tmp_path / 'bad.npz'
    bad.write_bytes(b'not a model')
    with pytest.raises(ModelError):
        ContactDetectorNode(context=context,
                            parameter_overrides=[Parameter('model.path', value=str(bad))])


# --- bad input -----------------------------------------------------------------------------------

def test_bad_messages_are_counted_and_never_release(harness_factory, trial):
    h = harness_factory(**{'audio.channels': 2, 'audio.channel': -1,
                           'audio.max_chunk_s': 0.5})
    events = node_support.trial_events(trial, t_from=trial.onset_t - 1.5,
                                       t_to=trial.onset_t + 0.5)
    n_audio = 0

    def stereo(e):
        mono = trial.audio[e.lo:e.hi]
        return Int16MultiArray(data=np.repeat(mono, 2).tolist())

    bad_audio = [Int16MultiArray(data=[]),                            # empty chunk
                 Int16MultiArray(data=[1, 2, 3]),                     # not a multiple of 2
                 Int16MultiArray(data=[0] * 40000)]                   # 1.25 s: too long
    for e in events:
        tick = np.floor((e.t - trial.start_time) / TICK_S) * TICK_S + trial.start_time
        if h.clock_t is None or tick > h.clock_t + 1e-9:
            h.set_clock(tick)
        if e.kind == 'audio':
            n_audio += 1
            h.send_audio(stereo(e))
            # Near the onset a corrupt message every 5th chunk keeps releases blocked.
            if e.t > trial.onset_t - 0.5 and n_audio % 5 == 0:
                h.send_audio(bad_audio[n_audio % 3])
        else:
            j = e.lo
            good = wrench_msg(trial.wrench_t[j], trial.force[j], trial.torque[j])
            h.send_wrench(good)
            if j % 25 == 0:
                h.send_wrench(good)                                   # duplicate
                h.send_wrench(wrench_msg(trial.wrench_t[j], [np.nan, 0, 0], [0, 0, 0]))
                h.send_wrench(wrench_msg(trial.wrench_t[j] + 30.0, trial.force[j],
                                         trial.torque[j]))            # from the future
    h.flush_outputs()
    counts = h.node.detector_counts()
    assert counts['audio_dropped'] >= 10 and counts['wrench_dropped'] >= 10
    assert counts['bad_stamps'] >= 5
    assert counts['callback_errors'] == 0
    assert counts['frames'] > 100            # the good stereo input was mixed and decided
    assert counts['releases'] == 0 and h.release == []
    h.spin_until(lambda: any(s.status[0].level == DiagnosticStatus.WARN for s in h.diag))
    warn = [s.status[0] for s in h.diag if s.status[0].level == DiagnosticStatus.WARN]
    assert any('audio_dropped' in s.message or 'wrench_dropped' in s.message for s in warn)


def test_stereo_read_as_mono_is_refused(harness_factory, trial):
    h = harness_factory()                                   # audio.channels: 1
    for e in node_support.trial_events(trial, t_from=trial.onset_t - 1.5,
                                       t_to=trial.onset_t + 0.5):
        tick = np.floor((e.t - trial.start_time) / TICK_S) * TICK_S + trial.start_time
        if h.clock_t is None or tick > h.clock_t + 1e-9:
            h.set_clock(tick)
        if e.kind == 'audio':
            h.send_audio(Int16MultiArray(data=np.repeat(trial.audio[e.lo:e.hi], 2).tolist()))
        else:
            h.send_wrench(wrench_msg(trial.wrench_t[e.lo], trial.force[e.lo],
                                     trial.torque[e.lo]))
    h.flush_outputs()
    counts = h.node.detector_counts()
    assert counts['audio_rate_mismatch'] > 50 and counts['releases'] == 0
    assert 'rate' in h.node.detector.last_error


def test_float32_audio_with_nan_is_dropped(harness_factory, trial):
    h = harness_factory(**{'audio.msg_type': 'std_msgs/msg/Float32MultiArray'},
                        audio_type=Float32MultiArray)
    h.set_clock(trial.start_time + 1.0)
    h.send_audio(Float32MultiArray(data=[0.1, float('nan')]))
    h.send_audio(Float32MultiArray(data=[0.1, 0.2]))
    counts = h.node.detector_counts()
    assert counts['audio_dropped'] == 1 and counts['audio_msgs'] == 1
    assert 'NaN' in h.node.detector.last_error


def big_endian_wrench(t: float, values) -> bytes:
    """Return a WrenchStamped in big-endian CDR (what io.cdr does not read; rclpy does)."""
    frame = b'wrist_ft_sensor_frame\x00'
    head = struct.pack('>iII', stamp(t).sec, stamp(t).nanosec, len(frame)) + frame
    return b'\x00\x00\x00\x00' + head + bytes(-len(head) % 8) + struct.pack('>6d', *values)


def test_serialised_input_fallback_and_garbage(harness_factory, trial):
    h = harness_factory()
    node = h.node
    h.set_clock(trial.start_time + 1.0)
    t = trial.start_time + 0.99
    node._on_wrench(serialize_message(wrench_msg(t, [1.0, 2.0, 3.0], [0.1, 0.2, 0.3])))
    assert node.wrench.last_stamp == pytest.approx(t, abs=1e-9)
    # Bytes io.cdr refuses are read by rclpy: the stamp and the values arrive.
    node._on_wrench(big_endian_wrench(t + 0.002, [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]))
    assert node.wrench.last_stamp == pytest.approx(t + 0.002, abs=1e-9)
    assert node.detector_counts()['wrench_dropped'] == 0
    node._on_wrench(big_endian_wrench(t + 0.004, [np.nan, 2.0, 3.0, 0.1, 0.2, 0.3]))
    counts = node.detector_counts()
    assert counts['wrench_dropped'] == 1 and counts['callback_errors'] == 0
    # Bytes nothing can read (a truncated message) are bad input like any other: logged,
    # counted as dropped, releases held off; not a failed callback.
    node._on_wrench(b'\x00\x01\x00\x00\x01')
    node._on_audio(b'\x00\x01\x00\x00\x01\x00')
    counts = node.detector_counts()
    assert counts['callback_errors'] == 0
    assert counts['wrench_dropped'] == 2 and counts['audio_dropped'] == 1
    assert counts['wrench_msgs'] == 3 and counts['audio_msgs'] == 0
    assert 'cannot deserialise' in node.detector.last_error


# --- time ----------------------------------------------------------------------------------------

def test_time_jump_backwards_resets_and_recovers(harness_factory, trial):
    h = harness_factory()
    span = node_support.trial_events(trial, t_from=trial.start_time + 1.0,
                                     t_to=trial.start_time + 2.5)
    h.feed(trial, span)
    before = h.node.detector_counts()
    assert before['frames'] > 50 and before['clock_jumps'] == 0
    # A bag loop: /clock and every stamp go back to the start of the span.
    h.clock_t = None
    h.feed(trial, span)
    h.flush_outputs()
    looped = h.node.detector_counts()
    assert looped['clock_jumps'] == 1 and looped['callback_errors'] == 0
    assert looped['frames'] > before['frames'] + 50          # decisions again after warm-up
    # The wrench driver restarts with stamps 30 s back while the clock goes on.
    h.feed(trial, span, offset=10.0, wrench_offset=-30.0)
    h.flush_outputs()
    after = h.node.detector_counts()
    assert after['time_jumps'] >= 1 and after['callback_errors'] == 0
    assert after['frames'] > looped['frames'] + 50            # invalid (stale F/T), not stuck
    assert after['releases'] == 0


def test_44k_audio_without_retraining(harness_factory, model):
    trial = simulate_trial(audio_rate=44100, **TRIAL)
    h = harness_factory(**{'audio.sample_rate': 44100.0})
    events = node_support.trial_events(trial, t_from=trial.onset_t - 1.0,
                                       t_to=trial.onset_t + 0.5)
    fed = h.feed(trial, events)
    h.flush_outputs()
    p, contact, releases = offline_run(model, trial, fed)
    assert h.node.detector_counts()['frames'] == len(h.prob) == len(p) > 140
    np.testing.assert_array_equal([m.data for m in h.prob], p.astype(np.float32))
    assert len(h.release) == len(releases)
    if not node_support.uses_shipped(model):
        assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.3
