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
from contact_detector.model.storage import load_bundle
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
from contact_detector.training.protocol import read_labels_csv
import numpy as np
import pytest
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
