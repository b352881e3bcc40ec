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
detect, evaluate and train on recordings without a microphone (no audio topic at all).

Bags are written in tmp_path from simulated trials with ``write_trial_bag(audio=False)``. Without
``--model`` the tools pick the shipped F/T-only model for such a recording and say so.
"""

import json
from pathlib import Path

from contact_detector.cli import main as cli_main
from contact_detector.io.bags import topic_types
from contact_detector.model.shipped import default_ft_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim import simulate_trials
from contact_detector.sim.bag_writer import manifest_entry, write_manifest, write_trial_bag
import pytest

pytestmark = pytest.mark.slow   # simulates bags, runs the commands, trains

N_TRIALS = 8


@pytest.fixture(scope='module')
def no_audio(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp('no_audio')
    trials = list(simulate_trials(n=N_TRIALS, seed=5, conditions=('wide',)))
    for trial in trials:
        write_trial_bag(trial=trial, path=out / trial.name, audio=False)
    write_manifest(trials=[manifest_entry(t) for t in trials], out_dir=out)
    return out


def _rows(path: Path) -> list:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_detect_uses_the_shipped_ft_model_without_audio(no_audio, tmp_path, capsys):
    bag = no_audio / 'trial_0000'
    assert '/audio' not in topic_types(bag)
    out = tmp_path / 'd.jsonl'
    assert cli_main.main(['detect', str(bag), '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    assert 'without an audio topic' in printed and 'contact_forest_ft.npz' in printed
    assert 'F/T-only' in printed and 'no audio topic' in printed       # discovery's summary
    rows = _rows(out)
    frames = [r for r in rows if 'p' in r]
    releases = [r for r in rows if r.get('event') == 'release']
    # ~one frame per 10 ms F/T sample from the first full window on; one release at most
    assert len(frames) > 300 and len(releases) <= 1
    times = [r['t'] for r in frames]
    assert times == sorted(times)


def test_a_multimodal_model_refuses_a_recording_without_audio(no_audio, tmp_path, capsys):
    # --model wins, and a model that needs audio cannot decide such a recording: an error.
    from contact_detector.model.shipped import default_model_path
    out = tmp_path / 'm.jsonl'
    assert cli_main.main(['detect', str(no_audio / 'trial_0001'), '--model',
                          str(default_model_path()), '--out', str(out)]) == 1
    assert 'no audio' in capsys.readouterr().err
    assert not out.exists()
    assert cli_main.main(['evaluate', str(no_audio / 'trial_0001'), '--model',
                          str(default_model_path())]) == 1
    assert 'no audio' in capsys.readouterr().err


def test_audio_disabled_in_params_picks_the_ft_model_for_audio_bags(tmp_path, capsys):
    trial = next(simulate_trials(n=1, seed=6, conditions=('paper',)))
    bag = write_trial_bag(trial=trial, path=tmp_path / 'with_audio')
    params = tmp_path / 'p.yaml'
    params.write_text('/**:\n  ros__parameters:\n    audio:\n      enabled: false\n')
    out = tmp_path / 'a.jsonl'
    assert cli_main.main(['detect', str(bag), '--params', str(params), '--out', str(out)]) == 0
    assert 'contact_forest_ft.npz' in capsys.readouterr().out
    assert len([r for r in _rows(out) if 'p' in r]) > 300


def test_the_second_load_path_from_params_releases_sooner_on_the_same_frames(
        no_audio, tmp_path):
    # release.load2_* in --params change the shipped F/T-only model's second load path: the
    # same P(contact) per frame, and the release sooner at 0.5 N held 1 frame with no backing
    # (the force leaves the carried load as the table takes it) than at its 2 N for 0.4 s
    bag = no_audio / 'trial_0002'
    params = tmp_path / 'fast.yaml'
    # (and without the model's steady check, which waits for 10 steady frames)
    params.write_text('/**:\n  ros__parameters:\n    release:\n      load2_threshold: 0.5\n'
                      '      load2_frames: 1\n      load2_support: 0.0\n'
                      '      load2_steady: 0.0\n')
    shipped, fast = tmp_path / 's.jsonl', tmp_path / 'f.jsonl'
    assert cli_main.main(['detect', str(bag), '--out', str(shipped)]) == 0
    assert cli_main.main(['detect', str(bag), '--params', str(params), '--out', str(fast)]) == 0
    rows_s, rows_f = _rows(shipped), _rows(fast)
    assert [r['p'] for r in rows_s if 'p' in r] == [r['p'] for r in rows_f if 'p' in r]
    rel_s = [r['t'] for r in rows_s if r.get('event') == 'release']
    rel_f = [r['t'] for r in rows_f if r.get('event') == 'release']
    assert len(rel_f) == len(rel_s) == 1 and rel_f[0] < rel_s[0]


def test_evaluate_shows_the_ft_model_beside_the_others(no_audio, tmp_path, capsys):
    report = tmp_path / 'report'
    assert cli_main.main(['evaluate', str(no_audio), '--detector', 'all',
                          '--report', str(report)]) == 0
    captured = capsys.readouterr()
    table = captured.out
    for name in ('| forest |', '| forest-ft |', '| threshold |'):
        assert name in table
    assert 'forest on recordings without an audio topic' in captured.err
    assert 'contact_forest_ft.npz' in captured.err
    metrics = json.loads((report / 'metrics.json').read_text())
    # Without audio, forest is the F/T-only model: the same outcomes as forest-ft.
    assert metrics['forest']['summary'] == metrics['forest-ft']['summary']
    assert metrics['forest']['summary']['all']['premature'] == 0


def test_train_no_audio_writes_an_ft_only_model(no_audio, tmp_path, capsys):
    model = tmp_path / 'ft.npz'
    assert cli_main.main(['train', str(no_audio), '--no-audio', '--no-events', '--jobs', '1',
                          '--trees', '2', '--augment', '--out', str(model)]) == 0
    bundle = load_bundle(path=model)
    shipped = load_bundle(path=default_ft_model_path())
    assert bundle.feature_config.ft_only and 'audio_power' not in bundle.feature_names
    assert bundle.feature_config.extra_features == shipped.feature_config.extra_features
    # --no-audio's defaults are the shipped F/T-only recipe's: labels from 30 ms after the
    # onset, every frame weighing the same, a tare on half the trials, lever arms x1/3-3
    assert bundle.label_window == shipped.label_window == {'start_s': 0.03, 'end_s': 0.3}
    assert bundle.training['augmentation'] == shipped.training['augmentation']
    # and its rule, the load path included
    assert bundle.decision_rule == shipped.decision_rule and bundle.decision_rule.uses_load
    out = tmp_path / 'd.jsonl'
    assert cli_main.main(['detect', str(no_audio / 'trial_0002'), '--model', str(model),
                          '--out', str(out)]) == 0
    assert 'ft.npz' in capsys.readouterr().out


def test_train_no_audio_options_override_the_ft_only_defaults(no_audio, tmp_path):
    model = tmp_path / 'ft.npz'
    assert cli_main.main(['train', str(no_audio), '--no-audio', '--no-events', '--jobs', '1',
                          '--trees', '1', '--augment', '--label-start', '0',
                          '--event-weight', '2', '--augment-tare', '0.1',
                          '--load-threshold', '0', '--load2-threshold', '0',
                          '--sustain-threshold', '0.3', '--out', str(model)]) == 0
    bundle = load_bundle(path=model)
    assert bundle.label_window == {'start_s': 0.0, 'end_s': 0.3, 'event_weight': 2.0}
    assert not bundle.decision_rule.uses_load
    assert bundle.decision_rule.sustain_threshold == 0.3
    assert bundle.training['augmentation']['tare_probability'] == 0.1
    assert bundle.training['augmentation']['torque_scale'] == [0.333, 3.0]


def test_train_no_audio_without_carried_features_needs_the_load_path_off(no_audio, tmp_path,
                                                                         capsys):
    # --no-audio's rule has both load paths, which need the carried load: features without it
    # are refused before any work, with the way out; with both thresholds 0 they train
    args = ['train', str(no_audio), '--no-audio', '--no-events', '--jobs', '1', '--trees', '1',
            '--extra-features', 'force_shift,torque_shift', '--out', str(tmp_path / 'x.npz')]
    assert cli_main.main(args) == 1
    err = capsys.readouterr().err
    assert 'need the carried load' in err and 'set both to 0' in err
    assert cli_main.main(args + ['--load-threshold', '0']) == 1        # the second path too
    assert cli_main.main(args + ['--load-threshold', '0', '--load2-threshold', '0']) == 0
    assert not load_bundle(path=tmp_path / 'x.npz').decision_rule.uses_load


def test_train_no_audio_refuses_audio_features(no_audio, tmp_path, capsys):
    assert cli_main.main(['train', str(no_audio), '--no-audio', '--extra-features',
                          'audio_peak_rel_db,force_shift', '--out',
                          str(tmp_path / 'x.npz')]) == 1
    assert 'audio_peak_rel_db' in capsys.readouterr().err


def test_train_with_audio_features_refuses_a_recording_without_audio(no_audio, tmp_path,
                                                                     capsys):
    assert cli_main.main(['train', str(no_audio), '--out', str(tmp_path / 'x.npz')]) == 1
    assert 'no audio' in capsys.readouterr().err


def test_sweep_scores_the_ft_model_on_recordings_without_audio(no_audio, tmp_path, capsys):
    out = tmp_path / 'rules.md'
    assert cli_main.main(['sweep', str(no_audio), '--model', str(default_ft_model_path()),
                          '--out', str(out), '--jobs', '1']) == 0
    assert 'no audio topic' in capsys.readouterr().out
    own = load_bundle(path=default_ft_model_path()).decision_rule.short()
    shipped = next(line for line in out.read_text().splitlines() if f'| {own} |' in line)
    cells = [cell.strip() for cell in shipped.strip('|').split('|')]
    detected, premature = cells[2], cells[4]    # the model decided every trial, none early
    assert detected.endswith(f'/{N_TRIALS}') and int(detected.split('/')[0]) >= N_TRIALS - 1
    assert premature == '0'
    # a multimodal model still needs the audio topic
    assert cli_main.main(['sweep', str(no_audio), '--model',
                          'models/contact_forest.npz', '--jobs', '1']) == 1
    assert 'no audio' in capsys.readouterr().err
