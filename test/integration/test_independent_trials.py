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

"""The independent generators in benchmarks/: their labelled bags read as recordings do."""

import ast
import csv
import json
from pathlib import Path
import subprocess
import sys

from contact_detector.cli import evaluate as evaluate_cli
from contact_detector.cli import simulate as simulate_cli
from contact_detector.cli import train as train_cli
from contact_detector.io.bags import read_wrench
from contact_detector.io.discovery import discover_streams
from contact_detector.model.storage import load_bundle
from contact_detector.sim.bag_writer import simulator_fingerprint
import pytest

pytestmark = pytest.mark.slow   # runs the generator's 8 kHz mechanics
BENCHMARKS = Path(__file__).resolve().parents[2] / 'benchmarks'
#: generator -> two families of it, one of them without a microphone where it has one
GENERATORS = {'independent_trials.py': ('rigid', 'fixture'),
              'independent_robots.py': ('ur5e_guarded', 'heavy_slow')}


@pytest.mark.parametrize('script', sorted(GENERATORS))
def test_the_generator_imports_nothing_of_the_package_it_checks(script):
    tree = ast.parse((BENCHMARKS / script).read_text())
    imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module or '' for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert not any(name.startswith('contact_detector') for name in imported)


@pytest.mark.parametrize('script', sorted(GENERATORS))
def test_trials_are_labelled_bags_that_evaluate_reads(script, tmp_path, capsys):
    families = GENERATORS[script]
    out = tmp_path / 'indep'
    subprocess.run([sys.executable, BENCHMARKS / script, out, '--trials-per-family', '1',
                    '--seed', '7', '--families', ','.join(families), '--jobs', '1'],
                   check=True, capture_output=True)
    with open(out / 'labels.csv') as handle:
        rows = list(csv.DictReader(handle))
    assert sorted(Path(r['bag']).parts[0] for r in rows) == sorted(families)
    trials = json.loads((out / 'trials.json').read_text())['trials']
    assert len(trials) == len(rows)
    for row in rows:
        bag = out / row['bag']
        streams = discover_streams(bag, allow_no_audio=True)
        t = read_wrench(bag, topic=streams.wrench_topic).t
        # the onset is inside the recording, after the object was held still
        assert t[0] + 0.4 < float(row['onset_start']) < t[-1]
    # evaluate reads them with the labels (the F/T-only model where there is no microphone)
    assert evaluate_cli.main([*(str(out / f) for f in families), '--labels',
                              str(out / 'labels.csv'), '--detector', 'forest']) == 0
    printed = capsys.readouterr().out
    for row in rows:
        assert f'| {Path(row["bag"]).name} | 1 |' in printed or f'| {row["bag"]} | 1 |' in printed


def test_a_generator_and_simulated_trials_train_together_from_one_labels_csv(tmp_path):
    # benchmarks/training_set_labels.py: the decision notes' training on a second world
    sim, gen = tmp_path / 'sim', tmp_path / 'gen'
    assert simulate_cli.main([str(sim), '--trials', '3', '--seed', '5', '--conditions', 'paper',
                              '--quiet']) == 0
    subprocess.run([sys.executable, BENCHMARKS / 'independent_trials.py', gen,
                    '--trials-per-family', '2', '--seed', '7', '--families', 'disturbed',
                    '--jobs', '1'], check=True, capture_output=True)
    labels = tmp_path / 'csv' / 'all.csv'
    done = subprocess.run([sys.executable, BENCHMARKS / 'training_set_labels.py', labels, sim,
                           gen, '--events'], check=True, capture_output=True, text=True)
    folders = done.stdout.split()
    assert folders == [str(sim), str(gen / 'disturbed')]
    with open(labels) as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 5 and all(not Path(r['bag']).is_absolute() for r in rows)
    # the generator's events are in the family folder's manifest, at their bag times
    trials = json.loads((gen / 'trials.json').read_text())['trials']
    manifest = json.loads((gen / 'disturbed' / 'manifest.json').read_text())['trials']
    assert [[i['t'] for i in m['impacts']] for m in manifest] == [
        [e['t_abs'] for e in t['events']] for t in trials]
    assert any(m['impacts'] for m in manifest)
    model = tmp_path / 'm.npz'
    assert train_cli.main([*folders, '--labels', str(labels), '--trees', '2', '--jobs', '1',
                           '--no-events', '--event-weight', '3', '--out', str(model)]) == 0
    training = load_bundle(path=model).training
    assert training['sources']['recordings']['count'] == 5
    # which simulator code made the simulated folder; the generator's folder has no fingerprint
    assert training['sources']['recordings']['simulator'] == {'sim': simulator_fingerprint()}
    assert sum(training['exogenous_events'].values()) >= sum(len(m['impacts']) for m in manifest)


def _evaluated_b_set(tmp_path: Path, *, seed: int, detectors: tuple) -> tuple:
    """Return generator B's two trials of hsr_side and tiago_mobile, and evaluate's report."""
    out = tmp_path / 'B'
    subprocess.run([sys.executable, BENCHMARKS / 'independent_robots.py', out,
                    '--trials-per-family', '2', '--seed', str(seed), '--families',
                    'hsr_side,tiago_mobile', '--jobs', '1'], check=True, capture_output=True)
    report = tmp_path / 'report'
    assert evaluate_cli.main([str(out / 'hsr_side'), str(out / 'tiago_mobile'), '--labels',
                              str(out / 'labels.csv'), '--report', str(report),
                              *(a for d in detectors for a in ('--detector', d))]) == 0
    return out, report


def test_generator_rules_scores_the_model_as_evaluate_does_and_blames_the_events(
        tmp_path, monkeypatch):
    # benchmarks/generator_rules.py, the command behind docs/generalisation.md's early releases
    out, report = _evaluated_b_set(tmp_path, seed=7, detectors=('forest',))
    # one hsr_side trial has a 47 ms gap in its F/T 0.3 s before the onset: the F/T window
    # restarts, and the frames the detector decides invalid there empty the rule's history
    expected = json.loads((report / 'metrics.json').read_text())['forest']['summary']['all']
    counts = tmp_path / 'rules.json'
    done = subprocess.run([sys.executable, BENCHMARKS / 'generator_rules.py', out, '--early',
                           '--jobs', '1', '--json', counts], cwd=tmp_path,
                          capture_output=True, text=True, check=True)
    scored = json.loads(counts.read_text())['summary']['all']['S']['by_family']['all']
    assert scored['trials'] == expected['trials'] == 4
    assert [scored[k] for k in ('detected', 'late', 'missed', 'premature')] == [
        expected[k] for k in ('detected', 'late', 'missed', 'premature')]
    assert scored['latency_ms_median'] == pytest.approx(expected['latency_ms_median'], abs=0.01)
    assert done.stdout.count(' before the onset, after ') == scored['premature']
    # the generator's exogenous events are the truth's impacts, in the project's kinds
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    import generator_rules
    events = generator_rules.generator_events(out)
    trials = json.loads((out / 'trials.json').read_text())['trials']
    assert set(events) == {t['bag'] for t in trials}
    assert [len(e) for e in events.values()] == [len(t['events']) for t in trials]
    kinds = {kind for found in events.values() for _, kind, _ in found}
    assert kinds & set(generator_rules.EVENT_KINDS)
    assert set(generator_rules.EVENT_KINDS.values()) <= {'hand', 'table', 'touch', 'brush',
                                                         'setdown'}


def _ablation_inputs(tmp_path: Path, *, name: str, per_family: int, families: str,
                     train_seed: int, events: tuple = ()) -> tuple:
    """Return a generator-B set (its seed from ``name``) and 12 simulated training trials."""
    out = tmp_path / name
    subprocess.run([sys.executable, BENCHMARKS / 'independent_robots.py', out,
                    '--trials-per-family', str(per_family), '--seed', name[1:], '--families',
                    families, '--jobs', '1'], check=True, capture_output=True)
    train = tmp_path / 'train'
    assert simulate_cli.main([str(train), '--trials', '12', '--seed', str(train_seed),
                              '--conditions', 'wide', *events, '--quiet']) == 0
    return out, train


def test_generator_ablation_leaves_a_group_out_and_pools_a_generators_families(tmp_path):
    # benchmarks/generator_ablation.py, the screen of
    # docs/decisions/2026-12-07-feature-groups-on-the-generators.md
    out, train = _ablation_inputs(tmp_path, name='B7', per_family=2,
                                  families='hsr_side,tiago_mobile', train_seed=5)
    counts = tmp_path / 'ablation.json'
    done = subprocess.run([sys.executable, BENCHMARKS / 'generator_ablation.py', out,
                           '--train', train, '--drop', 'torque', '--union', 'torque+audio_abs',
                           '--seeds', '0,1', '--jobs', '1', '--json', counts],
                          cwd=tmp_path, capture_output=True, text=True, check=True)
    candidates = json.loads(counts.read_text())['candidates']
    assert list(candidates) == ['F', '-torque', '-torque-audio_abs']
    shipped = load_bundle(path=Path(__file__).parents[2] / 'models' / 'contact_forest.npz')
    assert candidates['F']['columns'] == list(shipped.feature_names)
    assert candidates['-torque']['columns'] == [
        n for n in shipped.feature_names if not n.startswith('torque_')]
    assert candidates['-torque-audio_abs']['columns'] == candidates['-torque']['columns'][1:]
    for figures in candidates.values():
        by_family = figures['by_family']
        # both seeds' forests decide each of the four recordings; a family spans the sets
        assert by_family['all']['trials'] == 8
        assert set(by_family) == {'all', 'B/hsr_side', 'B/tiago_mobile'}
        assert figures['worst'] in by_family
        assert by_family['all']['score'] == pytest.approx(
            (by_family['all']['detected'] - by_family['all']['premature']) / 8)
    assert done.stdout.count(' features): all ') == 3
    # a group the recipe does not have is refused before any work
    refused = subprocess.run([sys.executable, BENCHMARKS / 'generator_ablation.py', out,
                              '--train', train, '--recipe', 'ft-only', '--drop', 'audio_abs'],
                             cwd=tmp_path, capture_output=True, text=True)
    assert refused.returncode == 2
    assert "group 'audio_abs' takes no feature out of" in refused.stderr


def test_generator_ablation_decides_recordings_without_a_microphone_for_the_ft_only_recipe(
        tmp_path):
    # the F/T-only recipe's frames are clocked by the F/T stream, as the shipped F/T-only
    # model's: heavy_slow has no microphone and must be decided, not left without frames
    out, train = _ablation_inputs(tmp_path, name='B8', per_family=3,
                                  families='heavy_slow,ur5e_guarded', train_seed=6,
                                  events=('--events', 'everywhere'))
    counts = tmp_path / 'ablation.json'
    subprocess.run([sys.executable, BENCHMARKS / 'generator_ablation.py', out, '--train', train,
                    '--recipe', 'ft-only', '--drop', 'torque', '--seeds', '0', '--jobs', '1',
                    '--json', counts], cwd=tmp_path, capture_output=True, text=True, check=True)
    candidates = json.loads(counts.read_text())['candidates']
    shipped = load_bundle(path=Path(__file__).parents[2] / 'models' / 'contact_forest_ft.npz')
    assert candidates['F']['columns'] == list(shipped.feature_names)
    for figures in candidates.values():
        slow = figures['by_family']['B/heavy_slow']
        assert slow['trials'] == 3
        assert slow['missed'] < 3, 'no release at all: the recordings had no frames'


def test_generator_gate_with_an_open_gate_is_the_model_and_both_is_forest_both(tmp_path):
    # benchmarks/generator_gate.py, the screen of docs/decisions/2026-12-08-ft-only-gate.md
    out, report = _evaluated_b_set(tmp_path, seed=13, detectors=('forest', 'forest-both'))
    metrics = json.loads((report / 'metrics.json').read_text())
    counts = tmp_path / 'gate.json'
    subprocess.run([sys.executable, BENCHMARKS / 'generator_gate.py', out, '--gate', 'open:0:0.1',
                    '--gate', 'sure:1:0.01', '--both', '--jobs', '1', '--json', counts],
                   cwd=tmp_path, capture_output=True, text=True, check=True)
    scored = {name: figures['by_family']['all']
              for name, figures in json.loads(counts.read_text())['summary']['all'].items()}
    keys = ('trials', 'detected', 'late', 'missed', 'premature')
    for name, detector in (('S', 'forest'), ('open', 'forest'), ('S+ft', 'forest-both'),
                           ('open+ft', 'forest-both')):
        expected = metrics[detector]['summary']['all']
        assert [scored[name][k] for k in keys] == [expected[k] for k in keys], name
        assert scored[name]['latency_ms_median'] == pytest.approx(
            expected['latency_ms_median'], abs=0.01)
    # on these recordings the F/T-only model releases first once: S+ft is not S again
    assert scored['S+ft']['latency_ms_median'] < scored['S']['latency_ms_median']
    # a gate only takes contact frames away: it never catches more, nor releases earlier
    assert scored['sure']['detected'] + scored['sure']['premature'] <= (
        scored['S']['detected'] + scored['S']['premature'])    # released by 500 ms
    # a gate on the fast path alone: open, it is the model again; it never catches more
    subprocess.run([sys.executable, BENCHMARKS / 'generator_gate.py', out, '--gate', 'open:0:0.1',
                    '--gate', 'sure:1:0.01', '--fast-only', '--jobs', '1', '--json', counts],
                   cwd=tmp_path, capture_output=True, text=True, check=True)
    fast = {name: figures['by_family']['all']
            for name, figures in json.loads(counts.read_text())['summary']['all'].items()}
    assert [fast['open'][k] for k in keys] == [scored['S'][k] for k in keys]

    def by_500ms(f):
        return f['detected'] + f['premature']       # released by 500 ms after the onset
    assert by_500ms(scored['sure']) <= by_500ms(fast['sure']) <= by_500ms(fast['S'])
    # a gate that is not NAME:FLOOR:WINDOW_S is refused before any work
    refused = subprocess.run([sys.executable, BENCHMARKS / 'generator_gate.py', out, '--gate',
                              'bad:2:0.1'], cwd=tmp_path, capture_output=True, text=True)
    assert refused.returncode == 2 and 'the floor must lie in [0, 1]' in refused.stderr


def test_gated_run_starts_an_event_per_gated_run_after_the_refractory_period(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    import generator_gate
    import numpy as np
    t = np.arange(10) * 0.1
    contact = np.array([0, 0, 1, 0, 1, 1, 1, 0, 0, 1], bool)
    releases, events = generator_gate.gated_run(t=t, contact=contact, refractory_s=0.5)
    # runs of contact frames start at 0.2, 0.4 (0.2 s after: the same contact) and 0.9
    assert releases == [pytest.approx(0.2)] and events == pytest.approx([0.2, 0.9])
    # the F/T-only model's largest P of (t - window, t]; 0 before its first frame
    recent = generator_gate.recent_max(t=np.array([0.0, 0.15, 0.3]),
                                       t_src=np.array([0.1, 0.2, 0.3]),
                                       p_src=np.array([0.9, 0.2, 0.4]), window_s=0.1)
    assert recent.tolist() == [0.0, 0.9, 0.4]
