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
``contact-detector replay`` of a damaged bag: it plays what can be read, then stops.

The bag is written in tmp_path with rosbags' writers (the simulator's bag writer) and cut as a
recorder killed mid-write leaves it. The replay runs in this process (``replay`` main, real
rclpy, DDS on loopback: conftest.py); a subscriber in a context of its own, spun in a thread,
records what arrives.
"""

import logging
from pathlib import Path
import threading
import time

from contact_detector.cli import replay as replay_cli
from contact_detector.io.bags import iter_messages
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy

pytestmark = pytest.mark.rclpy


def _cut(file: Path, fraction: float) -> None:
    data = file.read_bytes()
    file.write_bytes(data[:int(len(data) * fraction)])


def _storage_file(bag: Path) -> Path:
    if bag.is_file():
        return bag
    return next(p for p in bag.iterdir() if p.suffix in ('.db3', '.mcap'))


def _stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


class Subscriber:
    """Records /wrist_wrench and /audio in a context of its own, spun in a thread."""

    def __init__(self) -> None:
        from geometry_msgs.msg import WrenchStamped
        from std_msgs.msg import Int16MultiArray

        self.context = Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('damaged_replay_listener', context=self.context)
        self.got = {'/wrist_wrench': [], '/audio': []}
        qos = QoSProfile(depth=2000, reliability=ReliabilityPolicy.RELIABLE)
        for cls, topic in ((WrenchStamped, '/wrist_wrench'), (Int16MultiArray, '/audio')):
            self.node.create_subscription(
                cls, topic, lambda msg, topic=topic: self.got[topic].append(msg), qos)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.005)

    def close(self, *, drain_s: float = 0.5) -> None:
        time.sleep(drain_s)
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.mark.parametrize('storage', ['ros1', 'mcap'])
def test_a_cut_bag_replays_the_messages_before_the_cut(tmp_path, caplog, storage):
    bag = write_trial_bag(trial=simulate_trial(seed=5, index=0), path=tmp_path / 'trial',
                          storage=storage)
    intact = {topic: [m.msg for m in iter_messages(bag, topics=[topic])]
              for topic in ('/wrist_wrench', '/audio')}
    _cut(_storage_file(bag), 0.5)
    listener = Subscriber()
    try:
        with caplog.at_level(logging.WARNING):
            status = replay_cli.main([str(bag), '--rate', '4', '--wait-for-subscribers', '15'])
    finally:
        listener.close()
    assert status == 0
    # one warning naming the bag and the damage, as every offline command gives
    warnings = [r.getMessage() for r in caplog.records
                if r.levelno == logging.WARNING and 'damaged bag' in r.getMessage()]
    assert len(warnings) == 1 and str(bag) in warnings[0], warnings
    wrench, audio = listener.got['/wrist_wrench'], listener.got['/audio']
    # the bag's start, in order and unchanged, up to the cut: nothing after it, nothing invented
    assert 0 < len(wrench) < len(intact['/wrist_wrench'])
    assert 0 < len(audio) < len(intact['/audio'])
    assert [_stamp_ns(m) for m in wrench] == [
        _stamp_ns(m) for m in intact['/wrist_wrench'][:len(wrench)]]
    assert all(g.wrench.force.z == r.wrench.force.z
               for g, r in zip(wrench, intact['/wrist_wrench']))
    assert all(np.array_equal(np.asarray(g.data), r.data)
               for g, r in zip(audio, intact['/audio']))
    # what the damaged bag reads is exactly what was played
    readable = list(iter_messages(bag, topics=['/wrist_wrench']))
    assert len(wrench) == len(readable)


def test_a_bag_with_nothing_readable_is_a_clear_error(tmp_path, capsys):
    bag = write_trial_bag(trial=simulate_trial(seed=5, index=0), path=tmp_path / 'trial',
                          storage='ros1')
    _cut(bag, 0.001)
    assert replay_cli.main([str(bag)]) == 1
    err = capsys.readouterr().err
    assert str(bag) in err and 'no readable topic or message' in err
    assert 'Traceback' not in err
