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
Publish a bag into the live ROS graph with its original timing (no ``ros2 bag``).

rosbag2 messages go out as their recorded CDR bytes, so any type rclpy can import plays back
unchanged; ROS 1 bags are converted to ROS 2 CDR first
(:func:`contact_detector.io.bags.iter_cdr`). The bag is read by the offline commands' reader,
so a damaged bag plays up to where it is readable, with one warning naming the damage
(:mod:`contact_detector.io.salvage`). Two options make a recording look live:

* ``clock``: publish ``/clock`` (rosgraph_msgs/Clock) with the bag time before every message
  and at least every 10 ms, for nodes running with ``use_sim_time`` — as
  ``ros2 bag play --clock`` does;
* ``restamp``: shift every ``header.stamp`` by the offset between bag time and this machine's
  time, as if the sensors were publishing now (for nodes on wall time, like a real robot;
  real-time rate only).

:func:`replay_bag` plays a bag on a node of its own (``contact-detector replay``).
"""

from dataclasses import dataclass
import importlib
from pathlib import Path
import threading
import time
from typing import Callable, Dict, List, Optional, Sequence

from contact_detector.errors import BagError
from contact_detector.io.bags import iter_cdr
import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message

CLOCK_PERIOD_S = 0.01
#: History depth of the /clock publisher, three times the data topics' 200: it sends a tick
#: before the message of every topic and every CLOCK_PERIOD_S besides, so more messages than any
#: one data topic (at --rate 4 with 100 Hz F/T and 16 kHz audio, about twice the F/T topic's).
CLOCK_DEPTH = 600


def import_message(msgtype: str):
    """Return the rclpy class of ``pkg/msg/Name``; ImportError if the package is missing."""
    package, _, name = msgtype.split('/')
    return getattr(importlib.import_module(f'{package}.msg'), name)


@dataclass
class Recorded:
    """One message: topic, type name, log time (ns), CDR bytes."""

    topic: str
    msgtype: str
    log_ns: int
    raw: bytes


def read_recording(bag: Path, *, topics: Optional[Sequence[str]] = None) -> List[Recorded]:
    """
    Read every message of a bag (rosbag2 or ROS 1) as ROS 2 CDR, in log-time order.

    A damaged bag gives its readable messages and logs one warning (logger
    ``contact_detector.io.bags``); BagError if nothing in it can be read.
    """
    try:
        return [Recorded(topic=topic, msgtype=msgtype, log_ns=t, raw=raw)
                for topic, msgtype, t, raw in iter_cdr(Path(bag), topics=topics)]
    except BagError:
        raise
    except Exception as err:  # rosbags raises several unrelated types for unreadable bags
        raise BagError(f'cannot read bag {bag}: {err}') from err


class BagPlayer:
    """
    Publish recordings on a node with their original timing, scaled by ``rate``.

    Parameters
    ----------
    node : Node
        Publishes the topics (and ``/clock``).
    rate : float
        Playback speed (2 = twice as fast).
    clock : bool
        Publish ``/clock`` with the bag time.
    restamp : bool
        Shift header stamps to this machine's time.
    log : callable
        Where to report skipped topics.

    """

    def __init__(self, *, node: Node, rate: float = 1.0, clock: bool = False,
                 restamp: bool = False, log: Callable[[str], None] = print) -> None:
        if not rate > 0:
            raise BagError(f'--rate must be > 0, got {rate}')
        if restamp and rate != 1.0:
            # Audio without headers is timed by arrival: it cannot play faster than real time.
            raise BagError('--restamp plays in real time only (--rate 1); use --clock with '
                           'use_sim_time to play faster')
        self.node = node
        self.rate = rate
        self.clock = clock
        self.restamp = restamp
        self.log = log
        self._publishers: Dict[str, object] = {}
        self._types: Dict[str, object] = {}
        self._skipped: set = set()
        qos = QoSProfile(depth=200, reliability=ReliabilityPolicy.RELIABLE)
        self._qos = qos
        self._clock_pub = None
        if clock:
            from rosgraph_msgs.msg import Clock
            self._clock_msg = Clock
            # Reliable, and deeper than the data topics: with their depth (200) /clock was the
            # first history to overrun when a subscriber fell behind at --rate 4 on a loaded
            # machine, and a tick was lost (a depth of 10 lost them at once).
            self._clock_pub = node.create_publisher(Clock, '/clock', QoSProfile(
                depth=CLOCK_DEPTH, reliability=ReliabilityPolicy.RELIABLE))
        self.published = 0

    def _publisher(self, record: Recorded):
        if record.topic in self._publishers:
            return self._publishers[record.topic]
        try:
            cls = import_message(record.msgtype)
        except (ImportError, AttributeError, ValueError):
            if record.topic not in self._skipped:
                self._skipped.add(record.topic)
                self.log(f'skipping {record.topic}: message type {record.msgtype} is not '
                         'installed')
            return None
        self._types[record.topic] = cls
        self._publishers[record.topic] = self.node.create_publisher(cls, record.topic,
                                                                    self._qos)
        return self._publishers[record.topic]

    def wait_for_subscribers(self, records: Sequence[Recorded], *, timeout_s: float,
                             stop: Optional[threading.Event] = None) -> List[str]:
        """
        Create the publishers of ``records`` now and wait until each has a subscriber.

        DDS discovery of a new publisher can take seconds (FastDDS on loopback: up to ~3 s),
        and a volatile subscription never sees what was published before it matched, so
        without this wait the start of a short recording is lost. Topics nobody subscribes
        to hold the start back by ``timeout_s`` at most.

        Parameters
        ----------
        records : sequence of Recorded
            The recording to be played.
        timeout_s : float
            Longest wait, seconds of this machine's time.
        stop : threading.Event or None
            Ends the wait early when set.

        Returns
        -------
        list of str
            The topics (``/clock`` included) still without a subscriber.

        """
        publishers = {}
        for record in records:
            if record.topic not in publishers:
                publishers[record.topic] = self._publisher(record)
        if self._clock_pub is not None:
            publishers['/clock'] = self._clock_pub
        waiting = {t: p for t, p in publishers.items() if p is not None}
        end = time.monotonic() + timeout_s
        while waiting and time.monotonic() < end:
            if stop is not None and stop.is_set():
                break
            waiting = {t: p for t, p in waiting.items() if p.get_subscription_count() == 0}
            if waiting:
                time.sleep(0.01)
        return sorted(waiting)

    def _publish_clock(self, bag_ns: int) -> None:
        msg = self._clock_msg()
        msg.clock.sec, msg.clock.nanosec = divmod(int(bag_ns), 1_000_000_000)
        self._clock_pub.publish(msg)

    def play(self, records: Sequence[Recorded], *,
             stop: Optional[threading.Event] = None,
             on_start: Optional[Callable[[float, float], None]] = None) -> int:
        """
        Publish ``records`` once; return how many were published.

        ``on_start(bag_start_s, wall_start_s)`` is called when the first message goes out, so
        callers can map bag times to this machine's time.
        """
        if not records:
            return 0
        start_ns = records[0].log_ns
        wall0 = time.time()
        mono0 = time.monotonic()
        offset_ns = int(wall0 * 1e9) - start_ns
        if on_start:
            on_start(start_ns * 1e-9, wall0)
        next_clock = 0.0
        for record in records:
            due = (record.log_ns - start_ns) * 1e-9 / self.rate
            while True:
                if stop is not None and stop.is_set():
                    return self.published
                ahead = due - (time.monotonic() - mono0)
                if self.clock and time.monotonic() - mono0 >= next_clock:
                    elapsed = (time.monotonic() - mono0) * self.rate
                    self._publish_clock(start_ns + int(min(elapsed * 1e9,
                                                           record.log_ns - start_ns)))
                    next_clock = time.monotonic() - mono0 + CLOCK_PERIOD_S
                if ahead <= 0:
                    break
                time.sleep(min(ahead, CLOCK_PERIOD_S / 2))
            publisher = self._publisher(record)
            if publisher is None:
                continue
            if self.clock:
                self._publish_clock(record.log_ns)
            raw = record.raw
            if self.restamp:
                raw = self._restamped(record, offset_ns)
            publisher.publish(raw)
            self.published += 1
        return self.published

    def flush(self, *, timeout_s: float = 5.0) -> bool:
        """
        Wait until every subscriber has acknowledged what was published; True if all did.

        Publishing is asynchronous: a process that exits right after its last ``publish`` can
        take the final messages with it, and the subscriber never sees the end of the bag.
        Only reliable publishers wait (all of ours are); ``timeout_s`` bounds the wait.
        """
        from rclpy.duration import Duration

        publishers = [p for p in self._publishers.values() if p is not None]
        if self._clock_pub is not None:
            publishers.append(self._clock_pub)
        end = time.monotonic() + timeout_s
        acked = True
        for publisher in publishers:
            left = max(0.0, end - time.monotonic())
            acked = publisher.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9))) and acked
        return acked

    def _restamped(self, record: Recorded, offset_ns: int) -> bytes:
        cls = self._types[record.topic]
        if 'header' not in cls.get_fields_and_field_types():
            return record.raw
        msg = deserialize_message(record.raw, cls)
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp + offset_ns,
                                                                1_000_000_000)
        return serialize_message(msg)


def replay_bag(*, bag: Path, rate: float = 1.0, loop: bool = False, clock: bool = False,
               restamp: bool = False, topics: Optional[Sequence[str]] = None,
               wait_for_subscribers_s: float = 0.0) -> None:
    """
    Publish a bag on a node of its own (``contact_detector_replay``), as ``ros2 bag play``.

    Prints what it plays to stdout. Returns when the bag has played (``loop``: never) and the
    subscribers have acknowledged it (5 s at most), or on Ctrl-C or an external shutdown.

    Parameters
    ----------
    bag : Path
        rosbag2 folder or ROS 1 ``.bag``.
    rate : float
        Playback speed (2 = twice as fast).
    loop : bool
        Play again and again.
    clock : bool
        Publish ``/clock`` with the bag time.
    restamp : bool
        Shift header stamps to this machine's time (rate 1 only).
    topics : sequence of str or None
        Only these topics (None: all).
    wait_for_subscribers_s : float
        Before playing, wait up to this long until every topic has a subscriber, s (0: start
        at once).

    Raises
    ------
    BagError
        Nothing in the bag can be read or it has no messages, or the options do not fit
        together. A damaged bag plays what can be read (one warning names the damage).

    """
    from rclpy.executors import ExternalShutdownException

    records = read_recording(bag, topics=topics)
    if not records:
        raise BagError(f'{bag} has no messages')
    rclpy.init()
    node = rclpy.create_node('contact_detector_replay')
    try:
        player = BagPlayer(node=node, rate=rate, clock=clock, restamp=restamp,
                           log=node.get_logger().warning)
        duration = (records[-1].log_ns - records[0].log_ns) * 1e-9
        if wait_for_subscribers_s > 0:
            lonely = player.wait_for_subscribers(records, timeout_s=wait_for_subscribers_s)
            if lonely:
                print(f'no subscriber after {wait_for_subscribers_s:g} s on '
                      f'{", ".join(lonely)}; playing anyway', flush=True)
        while True:
            print(f'playing {bag.name}: {len(records)} messages, {duration:.1f} s '
                  f'at {rate:g}x', flush=True)
            player.play(records)
            if not loop:
                break
        if not player.flush(timeout_s=5.0):
            print('some subscribers did not acknowledge the last messages within 5 s',
                  flush=True)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
