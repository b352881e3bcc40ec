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
Fault injection against the live node in its own process, over DDS (loopback).

Processes: the node (``python -m contact_detector.ros.node``, default parameters: best-effort
sensor-data QoS of depth 10, audio stamped on receipt, wrench by its header), and two trial
publishers (``fault_publisher.py``) one after the other; this test process listens to
``release`` and ``/diagnostics`` and calls the node's ``set_parameters`` service.

1. The node refuses invalid parameters at run time, with a clear reason, and keeps running.
2. Publisher A plays the trial with faults in the air phase (NaN wrench, empty and 10 s audio
   chunks, wrench stamps backwards / duplicated / 30 s in the future, a 0.3 s burst, a 100 ms
   F/T dropout, a wrench stamp jump of -30 s) and dies (SIGKILL) 2.8 s before the contact.
3. Publisher B starts (the robot retries the placing) and plays the trial from its start with
   a 2 s F/T dropout, a 0.6 s audio dropout and NaN wrench samples in the air phase.

Checked: the node is still running and exits cleanly on SIGINT; ``/diagnostics`` counted every
fault kind and went WARN with "stale or missing input" during the dropouts; the node logged
each kind; no release before B's contact onset, exactly one within 0.3 s after it.
Invalid parameters at start-up: the node process exits with code 1 and names the parameter.
"""

import json
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
import node_support
import pytest
from rcl_interfaces.srv import SetParameters
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Bool

pytestmark = pytest.mark.rclpy

TEST_DIR = Path(__file__).resolve().parents[1]  # test/: the helper scripts
LATENCY_BUDGET_S = 0.3
FAULTS_A = 'nan,empty,huge,backwards,duplicate,future,burst,ft100ms,jump'
FAULTS_B = 'ft2s,audio600ms,nan_late'


@pytest.fixture(scope='module')
def model(tmp_path_factory):
    return node_support.model_path(tmp_path_factory.mktemp('model'), allow_shipped=False)


_start = node_support.start_process
_stop = node_support.stop_process


class Listener:
    """Records ``release`` and ``/diagnostics`` (wall time of receipt) and sets parameters."""

    def __init__(self, context: Context) -> None:
        self.node = rclpy.create_node('fault_listener', context=context)
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.releases, self.diags = [], []
        self.node.create_subscription(
            Bool, 'release', lambda m: self.releases.append((time.time(), m.data)), reliable)
        self.node.create_subscription(
            DiagnosticArray, '/diagnostics',
            lambda m: self.diags.append((time.time(), m.status[0])), reliable)
        self.params = self.node.create_client(SetParameters, '/contact_detector/set_parameters')
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.02)

    def spin_until(self, predicate, timeout: float, what: str) -> None:
        end = time.monotonic() + timeout
        while not predicate():
            assert time.monotonic() < end, f'timed out waiting for {what}'
            self.executor.spin_once(timeout_sec=0.02)

    def set_parameter(self, name: str, value):
        msg = Parameter(name, value=value).to_parameter_msg()
        request = SetParameters.Request(parameters=[msg])
        future = self.params.call_async(request)
        self.spin_until(future.done, 10.0, f'set_parameters {name}')
        return future.result().results[0]

    def values(self) -> dict:
        return {kv.key: kv.value for kv in self.diags[-1][1].values}

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()


def test_faults_against_the_live_node(model, tmp_path):
    node_log = tmp_path / 'node.log'
    node = _start(['-m', 'contact_detector.ros.node', '--ros-args', '-p', f'model.path:={model}',
                   '-p', 'diagnostics.period_s:=0.5'], node_log)
    context = Context()
    rclpy.init(context=context)
    listener = Listener(context)
    publishers = []
    try:
        listener.spin_until(lambda: listener.diags and listener.params.service_is_ready(), 30.0,
                            'the node')
        # 1. Invalid parameters at run time: refused, reason names the parameter and range.
        refused = listener.set_parameter('release.threshold', 1.5)
        assert not refused.successful and 'release.threshold' in refused.reason
        assert '1.5' in refused.reason
        refused = listener.set_parameter('warmup_s', -1.0)
        assert not refused.successful and 'warmup_s' in refused.reason
        refused = listener.set_parameter('audio.sample_rate', 44100.0)       # read-only
        assert not refused.successful and 'read-only' in refused.reason.lower()
        refused = listener.set_parameter('gripper.joint', ' ')              # node's own check
        assert not refused.successful and 'gripper.joint' in refused.reason
        assert listener.set_parameter('corrupt_holdoff_s', 0.25).successful

        # 2. Publisher A: faults in the air, then it crashes.
        pub_a = _start([str(TEST_DIR / 'fault_publisher.py'), '--out', str(tmp_path / 'a.json'),
                        '--faults', FAULTS_A, '--die-at', '-2.8'], tmp_path / 'a.log')
        publishers.append(pub_a)
        listener.spin_until(lambda: pub_a.poll() is not None, 40.0, 'publisher A')
        assert pub_a.returncode == -signal.SIGKILL, (tmp_path / 'a.log').read_text()
        dead_at = time.time()
        # 3. Publisher B: the robot tries again.
        pub_b = _start([str(TEST_DIR / 'fault_publisher.py'), '--out', str(tmp_path / 'b.json'),
                        '--faults', FAULTS_B, '--stop-at', '1.5'], tmp_path / 'b.log')
        publishers.append(pub_b)
        listener.spin_until(lambda: pub_b.poll() is not None, 40.0, 'publisher B')
        assert pub_b.returncode == 0, (tmp_path / 'b.log').read_text()
        listener.spin_for(1.2)                        # two more diagnostics periods
        alive = node.poll() is None
    finally:
        for proc in publishers:
            if proc.poll() is None:
                proc.kill()
        listener.close()
        rclpy.try_shutdown(context=context)
        node_code = _stop(node)
    log = node_log.read_text()
    assert alive and node_code == 0, log

    a = json.loads((tmp_path / 'a.json').read_text())
    b = json.loads((tmp_path / 'b.json').read_text())
    assert b['sent']['audio'] > 600 and b['sent']['wrench'] > 400
    # Exactly one release, after the true onset of B's contact (none in A's air phase).
    releases = [t for t, data in listener.releases if data]
    assert len(releases) == 1, (releases, b['onset_wall'], log)
    assert 0.0 < releases[0] - b['onset_wall'] <= LATENCY_BUDGET_S, (releases, log)
    assert a['start_wall'] < dead_at < b['start_wall']

    # Diagnostics counted every fault kind (cumulative counters of the last status).
    values = {kv.key: kv.value for kv in listener.diags[-1][1].values}
    counts = {k: int(v) for k, v in values.items() if v.isdigit()}
    assert counts['callback_errors'] == 0
    assert counts['wrench_dropped'] >= 8            # NaN, backwards, duplicates, future
    assert counts['audio_dropped'] >= 2             # empty and 10 s chunks
    assert counts['bad_stamps'] >= 1                # 30 s in the future
    assert counts['time_jumps'] >= 1                # wrench stamps 30 s back
    assert counts['wrench_restarts'] >= 3           # 100 ms, crash, 2 s
    assert counts['audio_restarts'] >= 2            # burst or crash, 0.6 s dropout
    assert counts['releases'] == 1 and counts['release_msgs'] == 1
    statuses = [(t, s) for t, s in listener.diags]
    warn = [s.message for t, s in statuses if s.level == DiagnosticStatus.WARN]
    during_crash = [s.message for t, s in statuses if dead_at < t < b['start_wall']]
    assert any('stale or missing input: audio, wrench' in m for m in during_crash), during_crash
    during_ft2s = [s.message for t, s in statuses
                   if b['onset_wall'] - 5.0 < t < b['onset_wall'] - 3.4]
    assert any('stale or missing input: wrench' in m for m in during_ft2s), during_ft2s
    assert any('wrench_dropped' in m for m in warn) and any('bad_stamps' in m for m in warn)
    # ... and logged each kind, clearly.
    for text in ('wrench contains NaN or Inf', 'audio chunk is empty',
                 'exceeds the limit of 16000', 'repeats or precedes the previous one',
                 's ahead of the receive time', 'time jumped backwards, state reset',
                 'diagnostics: stale or missing input', 'parameter update refused',
                 'RELEASE'):
        assert text in log, (text, log)


@pytest.mark.parametrize('param, value, match', [
    ('release.threshold', '1.5', 'release.threshold'),
    ('audio.sample_rate', '100.0', 'audio.sample_rate'),
    ('wrench.rate', '20000.0', 'outside'),
    ('qos.reliability', 'sometimes', 'qos.reliability'),
])
def test_invalid_parameter_stops_the_node_process(model, param, value, match):
    cmd = [sys.executable, '-m', 'contact_detector.ros.node', '--ros-args',
           '-p', f'model.path:={model}', '-p', f'{param}:={value}']
    done = subprocess.run(cmd, cwd=TEST_DIR.parent, env=dict(os.environ), capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 1, done.stderr
    assert 'cannot start' in done.stderr and match in done.stderr, done.stderr


@pytest.mark.parametrize('args, match', [
    (['-p', 'gripper.enabled:=true', '-p', 'gripper.topic:=bad topic!'],
     'not a valid topic name'),
    (['-p', 'use_sim_time:=notabool'], 'use_sim_time'),
    (['-p', 'qos.depth:= '], 'qos.depth was given no value'),
    (['-p', 'model.path:='], 'bad ROS arguments'),
    (['-r', '__node:=1bad'], 'bad ROS arguments'),
    (['--params-file', '/nonexistent/params.yaml'], 'bad ROS arguments'),
])
def test_what_rclpy_refuses_stops_the_node_process_too(model, args, match):
    # rclpy's own refusals (argument parsing, names, types of its parameters) are a wrong
    # configuration too: one FATAL line and exit status 1, no traceback
    cmd = [sys.executable, '-m', 'contact_detector.ros.node', '--ros-args',
           '-p', f'model.path:={model}', *args]
    done = subprocess.run(cmd, cwd=TEST_DIR.parent, env=dict(os.environ), capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 1, done.stderr
    assert 'cannot start' in done.stderr and match in done.stderr, done.stderr
    assert 'Traceback' not in done.stderr, done.stderr
