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

"""``contact-detector label``: hindsight onsets on simulated bags, unlabelled rows, train."""

import csv
import dataclasses
import importlib.util
from pathlib import Path
import subprocess
import sys

from contact_detector.cli import evaluate as evaluate_cli
from contact_detector.cli import label as label_cli
from contact_detector.cli import simulate as simulate_cli
from contact_detector.cli import train as train_cli
from contact_detector.errors import InputError
from contact_detector.evaluation.labelling import hinge_fit, NO_CHANGE, propose_onset
from contact_detector.io.bags import read_wrench
from contact_detector.model.storage import load_bundle
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
from contact_detector.training.protocol import read_labels_csv
import numpy as np
import pytest
from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import get_typestore, Stores
from scipy.stats import binomtest, norm

pytestmark = pytest.mark.slow   # simulates bags, labels and trains

#: (condition, index, storage): different families, a soft and a quiet contact, a ROS 1 bag.
TRIALS = [('paper', 0, 'sqlite3'), ('soft', 1, 'sqlite3'), ('compliant', 2, 'ros1'),
          ('quiet_contact', 3, 'mcap')]


@pytest.fixture(scope='module')
def labelled(tmp_path_factory):
    root = tmp_path_factory.mktemp('label')
    bags = root / 'bags'
    truth = {}
    for condition, index, storage in TRIALS:
        trial = simulate_trial(seed=3, index=index, condition=condition)
        path = write_trial_bag(trial=trial, path=bags / trial.name, storage=storage)
        truth[path.name] = trial.onset_t
    # the arm held still: the same load throughout, with the sensor's noise
    still = simulate_trial(seed=3, index=9, condition='paper')
    rng = np.random.default_rng(0)
    n = len(still.wrench_t)
    still = dataclasses.replace(
        still, force=still.force[:1] + rng.normal(0, 0.05, (n, 3)),
        torque=still.torque[:1] + rng.normal(0, 0.005, (n, 3)))
    write_trial_bag(trial=still, path=bags / still.name)
    out = root / 'labels.csv'
    plots = root / 'plots'
    assert label_cli.main([str(bags), '--out', str(out), '--plots', str(plots)]) == 0
    with open(out) as handle:
        rows = {r['bag']: r for r in csv.DictReader(handle)}
    return {'bags': bags, 'csv': out, 'rows': rows, 'truth': truth, 'still': still.name,
            'plots': plots, 'root': root}


def test_label_finds_onsets_within_20_ms(labelled):
    for bag, onset in labelled['truth'].items():
        row = labelled['rows'][bag]
        assert abs(float(row['onset_start']) - onset) <= 0.020, (bag, row)
        assert float(row['onset_end']) == pytest.approx(float(row['onset_start']) + 0.1)
        assert 0.0 < float(row['confidence']) <= 1.0
        assert (labelled['plots'] / f'{bag}.png').stat().st_size > 10_000


def test_a_bag_without_contact_gets_a_row_saying_why(labelled):
    row = labelled['rows'][labelled['still']]
    assert row['onset_start'] == '' and row['onset_end'] == ''
    assert float(row['confidence']) == 0.0 and row['reason'] == NO_CHANGE


def test_readers_skip_unlabelled_rows_with_a_warning(labelled):
    with pytest.warns(UserWarning, match=f'{labelled["still"]} has no onset'):
        onsets = read_labels_csv(labelled['csv'])
    assert sorted(onsets) == sorted(labelled['truth'])


def test_train_accepts_the_csv_label_writes(labelled):
    model = labelled['root'] / 'm.npz'
    with pytest.warns(UserWarning, match='no onset'):
        assert train_cli.main([str(labelled['bags']), '--labels', str(labelled['csv']),
                               '--no-events', '--jobs', '1', '--out', str(model)]) == 0
    assert load_bundle(path=model).training['trials'] == len(TRIALS)


def test_evaluate_accepts_the_csv_label_writes(labelled, capsys):
    # the bag label could not label is left out, as train leaves it out; the rest are scored
    with pytest.warns(UserWarning, match='no onset'):
        assert evaluate_cli.main([str(labelled['bags']), '--labels', str(labelled['csv']),
                                  '--detector', 'threshold']) == 0
    table = capsys.readouterr().out.split('| recording |', 1)[1]
    assert all(f'| {bag} |' in table for bag in labelled['truth'])
    assert labelled['still'] not in table


def test_label_prints_what_it_found(labelled, tmp_path, capsys):
    ros1 = next(b for b in labelled['bags'].iterdir() if b.suffix == '.bag')
    assert label_cli.main([str(ros1), '--out', str(tmp_path / 'one.csv')]) == 0
    printed = capsys.readouterr().out
    assert (f'contact-detector label: {ros1.name}: wrench /wrist_wrench at 100 Hz (stamps); '
            'audio /audio [std_msgs/Int16MultiArray] 16000 Hz') in printed


# --- input the detector refuses or drops: label does the same, and says so ---------------------

@pytest.fixture(scope='module')
def contact_bag(tmp_path_factory):
    """Simulate a recording with a clear contact; return it and its true onset (s)."""
    trial = simulate_trial(seed=3, index=0, condition='paper')
    bag = write_trial_bag(trial=trial, path=tmp_path_factory.mktemp('input') / trial.name)
    return bag, trial.onset_t


def _rewrite(src: Path, dst: Path, change) -> Path:
    """Copy ``src``, the k-th /wrist_wrench message ``msg`` replaced by ``change(k, msg)``."""
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(src) as reader, Writer(dst, version=9) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store)
                 for c in reader.connections}
        k = 0
        for conn, log_ns, raw in reader.messages():
            if conn.topic == '/wrist_wrench':
                msg = change(k, store.deserialize_cdr(raw, conn.msgtype))
                raw = store.serialize_cdr(msg, conn.msgtype)
                k += 1
            writer.write(conns[conn.id], log_ns, raw)
    return dst


def _restamp(msg, *, sec: int, nanosec: int):
    stamp = dataclasses.replace(msg.header.stamp, sec=sec, nanosec=nanosec)
    return dataclasses.replace(msg, header=dataclasses.replace(msg.header, stamp=stamp))


def _label(bags: list, out: Path, *extra) -> dict:
    assert label_cli.main([*map(str, bags), '--out', str(out), *extra]) == 0
    with open(out) as handle:
        return {r['bag']: r for r in csv.DictReader(handle)}


def test_label_refuses_what_detect_refuses_with_no_label(contact_bag, tmp_path, capsys):
    bag, _ = contact_bag
    # every stamp with nanosec = 1.5e9 (invalid): once labelled with confidence 1.00
    bad_ns = _rewrite(bag, tmp_path / 'bad_nanosec', lambda k, m: _restamp(
        m, sec=1_700_000_000 + k // 100, nanosec=1_500_000_000))
    # 1 us steps: a 1 MHz F/T stream, outside the rates detect accepts
    fast = _rewrite(bag, tmp_path / 'us_steps', lambda k, m: _restamp(
        m, sec=1_700_000_000, nanosec=1000 * k))
    rows = _label([bad_ns, fast], tmp_path / 'refused.csv')
    err = capsys.readouterr().err
    for name, why in (('bad_nanosec', 'no usable messages on /wrist_wrench'),
                      ('us_steps', 'Hz is outside [50; 10000] Hz (/wrist_wrench; measured '
                                   'from the header stamps)')):
        row = rows[name]
        assert (row['onset_start'], row['onset_end'], row['confidence']) == ('', '', '0.0')
        assert row['reason'].startswith('unreadable: ') and why in row['reason'], row
        assert why.replace(';', ',') in err
    assert 'nanosec=1500000000 is outside [0; 1e9)' in rows['bad_nanosec']['reason']
    assert 'Traceback' not in err


def test_label_refuses_a_wrench_topic_of_another_type(contact_bag, tmp_path, capsys):
    bag, _ = contact_bag
    rows = _label([bag], tmp_path / 'typed.csv', '--wrench-topic', '/contact_truth')
    row = rows[bag.name]
    assert row['onset_start'] == '' and row['reason'].startswith('unreadable: ')
    assert ('/contact_truth (--wrench-topic) holds std_msgs/msg/Bool; not '
            'geometry_msgs/msg/WrenchStamped') in row['reason']
    assert 'F/T only' not in capsys.readouterr().err   # no fallback to the topic it refused


def test_label_drops_counts_and_prints_bad_samples(contact_bag, tmp_path, capsys):
    bag, onset = contact_bag
    rng = np.random.default_rng(1)
    nan_at = set(np.flatnonzero(rng.random(10_000) < 0.2).tolist())

    def nan_some(k, msg):
        if k not in nan_at:
            return msg
        force = dataclasses.replace(msg.wrench.force, x=float('nan'))
        return dataclasses.replace(msg, wrench=dataclasses.replace(msg.wrench, force=force))

    def repeat_every_tenth(k, msg):
        # message k repeats the stamp of message k - 1: a duplicated sample
        if k % 10 or not k:
            return msg
        ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec - 10_000_000
        return _restamp(msg, sec=ns // 10**9, nanosec=ns % 10**9)

    nans = _rewrite(bag, tmp_path / 'nan_some', nan_some)
    dups = _rewrite(bag, tmp_path / 'dups', repeat_every_tenth)
    rows = _label([nans, dups], tmp_path / 'dropped.csv')
    err = capsys.readouterr().err
    total = sum(1 for _ in read_wrench(bag).t)
    n_nan = len([k for k in nan_at if k < total])
    n_dup = len(range(10, total, 10))
    assert (f'nan_some: dropped {n_nan} of {total} F/T messages: {n_nan} with NaN/Inf '
            'values') in err
    assert (f'dups: dropped {n_dup} of {total} F/T messages: {n_dup} with a stamp that '
            'repeats or precedes the previous one') in err
    # once the NaN samples are left out the contact is found (they used to hide it)
    for name in ('nan_some', 'dups'):
        assert abs(float(rows[name]['onset_start']) - onset) <= 0.020, rows[name]


def test_label_refuses_a_rate_flag_of_zero(contact_bag, tmp_path, capsys):
    bag, _ = contact_bag
    out = tmp_path / 'zero.csv'
    assert label_cli.main([str(bag), '--audio-rate', '0', '--out', str(out)]) == 1
    assert 'error: --audio-rate: audio sample rate must be in [1000, 384000] Hz, got 0' in (
        capsys.readouterr().err)
    assert not out.exists()


def test_label_accuracy_pools_sets_and_gives_the_interval(tmp_path):
    # benchmarks/label_accuracy.py, the command behind the accuracy the docs quote
    script = Path(__file__).resolve().parents[2] / 'benchmarks' / 'label_accuracy.py'
    sets = [tmp_path / 'a', tmp_path / 'b']
    for seed, folder in enumerate(sets):
        assert simulate_cli.main([str(folder), '--trials', '3', '--seed', str(40 + seed),
                                  '--conditions', 'paper', '--quiet']) == 0
    done = subprocess.run([sys.executable, str(script), '--dir', *map(str, sets)],
                          capture_output=True, text=True, check=True)
    rows = {line.split('|')[1].strip(): line for line in done.stdout.splitlines()
            if line.startswith('| ')}
    assert '| 6 |' in rows['all'] and '(6/6, 95 % 61.0-100.0 %)' in rows['all']
    assert f'{sets[0]}: 3/3 within 20 ms' in done.stdout
    # the interval is Wilson's: scipy's reference, 813 of 816 (scipy's z is not rounded)
    spec = importlib.util.spec_from_file_location('label_accuracy', script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    reference = binomtest(813, 816).proportion_ci(method='wilson')
    assert module.wilson(hits=813, n=816, z=norm.ppf(0.975)) == pytest.approx(
        (reference.low, reference.high), abs=1e-12)
    # pooled sets must exist: a clear usage error, before any labelling
    empty = tmp_path / 'empty'
    empty.mkdir()
    refused = subprocess.run([sys.executable, str(script), '--dir', str(sets[0]), str(empty)],
                             capture_output=True, text=True)
    assert refused.returncode == 2 and 'must be simulated first' in refused.stderr


def test_orientation_and_tare_do_not_matter():
    trial = simulate_trial(seed=3, index=0, condition='paper')
    base = propose_onset(ft_t=trial.wrench_t, force=trial.force, torque=trial.torque)
    angle = 1.1
    rot = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0],
                    [0.0, 0.0, 1.0]])
    moved = propose_onset(ft_t=trial.wrench_t, force=trial.force @ rot.T - 40.0,
                          torque=trial.torque @ rot.T + 3.0)
    assert moved.onset_t == pytest.approx(base.onset_t, abs=1e-3)
    assert abs(base.onset_t - trial.onset_t) <= 0.020


def test_a_knock_is_not_the_contact():
    trial = simulate_trial(seed=3, index=0, condition='paper', hits='none')
    force = trial.force.copy()
    j = int(np.searchsorted(trial.wrench_t, trial.onset_t - 1.0))
    force[j:j + 3] += [40.0, -30.0, 20.0]  # a 30 ms knock, larger than the contact
    p = propose_onset(ft_t=trial.wrench_t, force=force, torque=trial.torque)
    assert abs(p.onset_t - trial.onset_t) <= 0.020


def test_hinge_fit_finds_a_ramp_between_samples():
    dt = 0.01
    t = np.arange(40) * dt + dt
    t0 = 0.2237
    # a ramp averaged over each sample's period (t - dt, t], as the sensor does
    y = (np.maximum(t - t0, 0) ** 2 - np.maximum(t - dt - t0, 0) ** 2) / (2 * dt) * 50.0
    fit, power, _ = hinge_fit(t=t, y=y, dt=dt, lo=0.1, hi=0.3)
    assert power == 1 and fit == pytest.approx(t0, abs=dt / 20)


def test_bad_shapes_are_refused():
    with pytest.raises(InputError):
        propose_onset(ft_t=np.arange(5.0), force=np.zeros((4, 3)), torque=np.zeros((5, 3)))
