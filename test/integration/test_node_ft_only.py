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
The live node with an F/T-only model (a robot without a microphone), with real rclpy.

No audio subscription; one frame per F/T feature frame, equal to :class:`ContactDetector`
run offline on the same stamps; one release at the contact; audio.enabled false loads the
shipped F/T-only model and refuses a model that needs audio.
"""

import time

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.factory import DetectorFactory
from contact_detector.detection.offline import run_detector
from contact_detector.errors import ConfigError
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.ros.node import ContactDetectorNode
from contact_detector.sim.trial import simulate_trial
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
import node_support
import numpy as np
import pytest
from rcl_interfaces.msg import Log
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Bool, Float32, Int16MultiArray

pytestmark = pytest.mark.rclpy

TICK_S = 0.01
TRIAL = {'seed': 3, 'index': 21, 'hits': 'hand'}  # in-air hand hits 1.5 s and 1.1 s before onset


stamp = node_support.stamp


class FtHarness:
    """The node under test, a feeder for /clock, wrench and audio; its /rosout lines."""

    def __init__(self, context, name='contact_detector', **params):
        values = {'use_sim_time': True, 'qos.reliability': 'reliable', 'qos.depth': 1000,
                  'diagnostics.period_s': 0.5}
        values.update(params)
        self.node = ContactDetectorNode(
            name, context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in values.items()])
        self.io = rclpy.create_node('test_io_ft', context=context)
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.clock_pub = self.io.create_publisher(Clock, '/clock', 10)
        self.wrench_pub = self.io.create_publisher(WrenchStamped, 'wrist_wrench', reliable)
        self.audio_pub = self.io.create_publisher(Int16MultiArray, 'audio', reliable)
        self.contact, self.prob, self.release, self.diag = [], [], [], []
        for msg_type, topic, sink in ((Bool, 'contact', self.contact),
                                      (Float32, 'contact_probability', self.prob),
                                      (Bool, 'release', self.release),
                                      (DiagnosticArray, '/diagnostics', self.diag)):
            self.io.create_subscription(msg_type, topic, sink.append, reliable)
        self.logs = []
        logs_qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.io.create_subscription(
            Log, '/rosout', lambda m: self.logs.append(m) if m.name == name else None, logs_qos)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.io)
        self.clock_t = None
        self.spin_until(lambda: self.clock_pub.get_subscription_count() > 0
                        and self.wrench_pub.get_subscription_count() > 0
                        and len(self.io.get_publishers_info_by_topic('/release')) > 0)

    def spin_until(self, predicate, timeout=10.0):
        node_support.spin_until(self.executor, predicate, timeout=timeout)

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def set_clock(self, t: float) -> None:
        self.clock_pub.publish(Clock(clock=stamp(t)))
        target = stamp(t)
        want = target.sec * 1_000_000_000 + target.nanosec
        self.spin_until(lambda: self.node.get_clock().now().nanoseconds == want)
        self.clock_t = t

    def send_wrench(self, t, force, torque) -> None:
        msg = WrenchStamped()
        msg.header.stamp = stamp(float(t))
        f, m = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z = (float(v) for v in force)
        m.x, m.y, m.z = (float(v) for v in torque)
        n = self.node.wrench.received
        self.wrench_pub.publish(msg)
        self.spin_until(lambda: self.node.wrench.received > n)

    def send_audio(self, samples) -> None:
        n = self.node.audio.received
        self.audio_pub.publish(Int16MultiArray(data=samples.tolist()))
        self.spin_until(lambda: self.node.audio.received > n)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.io.destroy_node()


def test_ft_only_model_runs_without_audio_and_releases_once(context):
    trial = simulate_trial(**TRIAL)
    h = FtHarness(context, **{'model.path': str(default_ft_model_path())})
    try:
        assert h.node.audio_sub is None and h.node.info_sub is None
        assert h.audio_pub.get_subscription_count() == 0
        bundle = load_bundle(path=default_ft_model_path())
        det = ContactDetector(bundle=bundle, settings=DetectorSettings(
            wrench_rate=trial.ft_rate))
        keep = np.flatnonzero((trial.wrench_t >= trial.onset_t - 2.5)
                              & (trial.wrench_t < trial.onset_t + 1.5))
        p, releases = [], []
        for j in keep:
            tick = trial.start_time + np.floor(
                (trial.wrench_t[j] - trial.start_time) / TICK_S) * TICK_S
            if h.clock_t is None or tick > h.clock_t + 1e-9:
                h.set_clock(tick)
            h.send_wrench(trial.wrench_t[j], trial.force[j], trial.torque[j])
            d = det.on_wrench(t=trial.wrench_t[j:j + 1], force=trial.force[j:j + 1],
                              torque=trial.torque[j:j + 1], now=h.clock_t)
            p.extend(d.p)
            releases.extend(d.releases)
        counts = h.node.detector_counts()
        h.spin_until(lambda: len(h.prob) >= counts['frames'])
        # One frame per F/T feature frame, the offline detector's; one release at the contact.
        assert counts['frames'] == len(p) == len(h.prob) > 300
        np.testing.assert_array_equal([m.data for m in h.prob], np.array(p, np.float32))
        assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.3
        assert [m.data for m in h.release] == [True]
        h.spin_until(lambda: len(h.diag) > 0, timeout=5.0)
        values = {kv.key: kv.value for kv in h.diag[-1].status[0].values}
        assert values['audio'].startswith('off') and values['model_id'] == bundle.model_id
    finally:
        h.close()


def test_audio_disabled_loads_the_shipped_ft_model(context):
    h = FtHarness(context, **{'audio.enabled': False})
    try:
        assert h.node.bundle.feature_config.ft_only and h.node.audio_sub is None
        assert h.node.model_path == str(default_ft_model_path())
    finally:
        h.close()


def test_audio_disabled_refuses_a_model_that_needs_audio(context):
    overrides = [Parameter('audio.enabled', value=False),
                 Parameter('model.path', value=str(default_model_path()))]
    with pytest.raises(ConfigError, match='audio.enabled is false'):
        ContactDetectorNode(context=context, parameter_overrides=overrides)


def test_audio_stops_halfway_the_node_switches_and_releases_once(context):
    trial = simulate_trial(**TRIAL)
    # A node name of its own: rcl keeps one /rosout publisher per logger name and process.
    h = FtHarness(context, name='contact_detector_audio_stops',
                  **{'model.path': str(default_model_path()), 'audio.timeout_s': 0.3})
    try:
        h.spin_until(lambda: h.audio_pub.get_subscription_count() > 0)
        stop = trial.onset_t - 1.2          # the audio publisher dies between the two knocks
        events = node_support.trial_events(trial, t_from=trial.onset_t - 2.5,
                                           t_to=trial.onset_t + 1.5)
        frames_at_stop = release_at = None
        for e in events:
            tick = trial.start_time + np.floor((e.t - trial.start_time) / TICK_S) * TICK_S
            if h.clock_t is None or tick > h.clock_t + 1e-9:
                h.set_clock(tick)
            if e.kind == 'audio':
                if e.t < stop:
                    h.send_audio(trial.audio[e.lo:e.hi])
                continue
            if frames_at_stop is None and e.t >= stop:
                frames_at_stop = h.node.detector_counts()['contact_msgs']
            h.send_wrench(trial.wrench_t[e.lo], trial.force[e.lo], trial.torque[e.lo])
            if release_at is None and h.node.detector_counts()['release_msgs']:
                release_at = e.t
        counts = h.node.detector_counts()
        assert trial.onset_t < release_at <= trial.onset_t + 0.5
        # It kept deciding after the audio stopped, switched once, released once at the contact.
        assert counts['contact_msgs'] > frames_at_stop + 200
        assert counts['model_switches'] == 1 and counts['releases'] == 1
        assert [m.data for m in h.release] == [True]
        assert h.node.detector.active_name == 'F/T-only'
        h.spin_until(lambda: any(
            {kv.key: kv.value for kv in d.status[0].values}.get('model_active') == 'F/T-only'
            for d in h.diag), timeout=5.0)
        status = h.diag[-1].status[0]
        assert 'F/T-only model active' in status.message
        # One log line for the one switch.
        h.spin_until(lambda: any('model switched' in m.msg for m in h.logs), timeout=5.0)
        h.spin_for(0.3)
        switched = [m.msg for m in h.logs if 'model switched' in m.msg]
        assert len(switched) == 1 and 'model switched to F/T-only' in switched[0]
    finally:
        h.close()


def _feed_trial(h, trial, events) -> None:
    """Publish the trial's messages with /clock ticking, as a robot would."""
    h.spin_until(lambda: h.audio_pub.get_subscription_count() > 0)
    for e in events:
        tick = trial.start_time + np.floor((e.t - trial.start_time) / TICK_S) * TICK_S
        if h.clock_t is None or tick > h.clock_t + 1e-9:
            h.set_clock(tick)
        if e.kind == 'audio':
            h.send_audio(trial.audio[e.lo:e.hi])
        else:
            h.send_wrench(trial.wrench_t[e.lo], trial.force[e.lo], trial.torque[e.lo])


@pytest.mark.parametrize('both', [True, False])
def test_both_models_decide_and_the_first_release_of_either_is_published(context, both):
    # paper trial 0 of seed 5: the F/T-only model releases 12 ms before the audio
    # model (test_fallback.py); model.ft_also_decides false leaves the audio model alone
    trial = simulate_trial(seed=5, index=0, condition='paper')
    events = node_support.trial_events(trial, t_from=trial.onset_t - 2.5,
                                       t_to=trial.onset_t + 1.0)
    h = FtHarness(context, name=f'contact_detector_both_{both}',
                  **{'model.ft_also_decides': both})
    try:
        _feed_trial(h, trial, events)
        counts = h.node.detector_counts()
        assert counts['releases'] == 1 and [m.data for m in h.release] == [True]
        assert counts.get('ft_releases', 0) == int(both)
        h.spin_until(lambda: any('RELEASE' in m.msg for m in h.logs), timeout=5.0)
        line = next(m.msg for m in h.logs if 'RELEASE' in m.msg)
        assert ('by the F/T-only model' in line) == both
        released = float(line.split('t=')[1].split(' s')[0])
        # the node and the offline tools agree (detect, evaluate: run_both), to the /clock tick
        # the node stamps audio with on receipt
        offline = run_detector(
            [node_support.sensor_event(trial, e) for e in events],
            detector=DetectorFactory(model=None, audio_enabled=True, settings={}, rule=None,
                                     ft_also_decides=both)())
        assert released == pytest.approx(offline.releases[0], abs=TICK_S + 1e-3)
        assert trial.onset_t < released < trial.onset_t + 0.1
        deciding = 'audio + F/T and F/T-only' if both else 'audio + F/T'
        h.spin_until(lambda: any(
            {kv.key: kv.value for kv in d.status[0].values}.get('models_deciding') == deciding
            for d in h.diag), timeout=5.0)
    finally:
        h.close()


def test_zero_wrench_placeholders_never_release_and_are_reported(context):
    # A driver that publishes six zeros for 0.1 s while the hand holds the object, 1 s before
    # the contact. Read as a load that went, the shipped F/T-only model releases before the
    # contact (checked below offline, with the zeros a hair above zero). The node leaves the
    # zeros out, warns, and releases once, at the contact.
    trial = simulate_trial(**TRIAL)
    h = FtHarness(context, **{'audio.enabled': False})
    try:
        keep = np.flatnonzero((trial.wrench_t >= trial.onset_t - 2.5)
                              & (trial.wrench_t < trial.onset_t + 1.0))
        dropout = (trial.wrench_t >= trial.onset_t - 1.0) & (trial.wrench_t < trial.onset_t - 0.9)
        force, torque = trial.force.copy(), trial.torque.copy()
        hair = load_bundle(path=default_ft_model_path())
        det = ContactDetector(bundle=hair, settings=DetectorSettings(wrench_rate=trial.ft_rate))
        force[dropout], torque[dropout] = 1e-9, 1e-9
        early = det.on_wrench(t=trial.wrench_t[keep], force=force[keep], torque=torque[keep])
        assert early.releases and early.releases[0] < trial.onset_t
        force[dropout], torque[dropout] = 0.0, 0.0
        for j in keep:
            tick = trial.start_time + np.floor(
                (trial.wrench_t[j] - trial.start_time) / TICK_S) * TICK_S
            if h.clock_t is None or tick > h.clock_t + 1e-9:
                h.set_clock(tick)
            h.send_wrench(trial.wrench_t[j], force[j], torque[j])
        counts = h.node.detector_counts()
        assert counts['wrench_placeholders'] == int(dropout[keep].sum()) == 10
        assert counts['releases'] == 1 and counts['wrench_dropped'] == 0
        h.spin_until(lambda: len(h.release) == 1)
        h.spin_until(lambda: any('RELEASE' in m.msg for m in h.logs), timeout=5.0)
        released = [m.msg for m in h.logs if 'RELEASE' in m.msg]
        t = float(released[0].split('t=')[1].split(' ')[0])
        assert len(released) == 1 and trial.onset_t < t <= trial.onset_t + 0.5
        h.spin_until(lambda: any('exactly (0, 0, 0)' in m.msg for m in h.logs), timeout=5.0)
        warned = [m.msg for m in h.logs if 'exactly (0, 0, 0)' in m.msg]
        assert len(warned) == 1 and "driver's placeholder" in warned[0]
        h.spin_until(lambda: any('wrench_placeholders +' in d.status[0].message
                                 for d in h.diag), timeout=5.0)
    finally:
        h.close()
