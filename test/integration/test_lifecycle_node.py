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
The managed node with real rclpy: its transitions, driven as a lifecycle manager does.

The transitions go through the node's lifecycle services (``/<node>/change_state``,
``get_state``: what ``ros2 lifecycle set`` and nav2's lifecycle manager call), a few through
the public ``trigger_*`` methods. Time is simulated (``/clock``) and a simulated trial is fed
as in test_node.py.
"""

import time

from contact_detector.ros.lifecycle_node import ContactDetectorLifecycleNode
from contact_detector.sim.trial import simulate_trial
from geometry_msgs.msg import WrenchStamped
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
import node_support
import numpy as np
import pytest
from rcl_interfaces.msg import Log
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Bool, Int16MultiArray

pytestmark = pytest.mark.rclpy

TICK_S = 0.01
TRIAL = {'seed': 3, 'index': 21, 'hits': 'hand'}


@pytest.fixture(scope='module')
def trial():
    return simulate_trial(**TRIAL)


stamp = node_support.stamp


class Manager:
    """The managed node, plus a helper node that drives its transitions, feeds and listens."""

    made = 0

    def __init__(self, context, **params):
        # A name of its own per test: rcl keeps one /rosout publisher per logger name and
        # process.
        Manager.made += 1
        name = f'contact_detector_{Manager.made}'
        overrides = [Parameter(k, value=v) for k, v in params.items()]
        self.node = ContactDetectorLifecycleNode(name, context=context,
                                                 parameter_overrides=overrides)
        self.io = rclpy.create_node('manager', context=context)
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.clock_pub = self.io.create_publisher(Clock, '/clock', 10)
        self.wrench_pub = self.io.create_publisher(WrenchStamped, 'wrist_wrench', reliable)
        self.audio_pub = self.io.create_publisher(Int16MultiArray, 'audio', reliable)
        self.contact, self.release, self.logs = [], [], []
        self.io.create_subscription(Bool, 'contact', self.contact.append, reliable)
        self.io.create_subscription(Bool, 'release', self.release.append, reliable)
        logs_qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.io.create_subscription(
            Log, '/rosout', lambda m: self.logs.append(m) if m.name == name else None, logs_qos)
        self.change_state = self.io.create_client(ChangeState, f'{name}/change_state')
        self.get_state = self.io.create_client(GetState, f'{name}/get_state')
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.io)
        self.clock_t = None
        # The node's log lines are read from /rosout: wait until one of its lines arrives
        # (the graph may still list a node of the same name from an earlier test).
        end = time.monotonic() + 10.0
        while not any(log.msg == 'test: rosout ready' for log in self.logs):
            assert time.monotonic() < end, 'no /rosout from the node'
            self.node.get_logger().info('test: rosout ready')
            self.spin_for(0.05)
        self.logs[:] = [log for log in self.logs if log.msg != 'test: rosout ready']

    def spin_until(self, predicate, timeout: float = 10.0) -> None:
        node_support.spin_until(self.executor, predicate, timeout=timeout)

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def call(self, client, request):
        assert client.wait_for_service(timeout_sec=5.0)
        future = client.call_async(request)
        self.spin_until(future.done)
        return future.result()

    def transition(self, transition_id: int) -> bool:
        return self.call(self.change_state, ChangeState.Request(
            transition=Transition(id=transition_id))).success

    def state(self) -> str:
        return self.call(self.get_state, GetState.Request()).current_state.label

    def set_clock(self, t: float) -> None:
        self.clock_pub.publish(Clock(clock=stamp(t)))
        want = stamp(t).sec * 1_000_000_000 + stamp(t).nanosec
        self.spin_until(lambda: self.node.get_clock().now().nanoseconds == want)
        self.clock_t = t

    def feed(self, trial, *, offset: float, wait: bool) -> None:
        """Publish a trial's messages near its onset; ``wait`` for each to be received."""
        for e in node_support.trial_events(trial, t_from=trial.onset_t - 2.0,
                                           t_to=trial.onset_t + 1.0):
            tick = offset + np.floor((e.t - trial.start_time) / TICK_S) * TICK_S \
                + trial.start_time
            if self.clock_t is None or tick > self.clock_t + 1e-9:
                self.set_clock(tick)
            if e.kind == 'audio':
                stream, pub = 'audio', self.audio_pub
                msg = Int16MultiArray(data=trial.audio[e.lo:e.hi].tolist())
            else:
                stream, pub, j = 'wrench', self.wrench_pub, e.lo
                msg = WrenchStamped()
                msg.header.stamp = stamp(float(trial.wrench_t[j]) + offset)
                f, m = msg.wrench.force, msg.wrench.torque
                f.x, f.y, f.z = (float(v) for v in trial.force[j])
                m.x, m.y, m.z = (float(v) for v in trial.torque[j])
            before = getattr(self.node, stream).received if wait else 0
            pub.publish(msg)
            if wait:
                self.spin_until(lambda: getattr(self.node, stream).received > before)
            else:
                self.executor.spin_once(timeout_sec=0)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.io.destroy_node()


@pytest.fixture
def manager_factory(context, model):
    made = []

    def make(**params):
        values = {'model.path': str(model), 'use_sim_time': True,
                  'qos.reliability': 'reliable', 'qos.depth': 1000}
        values.update(params)
        made.append(Manager(context, **values))
        return made[-1]
    yield make
    for m in made:
        m.close()


def test_release_only_while_active(manager_factory, trial):
    m = manager_factory()
    node = m.node
    assert m.state() == 'unconfigured' and node.detector is None
    assert m.io.count_publishers('/release') == 0

    assert m.transition(Transition.TRANSITION_CONFIGURE)
    assert m.state() == 'inactive' and node.detector.armed
    m.spin_until(lambda: m.io.count_publishers('/release') == 1)
    # Inactive: the node does not subscribe; a contact fed now is not seen, nothing is
    # published.
    assert m.wrench_pub.get_subscription_count() == 0 == m.audio_pub.get_subscription_count()
    m.feed(trial, offset=0.0, wait=False)
    m.spin_for(0.3)
    assert node.audio.received == 0 and m.contact == [] and m.release == []

    assert m.transition(Transition.TRANSITION_ACTIVATE)
    assert m.state() == 'active'
    m.spin_until(lambda: m.wrench_pub.get_subscription_count() == 1
                 and m.audio_pub.get_subscription_count() == 1)
    m.feed(trial, offset=100.0, wait=True)
    m.spin_until(lambda: len(m.release) == 1 and len(m.contact) > 200)
    assert node.detector_counts()['releases'] == 1 and not node.detector.armed

    # Deactivated while armed: the same contact again releases nothing.
    node.detector.arm(True)
    assert m.transition(Transition.TRANSITION_DEACTIVATE)
    assert m.state() == 'inactive'
    m.spin_until(lambda: m.wrench_pub.get_subscription_count() == 0)
    received = node.audio.received
    m.feed(trial, offset=200.0, wait=False)
    m.spin_for(0.3)
    assert node.audio.received == received and len(m.release) == 1

    # Active again: the stream state was reset (warm-up), the contact releases once more.
    assert m.transition(Transition.TRANSITION_ACTIVATE)
    m.spin_until(lambda: m.wrench_pub.get_subscription_count() == 1)
    m.feed(trial, offset=300.0, wait=True)
    m.spin_until(lambda: len(m.release) == 2)

    assert node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
    assert node.trigger_cleanup() == TransitionCallbackReturn.SUCCESS
    assert m.state() == 'unconfigured' and node.detector is None and node.bundle is None
    m.spin_until(lambda: m.io.count_publishers('/release') == 0)
    # Configured again from the same parameters, then shut down from inactive.
    assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    assert node.trigger_shutdown() == TransitionCallbackReturn.SUCCESS
    assert m.state() == 'finalized' and node.detector is None
    said = [log.msg for log in m.logs]
    assert sum('waiting for input' in s for s in said) == 2        # once per activation
    assert any(s.startswith('inactive: inputs unsubscribed') for s in said)


@pytest.mark.parametrize('params, reason', [
    ({'model.path': '/nonexistent/model.joblib'}, 'model.joblib does not exist'),
    ({'audio.stamp_source': 'header'}, "audio.stamp_source='header' needs a stamped"),
    ({'wrench.rate': 20000.0}, 'outside'),
    ({'gripper.enabled': True, 'gripper.topic': 'bad topic!'}, 'not a valid topic name'),
])
def test_configure_fails_cleanly(manager_factory, params, reason):
    m = manager_factory(**params)
    assert not m.transition(Transition.TRANSITION_CONFIGURE)
    assert m.state() == 'unconfigured'
    assert m.node.detector is None and m.io.count_publishers('/release') == 0
    m.spin_until(lambda: any(log.level == Log.ERROR for log in m.logs))
    errors = [log.msg for log in m.logs if log.level == Log.ERROR]
    assert len(errors) == 1 and errors[0].startswith('configure failed: ')
    assert reason in errors[0]
    # A user fixes the parameter and configures again, or shuts it down: it exits cleanly.
    assert m.node.trigger_shutdown() == TransitionCallbackReturn.SUCCESS
    assert m.state() == 'finalized'


def test_ft_only_and_audio_fallback_configure_like_the_plain_node(manager_factory):
    from contact_detector.detection.fallback import AudioFallback
    # audio.enabled false: the shipped F/T-only model, and no audio subscription once active.
    m = manager_factory(**{'model.path': '', 'audio.enabled': False})
    assert m.transition(Transition.TRANSITION_CONFIGURE)
    assert m.node.bundle.feature_config.ft_only
    assert m.transition(Transition.TRANSITION_ACTIVATE)
    m.spin_until(lambda: m.wrench_pub.get_subscription_count() == 1)
    m.spin_for(0.2)
    assert m.audio_pub.get_subscription_count() == 0 and m.node.audio_sub is None
    values = {kv.key: kv.value for kv in m.node.diagnostics().status[0].values}
    assert values['model_active'] == 'F/T-only' and values['audio'].startswith('off')
    assert 'waiting for input: wrench' == m.node.diagnostics().status[0].message
    # audio.timeout_s: the multimodal model with the F/T-only one standing by; cleanup drops it.
    f = manager_factory(**{'audio.timeout_s': 0.5})
    assert f.transition(Transition.TRANSITION_CONFIGURE)
    assert isinstance(f.node.detector, AudioFallback) and f.node.ft_bundle is not None
    assert f.transition(Transition.TRANSITION_CLEANUP)
    assert f.node.ft_bundle is None and f.node.detector is None
