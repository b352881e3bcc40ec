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
``contact-detector demo``: the whole detector, live, on a laptop with no robot.

    contact-detector demo [--trials 6] [--seed 7] [--out DIR] [--model M]

1. simulates a handful of paper-like trials with exogenous hits on the hand and on the table;
2. starts ``contact_detector_node`` as its own process (DDS on loopback);
3. replays each trial into it in real time, as live sensors would publish (header stamps moved
   to now), arming the release before each trial as a placing routine would;
4. collects ``contact``, ``contact_probability`` and ``release`` and prints one row per trial
   (true onset, release, latency, exogenous hits, verdict) and a summary line;
5. writes a figure of one trial with the detections marked.

Exits non-zero if the node fails, a release comes before the glass touches (premature), or a
contact is missed.
"""

import argparse
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import threading
import time
from typing import List, Optional, Sequence

from contact_detector.evaluation.metrics import score_trial, summarize, Truth
from contact_detector.model.shipped import default_model_path
from contact_detector.sim.bag_writer import write_manifest, write_trial_bag
from contact_detector.sim.trial import simulate_trial, Trial
import numpy as np

NODE_NAME = 'contact_detector'


def pick_trials(*, n: int, seed: int) -> List[Trial]:
    """Paper-like trials, alternating hand and table hits, preferring hits in the air."""
    wanted = ['hand', 'table']
    chosen: List[Trial] = []
    index = 0
    while len(chosen) < n and index < 40 * n:
        trial = simulate_trial(seed=seed, index=index, condition='paper')
        index += 1
        kind = wanted[len(chosen) % 2]
        kinds = {i.kind for i in trial.impacts}
        in_air = any(i.in_air for i in trial.impacts)
        if kind in kinds and in_air:
            chosen.append(trial)
    return chosen


class Collector:
    """Subscribes to the node's outputs and records them with this machine's receive time."""

    def __init__(self, node) -> None:
        from std_msgs.msg import Bool, Float32
        self.lock = threading.Lock()
        self.contact: list = []
        self.probability: list = []
        self.releases: list = []
        node.create_subscription(Bool, 'contact', self._on_contact, 100)
        node.create_subscription(Float32, 'contact_probability', self._on_probability, 100)
        node.create_subscription(Bool, 'release', self._on_release, 10)

    def _on_contact(self, msg) -> None:
        with self.lock:
            self.contact.append((time.time(), bool(msg.data)))

    def _on_probability(self, msg) -> None:
        with self.lock:
            self.probability.append((time.time(), float(msg.data)))

    def _on_release(self, msg) -> None:
        if msg.data:
            with self.lock:
                self.releases.append(time.time())

    def clear(self) -> None:
        with self.lock:
            self.contact, self.probability, self.releases = [], [], []


def call(node, client, request, timeout: float = 5.0):
    """Call a service from a thread that is not spinning; return the response or None."""
    if not client.wait_for_service(timeout_sec=timeout):
        return None
    future = client.call_async(request)
    end = time.monotonic() + timeout
    while not future.done() and time.monotonic() < end:
        time.sleep(0.01)
    return future.result() if future.done() else None


def start_node(*, model: Path, log: Path) -> subprocess.Popen:
    """Start the node in its own process, logging to ``log``."""
    cmd = [sys.executable, '-m', 'contact_detector.ros.node', '--ros-args',
           '-p', f'model.path:={model}', '-p', 'diagnostics.period_s:=1.0']
    handle = log.open('w')
    return subprocess.Popen(cmd, stdout=handle, stderr=subprocess.STDOUT, env=os.environ.copy())


def plot_trial(*, trial: Trial, wall0: float, collected: dict, path: Path) -> None:
    """|F|, audio and P(contact) of one trial with onset, hits and the release marked."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    def rel(t_bag):
        return np.asarray(t_bag) - trial.start_time

    fig, axes = plt.subplots(3, 1, figsize=(9, 6), sharex=True)
    axes[0].plot(rel(trial.wrench_t), np.linalg.norm(trial.force, axis=1), lw=0.8)
    axes[0].set_ylabel('|F| [N]')
    ta = np.arange(trial.audio.size) / trial.audio_rate
    axes[1].plot(ta, trial.audio / 32768.0, lw=0.3)
    axes[1].set_ylabel('audio')
    if collected['probability']:
        tp, p = zip(*collected['probability'])
        axes[2].plot(np.asarray(tp) - wall0, p, lw=0.8, label='P(contact) (received)')
    if collected['contact']:
        tc, c = zip(*collected['contact'])
        axes[2].fill_between(np.asarray(tc) - wall0, 0, np.asarray(c, float), alpha=0.2,
                             step='post', label='contact')
    axes[2].set_ylabel('P(contact)')
    axes[2].set_ylim(-0.05, 1.05)
    axes[2].set_xlabel('time in trial [s]')
    for ax in axes:
        ax.axvline(trial.onset_t - trial.start_time, color='g', ls='--', lw=1)
        for impact in trial.impacts:
            ax.axvline(impact.t - trial.start_time, color='r', ls=':', lw=1)
        for release in collected['releases']:
            ax.axvline(release - wall0, color='k', lw=1.2)
    axes[0].set_title(f'{trial.name}: true onset (green dashed), exogenous hits (red dotted), '
                      'release (black)', fontsize=9)
    axes[2].legend(loc='upper left', fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the demo; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector demo', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--trials', type=int, default=6)
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--out', type=Path, default=None,
                        help='keep bags, node log and figure here (default: a temp folder, '
                             'figure in ./demo_trial.png)')
    parser.add_argument('--model', type=Path, default=None)
    args = parser.parse_args(argv)
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    model = args.model or default_model_path()
    with tempfile.TemporaryDirectory(prefix='contact_detector_demo_') as tmp:
        out = args.out or Path(tmp)
        figure = (args.out / 'demo_trial.png') if args.out else Path('demo_trial.png')
        return run_demo(trials=args.trials, seed=args.seed, out=out, model=model,
                        figure=figure)


def run_demo(*, trials: int, seed: int, out: Path, model: Path, figure: Path) -> int:
    """Simulate, start the node, replay live, report; return the exit status."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_srvs.srv import SetBool, Trigger

    from contact_detector.ros.player import BagPlayer, read_recording

    out.mkdir(parents=True, exist_ok=True)
    print(f'simulating {trials} paper-like trials with exogenous hits ...', flush=True)
    chosen = pick_trials(n=trials, seed=seed)
    for trial in chosen:
        write_trial_bag(trial=trial, path=out / trial.name)
    write_manifest(trials=chosen, out_dir=out)
    log = out / 'node.log'
    print(f'starting contact_detector_node (model {model.name}, log {log}) ...', flush=True)
    node_proc = start_node(model=model, log=log)
    rclpy.init()
    node = rclpy.create_node('contact_detector_demo')
    collector = Collector(node)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    arm = node.create_client(SetBool, f'/{NODE_NAME}/arm')
    reset = node.create_client(Trigger, f'/{NODE_NAME}/reset')
    failures = []
    outcomes = []
    try:
        if call(node, arm, SetBool.Request(data=False), timeout=20.0) is None:
            failures.append('the node did not come up (no ~/arm service)')
            raise RuntimeError
        player = BagPlayer(node=node, restamp=True, log=print)
        header = (f'{"trial":<11} {"onset [s]":>9} {"release [s]":>11} {"latency [ms]":>12}  '
                  f'{"exogenous hits (s, in air?)":<34} verdict')
        print(header)
        print('-' * len(header))
        figure_data = None
        for trial in chosen:
            if node_proc.poll() is not None:
                failures.append(f'the node exited with code {node_proc.returncode}')
                break
            call(node, reset, Trigger.Request())
            call(node, arm, SetBool.Request(data=True))
            time.sleep(0.2)
            collector.clear()
            records = read_recording(out / trial.name)
            starts = {}

            def remember(bag0, wall0):
                starts.update(bag0=bag0, wall0=wall0)
            player.play(records, on_start=remember)
            player.flush(timeout_s=2.0)
            time.sleep(0.3)
            wall0 = starts['wall0'] - (starts['bag0'] - trial.start_time)
            with collector.lock:
                collected = {'contact': list(collector.contact),
                             'probability': list(collector.probability),
                             'releases': list(collector.releases)}
            releases = [r - wall0 + trial.start_time for r in collected['releases']]
            truth = Truth(name=trial.name, condition=trial.condition, onset_t=trial.onset_t,
                          contact_end_t=trial.contact_end_t,
                          impacts=tuple((i.t, i.kind, i.in_air) for i in trial.impacts))
            outcome = score_trial(truth=truth, releases=releases, events=releases)
            outcomes.append(outcome)
            hits = ', '.join(f'{i.kind} {i.t - trial.start_time:.1f}'
                             f'{" air" if i.in_air else ""}' for i in trial.impacts)
            release = '-' if outcome.release_t is None else (
                f'{outcome.release_t - trial.start_time:.3f}')
            latency = '-' if outcome.latency_s is None else f'{1000 * outcome.latency_s:.0f}'
            print(f'{trial.name:<11} {trial.onset_t - trial.start_time:9.3f} {release:>11} '
                  f'{latency:>12}  {hits:<34} {outcome.verdict}', flush=True)
            if not collected['contact']:
                failures.append(f'{trial.name}: no contact decisions received')
            if figure_data is None or (outcome.verdict == 'detected' and trial.impacts):
                figure_data = (trial, wall0, collected)
        if figure_data:
            plot_trial(trial=figure_data[0], wall0=figure_data[1], collected=figure_data[2],
                       path=figure)
            print(f'figure: {figure}')
    except RuntimeError:
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
        node_proc.terminate()
        try:
            node_proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            node_proc.kill()
    summary = summarize(outcomes)
    if outcomes:
        median = summary['latency_ms_median']
        latency = '-' if median is None else f'{median:.0f} ms'
        missed = summary['missed'] + summary['late']
        hits = sum(o.impacts for o in outcomes)
        in_air = sum(o.impacts_in_air for o in outcomes)
        print(f'\n{summary["detected"]}/{summary["trials"]} contacts detected, '
              f'{summary["premature"]} premature, {missed} missed, median latency {latency}; '
              f'{hits} exogenous hits, {in_air} while the glass was in the air')
    if summary.get('premature'):
        failures.append(f"{summary['premature']} premature release(s)")
    if summary.get('missed') or summary.get('late'):
        failures.append(f"{summary['missed'] + summary['late']} missed contact(s)")
    if len(outcomes) < len(chosen):
        failures.append(f'only {len(outcomes)} of {len(chosen)} trials ran')
    if failures:
        print('DEMO FAILED: ' + '; '.join(failures), file=sys.stderr)
        if log.exists():
            print('--- node log (last lines) ---\n' + '\n'.join(
                log.read_text().splitlines()[-20:]), file=sys.stderr)
        return 1
    print('demo passed')
    return 0


if __name__ == '__main__':
    sys.exit(main())
