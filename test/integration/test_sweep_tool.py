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

"""``contact-detector sweep --model`` and ``--seeds``: rules on a trained model, seed sums."""

from contact_detector.cli import sweep as sweep_cli
from contact_detector.cli import train as train_cli
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.rule import DecisionRule
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim import simulate_trials
from contact_detector.sim.bag_writer import manifest_entry, write_manifest, write_trial_bag
from contact_detector.training.recipe import DEFAULT_FEATURES, DEFAULT_LABELS
from contact_detector.training.sweep import (compute_frames, decode_bags, FeatureSetting,
                                             fit_forest, model_rules, score_over_seeds,
                                             score_rules)
import pytest

pytestmark = pytest.mark.slow   # simulates bags and trains forests


@pytest.fixture(scope='module')
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp('sweep')
    bags = root / 'bags'
    trials = list(simulate_trials(n=8, seed=5, conditions=['all']))
    for trial in trials:
        write_trial_bag(trial=trial, path=bags / trial.name)
    write_manifest(trials=[manifest_entry(t) for t in trials], out_dir=bags)
    model = root / 'm.npz'
    assert train_cli.main([str(bags), '--no-events', '--jobs', '1', '--trees', '3',
                           '--out', str(model)]) == 0
    return {'bags': bags, 'model': model, 'trials': trials}


def _table(text: str) -> list:
    """Rows of the markdown tables in ``text`` (header and rule lines dropped)."""
    rows = [[cell.strip() for cell in line.strip('|').split('|')]
            for line in text.splitlines() if line.startswith('| ')]
    return [r for r in rows if r[0] != 'setting' and not r[0].startswith('---')]


def test_model_rules_are_scored_on_its_test_trials_and_the_folders(data, tmp_path, capsys):
    out = tmp_path / 'rules.md'
    assert sweep_cli.main([str(data['bags']), '--model', str(data['model']), '--own-test',
                           str(data['bags']), '--jobs', '1', '--out', str(out)]) == 0
    bundle = load_bundle(path=data['model'])
    rules = model_rules(bundle.decision_rule)
    rows = _table(out.read_text())
    own = [r for r in rows if r[0].startswith('own ')]
    folder = [r for r in rows if r[0].startswith('bags: ')]
    assert len(own) == len(folder) == len(rules)
    assert [r[1] for r in own] == [rule.short() for rule in rules]
    assert own[0][1] == bundle.decision_rule.short()
    n_test = len(bundle.training['test_trials'])
    assert own[0][0] == f'own {n_test} test trials'
    assert {r[2].split('/')[1] for r in own} == {str(n_test)}
    assert {r[2].split('/')[1] for r in folder} == {'8'}
    # With one confirmation frame, a lower threshold fires at the same frame or sooner: it
    # cannot detect fewer contacts plus premature releases than a higher one.
    by_rule = {r[1]: r for r in folder}
    fired = [int(by_rule[f'p>={t:g} x1'][2].split('/')[0]) + int(by_rule[f'p>={t:g} x1'][4])
             for t in (0.3, 0.5, 0.7, 0.9)]
    assert fired == sorted(fired, reverse=True)
    capsys.readouterr()


def test_sweep_measures_the_ft_rate_of_each_bag_and_a_flag_overrides_it(tmp_path, capsys):
    bags = tmp_path / 'bags200'
    trials = list(simulate_trials(n=4, seed=8, conditions=['all'], ft_rate=200.0))
    for trial in trials:
        write_trial_bag(trial=trial, path=bags / trial.name)
    write_manifest(trials=[manifest_entry(t) for t in trials], out_dir=bags)
    model = str(default_model_path())

    def sweep(*flags):
        out = tmp_path / 'rules.md'
        assert sweep_cli.main([str(bags), '--model', model, '--jobs', '1', '--out', str(out),
                               *flags]) == 0
        return out.read_text(), capsys.readouterr().out

    measured, said = sweep()
    assert f'contact-detector sweep: {bags}: 4 bags: wrench /wrist_wrench at 200 Hz (stamps)' \
        in said
    assert '16000 Hz, 1 ch (manifest)' in said
    given, said = sweep('--wrench-rate', '200')
    assert '200 Hz (flag)' in said
    assert _table(measured) == _table(given)
    wrong, said = sweep('--wrench-rate', '100')
    assert 'wrench /wrist_wrench at 100 Hz (flag)' in said
    assert _table(wrong) != _table(measured)      # 200 Hz read as 100 Hz: other features


def test_sweep_refuses_bags_whose_ft_rates_disagree(tmp_path, capsys):
    for rate in (100.0, 200.0):
        trial = next(simulate_trials(n=1, seed=8, conditions=['paper'], ft_rate=rate))
        write_trial_bag(trial=trial, path=tmp_path / f'at{rate:g}' / trial.name)
    assert sweep_cli.main([str(tmp_path / 'at100'), str(tmp_path / 'at200'), '--model',
                           str(default_model_path()), '--jobs', '1']) == 1
    err = capsys.readouterr().err
    assert 'one F/T rate' in err and '100 Hz: 1 bags' in err and '200 Hz: 1 bags' in err


def test_knocks_scores_the_trials_knocked_on_the_hand_in_the_air(data, tmp_path, capsys):
    out = tmp_path / 'knocks.md'
    assert sweep_cli.main([str(data['bags']), '--model', str(data['model']), '--knocks',
                           '--jobs', '1', '--out', str(out)]) == 0
    knocked = sum(any(i.kind == 'hand' and i.in_air for i in t.impacts) for t in data['trials'])
    assert 0 < knocked < len(data['trials'])
    rows = _table(out.read_text())
    bundle = load_bundle(path=data['model'])
    group = [r for r in rows if 'knock on the hand' in r[0]]
    assert len(group) == len(model_rules(bundle.decision_rule))
    assert group[0][0] == f'bags: {knocked} trials with a knock on the hand in the air'
    assert {r[2].split('/')[1] for r in group} == {str(knocked)}
    capsys.readouterr()


def test_the_load_path_is_scored_beside_the_model_rule(data, tmp_path, capsys):
    # the model's rule with the load path comes second; a lower load threshold held as long
    # fires at the same frame or sooner, so it releases on at least as many trials
    def rows(threshold):
        out = tmp_path / f'load{threshold}.md'
        assert sweep_cli.main([str(data['bags']), '--model', str(data['model']), '--jobs', '1',
                               '--load-threshold', str(threshold), '--load-frames', '5',
                               '--load-support', '0', '--out', str(out)]) == 0
        return _table(out.read_text())
    bundle = load_bundle(path=data['model'])
    low, high = rows(0.5), rows(3.0)
    assert low[1][1] == bundle.decision_rule.short() + ' or load>=0.5N x5 & mean25>=0'
    assert low[0][1] == high[0][1] == bundle.decision_rule.short()
    assert low[0][2:] == high[0][2:]                       # the model's own rule: unchanged

    def fired(row):
        return int(row[2].split('/')[0]) + int(row[4])
    assert fired(low[1]) >= fired(high[1]) >= fired(low[0])
    with pytest.raises(SystemExit):
        sweep_cli.main([str(data['bags']), '--model', str(data['model']),
                        '--load-threshold', '2', '--load-support', '2'])
    assert 'load_support' in capsys.readouterr().err


def test_the_fast_load_path_is_scored_after_the_load_path_alone(data, tmp_path, capsys):
    # one run scores the load path alone and with the fast path on the same probabilities:
    # the fast path only adds ways to fire
    out = tmp_path / 'fast.md'
    assert sweep_cli.main([str(data['bags']), '--model', str(data['model']), '--jobs', '1',
                           '--load-threshold', '3', '--load-frames', '20', '--load-support', '0',
                           '--load2-threshold', '0.5', '--load2-frames', '2',
                           '--load2-support', '0', '--out', str(out)]) == 0
    table = _table(out.read_text())
    alone = load_bundle(path=data['model']).decision_rule.short() + ' or load>=3N x20 & mean25>=0'
    assert [table[1][1], table[2][1]] == [alone, alone + ' or load>=0.5N x2 & mean5>=0']

    def fired(row):
        return int(row[2].split('/')[0]) + int(row[4])
    assert fired(table[2]) >= fired(table[1])
    with pytest.raises(SystemExit):
        sweep_cli.main([str(data['bags']), '--model', str(data['model']),
                        '--load2-threshold', '5'])
    assert '--load2-threshold needs --load-threshold' in capsys.readouterr().err
    # a steady load as well: the same second path, which can only fire less often
    steady = tmp_path / 'steady.md'
    assert sweep_cli.main([str(data['bags']), '--model', str(data['model']), '--jobs', '1',
                           '--load-threshold', '3', '--load-frames', '20', '--load-support', '0',
                           '--load2-threshold', '0.5', '--load2-frames', '2',
                           '--load2-support', '0', '--load2-steady', '0.5',
                           '--out', str(steady)]) == 0
    held = _table(steady.read_text())
    assert held[2][1] == alone + ' or load>=0.5N x2 & mean5>=0 & steady10<=0.5'
    assert held[1] == table[1]
    assert fired(held[2]) <= fired(table[2])
    with pytest.raises(SystemExit):
        sweep_cli.main([str(data['bags']), '--model', str(data['model']),
                        '--load-threshold', '3', '--load2-steady', '0.5'])
    assert '--load2-steady needs --load2-threshold' in capsys.readouterr().err


def test_own_test_needs_a_model(data, capsys):
    with pytest.raises(SystemExit):
        sweep_cli.main([str(data['bags']), '--own-test', str(data['bags'])])
    assert '--own-test and --knocks need --model' in capsys.readouterr().err


def test_scores_over_seeds_are_the_sums_of_one_forest_per_seed(data):
    events = decode_bags(bags=sorted(p for p in data['bags'].iterdir() if p.is_dir()),
                         spec=StreamSpec(), tag='t')
    frames = list(compute_frames(events_by_trial=events, config=DEFAULT_FEATURES,
                                 audio_rate=16000.0, wrench_rate=100.0, jobs=1).values())
    train, heldout = frames[:5], frames[5:]
    setting = FeatureSetting('shipped', DEFAULT_FEATURES, DEFAULT_LABELS)
    rules = [DecisionRule(threshold=0.5), DecisionRule(threshold=0.9, confirm_frames=2)]
    totals = score_over_seeds(train=train, heldout=heldout, setting=setting, rules=rules,
                              seeds=[0, 1], n_estimators=3, jobs=1)
    single = [score_rules(forest=fit_forest(frames=train, setting=setting, n_estimators=3,
                                            seed=seed, jobs=1),
                          frames=heldout, setting=setting, rules=rules) for seed in (0, 1)]
    for k, total in enumerate(totals):
        rows = [single[0][k].summary, single[1][k].summary]
        assert total['rule'] == rules[k].short()
        assert total['trials'] == 2 * len(heldout)
        assert total['detected'] == sum(s['detected'] for s in rows)
        assert total['premature'] == sum(s['premature'] for s in rows)
        assert total['miss'] == sum(s['missed'] + s['late'] for s in rows)
        assert total['medians'] == [s['latency_ms_median'] for s in rows
                                    if s['latency_ms_median'] is not None]


def test_seed_list_option(capsys):
    assert sweep_cli.seed_list('0,1, 3') == [0, 1, 3]
    with pytest.raises(SystemExit):
        sweep_cli.main(['a', 'b', '--seeds', 'x'])
    assert 'not a list of seeds' in capsys.readouterr().err
