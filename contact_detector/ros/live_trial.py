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
A simulated trial played live into the node, and a listener of its outputs: two processes.

Used by the multi-process test (test/e2e/), the Ubuntu 24.04 test and
``benchmarks/bench_node.py``, each as its own process, so the node is measured against real DDS
traffic.

``publish``: plays a simulated trial at the real rate on ``wrist_wrench`` and ``audio``, its
times shifted to the wall clock, once the node and the listener are up. Writes the shift, the
true onset and the exogenous impacts (wall time) and every audio publish time as JSON.

``listen``: records the wall time of every ``contact``, ``contact_probability`` and ``release``
message until ``--stop-file`` appears (or ``--max-s``), then writes JSON.

    python -m contact_detector.ros.live_trial publish --out pub.json [--seed 3 --index 21]
    python -m contact_detector.ros.live_trial listen --out listen.json --stop-file stop
"""

import argparse
import json
from pathlib import Path
import sys
import time
from typing import Optional, Sequence

from contact_detector.sim.messages import message_events
from contact_detector.sim.trial import simulate_trial
import rclpy
from rclpy.qos import qos_profile_sensor_data, QoSProfile, ReliabilityPolicy


def _stamp(t: float):
    """Return a ``builtin_interfaces/Time`` of ``t`` seconds."""
    from builtin_interfaces.msg import Time
    sec = int(t)
    return Time(sec=sec, nanosec=min(999_999_999, int(round((t - sec) * 1e9))))


def _wait(node, predicate, timeout: float, what: str) -> None:
    """Spin ``node`` until ``predicate()`` holds; exit with a message after ``timeout`` s."""
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            raise SystemExit(f'live_trial: timed out waiting for {what}')
        rclpy.spin_once(node, timeout_sec=0.05)


def publish(args: argparse.Namespace) -> None:
    """Play one simulated trial at its real rate, then write what was sent (JSON)."""
    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Int16MultiArray

    trial = simulate_trial(seed=args.seed, index=args.index, hits=args.hits,
                           audio_rate=args.audio_rate, ft_rate=args.ft_rate,
                           chunk_size=args.chunk or None)
    events = message_events(trial=trial)
    if args.seconds:
        events = [e for e in events if e.t < trial.start_time + args.seconds]
    if args.after_onset:
        events = [e for e in events if e.t < trial.onset_t + args.after_onset]
    rclpy.init()
    node = rclpy.create_node('e2e_publisher')
    qos = qos_profile_sensor_data
    wrench_pub = node.create_publisher(WrenchStamped, 'wrist_wrench', qos)
    audio_pub = node.create_publisher(Int16MultiArray, 'audio', qos)
    _wait(node, lambda: (wrench_pub.get_subscription_count() > 0
                         and audio_pub.get_subscription_count() > 0
                         and node.count_subscribers('contact') >= args.listeners
                         and node.count_subscribers('release') >= args.listeners
                         and all(Path(f).exists() for f in args.wait_file)),
          60.0, 'the node and the listener')
    time.sleep(1.0)     # let the DDS readers of all parties match
    wall0 = time.time() + 0.1
    shift = wall0 - trial.start_time
    msg = WrenchStamped()
    msg.header.frame_id = 'wrist_ft_sensor_frame'
    audio_times = []
    late = []
    for e in events:
        target = e.t + shift
        delay = target - time.time()
        if delay > 0:
            time.sleep(delay)
        else:
            late.append(-delay)
        if e.kind == 'wrench':
            j = e.lo
            msg.header.stamp = _stamp(float(trial.wrench_t[j] + shift))
            f, m = trial.force[j], trial.torque[j]
            msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = map(float, f)
            msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = map(float, m)
            wrench_pub.publish(msg)
        else:
            chunk = Int16MultiArray()
            chunk.data = trial.audio[e.lo:e.hi]
            audio_times.append(time.time())      # just before the chunk leaves
            audio_pub.publish(chunk)
    time.sleep(0.3)
    result = {
        'shift': shift, 'start_wall': trial.start_time + shift,
        'end_wall': time.time(),
        'onset_wall': trial.onset_t + shift,
        'impacts': [{'t_wall': i.t + shift, 'kind': i.kind, 'in_air': i.in_air}
                    for i in trial.impacts],
        'audio_times': audio_times,
        'audio_chunks': len(audio_times),
        'audio_samples': int(sum(e.hi - e.lo for e in events if e.kind == 'audio')),
        'late_p99_ms': 1e3 * sorted(late)[int(0.99 * len(late))] if late else 0.0,
    }
    Path(args.out).write_text(json.dumps(result))
    node.destroy_node()
    rclpy.try_shutdown()


def listen(args: argparse.Namespace) -> None:
    """Record the wall time of every output message until the stop file appears (JSON)."""
    from std_msgs.msg import Bool, Float32

    rclpy.init()
    node = rclpy.create_node('e2e_listener')
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    record = {'contact': [], 'contact_probability': [], 'release': []}

    def sink(name):
        def callback(msg):
            record[name].append((time.time(), msg.data if name != 'contact_probability'
                                 else float(msg.data)))
        return callback

    subs = [node.create_subscription(Bool, 'contact', sink('contact'), qos),
            node.create_subscription(Float32, 'contact_probability', sink('contact_probability'),
                                     qos),
            node.create_subscription(Bool, 'release', sink('release'), qos)]
    stop = Path(args.stop_file)
    ready = Path(args.ready_file) if args.ready_file else None
    end = time.monotonic() + args.max_s
    while not stop.exists() and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.02)
        # Matched with the node's publishers: the publisher may start (frames before that are
        # lost to this listener, however reliable the QoS, and a start-up race is not the node's).
        if ready is not None and all(sub.get_publisher_count() > 0 for sub in subs):
            ready.touch()
            ready = None
    Path(args.out).write_text(json.dumps(record))
    node.destroy_node()
    rclpy.try_shutdown()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``publish`` or ``listen``; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='cmd', required=True)
    pub = sub.add_parser('publish')
    pub.add_argument('--out', required=True)
    pub.add_argument('--seed', type=int, default=3)
    pub.add_argument('--index', type=int, default=21)
    pub.add_argument('--hits', default='hand')
    pub.add_argument('--audio-rate', type=int, default=16000)
    pub.add_argument('--ft-rate', type=float, default=100.0)
    pub.add_argument('--chunk', type=int, default=0, help='audio samples per message')
    pub.add_argument('--seconds', type=float, default=0.0, help='play only this much')
    pub.add_argument('--after-onset', type=float, default=0.0,
                     help='stop this long after the true onset')
    pub.add_argument('--listeners', type=int, default=1)
    pub.add_argument('--wait-file', action='append', default=[],
                     help="start once this file exists (a listener's --ready-file)")
    lis = sub.add_parser('listen')
    lis.add_argument('--out', required=True)
    lis.add_argument('--stop-file', required=True)
    lis.add_argument('--max-s', type=float, default=120.0)
    lis.add_argument('--ready-file', default='',
                     help="touched once every subscription has matched the node's publishers")
    args = parser.parse_args(argv)
    if args.cmd == 'publish':
        publish(args)
    else:
        listen(args)
    return 0


if __name__ == '__main__':
    sys.exit(main())
