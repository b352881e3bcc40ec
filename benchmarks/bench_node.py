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
Latency and CPU share of the live node at 16 kHz / 44.1 kHz audio with 100 Hz F/T and 1 kHz.

Two measurements per input configuration (10 ms audio chunks, one wrench sample per message,
the simulated trial of test/e2e/test_e2e_node.py), medians over the repeats:

1. Replay, in this process: the node's callbacks are called directly with real rclpy messages,
   ``/clock`` time set to each message's log time (no DDS, no executor). Gives the node's own
   work: CPU time / trial duration, the node's latency (callback entry to the return of the
   last ``contact`` publish, wall clock) and the CPU time per callback (unaffected by other
   processes taking the core).
2. Live: three processes on loopback DDS as in test/e2e/test_e2e_node.py: the trial publisher at
   the real rate (best-effort sensor-data QoS), the node (``_serve`` below, default
   parameters) and a listener. Gives the node process's CPU time / wall time while the trial
   streams (psutil, start-up excluded), the node's callback latency, and end to end: the
   publisher's ``publish`` of the audio chunk that completes a frame to the listener's receipt
   of that frame's ``contact`` (DDS both ways, executor wake-ups, any wait for F/T), and the
   node's latency from the audio message's arrival (DDS reception time) to the return of the
   audio callback that published its frames (wrench messages taken before it included).

    python benchmarks/bench_node.py [--repeats 3] [--model PATH]
                                    [--executors single_threaded,hot_path]
                                    [--gap-ms 4 --replay-only] [--only 44100:100 --live-only]
                                    [--set executor.lazy_wrench=true]

With several ``--executors`` the live runs alternate between them (one run of each in turn,
``--repeats`` rounds), so that they share the machine's load; one row per executor. The model
is the shipped ``models/contact_forest.npz`` unless ``--model`` is given. On a machine shared
with other work the latency tails measure the scheduler as much as the node: compare the CPU
time per callback, and read the load averages printed before and after.
"""

import argparse
import gc
import json
import math
import os
from pathlib import Path
import signal
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = Path(__file__).resolve().parents[1]
HELPER = ['-m', 'contact_detector.ros.live_trial']
SHIPPED_MODEL = REPO / 'models' / 'contact_forest.npz'
EXECUTORS = ('single_threaded', 'hot_path')
CONFIGS = ((16000, 100.0), (44100, 100.0), (16000, 1000.0))


def serve(args: argparse.Namespace) -> None:
    """Run the node in this process; on SIGINT write its latency samples to ``args.out``."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.parameter import Parameter
    from rclpy.subscription import Subscription

    from contact_detector.ros.node import ContactDetectorNode, make_executor

    rclpy.init()
    node = ContactDetectorNode(parameter_overrides=[
        Parameter('model.path', value=args.model),
        Parameter('audio.sample_rate', value=float(args.audio_rate)),
        Parameter('wrench.rate', value=float(args.ft_rate)),
        Parameter('executor.type', value=args.executor),
        *[Parameter(name, value=json.loads(value))
          for name, value in (item.split('=', 1) for item in args.set)]])
    # Arrival (the DDS reception time of the audio message) -> return of the audio callback
    # that published frames: includes any wait in the executor and the wrench messages taken
    # before the chunk, which the node's own latency (from callback entry) leaves out.
    arrival = []
    on_audio = node.audio_sub.callback

    def timed_on_audio(msg, info) -> None:
        published = node.counts['contact_msgs']
        on_audio(msg)
        if node.counts['contact_msgs'] > published:
            arrival.append((time.time_ns() - info['received_timestamp']) * 1e-9)
    node.audio_sub.callback = timed_on_audio
    node.audio_sub._callback_type = Subscription.CallbackType.WithMessageInfo
    executor = make_executor(node)
    gc.freeze()
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    Path(args.out).write_text(json.dumps({
        'arrival': arrival,
        'audio': node.latency_samples('audio').tolist(),
        'wrench': node.latency_samples('wrench').tolist(),
        'counts': node.detector_counts(), 'model_id': node.bundle.model_id}))
    node.destroy_node()
    rclpy.try_shutdown()


def _spawn(cmd, log: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, *cmd], cwd=REPO, env=dict(os.environ),
                            stdout=open(log, 'w'), stderr=subprocess.STDOUT)


def _frame_chunks(*, audio_rate: int, n_chunks: int, chunk: int) -> np.ndarray:
    """Index of the audio chunk that completes each frame (the feature core's frame ends)."""
    from contact_detector.features.config import FeatureConfig
    from contact_detector.features.audio import frame_ends
    config = FeatureConfig()
    length = config.audio_frame_samples(audio_rate)
    hop = config.audio_hop_s * audio_rate
    total = n_chunks * chunk
    count = int((total - length) / hop) + 2
    ends = frame_ends(first=0, count=count, frame_length=length, hop=hop)
    ends = ends[ends <= total]
    return (ends + chunk - 1) // chunk - 1


def run_once(*, model: str, audio_rate: int, ft_rate: float, work: Path,
             executor: str, settings=()) -> dict:
    """One three-process run; return the measurements."""
    import psutil
    chunk = audio_rate // 100
    paths = {name: work / f'{name}.json' for name in ('node', 'pub', 'listen')}
    stop, ready = work / 'stop', work / 'listener_ready'
    for path in list(paths.values()) + [stop, ready]:
        if path.exists():
            path.unlink()
    sets = [arg for item in settings for arg in ('--set', item)]
    node = _spawn([__file__, '_serve', '--executor', executor, '--model', model, *sets,
                   '--audio-rate', str(audio_rate),
                   '--ft-rate', str(ft_rate), '--out', str(paths['node'])], work / 'node.log')
    listener = _spawn([*HELPER, 'listen', '--out', str(paths['listen']), '--stop-file',
                       str(stop), '--ready-file', str(ready)], work / 'listen.log')
    publisher = _spawn([*HELPER, 'publish', '--out', str(paths['pub']), '--audio-rate',
                        str(audio_rate), '--ft-rate', str(ft_rate), '--chunk', str(chunk),
                        '--wait-file', str(ready)], work / 'pub.log')
    proc = psutil.Process(node.pid)
    samples = []
    while publisher.poll() is None:
        times = proc.cpu_times()
        samples.append((time.time(), times.user + times.system, times.system))
        time.sleep(0.2)
    time.sleep(0.5)
    stop.touch()
    listener.wait(timeout=30)
    node.send_signal(signal.SIGINT)
    node.wait(timeout=30)
    if publisher.returncode or listener.returncode or node.returncode:
        raise RuntimeError(f'a process failed; see the logs in {work}')
    pub = json.loads(paths['pub'].read_text())
    got = json.loads(paths['listen'].read_text())
    served = json.loads(paths['node'].read_text())
    # CPU over the streaming window, start-up excluded.
    t0, t1 = pub['start_wall'] + 0.5, pub['end_wall'] - 0.4
    window = [w for w in samples if t0 <= w[0] <= t1]
    span = window[-1][0] - window[0][0] if len(window) >= 2 else math.nan
    cpu = (window[-1][1] - window[0][1]) / span
    sys_cpu = (window[-1][2] - window[0][2]) / span
    # End to end: the chunk that completes frame k -> receipt of the k-th contact message.
    completes = _frame_chunks(audio_rate=audio_rate, n_chunks=pub['audio_chunks'], chunk=chunk)
    received = [t for t, _ in got['contact']]
    e2e = []
    if len(received) == completes.size:
        sent = np.asarray(pub['audio_times'])[completes]
        e2e = (np.asarray(received) - sent).tolist()
    return {'cpu': cpu, 'sys_cpu': sys_cpu, 'audio': served['audio'],
            'arrival': served['arrival'],
            'wrench': served['wrench'], 'e2e': e2e, 'frames': len(received),
            'node_frames': served['counts']['frames'], 'expected': int(completes.size),
            'model_id': served['model_id'], 'late_p99_ms': pub['late_p99_ms']}


def _pct(values, q) -> float:
    return 1e3 * float(np.percentile(values, q)) if len(values) else math.nan


def _pair(runs, key) -> str:
    """'p50 / p99' in ms, medians over runs; '-' where no callback of that kind published."""
    runs = [r for r in runs if len(r[key])]
    if not runs:
        return '-'
    p50 = statistics.median(_pct(r[key], 50) for r in runs)
    p99 = statistics.median(_pct(r[key], 99) for r in runs)
    return f'{p50:.3f} / {p99:.3f}'


def _wrench_msg(t: float, force, torque):
    """Return a ``WrenchStamped`` of one sample stamped ``t`` (s)."""
    from builtin_interfaces.msg import Time
    from geometry_msgs.msg import WrenchStamped

    msg = WrenchStamped()
    sec = int(np.floor(t))
    msg.header.stamp = Time(sec=sec, nanosec=min(999_999_999, int(round((t - sec) * 1e9))))
    msg.header.frame_id = 'wrist_ft_sensor_frame'
    f, m = msg.wrench.force, msg.wrench.torque
    f.x, f.y, f.z = (float(v) for v in force)
    m.x, m.y, m.z = (float(v) for v in torque)
    return msg


def replay(*, model: str, audio_rate: int, ft_rate: float, gap_s: float = 0.0,
           settings=()) -> dict:
    """
    Call the node's callbacks directly with real messages of a trial (no DDS, no executor).

    Measures the node's own work: adapters, detector, publishing (no subscriber). With
    ``gap_s`` > 0 the process sleeps that long before each callback (outside the measured
    CPU time), as a live node does between messages: the callbacks then start with cold caches.
    """
    import rclpy
    from rclpy.context import Context
    from rclpy.parameter import Parameter
    from rclpy.time import Time
    from std_msgs.msg import Int16MultiArray

    from contact_detector.ros.node import ContactDetectorNode
    from contact_detector.sim.messages import message_events
    from contact_detector.sim.trial import simulate_trial

    trial = simulate_trial(seed=3, index=21, hits='hand', audio_rate=audio_rate,
                           ft_rate=ft_rate, chunk_size=audio_rate // 100)
    messages = []
    for e in message_events(trial=trial):
        if e.kind == 'audio':
            msg = Int16MultiArray()
            msg.data = trial.audio[e.lo:e.hi]
        else:
            msg = _wrench_msg(trial.wrench_t[e.lo], trial.force[e.lo], trial.torque[e.lo])
        messages.append((e.kind, msg, Time(nanoseconds=int(round(e.t * 1e9)))))
    context = Context()
    rclpy.init(context=context, args=['--ros-args', '--log-level', 'warn'])
    node = ContactDetectorNode(context=context, parameter_overrides=[
        Parameter('model.path', value=model),
        Parameter('audio.sample_rate', value=float(audio_rate)),
        Parameter('wrench.rate', value=float(ft_rate)),
        Parameter('use_sim_time', value=True),
        *[Parameter(name, value=json.loads(value))
          for name, value in (item.split('=', 1) for item in settings)]])
    clock = node.get_clock()
    gc.collect()
    gc.freeze()
    cpu_per_call = {'audio': [], 'wrench': []}
    gap_cpu = 0.0
    if gap_s:       # the CPU time of the sleep call itself, not part of the node's work
        t0 = time.thread_time()
        for _ in range(20):
            time.sleep(gap_s)
        gap_cpu = (time.thread_time() - t0) / 20
    start = time.thread_time()
    for kind, msg, receive_time in messages:
        clock.set_ros_time_override(receive_time)      # as /clock would: the log time
        if gap_s:
            time.sleep(gap_s)
        before = time.thread_time()
        (node._on_audio if kind == 'audio' else node._on_wrench)(msg)
        cpu_per_call[kind].append(time.thread_time() - before)
    cpu = ((time.thread_time() - start - gap_cpu * len(messages))
           / (trial.end_time - trial.start_time))
    counts = node.detector_counts()
    if counts['audio_dropped'] or counts['wrench_dropped'] or counts['frames'] < 800:
        raise RuntimeError(f'replay went wrong: {counts}')
    out = {'cpu': cpu, 'audio': node.latency_samples('audio').tolist(),
           'wrench': node.latency_samples('wrench').tolist(), 'frames': counts['frames'],
           'audio_cpu': cpu_per_call['audio'], 'wrench_cpu': cpu_per_call['wrench']}
    node.destroy_node()
    rclpy.try_shutdown(context=context)
    gc.unfreeze()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('cmd', nargs='?', default='bench', choices=('bench', '_serve'))
    parser.add_argument('--repeats', type=int, default=3)
    parser.add_argument('--model', default='')
    parser.add_argument('--audio-rate', type=int, default=16000)
    parser.add_argument('--ft-rate', type=float, default=100.0)
    parser.add_argument('--out', default='')
    parser.add_argument('--executor', default='single_threaded', choices=EXECUTORS,
                        help=argparse.SUPPRESS)        # _serve: the node's executor.type
    parser.add_argument('--executors', default='single_threaded',
                        help='live: comma-separated executor.type values, run alternately '
                        f'(of {", ".join(EXECUTORS)}; default single_threaded)')
    parser.add_argument('--gap-ms', type=float, default=0.0,
                        help='replay: sleep this long before each callback (cold caches, as '
                        'in a live node); default 0 (back to back)')
    parser.add_argument('--replay-only', action='store_true', help='skip the live runs')
    parser.add_argument('--live-only', action='store_true', help='skip the replays')
    parser.add_argument('--set', action='append', default=[], metavar='NAME=JSON',
                        help='a node parameter, e.g. executor.lazy_wrench=true or '
                        'model.ft_also_decides=true')
    parser.add_argument('--only', default='', help='run one configuration, AUDIO_HZ:FT_HZ '
                        '(e.g. 44100:100)')
    args = parser.parse_args()
    if args.cmd == '_serve':
        serve(args)
        return
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ['ROS_STATIC_PEERS'] = ''
    os.environ.setdefault('ROS_DOMAIN_ID', str(10 + os.getpid() % 90))
    executors = args.executors.split(',')
    for name in executors:
        if name not in EXECUTORS:
            parser.error(f'--executors: {name!r} is not one of {EXECUTORS}')
    configs = CONFIGS
    if args.only:
        audio_hz, ft_hz = args.only.split(':')
        configs = ((int(audio_hz), float(ft_hz)),)
    work = Path(tempfile.mkdtemp(prefix='bench_node_'))
    model = args.model or str(SHIPPED_MODEL)
    print(f'node benchmark, model {model}, median of {args.repeats} runs, '
          f'{os.cpu_count()} CPUs, load average (1, 5, 15 min) '
          f'{", ".join(f"{v:.1f}" for v in os.getloadavg())}\n')

    print('In-process replay: callbacks called with real messages, no DDS (the work of the '
          f'node itself), {args.gap_ms:g} ms sleep before each callback\n')
    print('| audio | F/T | node CPU, % of one core | audio callback p50 / p99 (ms) '
          '| wrench callback p50 / p99 (ms) | CPU time per audio / wrench callback, '
          'p50 / p99 (ms) |')
    print('|---|---|---|---|---|---|')
    for audio_rate, ft_rate in ([] if args.live_only else configs):
        runs = [replay(model=model, audio_rate=audio_rate, ft_rate=ft_rate,
                       gap_s=args.gap_ms * 1e-3, settings=args.set)
                for _ in range(args.repeats)]
        cpu = statistics.median(100 * r['cpu'] for r in runs)
        print(f'| {audio_rate / 1000:g} kHz | {ft_rate:g} Hz | {cpu:.1f} '
              f'| {_pair(runs, "audio")} | {_pair(runs, "wrench")} '
              f'| {_pair(runs, "audio_cpu")}; {_pair(runs, "wrench_cpu")} |', flush=True)
    if args.replay_only:
        return

    print(f'\nLive: publisher, node ({", ".join(executors)} executor, alternating) and '
          'listener processes on loopback DDS, one simulated trial (~9 s) at the real rate\n')
    print('| audio | F/T | executor | node CPU, % of one core (sys) | node CPU per run '
          '| audio callback p50 / p99 (ms) | audio arrival -> published p50 / p99 (ms) '
          '| wrench callback p50 / p99 (ms) | end to end p50 / p99 (ms) '
          '| frames: node / listener / expected, per run |')
    print('|---|---|---|---|---|---|---|---|---|---|')
    for audio_rate, ft_rate in configs:
        by_executor = {name: [] for name in executors}
        for _ in range(args.repeats):
            for name in executors:
                by_executor[name].append(run_once(
                    model=model, audio_rate=audio_rate, ft_rate=ft_rate, work=work,
                    executor=name, settings=args.set))
        for name, runs in by_executor.items():
            cpu = statistics.median(100 * r['cpu'] for r in runs)
            sys_cpu = statistics.median(100 * r['sys_cpu'] for r in runs)
            each = ', '.join(f'{100 * r["cpu"]:.1f}' for r in runs)
            frames = ', '.join(f'{r["node_frames"]}/{r["frames"]}/{r["expected"]}'
                               for r in runs)
            print(f'| {audio_rate / 1000:g} kHz | {ft_rate:g} Hz | {name} '
                  f'| {cpu:.1f} ({sys_cpu:.1f}) | {each} | {_pair(runs, "audio")} '
                  f'| {_pair(runs, "arrival")} | {_pair(runs, "wrench")} '
                  f'| {_pair(runs, "e2e")} | {frames} |', flush=True)
    print(f'\nload average (1, 5, 15 min) at the end '
          f'{", ".join(f"{v:.1f}" for v in os.getloadavg())}')
    print(f'\nmodel id {runs[0]["model_id"]}; publisher lateness p99 '
          f'{runs[0]["late_p99_ms"]:.2f} ms; logs in {work}')


if __name__ == '__main__':
    main()
