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
Every input fault of docs/reliability.md against the real node, in-process, one case each.

The node (:class:`ContactDetectorNode` with a test model) gets real rclpy messages through its
own subscription callbacks, its clock set to each message's receive time first (``use_sim_time``
with the time override, as ``/clock`` does): the code path of a message once DDS delivered it,
at thousands of messages per second. ``test_faults_e2e.py`` does the same over DDS, between
processes. ``node.diagnostics()`` is called every 0.5 s of stream time, as the timer would.

Each case plays trial seed 3 / index 21 (in-air hits on the hand 1.5 s and 1.1 s before the
contact) from its start to 1 s after the onset with one fault injected before the contact,
and checks: no callback error; the fault is counted (diagnostics key) and logged (text);
a diagnostics status during the fault is WARN and names it; no release before the onset and
exactly one within 0.3 s after it (the node recovered by itself).
"""

from array import array
from dataclasses import dataclass, field
import re
from typing import Callable, Optional

from builtin_interfaces.msg import Time as TimeMsg
from contact_detector.ros.node import ContactDetectorNode
from contact_detector.sim.trial import simulate_trial
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
import node_support
import numpy as np
import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter
from rclpy.time import Time
from std_msgs.msg import Float32MultiArray, Int16MultiArray

pytestmark = pytest.mark.rclpy

TRIAL = {'seed': 3, 'index': 21, 'hits': 'hand'}
LATENCY_BUDGET_S = 0.3
DIAG_PERIOD_S = 0.5


@pytest.fixture(scope='module')
def bundle(tmp_path_factory):
    # Always the test model: the expected release times are those of this model.
    return node_support.load_test_model(tmp_path_factory.mktemp('model'))


@pytest.fixture(scope='module')
def trial():
    return simulate_trial(**TRIAL)


def stamp_msg(t: float) -> TimeMsg:
    sec = int(np.floor(t))
    return TimeMsg(sec=sec, nanosec=min(999_999_999, int(round((t - sec) * 1e9))))


def wrench(t: float, force, torque) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.stamp = stamp_msg(t)
    msg.header.frame_id = 'wrist_ft_sensor_frame'
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = (float(v) for v in force)
    msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = (float(v) for v in torque)
    return msg


def int16_msg(samples: np.ndarray) -> Int16MultiArray:
    msg = Int16MultiArray()
    msg.data = array('h', np.ascontiguousarray(samples, dtype=np.int16).tobytes())
    return msg


def float32_msg(samples: np.ndarray) -> Float32MultiArray:
    msg = Float32MultiArray()
    msg.data = array('f', np.ascontiguousarray(samples, dtype=np.float32).tobytes())
    return msg


@dataclass
class Item:
    """One delivery: at receive time ``now`` (s), ``msg`` to the ``kind`` callback."""

    now: float
    kind: str                      # 'audio' or 'wrench'
    msg: object
    rel: float                     # trial time relative to the onset, s (before any shift)


@dataclass
class Case:
    """A fault: how it changes the stream, and what the node must show."""

    name: str
    inject: Callable                # (items, trial) -> items
    counters: dict                  # counter -> minimum increase
    log: str                        # regular expression the node's log must contain
    diag: str                       # text of a WARN/ERROR diagnostics status during the fault
    window: tuple                   # (from, to) s relative to the onset: the fault's span
    params: dict = field(default_factory=dict)
    audio: str = 'int16'            # 'int16', 'float32' or 'stereo'
    shift: float = 0.0              # the whole time line after the fault moves by this


def base_items(trial, audio: str) -> list:
    items = []
    for e in node_support.trial_events(trial):
        rel = e.t - trial.onset_t
        if e.kind == 'audio':
            chunk = trial.audio[e.lo:e.hi]
            if audio == 'float32':
                msg = float32_msg(chunk / 32768.0)
            elif audio == 'stereo':
                msg = int16_msg(np.repeat(chunk, 2))
            else:
                msg = int16_msg(chunk)
            items.append(Item(e.t, 'audio', msg, rel))
        else:
            j = e.lo
            items.append(Item(e.t, 'wrench', wrench(trial.wrench_t[j], trial.force[j],
                                                    trial.torque[j]), rel))
    return [i for i in items if i.rel < 1.0]


def _inside(item: Item, lo: float, hi: float) -> bool:
    return lo <= item.rel < hi


def replace_wrench(lo, hi, change):
    def inject(items, trial):
        for item in items:
            if item.kind == 'wrench' and _inside(item, lo, hi):
                change(item.msg.wrench)
        return items
    return inject


def add_after(kind, lo, hi, make, every=1):
    """After every ``every``-th ``kind`` item in [lo, hi), insert ``make(item)``."""
    def inject(items, trial):
        out, n = [], 0
        for item in items:
            out.append(item)
            if item.kind == kind and _inside(item, lo, hi):
                n += 1
                if n % every == 0:
                    out.append(Item(item.now, kind, make(item), item.rel))
        return out
    return inject


def drop(kinds, lo, hi):
    def inject(items, trial):
        return [i for i in items if not (i.kind in kinds and _inside(i, lo, hi))]
    return inject


def map_audio(lo, hi, change):
    def inject(items, trial):
        for item in items:
            if item.kind == 'audio' and _inside(item, lo, hi):
                samples = np.frombuffer(item.msg.data, dtype=np.int16)
                item.msg = int16_msg(change(samples))
        return items
    return inject


def burst(lo, hi):
    """Everything received in [lo, hi) arrives at once at ``hi`` (a stalled executor/link)."""
    def inject(items, trial):
        for item in items:
            if _inside(item, lo, hi):
                item.now = hi + trial.onset_t
        return items
    return inject


def shift_after(at, by):
    """From ``at`` on, the receive times and every stamp move by ``by`` (a bag loop)."""
    def inject(items, trial):
        for item in items:
            if item.rel >= at:
                item.now += by
                if item.kind == 'wrench':
                    t = item.msg.header.stamp.sec + item.msg.header.stamp.nanosec * 1e-9
                    item.msg.header.stamp = stamp_msg(t + by)
        return items
    return inject


def wrench_with_stamp(offset):
    def make(item):
        t = item.msg.header.stamp.sec + item.msg.header.stamp.nanosec * 1e-9
        w = item.msg.wrench
        return wrench(t + offset, (w.force.x, w.force.y, w.force.z),
                      (w.torque.x, w.torque.y, w.torque.z))
    return make


def restamp_wrench(lo, hi, offset):
    def inject(items, trial):
        for item in items:
            if item.kind == 'wrench' and _inside(item, lo, hi):
                item.msg = wrench_with_stamp(offset)(item)
        return items
    return inject


def unset_stamp(item):
    """Return a copy of a wrench item's message whose header.stamp was never set (0)."""
    w = item.msg.wrench
    return wrench(0.0, (w.force.x, w.force.y, w.force.z), (w.torque.x, w.torque.y, w.torque.z))


def _zero_all(w):
    # a driver's placeholder for a missing reading: a wrench of six zeros
    w.force.x = w.force.y = w.force.z = w.torque.x = w.torque.y = w.torque.z = 0.0


def _zero_torque(w):
    # a driver that fills the force and leaves the torque of a missing reading at zero
    w.torque.x = w.torque.y = w.torque.z = 0.0


def white_noise(lo, hi, sigma):
    """Add white noise of ``sigma`` N per force axis to the wrench in [lo, hi): interference."""
    def inject(items, trial):
        rng = np.random.default_rng(0)
        for item in items:
            if item.kind == 'wrench' and _inside(item, lo, hi):
                f = item.msg.wrench.force
                f.x, f.y, f.z = np.array([f.x, f.y, f.z]) + rng.normal(0.0, sigma, 3)
        return items
    return inject


def _set(name, value):
    def change(w):
        target, axis = name.split('.')
        setattr(getattr(w, target), axis, value)
    return change


def clip(gain):
    return lambda s: np.clip(s.astype(np.int32) * gain, -32768, 32767).astype(np.int16)


CASES = [
    Case('wrench_nan', replace_wrench(-2.6, -2.55, _set('force.x', float('nan'))),
         {'wrench_dropped': 5}, 'wrench message dropped: wrench contains NaN or Inf',
         'wrench_dropped', (-2.6, -2.55)),
    Case('wrench_inf', replace_wrench(-2.6, -2.55, _set('torque.y', float('inf'))),
         {'wrench_dropped': 5}, 'wrench contains NaN or Inf', 'wrench_dropped', (-2.6, -2.55)),
    Case('audio_empty', add_after('audio', -2.6, -2.5, lambda i: Int16MultiArray()),
         {'audio_dropped': 10}, 'audio message dropped: audio chunk is empty', 'audio_dropped',
         (-2.6, -2.5)),
    Case('audio_odd_count_stereo',
         add_after('audio', -2.6, -2.5, lambda i: int16_msg(np.zeros(161, np.int16))),
         {'audio_dropped': 10}, r'audio chunk of 161 samples is not a multiple of the 2 '
         'configured channels', 'audio_dropped', (-2.6, -2.5), params={'audio.channels': 2},
         audio='stereo'),
    Case('audio_wrong_array_type',
         add_after('audio', -2.6, -2.5, lambda i: float32_msg(np.zeros(160))),
         {'audio_dropped': 10}, r'Int16MultiArray.data must hold integers \(int16\), got '
         'float32', 'audio_dropped', (-2.6, -2.5)),
    Case('audio_nan', add_after('audio', -2.6, -2.5, lambda i: float32_msg(
        np.full(160, np.nan))), {'audio_dropped': 10}, 'contains NaN or Inf', 'audio_dropped',
         (-2.6, -2.5), params={'audio.msg_type': 'std_msgs/msg/Float32MultiArray'},
         audio='float32'),
    Case('audio_huge_chunk_10s',
         add_after('audio', -2.6, -2.5, lambda i: int16_msg(np.zeros(160000, np.int16)),
                   every=5),
         {'audio_dropped': 2}, 'audio chunk of 160000 samples exceeds the limit of 16000',
         'audio_dropped', (-2.6, -2.5)),
    Case('audio_stereo_read_as_mono', map_audio(-5.0, -3.5, lambda s: np.repeat(s, 2)),
         {'audio_rate_mismatch': 10}, r'audio arrives at \d+ samples per second of stamps, '
         'but the configured rate is 16000 Hz', 'audio_rate_mismatch', (-5.0, -3.0)),
    Case('audio_rate_half_of_configured', map_audio(-5.0, -3.5, lambda s: s[::2]),
         {'audio_rate_mismatch': 10}, r'audio arrives at \d{4} samples per second',
         'audio_rate_mismatch', (-5.0, -3.0)),
    Case('audio_clipped', map_audio(-3.5, -2.5, clip(400)), {'audio_clipped': 50},
         'diagnostics: bad input: .*audio_clipped', 'audio_clipped', (-3.5, -2.5)),
    Case('wrench_stamps_backwards', add_after('wrench', -2.6, -2.5, wrench_with_stamp(-0.2)),
         {'wrench_dropped': 10}, 'repeats or precedes the previous one', 'wrench_dropped',
         (-2.6, -2.5)),
    Case('wrench_duplicated', add_after('wrench', -2.6, -2.5, lambda i: i.msg),
         {'wrench_dropped': 10}, 'repeats or precedes the previous one', 'wrench_dropped',
         (-2.6, -2.5)),
    Case('wrench_stamps_in_future', add_after('wrench', -2.6, -2.5, wrench_with_stamp(30.0)),
         {'wrench_dropped': 10, 'bad_stamps': 10}, r'ahead of the receive time',
         'bad_stamps', (-2.6, -2.5)),
    Case('wrench_unset_stamps', add_after('wrench', -2.6, -2.5, unset_stamp),
         {'wrench_dropped': 10, 'bad_stamps': 10},
         r'wrench stamp is 0: the publisher does not set header.stamp \(set '
         r'wrench.stamp_source: receive\)', 'bad_stamps', (-2.6, -2.5)),
    Case('wrench_zero_placeholders', replace_wrench(-2.6, -2.5, _zero_all),
         {'wrench_placeholders': 10},
         r'F/T sample with a force or torque of exactly \(0, 0, 0\) after a load dropped',
         'wrench_placeholders', (-2.6, -2.5)),
    Case('wrench_zero_torque_placeholders', replace_wrench(-2.6, -2.5, _zero_torque),
         {'wrench_placeholders': 10}, r'exactly \(0, 0, 0\) after a load dropped',
         'wrench_placeholders', (-2.6, -2.5)),
    Case('wrench_noise_burst', white_noise(-2.6, -2.4, 20.0), {'wrench_noise': 5},
         r'F/T reading noisy: the force jumps back and forth by \d+\.\d N per sample',
         'wrench_noise', (-2.6, -2.4)),
    Case('wrench_stamps_jump_back_30s', restamp_wrench(-3.0, -2.8, -30.0),
         {'time_jumps': 1, 'wrench_restarts': 1}, 'time jumped backwards, state reset',
         'time_jumps', (-3.0, -2.5)),
    Case('bag_loop', shift_after(-3.0, -20.0), {'clock_jumps': 1},
         r'node clock jumped by -\d+\.\d+ s \(bag loop or seek\?\)', 'clock_jumps',
         (-23.0, -22.0), shift=-20.0),
    Case('ft_dropout_100ms', drop({'wrench'}, -2.6, -2.5), {'wrench_restarts': 1},
         'diagnostics: bad input: .*wrench_restarts', 'wrench_restarts', (-2.6, -2.0)),
    Case('ft_dropout_2s', drop({'wrench'}, -3.5, -1.5), {'wrench_restarts': 1},
         'diagnostics: stale or missing input: wrench', 'stale or missing input: wrench',
         (-3.5, -1.5)),
    Case('audio_dropout_800ms', drop({'audio'}, -3.3, -2.5), {'audio_restarts': 1},
         'diagnostics: stale or missing input: audio', 'stale or missing input: audio',
         (-3.3, -2.5)),
    Case('burst_300ms', burst(-3.0, -2.7), {'audio_restarts': 1},
         'diagnostics: bad input: .*audio_restarts', 'audio_restarts', (-3.0, -2.2)),
    Case('burst_1s', burst(-3.6, -2.6), {'audio_restarts': 1},
         'diagnostics: bad input: .*audio_restarts', 'audio_restarts', (-3.6, -2.0)),
    Case('publisher_dies_and_returns', drop({'audio', 'wrench'}, -4.0, -2.0),
         {'audio_restarts': 1, 'wrench_restarts': 1},
         'diagnostics: stale or missing input: audio, wrench',
         'stale or missing input: audio, wrench', (-4.0, -2.0)),
]


def play(bundle, trial, case: Optional[Case], capfd):
    """Run the trial with ``case`` through a fresh node; return what it did."""
    context = Context()
    rclpy.init(context=context)
    # No throttling: the whole trial takes a fraction of a second of wall time here.
    params = {'use_sim_time': True, 'diagnostics.period_s': 3600.0, 'log_throttle_s': 0.0}
    params.update(case.params if case else {})
    node = ContactDetectorNode(context=context, bundle=bundle, parameter_overrides=[
        Parameter(k, value=v) for k, v in params.items()])
    try:
        items = base_items(trial, case.audio if case else 'int16')
        if case is not None:
            items = case.inject(items, trial)
        clock = node.get_clock()
        callbacks = {'audio': node._on_audio, 'wrench': node._on_wrench}
        before = node.detector_counts()
        diags, next_diag = [], None
        for item in items:
            clock.set_ros_time_override(Time(nanoseconds=int(round(item.now * 1e9))))
            if next_diag is None or item.now >= next_diag or item.now < next_diag - 10.0:
                status = node.diagnostics().status[0]
                diags.append((item.now - trial.onset_t, status.level, status.message))
                next_diag = item.now + DIAG_PERIOD_S
            callbacks[item.kind](item.msg)
        after = node.detector_counts()
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    log = capfd.readouterr().err
    releases = [float(t) for t in re.findall(r'contact at t=(\d+\.\d+) s: RELEASE', log)]
    increase = {k: after[k] - before.get(k, 0) for k in after}
    return releases, increase, diags, log


def test_clean_trial_releases_once_at_the_contact(bundle, trial, capfd):
    releases, increase, _, log = play(bundle, trial, None, capfd)
    assert len(releases) == 1, log
    assert 0.0 < releases[0] - trial.onset_t <= LATENCY_BUDGET_S
    assert increase['callback_errors'] == 0 and increase['audio_dropped'] == 0


@pytest.mark.parametrize('case', CASES, ids=[c.name for c in CASES])
def test_fault(bundle, trial, capfd, case):
    releases, increase, diags, log = play(bundle, trial, case, capfd)
    assert increase['callback_errors'] == 0, log
    for name, least in case.counters.items():
        assert increase[name] >= least, (name, increase)
    assert re.search(case.log, log), log
    lo, hi = case.window
    during = [(rel, level, msg) for rel, level, msg in diags if lo <= rel < hi + 1.0]
    assert any(level == DiagnosticStatus.WARN and case.diag in msg
               for _, level, msg in during), during
    onset = trial.onset_t + case.shift
    assert len(releases) == 1, (releases, onset, log)
    assert 0.0 < releases[0] - onset <= LATENCY_BUDGET_S, (releases[0] - onset, log)


def test_warnings_are_throttled(bundle, trial, capfd):
    """With the default log_throttle_s (2 s of wall time) a fault kind is logged once here."""
    case = next(c for c in CASES if c.name == 'wrench_duplicated')
    context = Context()
    rclpy.init(context=context)
    node = ContactDetectorNode(context=context, bundle=bundle, parameter_overrides=[
        Parameter('use_sim_time', value=True)])
    try:
        clock = node.get_clock()
        for item in case.inject(base_items(trial, 'int16'), trial):
            clock.set_ros_time_override(Time(nanoseconds=int(round(item.now * 1e9))))
            (node._on_audio if item.kind == 'audio' else node._on_wrench)(item.msg)
        dropped = node.detector_counts()['wrench_dropped']
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    log = capfd.readouterr().err
    assert dropped >= 10
    assert log.count('repeats or precedes the previous one') == 1, log
