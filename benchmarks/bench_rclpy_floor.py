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
CPU floor of a Python rclpy process that only receives the node's two sensor inputs.

A publisher process sends what the node subscribes to: ``geometry_msgs/WrenchStamped`` at
100 Hz and ``std_msgs/Int16MultiArray`` with 441-sample chunks (10 ms of 44.1 kHz audio) at
100 Hz, best-effort sensor-data QoS, 200 messages/s in all. A subscriber process per variant
receives them and does nothing else (the callbacks count); its CPU time (all threads: Python,
the executor, Fast DDS's receive and event threads) over wall time is measured in-process
(``time.process_time``) over a window that starts 2 s after the first message. Variants:

==================  =========================================================================
``idle``            a node without subscriptions (the DDS participant alone: discovery etc.)
``stock``           rclpy ``SingleThreadedExecutor``, empty callbacks (messages built)
``stock_raw``       the same with ``raw=True`` subscriptions (serialised bytes)
``waitset``         one rclpy ``WaitSet`` reused across iterations, one take per ready sub
``waitset_raw``     the same, ``raw=True``
``waitset_drain``   ``waitset_raw``, and every ready subscription taken until it is empty
``events``          ``rclpy.experimental.EventsExecutor`` (C++ executor, ``spin_once``
                    loop), empty callbacks
``events_raw``      the same, ``raw=True``
``raw_shm``         ``waitset_raw`` with ``FASTDDS_BUILTIN_TRANSPORTS=SHM`` (subscriber)
``raw_udp``         ``waitset_raw`` with ``FASTDDS_BUILTIN_TRANSPORTS=UDPv4`` (subscriber)
``poll_10ms_raw``   sleep 10 ms, then take everything (batching: adds up to 10 ms latency;
                    a reference only, the node's latency target excludes it)
``echo_raw``        ``waitset_raw``, and for each audio chunk the node's two per-frame outputs
                    published as CDR bytes (``contact`` Bool, ``contact_probability``
                    Float32, reliable, as the node does) to a listener in the publisher
                    process: the floor of the node's whole interface with no work at all
==================  =========================================================================

All variants run in each round (rounds repeated ``--repeats`` times, variants interleaved) so
the medians share the machine's load; the load average and the machine's total CPU use over
the run are printed with the table, since on a shared machine another job's load changes
wake-up costs.

    python benchmarks/bench_rclpy_floor.py [--repeats 3] [--seconds 10] [--variants a,b]
"""

import argparse
import json
import os
from pathlib import Path
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

REPO = Path(__file__).resolve().parents[1]
RATE_HZ = 100.0
CHUNK = 441
WARMUP_S = 2.0

#: Variant -> extra environment of the subscriber process.
VARIANTS = {
    'idle': {},
    'stock': {},
    'stock_raw': {},
    'waitset': {},
    'waitset_raw': {},
    'waitset_drain': {},
    'events': {},
    'events_raw': {},
    'raw_shm': {'FASTDDS_BUILTIN_TRANSPORTS': 'SHM'},
    'raw_udp': {'FASTDDS_BUILTIN_TRANSPORTS': 'UDPv4'},
    'poll_10ms_raw': {},
    'echo_raw': {},
}


def _output_qos():
    """Return the node's output QoS (reliable, depth ``node.OUTPUT_DEPTH``)."""
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from contact_detector.ros.node import OUTPUT_DEPTH
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=OUTPUT_DEPTH,
                      reliability=ReliabilityPolicy.RELIABLE)


def _echo_outputs(node):
    """Return a callable that publishes the node's two per-frame outputs, as CDR bytes."""
    from std_msgs.msg import Bool, Float32
    from contact_detector.io.cdr import BOOL_FALSE, write_float32
    contact_pub = node.create_publisher(Bool, 'contact', _output_qos())
    probability_pub = node.create_publisher(Float32, 'contact_probability', _output_qos())

    def echo() -> None:
        contact_pub.publish(BOOL_FALSE)
        probability_pub.publish(write_float32(0.25))
    return echo


def _cpu_busy() -> tuple:
    """(busy, total) jiffies of the whole machine, from /proc/stat."""
    fields = [int(v) for v in Path('/proc/stat').read_text().split('\n')[0].split()[1:]]
    idle = fields[3] + fields[4]
    return sum(fields) - idle, sum(fields)


def publish(args: argparse.Namespace) -> None:
    """Publish both inputs at :data:`RATE_HZ` until SIGINT."""
    import numpy as np
    import rclpy
    from rclpy.qos import qos_profile_sensor_data
    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Bool, Float32, Int16MultiArray

    rclpy.init()
    node = rclpy.create_node('floor_publisher')
    wrench_pub = node.create_publisher(WrenchStamped, 'wrist_wrench', qos_profile_sensor_data)
    audio_pub = node.create_publisher(Int16MultiArray, 'audio', qos_profile_sensor_data)
    # The node's outputs, for the ``echo_raw`` variant (a listener, as in bench_node.py).
    heard = [0]
    for msg_type, topic in ((Bool, 'contact'), (Float32, 'contact_probability')):
        node.create_subscription(msg_type, topic, lambda _msg: heard.__setitem__(0, heard[0] + 1),
                                 _output_qos())
    threading.Thread(target=rclpy.spin, args=(node,), daemon=True).start()
    rng = np.random.default_rng(0)
    chunks = [rng.integers(-3000, 3000, CHUNK, dtype=np.int16) for _ in range(16)]
    wrench = WrenchStamped()
    wrench.header.frame_id = 'wrist_ft_sensor_frame'
    audio = Int16MultiArray()
    period = 1.0 / RATE_HZ
    deadline = time.monotonic()
    count = 0
    try:
        while True:
            deadline += period
            delay = deadline - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            elif delay < -0.5:
                deadline = time.monotonic()       # far behind (machine stalled): resync
            now = time.time_ns()
            wrench.header.stamp.sec, wrench.header.stamp.nanosec = divmod(now, 10**9)
            wrench.wrench.force.x = float(count % 100)
            wrench_pub.publish(wrench)
            audio.data = chunks[count % len(chunks)]
            audio_pub.publish(audio)
            count += 1
    except KeyboardInterrupt:
        pass
    node.destroy_node()
    rclpy.try_shutdown()


def _measure(counts: list, seconds: float, out: Path) -> None:
    """Wait for traffic, measure the process's CPU over ``seconds``, write, exit the process."""
    while not (counts[0] and counts[1]):
        time.sleep(0.05)
    time.sleep(WARMUP_S)
    c0, w0, n0 = time.process_time(), time.monotonic(), sum(counts)
    time.sleep(seconds)
    c1, w1, n1 = time.process_time(), time.monotonic(), sum(counts)
    out.write_text(json.dumps({'cpu': (c1 - c0) / (w1 - w0), 'msgs': n1 - n0,
                               'seconds': w1 - w0}))
    os._exit(0)


def subscribe(args: argparse.Namespace) -> None:
    """Receive both inputs as ``args.variant`` says; measure; exit."""
    import rclpy
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.qos import qos_profile_sensor_data
    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Int16MultiArray

    variant = args.variant
    raw = variant.endswith('raw') or variant in ('waitset_drain', 'raw_shm', 'raw_udp')
    rclpy.init()
    node = rclpy.create_node('floor_subscriber')
    counts = [0, 0]

    def on_wrench(msg) -> None:
        counts[0] += 1

    echo = _echo_outputs(node) if variant == 'echo_raw' else None

    def on_audio(msg) -> None:
        counts[1] += 1
        if echo is not None:
            echo()

    if variant == 'idle':
        counts[:] = [1, 1]
        threading.Thread(target=_measure, args=(counts, args.seconds, Path(args.out)),
                         daemon=True).start()
        rclpy.spin(node)
        return
    subs = [node.create_subscription(WrenchStamped, 'wrist_wrench', on_wrench,
                                     qos_profile_sensor_data, raw=raw),
            node.create_subscription(Int16MultiArray, 'audio', on_audio,
                                     qos_profile_sensor_data, raw=raw)]
    threading.Thread(target=_measure, args=(counts, args.seconds, Path(args.out)),
                     daemon=True).start()
    if variant.startswith('stock'):
        executor = rclpy.executors.SingleThreadedExecutor()
        executor.add_node(node)
        executor.spin()
        return
    if variant.startswith('events'):
        from rclpy.experimental import EventsExecutor
        executor = EventsExecutor()
        executor.add_node(node)
        # Its spin() delivered no message here (rclpy 7.1.6 wheel), spin_once does.
        while True:
            executor.spin_once(timeout_sec=1.0)
    # Hand-made loops: enter the handles once (they stay valid until os._exit).
    handles = [sub.handle for sub in subs]
    for handle in handles:
        handle.__enter__()
    node.context.handle.__enter__()
    pairs = [(sub.handle, sub.msg_type, sub.callback) for sub in subs]
    if variant == 'poll_10ms_raw':
        while True:
            time.sleep(0.01)
            for handle, msg_type, callback in pairs:
                while (taken := handle.take_message(msg_type, True)) is not None:
                    callback(taken[0])
    wait_set = _rclpy.WaitSet(len(subs), 0, 0, 0, 0, 0, node.context.handle)
    drain = variant == 'waitset_drain'
    while True:
        wait_set.clear_entities()
        for handle in handles:
            wait_set.add_subscription(handle)
        wait_set.wait(-1)
        for index, (handle, msg_type, callback) in enumerate(pairs):
            if not wait_set.is_ready('subscription', index):
                continue
            while (taken := handle.take_message(msg_type, raw)) is not None:
                callback(taken[0])
                if not drain:
                    break


def run_variant(*, variant: str, seconds: float, work: Path) -> dict:
    """Run one subscriber process for ``variant``; return its measurement."""
    out = work / f'{variant}.json'
    if out.exists():
        out.unlink()
    env = dict(os.environ, **VARIANTS[variant])
    proc = subprocess.Popen([sys.executable, __file__, '_subscribe', '--variant', variant,
                             '--seconds', str(seconds), '--out', str(out)], cwd=REPO, env=env,
                            stdout=open(work / f'{variant}.log', 'w'), stderr=subprocess.STDOUT)
    try:
        proc.wait(timeout=seconds + 60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise RuntimeError(f'{variant}: no traffic or hung; see {work / variant}.log')
    if not out.exists():
        raise RuntimeError(f'{variant} failed; see {work / variant}.log')
    return json.loads(out.read_text())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('cmd', nargs='?', default='bench',
                        choices=('bench', '_publish', '_subscribe'))
    parser.add_argument('--repeats', type=int, default=3)
    parser.add_argument('--seconds', type=float, default=10.0)
    parser.add_argument('--variants', default=','.join(VARIANTS))
    parser.add_argument('--variant', default='stock')
    parser.add_argument('--out', default='')
    args = parser.parse_args()
    if args.cmd == '_publish':
        publish(args)
        return
    if args.cmd == '_subscribe':
        subscribe(args)
        return
    variants = [v for v in args.variants.split(',') if v]
    unknown = set(variants) - set(VARIANTS)
    if unknown:
        parser.error(f'unknown variants {sorted(unknown)}; choose from {list(VARIANTS)}')
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ['ROS_STATIC_PEERS'] = ''
    os.environ.setdefault('ROS_DOMAIN_ID', str(10 + os.getpid() % 90))
    work = Path(tempfile.mkdtemp(prefix='bench_floor_'))
    load0 = os.getloadavg()
    busy0 = _cpu_busy()
    publisher = subprocess.Popen([sys.executable, __file__, '_publish'], cwd=REPO,
                                 stdout=open(work / 'publisher.log', 'w'),
                                 stderr=subprocess.STDOUT)
    results = {v: [] for v in variants}
    try:
        for _ in range(args.repeats):
            for variant in variants:
                results[variant].append(run_variant(variant=variant, seconds=args.seconds,
                                                    work=work))
    finally:
        publisher.send_signal(signal.SIGINT)
        publisher.wait(timeout=30)
    busy1 = _cpu_busy()
    machine = 100 * (busy1[0] - busy0[0]) / max(busy1[1] - busy0[1], 1) * os.cpu_count()
    print(f'rclpy receive floor: WrenchStamped + Int16MultiArray[{CHUNK}] at {RATE_HZ:g} Hz '
          f'each, best effort, {args.seconds:g} s windows, median of {args.repeats} runs; '
          f'{os.cpu_count()} CPUs, load average {load0[0]:.2f} at start, '
          f'{os.getloadavg()[0]:.2f} at end; whole machine busy {machine:.0f} % of one core '
          'during the run (this benchmark included)\n')
    print('| variant | subscriber CPU, % of one core | CPU per message (ms) '
          '| messages/s received | runs (CPU %) |')
    print('|---|---|---|---|---|')
    for variant in variants:
        runs = results[variant]
        cpu = statistics.median(100 * r['cpu'] for r in runs)
        rate = statistics.median(r['msgs'] / r['seconds'] for r in runs)
        per_msg = f'{10 * cpu / rate:.3f}' if rate > 0 and variant != 'idle' else '-'
        each = ', '.join(f'{100 * r["cpu"]:.1f}' for r in runs)
        print(f'| {variant} | {cpu:.1f} | {per_msg} '
              f'| {"-" if variant == "idle" else f"{rate:.1f}"} | {each} |', flush=True)
    print(f'\n(sent: {2 * RATE_HZ:g} messages/s; logs in {work})')


if __name__ == '__main__':
    main()
