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
Soak: many simulated minutes of input through the node's processing at full speed; memory.

Simulated trials (``--pool`` of them, all condition sets in turn: paper, heavy, soft, noisy,
gain, odd_chunking; random exogenous hits; simulated before the measurement starts) are played
in turn as one continuous stream, each trial re-armed as the robot would before a placing, and
fed as fast as the process takes them:

* ``detector``: :class:`ContactDetector` directly (``on_audio`` / ``on_wrench`` with the
  node's stamps: audio on receipt, wrench by header), the work of every message;
* ``node``: a real :class:`ContactDetectorNode` in this process (``use_sim_time``, its clock
  set to each message's receive time), the messages given to its subscription callbacks as
  rclpy messages, its outputs published to DDS, ``diagnostics()`` called every simulated
  second as its timer would.

Every simulated minute the resident set size (``/proc/self/statm``) and the memory
``tracemalloc`` sees (current, and peak since the previous sample) are sampled. Printed: one
row per minute, then first / last / max and the least-squares slope over minutes 1.. (minute 0
includes imports and warm-up).

    python benchmarks/bench_soak.py [--minutes 30] [--mode detector|node|both]
                                    [--pool 24] [--model PATH] [--no-tracemalloc]
                                    [--json out.json]

The model is the shipped one if it exists, else the small test model (trained first, ~5 s).
"""

import argparse
from array import array
from dataclasses import dataclass, field
import gc
import json
import os
from pathlib import Path
import sys
import tempfile
import time
import tracemalloc
from typing import Callable, Iterator, List, Optional

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / 'test'))

from contact_detector.detection.detector import ContactDetector, DetectorSettings  # noqa: E402
from contact_detector.model.bundle import ModelBundle  # noqa: E402
from contact_detector.model.storage import load_bundle  # noqa: E402
from contact_detector.sim.conditions import ALIASES  # noqa: E402
from contact_detector.sim.trial import simulate_trial  # noqa: E402
import numpy as np  # noqa: E402

PAGE = os.sysconf('SC_PAGE_SIZE')
MB = 1024.0 * 1024.0


def rss_mb() -> float:
    """Resident set size of this process, MB."""
    with open('/proc/self/statm') as stream:
        return int(stream.read().split()[1]) * PAGE / MB


@dataclass
class Message:
    """One input message: receive time (s), kind, and its arrays."""

    now: float
    kind: str                   # 'audio' or 'wrench'
    samples: Optional[np.ndarray] = None
    t: Optional[np.ndarray] = None
    force: Optional[np.ndarray] = None
    torque: Optional[np.ndarray] = None
    first_of_trial: bool = False


def make_pool(*, n: int, seed: int = 5) -> list:
    """Simulate ``n`` trials (condition sets in turn) and their events in log-time order."""
    conditions = list(ALIASES['wide'])  # the twelve sets that need no sound bank
    pool = []
    for index in range(n):
        trial = simulate_trial(seed=seed, index=index,
                               condition=conditions[index % len(conditions)])
        events = []
        starts = np.concatenate([[0], trial.chunk_ends[:-1]])
        for lo, hi, t in zip(starts, trial.chunk_ends, trial.chunk_log_t):
            events.append((float(t), 1, int(lo), int(hi)))
        log_t = trial.wrench_log_t if trial.wrench_log_t is not None else trial.wrench_t
        for j, t in enumerate(log_t):
            events.append((float(t), 0, j, j + 1))
        events.sort()
        pool.append((trial, events))
    return pool


def stream(pool: list) -> Iterator[Message]:
    """Endless stream: the pool's trials in turn on one continuous time line."""
    previous_end = None
    k = 0
    while True:
        trial, events = pool[k % len(pool)]
        # Each trial starts 20 ms after the previous one ends.
        shift = 0.0 if previous_end is None else previous_end + 0.02 - trial.start_time
        first = True
        for t, is_audio, lo, hi in events:
            if is_audio:
                yield Message(now=t + shift, kind='audio', samples=trial.audio[lo:hi],
                              first_of_trial=first)
            else:
                yield Message(now=t + shift, kind='wrench', t=trial.wrench_t[lo:hi] + shift,
                              force=trial.force[lo:hi], torque=trial.torque[lo:hi],
                              first_of_trial=first)
            first = False
        previous_end = events[-1][0] + shift
        k += 1


@dataclass
class Sample:
    """Memory after ``minute`` simulated minutes."""

    minute: float
    wall_s: float
    rss_mb: float
    traced_mb: float
    traced_peak_mb: float
    messages: int


@dataclass
class SoakResult:
    """Samples of one run, and what the detector counted."""

    mode: str
    samples: List[Sample] = field(default_factory=list)
    counts: dict = field(default_factory=dict)
    trials: int = 0
    growth_sites: List[str] = field(default_factory=list)
    growth: List[tuple] = field(default_factory=list)     # (file, line, bytes, blocks)

    def slope(self, key: str) -> float:
        """Least-squares slope of ``key`` over minutes 1.., MB per simulated hour."""
        rows = [s for s in self.samples if s.minute >= 1]
        if len(rows) < 2:
            return float('nan')
        x = np.array([s.minute for s in rows], dtype=float)
        y = np.array([getattr(s, key) for s in rows], dtype=float)
        return float(np.polyfit(x, y, 1)[0] * 60.0)


def _detector_sink(bundle: ModelBundle) -> tuple:
    detector = ContactDetector(bundle=bundle, settings=DetectorSettings())

    def feed(msg: Message) -> None:
        if msg.first_of_trial:
            detector.arm(True)
        if msg.kind == 'audio':
            detector.on_audio(msg.samples, stamp=msg.now, now=msg.now)
        else:
            detector.on_wrench(t=msg.t, force=msg.force, torque=msg.torque, now=msg.now)

    return feed, lambda: dict(detector.counts), lambda: None


def _node_sink(bundle: ModelBundle) -> tuple:
    import rclpy
    from rclpy.context import Context
    from rclpy.parameter import Parameter
    from rclpy.time import Time
    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Int16MultiArray

    from contact_detector.ros.node import ContactDetectorNode

    context = Context()
    rclpy.init(context=context)
    node = ContactDetectorNode(context=context, bundle=bundle, parameter_overrides=[
        Parameter('use_sim_time', value=True),
        Parameter('diagnostics.period_s', value=3600.0)])
    clock = node.get_clock()
    wrench = WrenchStamped()
    state = {'next_diag': None}

    def feed(msg: Message) -> None:
        clock.set_ros_time_override(Time(nanoseconds=int(round(msg.now * 1e9))))
        if state['next_diag'] is None or msg.now >= state['next_diag']:
            node.diagnostics()                      # what the 1 Hz timer does
            state['next_diag'] = msg.now + 1.0
        if msg.first_of_trial:
            node.detector.arm(True)
        if msg.kind == 'audio':
            audio = Int16MultiArray()
            audio.data = array('h', msg.samples.tobytes())
            node._on_audio(audio)
        else:
            t = float(msg.t[0])
            sec = int(t)
            wrench.header.stamp.sec = sec
            wrench.header.stamp.nanosec = min(999_999_999, int(round((t - sec) * 1e9)))
            f, m = msg.force[0], msg.torque[0]
            wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z = map(float, f)
            wrench.wrench.torque.x, wrench.wrench.torque.y, wrench.wrench.torque.z = map(
                float, m)
            node._on_wrench(wrench)

    def close() -> None:
        node.destroy_node()
        rclpy.try_shutdown(context=context)

    return feed, node.detector_counts, close


def run_soak(*, bundle: ModelBundle, minutes: float, mode: str = 'detector',
             pool: list, trace: bool = True, sample_s: float = 60.0,
             progress: Optional[Callable[[Sample], None]] = None) -> SoakResult:
    """
    Feed ``minutes`` simulated minutes of ``pool`` through ``mode``; return the samples.

    Memory is sampled every ``sample_s`` simulated seconds (after a full garbage collection);
    with ``trace`` the lines whose allocations grew most from the sample at minute 1 (or the
    second sample) to the end are listed in ``growth_sites``.
    """
    feed, counts, close = (_detector_sink if mode == 'detector' else _node_sink)(bundle)
    result = SoakResult(mode=mode)
    gc.collect()
    if trace:
        tracemalloc.start()
    start_wall = time.perf_counter()
    t0 = None
    next_sample = 0
    n = 0
    base = {}

    def sample(minute: float) -> None:
        gc.collect()
        current, peak = tracemalloc.get_traced_memory() if trace else (0, 0)
        if trace:
            tracemalloc.reset_peak()
        row = Sample(minute=minute, wall_s=time.perf_counter() - start_wall, rss_mb=rss_mb(),
                     traced_mb=current / MB, traced_peak_mb=peak / MB, messages=n)
        result.samples.append(row)
        if trace and 'snapshot' not in base and (minute >= 1.0 or len(result.samples) == 2):
            base['snapshot'] = tracemalloc.take_snapshot()
        if progress is not None:
            progress(row)

    try:
        for msg in stream(pool):
            if t0 is None:
                t0 = msg.now
            elapsed = (msg.now - t0) / 60.0
            while elapsed >= next_sample * sample_s / 60.0:
                sample(next_sample * sample_s / 60.0)
                next_sample += 1
            if elapsed >= minutes:
                break
            if msg.first_of_trial:
                result.trials += 1
            feed(msg)
            n += 1
        result.counts = dict(counts())
        if trace and 'snapshot' in base:
            here = str(REPO) + os.sep
            diff = tracemalloc.take_snapshot().compare_to(base['snapshot'], 'lineno')
            result.growth = [(d.traceback[0].filename, d.traceback[0].lineno, d.size_diff,
                              d.count_diff) for d in diff[:30]]
            result.growth_sites = [
                f'{str(d.traceback).replace(here, "")}: {d.size_diff / 1024:+.1f} KiB '
                f'({d.count_diff:+d} blocks)' for d in diff[:5] if d.size_diff > 0]
    finally:
        if trace:
            tracemalloc.stop()
        close()
    return result


def summary(result: SoakResult) -> str:
    """Markdown table of the samples plus first / last / max and slopes."""
    lines = [f'### {result.mode}: {result.samples[-1].minute:g} simulated minutes, '
             f'{result.trials} trials, {result.samples[-1].messages} messages, '
             f'{result.samples[-1].wall_s:.0f} s wall',
             '', '| minute | wall s | RSS MB | traced MB | traced peak MB |',
             '|---|---|---|---|---|']
    for s in result.samples:
        lines.append(f'| {s.minute:g} | {s.wall_s:.1f} | {s.rss_mb:.1f} | {s.traced_mb:.3f} | '
                     f'{s.traced_peak_mb:.3f} |')
    rows = [s for s in result.samples if s.minute >= 1] or result.samples
    for key, name in (('rss_mb', 'RSS'), ('traced_mb', 'tracemalloc')):
        values = [getattr(s, key) for s in rows]
        lines.append(f'- {name} (minutes {rows[0].minute:g}..{rows[-1].minute:g}): first '
                     f'{values[0]:.3f} MB, last {values[-1]:.3f} MB, max {max(values):.3f} MB, '
                     f'slope {result.slope(key):+.3f} MB per simulated hour')
    if result.growth_sites:
        lines.append('- largest growth of traced memory from minute 1 to the end, by line:')
        lines.extend(f'  - {site}' for site in result.growth_sites)
    counts = result.counts
    lines.append(f'- detector: {counts.get("frames", 0)} frames, {counts.get("events", 0)} '
                 f'events, {counts.get("releases", 0)} releases, '
                 f'{counts.get("audio_dropped", 0)} audio / {counts.get("wrench_dropped", 0)} '
                 f'wrench dropped, {counts.get("callback_errors", 0)} callback errors')
    return '\n'.join(lines)


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--minutes', type=float, default=30.0,
                        help='simulated minutes per mode (default 30)')
    parser.add_argument('--mode', choices=('detector', 'node', 'both'), default='both')
    parser.add_argument('--model', default='', help='model file (default: shipped or test)')
    parser.add_argument('--no-tracemalloc', action='store_true',
                        help='RSS only (tracemalloc slows Python down about 2x)')
    parser.add_argument('--pool', type=int, default=24,
                        help='distinct simulated trials, played in turn (default 24)')
    parser.add_argument('--json', default='', help='also write the samples here')
    args = parser.parse_args(argv)

    if args.model:
        model = Path(args.model)
    else:
        import node_support
        model = node_support.model_path(Path(tempfile.mkdtemp(prefix='soak_')))
    bundle = load_bundle(path=model)
    print(f'model {bundle.model_id} ({model})', flush=True)
    pool = make_pool(n=args.pool)
    seconds = sum(events[-1][0] - events[0][0] for _, events in pool)
    print(f'{len(pool)} trials simulated ({seconds:.0f} s), played in turn', flush=True)
    modes = ('detector', 'node') if args.mode == 'both' else (args.mode,)
    results = []
    for mode in modes:
        def progress(s: Sample, mode=mode) -> None:
            print(f'  {mode} minute {s.minute:5.1f}: RSS {s.rss_mb:7.1f} MB, traced '
                  f'{s.traced_mb:7.3f} MB (peak {s.traced_peak_mb:7.3f}), wall {s.wall_s:6.1f} s',
                  flush=True)
        result = run_soak(bundle=bundle, minutes=args.minutes, mode=mode, pool=pool,
                          trace=not args.no_tracemalloc, progress=progress)
        results.append(result)
        print(summary(result), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps([{
            'mode': r.mode, 'trials': r.trials, 'counts': r.counts,
            'samples': [s.__dict__ for s in r.samples]} for r in results], indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(main())
