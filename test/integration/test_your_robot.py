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
Your robot, your data: labels CSV, evaluate --labels, train --with-sim, the tools/ helpers.

The "recordings" are simulated trials written as ROS 1 bags at 125 Hz F/T with no manifest
beside them, as a user's own bags come: their truth is what the labels CSV says.
"""

import json
from pathlib import Path
import subprocess
import sys

from contact_detector.cli import evaluate as evaluate_cli
from contact_detector.cli import simulate as simulate_cli
from contact_detector.cli import train as train_cli
from contact_detector.evaluation.metrics import score_onsets, score_trial, Truth
from contact_detector.io.bags import read_wrench
from contact_detector.io.discovery import discover_streams
from contact_detector.model.storage import load_bundle
from contact_detector.sim import simulate_trials
from contact_detector.sim.bag_writer import simulator_fingerprint, write_trial_bag
import numpy as np
import pytest
from rosbags.rosbag1 import Reader

pytestmark = pytest.mark.slow   # simulates recordings, trains, runs the tools/ scripts

ROOT = Path(__file__).resolve().parents[2]
N_RECORDINGS = 3


@pytest.fixture(scope='module')
def recordings(tmp_path_factory):
    root = tmp_path_factory.mktemp('robot')
    bags = root / 'bags'
    onsets = {}
    for trial in simulate_trials(n=N_RECORDINGS, seed=5, conditions=['paper'], ft_rate=125.0):
        bag = write_trial_bag(trial=trial, path=bags / f'{trial.name}.bag', storage='ros1')
        onsets[bag.name] = trial.onset_t
    return {'root': root, 'bags': bags, 'onsets': onsets}


def write_labels(path: Path, rows: dict) -> Path:
    lines = ['bag,onset_start,onset_end']
    lines += [f'{bag},{t!r},{t!r}' for bag, times in rows.items() for t in times]
    path.write_text('\n'.join(lines) + '\n')
    return path


def test_several_contacts_are_scored_each_as_if_re_armed():
    outcomes = score_onsets(name='r', condition='', onsets=[6.0, 1.0, 9.0, 3.0],
                            events=[0.5, 3.1, 6.7, 3.3])
    assert [o.verdict for o in outcomes] == ['premature', 'detected', 'late', 'missed']
    assert [o.name for o in outcomes] == ['r#1', 'r#2', 'r#3', 'r#4']
    assert outcomes[1].latency_s == pytest.approx(0.1)
    assert all(o.extra['recording'] == 'r' for o in outcomes)
    # One contact: the verdict of score_trial with the first event as the release.
    for events in ([], [0.2], [1.0, 1.2], [1.3, 5.0], [2.0]):
        one = score_onsets(name='r', condition='c', onsets=[1.0], events=events)
        ref = score_trial(truth=Truth(name='r', condition='c', onset_t=1.0),
                          releases=events[:1], events=())
        assert (one[0].verdict, one[0].latency_s, one[0].name) == (
            ref.verdict, ref.latency_s, ref.name)


def test_evaluate_takes_the_labels_csv_as_truth(recordings, tmp_path, capsys):
    bags, onsets = recordings['bags'], recordings['onsets']
    kw = ['--detector', 'forest', '--detector', 'threshold']
    assert evaluate_cli.main([str(bags), *kw, '--report', str(tmp_path / 'topic')]) == 0
    right = write_labels(tmp_path / 'right.csv', {b: [t] for b, t in onsets.items()})
    assert evaluate_cli.main([str(bags), *kw, '--labels', str(right),
                              '--report', str(tmp_path / 'csv')]) == 0
    printed = capsys.readouterr().out
    for bag in onsets:
        assert f'| {bag} | 1 |' in printed          # the per-recording table
    by_topic = json.loads((tmp_path / 'topic' / 'trials.json').read_text())
    by_csv = json.loads((tmp_path / 'csv' / 'trials.json').read_text())
    for name in ('forest', 'threshold'):
        assert ([(o['name'], o['verdict'], o['release_t']) for o in by_topic[name]]
                == [(o['name'], o['verdict'], o['release_t']) for o in by_csv[name]])
    # Labels 3 s late turn the same releases premature: the CSV is the truth used.
    late = write_labels(tmp_path / 'late.csv', {b: [t + 3.0] for b, t in onsets.items()})
    assert evaluate_cli.main([str(bags), *kw, '--labels', str(late),
                              '--report', str(tmp_path / 'late')]) == 0
    shifted = json.loads((tmp_path / 'late' / 'trials.json').read_text())
    for o, ref in zip(shifted['forest'], by_csv['forest']):
        if ref['release_t'] is not None:
            assert o['verdict'] == 'premature'
            assert o['latency_s'] == pytest.approx(ref['latency_s'] - 3.0)
    # ... and the per-recording table says by how much (release - label, ms)
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith('| trial')]
    assert any(' early -29' in row or ' early -30' in row for row in rows)
    summary = (tmp_path / 'csv' / 'summary.md').read_text()
    assert '## Per recording' in summary and (tmp_path / 'csv' / 'recordings.png').stat().st_size


def test_bags_that_share_a_name_are_labelled_and_reported_apart(recordings, tmp_path,
                                                                capsys):
    # Two days of recordings, each day's bags named alike: the CSV names them by path.
    bag = sorted(recordings['onsets'])[0]
    onset = recordings['onsets'][bag]
    for day in ('day1', 'day2'):
        (tmp_path / day).mkdir()
        (tmp_path / day / bag).write_bytes((recordings['bags'] / bag).read_bytes())
    labels = write_labels(tmp_path / 'labels.csv', {f'day1/{bag}': [onset],
                                                    f'day2/{bag}': [onset + 3.0]})
    days = [str(tmp_path / 'day1'), str(tmp_path / 'day2')]
    assert evaluate_cli.main([*days, '--labels', str(labels), '--report',
                              str(tmp_path / 'out')]) == 0
    printed = capsys.readouterr().out
    assert f'| day1/{bag} | 1 |' in printed and f'| day2/{bag} | 1 |' in printed
    verdicts = {o['name']: o['verdict'] for o in
                json.loads((tmp_path / 'out' / 'trials.json').read_text())['forest']}
    # the same recording, labelled 3 s later on day 2: released before that label
    assert verdicts == {f'day1/{bag}': 'detected', f'day2/{bag}': 'premature'}
    # ... and the tables by condition have a row per folder
    summary = (tmp_path / 'out' / 'summary.md').read_text()
    assert '| day1 | 1 | 1 | 0 | 0 | 0 |' in summary and '| day2 | 1 | 0 | 0 | 0 | 1 (' in summary
    # A CSV that names the bag alone cannot say which day it means: a clear error.
    bare = write_labels(tmp_path / 'bare.csv', {bag: [onset]})
    assert evaluate_cli.main([*days, '--labels', str(bare)]) == 1
    assert f"'{bag}' could be any of 2 bags" in capsys.readouterr().err
    # Each day's own CSV beside its bags (as `label` writes one per session), bare names and
    # all: every row is read relative to its own CSV, so the days keep their onsets apart.
    own = [write_labels(tmp_path / day / 'labels.csv', {bag: [t]})
           for day, t in (('day1', onset), ('day2', onset + 3.0))]
    assert evaluate_cli.main([*days, '--labels', str(own[0]), '--labels', str(own[1]),
                              '--report', str(tmp_path / 'own')]) == 0
    assert {o['name']: o['verdict'] for o in json.loads(
        (tmp_path / 'own' / 'trials.json').read_text())['forest']} == verdicts
    # Two CSVs that both name one bag are refused, naming both, rather than one chosen.
    capsys.readouterr()
    assert evaluate_cli.main([*days, '--labels', str(labels), '--labels', str(own[1])]) == 1
    err = capsys.readouterr().err
    assert f'{labels} and {own[1]} both name' in err and 'Traceback' not in err


def test_evaluate_scores_every_contact_of_a_recording(recordings, tmp_path, capsys):
    bag = sorted(recordings['onsets'])[0]
    onset = recordings['onsets'][bag]
    labels = write_labels(tmp_path / 'two.csv', {bag: [onset, onset + 2.5]})
    assert evaluate_cli.main([str(recordings['bags'] / bag), '--labels', str(labels),
                              '--report', str(tmp_path / 'r')]) == 0
    trials = json.loads((tmp_path / 'r' / 'trials.json').read_text())['forest']
    assert [o['name'] for o in trials] == [f'{bag}#1', f'{bag}#2']
    # the glass stays on the table: nothing new happens at the second "contact"
    assert trials[1]['verdict'] == 'missed'
    assert f'| {bag} | 2 |' in capsys.readouterr().out
    # The recordings the CSV does not name carry a /contact_truth (they are simulated): it
    # scores them, one contact each, and the command says so. (Without one: refused, see
    # test_offline_tools.)
    assert evaluate_cli.main([str(recordings['bags']), '--labels', str(labels)]) == 0
    printed = capsys.readouterr()
    assert 'without a row' in printed.err and f'| {bag} | 2 |' in printed.out
    for other in sorted(recordings['onsets'])[1:]:
        assert f'| {other} | 1 |' in printed.out


def test_train_on_recordings_mixed_with_simulated_trials(recordings, tmp_path, capsys):
    labels = write_labels(tmp_path / 'l.csv', {b: [t] for b, t in recordings['onsets'].items()})
    sim = tmp_path / 'sim'
    model = tmp_path / 'mine.npz'
    args = [str(recordings['bags']), '--labels', str(labels), '--trees', '2', '--jobs', '1',
            '--out', str(model)]
    assert train_cli.main([*args, '--with-sim', '8', '--sim-dir', str(sim)]) == 0
    assert ("8 simulated trials of wide at 125 Hz F/T, 16000 Hz audio: 6 with each family's "
            'own events, 2 with any event in every family') in capsys.readouterr().out
    sources = load_bundle(path=model).training['sources']
    assert sources['recordings'] == {'count': 3, 'contacts': 3,
                                     'bags': sorted(recordings['onsets']),
                                     'labels': 'l.csv (--labels)'}
    simulated = sources['simulated']
    assert simulated['trials'] == 8 and simulated['kept_in'] == str(sim)
    assert len(simulated['families']) == 8        # wide: the parts continue one family cycle
    assert simulated['ft_rate'] == 125.0
    assert simulated['simulator'] == simulator_fingerprint()   # the code that made them
    card = json.loads(model.with_name('mine.card.json').read_text())
    assert card['training']['sources'] == sources
    assert load_bundle(path=model).training['trials'] == 11
    # As the shipped model: 4/5 with each family's own events (brushes, touches and
    # set-downs only in 'exogenous'), 1/5 with any event in every family, seed + 1.
    family, mixed = simulated['parts']['family'], simulated['parts']['mixed']
    assert (family['trials'], family['seed'], family['events'], family['hits']) == (
        6, 0, 'family', None)
    assert (mixed['trials'], mixed['seed'], mixed['events'], mixed['hits']) == (
        2, 1, 'everywhere', 'mixed')
    held = {part: json.loads((sim / part / 'manifest.json').read_text())['trials']
            for part in ('family', 'mixed')}
    assert mixed['families'] == sorted(t['condition'] for t in held['mixed'])
    assert len(mixed['families']) == 2 and 'exogenous' not in mixed['families']
    # ... so the forest is shown brushes, touches or set-downs outside the exogenous family,
    # which the family part alone never has.
    kinds = {t['condition']: {i['kind'] for i in t['impacts']} for t in held['mixed']}
    assert any(k & {'touch', 'brush', 'setdown'} for k in kinds.values())
    assert not any({i['kind'] for i in t['impacts']} & {'touch', 'brush', 'setdown'}
                   for t in held['family'] if t['condition'] != 'exogenous')
    for part in ('family', 'mixed'):
        counted = [i['kind'] for t in held[part] for i in t['impacts']]
        assert simulated['parts'][part]['exogenous_events'] == {
            k: counted.count(k) for k in counted}
    # the card says which exogenous events the forest was shown: the simulated trials' ones
    kinds = [i['kind'] for part in held.values() for t in part for i in t['impacts']]
    assert kinds and card['training']['exogenous_events'] == {k: kinds.count(k) for k in kinds}
    assert sorted(p.name for p in (sim / 'family').glob('trial_*')) == [
        f'trial_000{i}' for i in range(6)]
    assert sorted(p.name for p in (sim / 'mixed').glob('trial_*')) == [
        'trial_0006', 'trial_0007']
    # each part is what `simulate` writes for the same settings (docs/your-robot.md)
    same = tmp_path / 'same'
    assert simulate_cli.main([str(same), '--trials', '2', '--seed', '1', '--start-index', '6',
                              '--conditions', 'wide', '--events', 'everywhere', '--hits',
                              'mixed', '--ft-rate', '125', '--quiet']) == 0
    assert (json.loads((same / 'manifest.json').read_text())
            == json.loads((sim / 'mixed' / 'manifest.json').read_text()))
    capsys.readouterr()
    # The kept trials are reused; a folder holding other trials is refused.
    # (one recording fewer moves the median F/T rate, here 125.0 -> 124.6 Hz: still the same;
    # trials simulated before --tared existed have no settings.tared: 'family')
    for part in ('family', 'mixed'):
        manifest = json.loads((sim / part / 'manifest.json').read_text())
        manifest['settings']['ft_rate'] = 124.6
        assert manifest['settings'].pop('tared') == 'family'
        (sim / part / 'manifest.json').write_text(json.dumps(manifest))
    assert train_cli.main([*args, '--with-sim', '8', '--sim-dir', str(sim),
                           '--no-events']) == 0
    out = capsys.readouterr().out
    assert 'reusing 6 simulated trials' in out and 'reusing 2 simulated trials' in out
    assert load_bundle(path=model).training['sources']['simulated']['ft_rate'] == 124.6
    assert train_cli.main([*args, '--with-sim', '9', '--sim-dir', str(sim)]) == 1
    assert 'holds other simulated trials' in capsys.readouterr().err
    # trials with other events (here: each family's own in the mixed part) are refused too
    manifest = json.loads((sim / 'mixed' / 'manifest.json').read_text())
    manifest['settings'].update(events='family', hits=None)
    (sim / 'mixed' / 'manifest.json').write_text(json.dumps(manifest))
    assert train_cli.main([*args, '--with-sim', '8', '--sim-dir', str(sim)]) == 1
    assert 'holds other simulated trials' in capsys.readouterr().err
    # ... and so is a folder of trials made before --with-sim added the mixed part (all with
    # each family's own events, one manifest in the folder itself)
    old = tmp_path / 'old_sim'
    old.mkdir()
    (old / 'manifest.json').write_text(json.dumps({'settings': {
        'seed': 0, 'trials': 8, 'start_index': 0, 'conditions': ['wide'],
        'storage': 'sqlite3', 'audio_rate': 16000, 'ft_rate': 125.0, 'chunk_size': None,
        'label_window_s': 0.1}, 'trials': []}))
    assert train_cli.main([*args, '--with-sim', '8', '--sim-dir', str(old)]) == 1
    assert f'{old} holds other simulated trials' in capsys.readouterr().err
    # Alone: the recordings only, and a temporary folder leaves nothing behind.
    assert train_cli.main([*args, '--no-events']) == 0
    assert set(load_bundle(path=model).training['sources']) == {'recordings'}
    # Too few recordings for the split by recording: a clear error, not a traceback.
    one = sorted(recordings['onsets'])[0]
    capsys.readouterr()
    assert train_cli.main([str(recordings['bags'] / one), *args[1:]]) == 1
    assert 'needs at least 3 recordings, got 1' in capsys.readouterr().err


def test_labels_from_a_topic_and_a_recording_cut_per_contact(recordings, tmp_path):
    labels = tmp_path / 'truth.csv'
    subprocess.run([sys.executable, ROOT / 'tools' / 'labels_from_topic.py',
                    recordings['bags'], '--topic', '/contact_truth', '--field', 'data',
                    '--out', labels], check=True, capture_output=True)
    rows = [line.split(',') for line in labels.read_text().splitlines()[1:]]
    assert {r[0]: float(r[1]) for r in rows} == pytest.approx(recordings['onsets'], abs=1e-6)
    bag = sorted(recordings['onsets'])[0]
    onset = recordings['onsets'][bag]
    two = write_labels(tmp_path / 'two.csv', {bag: [onset - 3.0, onset]})
    out = tmp_path / 'pieces'
    subprocess.run([sys.executable, ROOT / 'tools' / 'split_recording.py',
                    recordings['bags'] / bag, '--labels', two, '--out', out],
                   check=True, capture_output=True)
    stem = bag[:-len('.bag')]
    pieces = [out / f'{stem}_c1.bag', out / f'{stem}_c2.bag']

    def counts(path):
        with Reader(path) as reader:
            return [t for _, t, _ in reader.messages()]
    whole = counts(recordings['bags'] / bag)
    first, second = counts(pieces[0]), counts(pieces[1])
    assert first + second == whole
    assert max(first) < (onset - 1.5) * 1e9 <= min(second)
    assert (out / 'labels.csv').read_text().splitlines()[1:] == [
        f'{stem}_c1.bag,{onset - 3.0:.6f},{onset - 3.0:.6f}',
        f'{stem}_c2.bag,{onset:.6f},{onset:.6f}']


@pytest.mark.parametrize('layout', [('train', 'train_extra'), ('day1/rigid', 'day2/rigid')])
def test_two_folders_whose_trials_share_names_are_told_apart(tmp_path, capsys, layout):
    # tools/build_model.sh trains on two folders that both start at trial_0000; two days of
    # recordings may even share the folder's name
    folders = [tmp_path / name for name in layout]
    for seed, folder in enumerate(folders):
        assert simulate_cli.main([str(folder), '--trials', '5', '--seed', str(20 + seed),
                                  '--conditions', 'paper', '--quiet']) == 0
    model = tmp_path / 'both.npz'
    assert train_cli.main([*map(str, folders), '--trees', '2', '--jobs', '1',
                           '--out', str(model)]) == 0
    printed = capsys.readouterr().out
    test_trials = load_bundle(path=model).training['test_trials']
    bags = [f'{name}/{bag.name}' for name in layout for bag in (tmp_path / name).iterdir()
            if bag.name.startswith('trial_')]
    # each name in the card is one bag: with both folders' trial_0000 ... the bare name is
    # shared, so the folder (and, where the folders share a name, its parent) is part of it
    assert test_trials and set(test_trials) <= set(bags)
    scored = json.loads(printed.split('events on test trials:', 1)[1].splitlines()[0])
    assert scored['trials'] == len(test_trials)


def _models_per_value(*, tmp_path, seed: str, conditions: str, trees: str, option: str,
                      values: tuple) -> tuple:
    """Simulate 6 trials, train one model per value of a train option; (bags, value -> bundle)."""
    bags = tmp_path / 'trials'
    assert simulate_cli.main([str(bags), '--trials', '6', '--seed', seed, '--conditions',
                              conditions, '--quiet']) == 0
    models = {}
    for value in values:
        model = tmp_path / f'{option.strip("-")}{value}.npz'
        assert train_cli.main([str(bags), '--trees', trees, '--jobs', '1', '--no-events',
                               option, value, '--out', str(model)]) == 0
        models[value] = load_bundle(path=model)
    return bags, models


def test_train_leaves_the_frames_after_the_label_window_out_with_label_ignore(tmp_path):
    bags, cards = _models_per_value(tmp_path=tmp_path, seed='30', conditions='paper',
                                    trees='2', option='--label-ignore', values=('0', '0.2'))
    # train's default event weight is the shipped model's (3), recorded in the card
    assert cards['0'].label_window == {'start_s': 0.0, 'end_s': 0.3, 'event_weight': 3.0}
    assert cards['0.2'].label_window == {'start_s': 0.0, 'end_s': 0.3, 'ignore_s': 0.2,
                                         'event_weight': 3.0}
    # 0.2 s of 10 ms audio frames, 0.3-0.5 s after each of the 6 onsets, are not trained on
    dropped = cards['0'].training['frames'] - cards['0.2'].training['frames']
    assert 6 * 19 <= dropped <= 6 * 21
    assert cards['0'].training['contact_frames'] == cards['0.2'].training['contact_frames']
    assert train_cli.main([str(bags), '--label-ignore', '-1', '--out',
                           str(tmp_path / 'bad.npz')]) == 1


def test_train_leaves_the_first_frames_of_each_contact_out_with_label_ignore_lead(tmp_path):
    bags = tmp_path / 'trials'
    assert simulate_cli.main([str(bags), '--trials', '6', '--seed', '31', '--conditions',
                              'paper', '--quiet']) == 0
    cards = {}
    for name, extra in (('taught', []), ('left_out', ['--label-ignore-lead'])):
        model = tmp_path / f'{name}.npz'
        assert train_cli.main([str(bags), '--no-audio', '--trees', '2', '--jobs', '1',
                               '--no-events', '--out', str(model), *extra]) == 0
        cards[name] = load_bundle(path=model)
    # the F/T-only recipe labels contact from 30 ms after the onset
    assert cards['taught'].label_window == {'start_s': 0.03, 'end_s': 0.3}
    assert cards['left_out'].label_window == {'start_s': 0.03, 'end_s': 0.3,
                                              'ignore_lead': True}
    # 30 ms of 10 ms F/T frames after each of the 6 onsets are not trained on; the contact
    # frames are the same
    dropped = cards['taught'].training['frames'] - cards['left_out'].training['frames']
    assert 6 * 2 <= dropped <= 6 * 4
    assert cards['taught'].training['contact_frames'] == cards['left_out'].training[
        'contact_frames']
    # the multimodal recipe labels from the onset: nothing to leave out, a clear refusal
    assert train_cli.main([str(bags), '--label-ignore-lead', '--out',
                           str(tmp_path / 'bad.npz')]) == 1
    assert not (tmp_path / 'bad.npz').exists()


def test_train_weighs_the_frames_of_simulated_events_with_event_weight(tmp_path):
    bags, models = _models_per_value(tmp_path=tmp_path, seed='31', conditions='exogenous',
                                     trees='3', option='--event-weight', values=('1', '5'))
    assert models['1'].label_window == {'start_s': 0.0, 'end_s': 0.3}
    assert models['5'].label_window == {'start_s': 0.0, 'end_s': 0.3, 'event_weight': 5.0}
    assert models['1'].training['event_weighted_frames'] == 0
    # every exogenous trial has 2-4 events, each weighing about 0.8 s of 10 ms frames
    assert 6 * 2 * 40 <= models['5'].training['event_weighted_frames'] <= 6 * 4 * 82
    # the same frames and seed, other weights: other trees
    assert models['1'].forest_sha256 != models['5'].forest_sha256
    assert train_cli.main([str(bags), '--event-weight', '0.5', '--out',
                           str(tmp_path / 'bad.npz')]) == 1


def _hiro_trial(folder: Path, *, states: str, ramp_n_per_s: float = 10.0) -> None:
    """One trial as HongminWu/HIRO_SA_DATA lays it out: 6 s at 200 Hz, a rise from 3 s."""
    folder.mkdir(parents=True)
    t = np.arange(1200) * 0.005
    rng = np.random.default_rng(3)
    wrench = rng.normal(0.0, 0.02, (len(t), 6))
    wrench[:, 2] -= ramp_n_per_s * np.clip(t - 3.0, 0.0, None)
    np.savetxt(folder / 'R_Torques.dat', np.column_stack([t, wrench]), delimiter='\t')
    (folder / 'R_State.dat').write_text(states)


@pytest.mark.parametrize('quiet_audio', [False, True])
def test_the_hiro_recordings_become_labelled_bags_evaluate_decides(tmp_path, quiet_audio):
    # tools/hiro_to_bags.py: docs/your-robot.md's real 200 Hz recordings of a part lowered
    # onto a fixture, here as a synthetic trial in the data set's layout
    src = tmp_path / 'HIRO_SA_DATA'
    _hiro_trial(src / 'REAL_HIRO_ONE_SA_SUCCESS' / 'S-01', states='0.0\n3.5\n5.0\n5.5\n')
    _hiro_trial(src / 'REAL_HIRO_ONE_SA_ERROR_CHARAC' / 'E-01', states='0.0\n3.3\n')
    _hiro_trial(src / 'REAL_HIRO_ONE_SA_ERROR_CHARAC' / 'E-02', states='')
    _hiro_trial(src / 'REAL_HIRO_ONE_SA_ERROR_CHARAC' / 'E-03', states='0.0\n3.3\n')
    (src / 'REAL_HIRO_ONE_SA_ERROR_CHARAC' / 'E-03' / 'R_Torques.dat').write_text('0 1 x\n')
    out = tmp_path / 'bags'
    done = subprocess.run([sys.executable, ROOT / 'tools' / 'hiro_to_bags.py', src, out,
                           *(['--quiet-audio'] if quiet_audio else [])],
                          capture_output=True, text=True, check=True)
    assert 'no contact phase, not converted: E-02' in done.stderr
    assert 'E-03: not a table of numbers' in done.stderr
    assert '2 bags and labels.csv' in done.stdout
    assert '1 trial folders not converted' in done.stdout
    rows = [line.split(',') for line in (out / 'labels.csv').read_text().splitlines()[1:]]
    assert [r[0] for r in rows] == ['success/S-01', 'error/E-01']
    # the rise passes the 0.3 N band 30 ms after it began, at 3.030-3.035 s
    for _, start, end in rows:
        assert 1_700_000_003.025 <= float(start) == float(end) <= 1_700_000_003.040
    found = discover_streams(out / 'success' / 'S-01', allow_no_audio=True)
    assert found.wrench_rate == pytest.approx(200.0)
    assert found.has_audio == quiet_audio
    series = read_wrench(out / 'success' / 'S-01')
    assert len(series.t) == 1200
    assert series.force[-1, 2] == pytest.approx(-30.0, abs=0.1)
    # the 2 N guard is past 2 N 0.2 s after the label: both trials caught
    report = tmp_path / 'report'
    assert evaluate_cli.main([str(out / 'success'), str(out / 'error'), '--labels',
                              str(out / 'labels.csv'), '--detector', 'guard', '--report',
                              str(report)]) == 0
    summary = json.loads((report / 'metrics.json').read_text())['guard']['summary']['all']
    assert (summary['trials'], summary['detected'], summary['premature']) == (2, 2, 0)
    assert 150 <= summary['latency_ms_median'] <= 200
    # a second run into the same folder refuses rather than mixing two conversions
    again = subprocess.run([sys.executable, ROOT / 'tools' / 'hiro_to_bags.py', src, out],
                           capture_output=True, text=True)
    assert again.returncode == 1 and 'exists; give an empty OUT' in again.stderr


def test_hiro_to_bags_scales_the_torque_and_refuses_a_scale_that_is_no_size(tmp_path):
    # --torque-scale: the recorded forces with the torques of a contact S times farther off
    # the sensor's axis (docs/decisions/2026-12-07-ft-only-label-start.md)
    src = tmp_path / 'HIRO_SA_DATA'
    _hiro_trial(src / 'REAL_HIRO_ONE_SA_SUCCESS' / 'S-01', states='0.0\n3.5\n')
    table = np.loadtxt(src / 'REAL_HIRO_ONE_SA_SUCCESS' / 'S-01' / 'R_Torques.dat')
    series = {}
    for scale in ('1', '10'):
        out = tmp_path / f'bags{scale}'
        subprocess.run([sys.executable, ROOT / 'tools' / 'hiro_to_bags.py', src, out,
                        '--torque-scale', scale], capture_output=True, text=True, check=True)
        series[scale] = read_wrench(out / 'success' / 'S-01')
        # the onset is found on the force, which the scale leaves alone
        assert (out / 'labels.csv').read_text() == (
            tmp_path / 'bags1' / 'labels.csv').read_text().replace('bags1', f'bags{scale}')
    np.testing.assert_allclose(series['1'].torque, table[:, 4:7], atol=1e-9)
    np.testing.assert_allclose(series['10'].torque, 10 * table[:, 4:7], atol=1e-8)
    np.testing.assert_array_equal(series['10'].force, series['1'].force)
    for bad in ('0', '-2', 'nan'):
        refused = subprocess.run([sys.executable, ROOT / 'tools' / 'hiro_to_bags.py', src,
                                  tmp_path / f'no{bad}', '--torque-scale', bad],
                                 capture_output=True, text=True)
        assert refused.returncode == 2
        assert '--torque-scale must be a finite number > 0' in refused.stderr
        assert not (tmp_path / f'no{bad}').exists()
