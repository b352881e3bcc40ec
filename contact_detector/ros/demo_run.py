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
The demo's live run: the node as its own process, observed over DDS on loopback.

:func:`run_demo` simulates the trials (:mod:`contact_detector.evaluation.demo`), starts
``contact_detector_node`` as its own process, replays each trial into it in real time as live
sensors would publish (header stamps moved to now, :class:`~.player.BagPlayer`), arming the
release before each trial as a placing routine would, collects ``contact``,
``contact_probability`` and ``release`` with this machine's receive time, and prints one row per
trial, a summary line and the verdict. ``contact-detector demo`` (``cli/demo.py``) calls it.
"""

import os
from pathlib import Path
import subprocess
import sys
import threading
import time

from contact_detector.evaluation.demo import (pick_trials, plot_trial, score_live_trial,
                                              summary_line, table_header, table_row,
                                              verdict_failures)
from contact_detector.ros.player import BagPlayer, read_recording
from contact_detector.sim.bag_writer import write_manifest, write_trial_bag
import rclpy
from rclpy.executors import SingleThreadedExecutor
from std_msgs.msg import Bool, Float32
from std_srvs.srv import SetBool, Trigger

NODE_NAME = 'contact_detector'


class Collector:
    """Subscribes to the node's outputs and records them with this machine's receive time."""

    def __init__(self, node) -> None:
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


def run_demo(*, trials: int, seed: int, out: Path, model: Path, figure: Path) -> int:
    """
    Simulate, start the node, replay live, report; return the exit status.

    DDS stays on this machine: ``ROS_AUTOMATIC_DISCOVERY_RANGE`` is set to ``LOCALHOST``
    unless already set (this process and the node's); ``ROS_DOMAIN_ID`` is the caller's.

    Parameters
    ----------
    trials : int
        Number of trials to simulate and run.
    seed : int
        Simulator seed.
    out : Path
        Folder for the bags, ``manifest.json`` and ``node.log`` (created).
    model : Path
        Model the node loads.
    figure : Path
        Where the figure of one trial goes (PNG).

    Returns
    -------
    int
        0 if every trial ran, nothing was released before the touch and no contact was
        missed; 1 otherwise (the reasons and the node log's last lines on stderr).

    """
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
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
    stop = threading.Event()

    def spin() -> None:
        # spin_once in a loop that ends on a flag, not executor.spin(): shutting an executor
        # down while another thread waits in it can hang the process (ros2/rclpy#968), so the
        # thread is stopped and joined before the executor is shut down.
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)
    spinner = threading.Thread(target=spin, daemon=True)
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
        header = table_header()
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
            outcome = score_live_trial(trial=trial, releases=collected['releases'],
                                       wall0=wall0)
            outcomes.append(outcome)
            print(table_row(trial=trial, outcome=outcome), flush=True)
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
        stop.set()
        spinner.join(timeout=5.0)
        executor.shutdown(timeout_sec=5.0)
        node.destroy_node()
        rclpy.try_shutdown()
        node_proc.terminate()
        try:
            node_proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            node_proc.kill()
    summary = summary_line(outcomes)
    if summary is not None:
        print(f'\n{summary}')
    failures += verdict_failures(outcomes=outcomes, trials=len(chosen))
    if failures:
        print('DEMO FAILED: ' + '; '.join(failures), file=sys.stderr)
        if log.exists():
            print('--- node log (last lines) ---\n' + '\n'.join(
                log.read_text().splitlines()[-20:]), file=sys.stderr)
        return 1
    print('demo passed')
    return 0
