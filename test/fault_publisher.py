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
Trial publisher with injected faults, for test_faults_e2e.py (its own process).

Plays simulated trial ``--seed/--index/--hits`` from its start on ``wrist_wrench``
(geometry_msgs/WrenchStamped, one sample per message) and ``audio`` (std_msgs/Int16MultiArray,
10 ms chunks) at the real rate with best-effort sensor-data QoS, its times shifted to the wall
clock, once the node subscribes. Faults (``--faults``, comma-separated, times relative to the
trial's contact onset in s):

    nan         -4.80  three wrench samples with NaN force
    empty       -4.60  two empty audio chunks
    huge        -4.50  one 10 s audio chunk (160000 samples)
    backwards   -4.20  three extra wrench messages stamped 0.2 s back
    duplicate   -4.10  three wrench messages sent twice
    future      -4.00  three extra wrench messages stamped 30 s ahead
    burst       -3.80  0.3 s of messages held back, then sent at once
    ft100ms     -3.30  wrench dropout of 100 ms
    jump        -3.00  three wrench messages stamped 30 s back (a sensor driver restart)
    ft2s        -5.30  wrench dropout of 2 s
    audio600ms  -3.00  audio dropout of 0.6 s
    nan_late    -2.20  two wrench samples with NaN force

``--die-at REL`` kills the process with SIGKILL at that time (a crashed publisher); ``--stop-at
REL`` ends it cleanly there. The shift and the onset's wall time are written to ``--out`` before
the first message; at a clean end the file is rewritten with the count of messages sent.

    python test/fault_publisher.py --out a.json --faults nan,empty --die-at -2.8
"""

import argparse
from array import array
import json
import os
from pathlib import Path
import signal
import sys
import time

import rclpy
from rclpy.qos import qos_profile_sensor_data

sys.path.insert(0, str(Path(__file__).resolve().parent))

FAULT_TIMES = {'nan': -4.8, 'empty': -4.6, 'huge': -4.5, 'backwards': -4.2,
               'duplicate': -4.1, 'future': -4.0, 'burst': -3.8, 'ft100ms': -3.3,
               'jump': -3.0, 'ft2s': -5.3, 'audio600ms': -3.0, 'nan_late': -2.2}


def _stamp(t: float):
    from builtin_interfaces.msg import Time
    sec = int(t)
    return Time(sec=sec, nanosec=min(999_999_999, int(round((t - sec) * 1e9))))


def schedule(trial, faults: set) -> list:
    """Return ``(trial time to send at, topic, what)`` in order, faults applied."""
    import node_support
    onset = trial.onset_t
    out = []
    counts = {}

    def at(name: str) -> float:
        return onset + FAULT_TIMES[name]

    for e in node_support.trial_events(trial):
        if e.kind == 'audio':
            if 'audio600ms' in faults and at('audio600ms') <= e.t < at('audio600ms') + 0.6:
                continue
            out.append((e.t, 'audio', ('chunk', e.lo, e.hi)))
            for name, n, what in (('empty', 2, ('empty',)), ('huge', 1, ('huge',))):
                if name in faults and e.t >= at(name) and counts.get(name, 0) < n:
                    counts[name] = counts.get(name, 0) + 1
                    out.append((e.t, 'audio', what))
            continue
        j = e.lo
        stamp = float(trial.wrench_t[j])
        if 'ft100ms' in faults and at('ft100ms') <= e.t < at('ft100ms') + 0.1:
            continue
        if 'ft2s' in faults and at('ft2s') <= e.t < at('ft2s') + 2.0:
            continue
        nan = False
        for name, n in (('nan', 3), ('nan_late', 2)):
            if name in faults and e.t >= at(name) and counts.get(name, 0) < n:
                counts[name] = counts.get(name, 0) + 1
                nan = True
        if 'jump' in faults and e.t >= at('jump') and counts.get('jump', 0) < 3:
            counts['jump'] = counts.get('jump', 0) + 1
            stamp -= 30.0
        out.append((e.t, 'wrench', (stamp, j, nan)))
        for name, n, offset in (('backwards', 3, -0.2), ('duplicate', 3, 0.0),
                                ('future', 3, 30.0)):
            if name in faults and e.t >= at(name) and counts.get(name, 0) < n:
                counts[name] = counts.get(name, 0) + 1
                out.append((e.t, 'wrench', (stamp + offset, j, False)))
    if 'burst' in faults:
        lo, hi = at('burst'), at('burst') + 0.3
        out = [(hi if lo <= t < hi else t, topic, what) for t, topic, what in out]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--out', required=True)
    parser.add_argument('--seed', type=int, default=3)
    parser.add_argument('--index', type=int, default=21)
    parser.add_argument('--hits', default='hand')
    parser.add_argument('--faults', default='')
    parser.add_argument('--die-at', type=float, default=None)
    parser.add_argument('--stop-at', type=float, default=1.5)
    args = parser.parse_args()

    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Int16MultiArray

    from contact_detector.sim.trial import simulate_trial

    trial = simulate_trial(seed=args.seed, index=args.index, hits=args.hits)
    faults = {f for f in args.faults.split(',') if f}
    unknown = faults - set(FAULT_TIMES)
    if unknown:
        raise SystemExit(f'unknown faults {sorted(unknown)}')
    plan = [p for p in schedule(trial, faults) if p[0] < trial.onset_t + args.stop_at]

    rclpy.init()
    node = rclpy.create_node('fault_publisher')
    wrench_pub = node.create_publisher(WrenchStamped, 'wrist_wrench', qos_profile_sensor_data)
    audio_pub = node.create_publisher(Int16MultiArray, 'audio', qos_profile_sensor_data)
    end = time.monotonic() + 60.0
    while not (wrench_pub.get_subscription_count() and audio_pub.get_subscription_count()):
        if time.monotonic() > end:
            raise SystemExit('fault_publisher: the node did not subscribe')
        rclpy.spin_once(node, timeout_sec=0.05)
    time.sleep(0.5)             # let the DDS readers match
    shift = time.time() + 0.1 - trial.start_time
    info = {'shift': shift, 'onset_wall': trial.onset_t + shift,
            'start_wall': trial.start_time + shift, 'faults': sorted(faults)}
    Path(args.out).write_text(json.dumps(info))
    die_at = None if args.die_at is None else trial.onset_t + args.die_at
    msg = WrenchStamped()
    msg.header.frame_id = 'wrist_ft_sensor_frame'
    sent = {'audio': 0, 'wrench': 0}
    for t, topic, what in plan:
        if die_at is not None and t >= die_at:
            os.kill(os.getpid(), signal.SIGKILL)
        delay = t + shift - time.time()
        if delay > 0:
            time.sleep(delay)
        if topic == 'wrench':
            stamp, j, nan = what
            msg.header.stamp = _stamp(stamp + shift)
            f, m = trial.force[j], trial.torque[j]
            msg.wrench.force.x = float('nan') if nan else float(f[0])
            msg.wrench.force.y, msg.wrench.force.z = float(f[1]), float(f[2])
            msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = map(float, m)
            wrench_pub.publish(msg)
        else:
            chunk = Int16MultiArray()
            if what[0] == 'chunk':
                chunk.data = array('h', trial.audio[what[1]:what[2]].tobytes())
            elif what[0] == 'huge':
                chunk.data = array('h', bytes(2 * 160000))
            audio_pub.publish(chunk)
        sent[topic] += 1
    time.sleep(0.3)
    info['sent'] = sent
    Path(args.out).write_text(json.dumps(info))
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == '__main__':
    main()
