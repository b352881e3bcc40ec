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
``contact-detector replay`` into a live graph: real rclpy, DDS on loopback (conftest.py).

The replay runs as its own process, as a user would start it; this process subscribes to what
it publishes. ``--wait-for-subscribers`` holds the start until our subscriptions have matched
(DDS discovery takes up to ~3 s here), so every message can be counted.
"""

from functools import partial
import os
from pathlib import Path
import subprocess
import sys
import time

from contact_detector.io.bags import iter_messages, jazzy_typestore
from contact_detector.sim import simulate_trial
from contact_detector.sim.bag_writer import write_trial_bag
import numpy as np
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Writer

pytestmark = pytest.mark.rclpy

#: Length of the replayed piece of a trial, s.
SPAN_S = 2.0


def _replay_command(*args) -> list:
    script = Path(sys.executable).with_name('contact-detector')
    head = [str(script)] if script.exists() else [sys.executable, '-m',
                                                  'contact_detector.cli.main']
    return [*head, 'replay', *map(str, args)]


@pytest.fixture(scope='module')
def bag(tmp_path_factory) -> Path:
    """Return the first SPAN_S seconds of a simulated trial (wrench and audio, no truth yet)."""
    root = tmp_path_factory.mktemp('replay')
    full = write_trial_bag(trial=simulate_trial(seed=5, index=0), path=root / 'full')
    short = root / 'short'
    store = jazzy_typestore()
    with AnyReader([full], default_typestore=store) as reader, Writer(short, version=9) as out:
        conns = {c.topic: out.add_connection(c.topic, c.msgtype, typestore=store)
                 for c in reader.connections}
        for c, log_ns, raw in reader.messages():
            if log_ns - reader.start_time < SPAN_S * 1e9:
                out.write(conns[c.topic], log_ns, raw)
    return short


class Listener:
    """Subscribes to /wrist_wrench, /audio and /clock in a context of its own."""

    def __init__(self) -> None:
        from geometry_msgs.msg import WrenchStamped
        from rosgraph_msgs.msg import Clock
        from std_msgs.msg import Int16MultiArray

        self.context = Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('replay_listener', context=self.context)
        self.got = {'/wrist_wrench': [], '/audio': [], '/clock': []}
        # When each message was written, by the publisher's clock (DDS source timestamps, ns):
        # a listener that falls behind receives late, but cannot move these.
        self.sent = {topic: [] for topic in self.got}
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        for cls, topic in ((WrenchStamped, '/wrist_wrench'), (Int16MultiArray, '/audio'),
                           (Clock, '/clock')):
            self.node.create_subscription(cls, topic, partial(self._on_message, topic), qos)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def _on_message(self, topic: str, msg, info) -> None:
        self.got[topic].append((time.time(), msg))
        self.sent[topic].append(info['source_timestamp'])

    def run(self, command: list, *, timeout: float = 25.0) -> subprocess.CompletedProcess:
        """Spin while ``command`` runs, then a little longer to drain; return its result."""
        proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, env=dict(os.environ))
        end = time.monotonic() + timeout
        while proc.poll() is None and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.005)
        if proc.poll() is None:
            proc.kill()
        output = proc.communicate()[0]
        drain = time.monotonic() + 0.5
        while time.monotonic() < drain:
            self.executor.spin_once(timeout_sec=0.005)
        return subprocess.CompletedProcess(command, proc.returncode, output, '')

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def listener():
    it = Listener()
    yield it
    it.close()


def _stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def _missing(recorded, got) -> str:
    """Say which recorded messages (by index) did not arrive, for the assertion message."""
    seqs = [r.msg.header.stamp.sec * 1_000_000_000 + r.msg.header.stamp.nanosec
            for r in recorded]
    arrived = [_stamp_ns(m) for _, m in got]
    shift = arrived[0] - seqs[0] if arrived else 0
    lost = [i for i, s in enumerate(seqs) if s + shift not in set(arrived)]
    return f'{len(got)} of {len(recorded)} arrived; missing indices {lost[:10]}'


def test_replay_with_clock_at_4x(bag, listener):
    recorded = list(iter_messages(bag))
    wrench = [m for m in recorded if m.topic == '/wrist_wrench']
    audio = [m for m in recorded if m.topic == '/audio']
    result = listener.run(_replay_command(bag, '--clock', '--rate', 4,
                                          '--wait-for-subscribers', 15))
    assert result.returncode == 0, result.stdout
    got = listener.got
    # Every message, once, in the recorded order.
    assert len(got['/wrist_wrench']) == len(wrench), _missing(wrench, got['/wrist_wrench'])
    assert len(got['/audio']) == len(audio)
    assert [_stamp_ns(m) for _, m in got['/wrist_wrench']] == [
        m.msg.header.stamp.sec * 1_000_000_000 + m.msg.header.stamp.nanosec for m in wrench]
    assert all(np.array_equal(np.asarray(g.data), r.msg.data)
               for (_, g), r in zip(got['/audio'], audio))
    # /clock walks through the bag's times: from its first to its last log time, never back,
    # and it shows every message's log time.
    clock = [m.clock.sec * 1_000_000_000 + m.clock.nanosec for _, m in got['/clock']]
    assert clock[0] == recorded[0].log_time_ns and clock[-1] == recorded[-1].log_time_ns
    assert np.all(np.diff(clock) >= 0)
    assert {m.log_time_ns for m in recorded} <= set(clock)
    # The original timing, four times faster: the time between the writes of two wrench
    # messages half the bag apart is a quarter of their stamps' difference. Write times, not
    # arrival times: a listener starved of CPU falls behind and catches up in a burst, which
    # shortens the arrival gaps without the replay being fast (seen with two training jobs on
    # the two cores). The median over the pairs, against a late write now and then.
    sent = np.array(listener.sent['/wrist_wrench']) * 1e-9
    stamps = np.array([_stamp_ns(m) for _, m in got['/wrist_wrench']]) * 1e-9
    half = len(sent) // 2
    pace = np.median((sent[half:] - sent[:len(sent) - half])
                     / (stamps[half:] - stamps[:len(sent) - half]))
    assert 0.25 * 0.9 <= pace <= 0.25 * 1.1
    every = [t for _, items in got.items() for t, _ in items]
    bag_span = (recorded[-1].log_time_ns - recorded[0].log_time_ns) * 1e-9
    assert max(every) - min(every) <= bag_span / 4 + 1.0


def test_replay_restamp_moves_stamps_to_now(bag, listener):
    wrench = [m for m in iter_messages(bag) if m.topic == '/wrist_wrench']
    result = listener.run(_replay_command(bag, '--restamp', '--wait-for-subscribers', 15))
    assert result.returncode == 0, result.stdout
    got = listener.got['/wrist_wrench']
    assert len(got) == len(wrench), _missing(wrench, got)
    assert not listener.got['/clock']
    original = np.array([m.msg.header.stamp.sec * 1_000_000_000 + m.msg.header.stamp.nanosec
                         for m in wrench])
    stamps = np.array([_stamp_ns(m) for _, m in got])
    # One constant shift: the relative timing is kept to the nanosecond ...
    shift = stamps - original
    assert np.all(shift == shift[0])
    # ... and it moves the stamps to this machine's time (the bag is from 2023).
    age = np.array([t for t, _ in got]) - stamps * 1e-9
    assert shift[0] * 1e-9 > 1e7
    assert abs(np.median(age)) < 0.1 and np.max(np.abs(age)) < 0.5


def test_replay_refuses_restamp_faster_than_real_time(bag):
    result = subprocess.run(_replay_command(bag, '--restamp', '--rate', 2), capture_output=True,
                            text=True, env=dict(os.environ), timeout=60)
    assert result.returncode == 1 and 'Traceback' not in result.stderr
    assert '--rate 1' in result.stderr


def test_replay_publishes_a_ros1_bag_into_ros2(bag, listener, tmp_path):
    """An old ROS 1 recording drives ROS 2 subscribers: same stamps, same samples."""
    from contact_detector.sim.bag_writer import ros1_int16_multiarray, ros1_wrench
    from rosbags.rosbag1 import Writer as Ros1Writer
    from rosbags.typesys import get_typestore, Stores

    recorded = list(iter_messages(bag))
    store = get_typestore(Stores.ROS1_NOETIC)
    old = tmp_path / 'old.bag'
    with Ros1Writer(old) as writer:
        conns = {}
        for m in recorded:
            if m.topic not in conns:
                conns[m.topic] = writer.add_connection(m.topic, m.msgtype, typestore=store)
            if m.topic == '/wrist_wrench':
                w = m.msg.wrench
                raw = ros1_wrench(stamp_ns=_stamp_ns(m.msg), values=[
                    w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z])
            else:
                raw = ros1_int16_multiarray(m.msg.data)
            writer.write(conns[m.topic], m.log_time_ns, raw)
    result = listener.run(_replay_command(old, '--rate', 4, '--wait-for-subscribers', 15))
    assert result.returncode == 0, result.stdout
    wrench = [m for m in recorded if m.topic == '/wrist_wrench']
    audio = [m for m in recorded if m.topic == '/audio']
    got = listener.got
    assert len(got['/wrist_wrench']) == len(wrench), _missing(wrench, got['/wrist_wrench'])
    assert [_stamp_ns(m) for _, m in got['/wrist_wrench']] == [_stamp_ns(m.msg) for m in wrench]
    assert [g.wrench.force.z for _, g in got['/wrist_wrench']] == [
        m.msg.wrench.force.z for m in wrench]
    assert len(got['/audio']) == len(audio)
    assert all(np.array_equal(np.asarray(g.data), r.msg.data)
               for (_, g), r in zip(got['/audio'], audio))
