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
The offline tools on simulated bags: detect (the JSONL contract), evaluate, train, baselines.

A module fixture simulates eight short trials (every condition set) into sqlite3 bags and trains
a small model on them with ``contact-detector train``, so nothing here depends on the shipped
model. ``detect`` over all of them runs once through the console script; the other checks run
the commands in-process on single bags.
"""

from dataclasses import replace
import json
import math
import os
from pathlib import Path
import subprocess
import sys

from contact_detector.cli import main as cli_main
from contact_detector.cli import sweep as sweep_cli
from contact_detector.cli import train as train_cli
from contact_detector.detection import factory
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.fallback import AudioFallback
from contact_detector.errors import ConfigError
from contact_detector.evaluation.baselines import BASELINES, make_baseline
from contact_detector.evaluation.metrics import (frame_labels, phase_at, score_trial, summarize,
                                                 summarize_by_condition, Truth)
from contact_detector.evaluation.truth import conditions_of, truth_for
from contact_detector.io import node_params
from contact_detector.io.bags import jazzy_typestore, open_reader
from contact_detector.io.sensor_stream import (AudioEvent, BadEvent, load_events, WrenchEvent)
from contact_detector.model.shipped import default_ft_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim import simulate_trial, simulate_trials
from contact_detector.sim.bag_writer import manifest_entry, write_manifest, write_trial_bag
from contact_detector.training import recipe, studies
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Writer
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

pytestmark = pytest.mark.slow   # simulates bags, runs the commands, trains

SEED = 11
N_TRIALS = 8
AUDIO_DATA = 'audio_common_msgs/msg/AudioData'
#: ros-drivers/audio_common's AudioData.msg (ROS 2 branch), verbatim.
AUDIO_DATA_MSG = 'uint8[] data\n'
FRAME_KEYS = {'bag', 't', 'p', 'contact'}
RELEASE_KEYS = {'bag', 't', 'event'}


def _cli_command() -> list:
    script = Path(sys.executable).with_name('contact-detector')
    if script.exists():
        return [str(script)]
    return [sys.executable, '-m', 'contact_detector.cli.main']


def run_cli(*args, check: bool = True) -> subprocess.CompletedProcess:
    """Run ``contact-detector ARGS`` as a process (the console script when installed)."""
    result = subprocess.run([*_cli_command(), *map(str, args)], capture_output=True,
                            text=True, env=dict(os.environ), timeout=120)
    if check:
        assert result.returncode == 0, result.stderr[-3000:]
    return result


def read_jsonl(path: Path) -> list:
    return [json.loads(line) for line in Path(path).read_text().splitlines()]


def frames_of(rows: list, bag: str) -> list:
    return [r for r in rows if r['bag'] == bag and 'p' in r]


def releases_of(rows: list, bag: str) -> list:
    return [r['t'] for r in rows if r['bag'] == bag and r.get('event') == 'release']


def detect(tmp: Path, *bags, args=()) -> list:
    """Run ``detect`` in-process on ``bags``; return the parsed JSONL rows."""
    out = tmp / f'detect_{len(list(tmp.glob("detect_*")))}.jsonl'
    assert cli_main.main(['detect', *map(str, bags), '--out', str(out), *map(str, args)]) == 0
    return read_jsonl(out)


def copy_bag(src: Path, dst: Path, *, drop=(), audio_data: bool = False) -> Path:
    """
    Copy a bag message by message, dropping topics; optionally re-type /audio as AudioData.

    The AudioData type is registered from its .msg text in a typestore of its own (never in
    the tools' shared one), and the writer embeds its definition in the bag, as ``ros2 bag
    record`` does.
    """
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg(AUDIO_DATA_MSG, AUDIO_DATA))
    audio_cls = store.types[AUDIO_DATA]
    with AnyReader([src], default_typestore=jazzy_typestore()) as reader, \
            Writer(dst, version=9) as writer:
        conns = {}
        for c in reader.connections:
            if c.topic in drop:
                continue
            msgtype = AUDIO_DATA if audio_data and c.topic == '/audio' else c.msgtype
            conns[c.topic] = writer.add_connection(c.topic, msgtype, typestore=store)
        for c, log_ns, raw in reader.messages(connections=[c for c in reader.connections
                                                           if c.topic in conns]):
            if audio_data and c.topic == '/audio':
                pcm = np.asarray(reader.deserialize(raw, c.msgtype).data, dtype='<i2')
                raw = store.serialize_cdr(audio_cls(data=pcm.view(np.uint8)), AUDIO_DATA)
            writer.write(conns[c.topic], log_ns, raw)
    return dst


def write_params(path: Path, **values) -> Path:
    """Write a node parameter file (``contact_detector_node: ros__parameters:``)."""
    import yaml
    path.write_text(yaml.safe_dump({'contact_detector_node': {'ros__parameters': values}}))
    return path


@pytest.fixture(scope='module')
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp('offline')
    bags = root / 'bags'
    trials = list(simulate_trials(n=N_TRIALS, seed=SEED, conditions=['all']))
    for trial in trials:
        write_trial_bag(trial=trial, path=bags / trial.name)
    write_manifest(trials=[manifest_entry(t) for t in trials], out_dir=bags)
    model = root / 'm.npz'
    assert train_cli.main([str(bags), '--no-events', '--jobs', '1', '--out', str(model)]) == 0
    return {'root': root, 'bags': bags, 'trials': {t.name: t for t in trials}, 'model': model,
            'bundle': load_bundle(path=model)}


def _write_folder(trials, out: Path) -> Path:
    """Write ``trials`` as bags under ``out`` with their manifest; return ``out``."""
    for trial in trials:
        write_trial_bag(trial=trial, path=out / trial.name)
    write_manifest(trials=[manifest_entry(t) for t in trials], out_dir=out)
    return out


@pytest.fixture(scope='module')
def all_rows(data):
    """``contact-detector detect BAGS_DIR`` (the console script) over every trial."""
    out = data['root'] / 'all.jsonl'
    run_cli('detect', data['bags'], '--model', data['model'], '--out', out)
    return read_jsonl(out)


# --- detect: the contract -----------------------------------------------------------------------

def test_detect_jsonl_schema_frames_and_times(data, all_rows):
    trials = data['trials']
    assert list(dict.fromkeys(r['bag'] for r in all_rows)) == sorted(trials)
    config = data['bundle'].feature_config
    for name, trial in trials.items():
        rows = [r for r in all_rows if r['bag'] == name]
        for r in rows:
            if 'event' in r:
                assert set(r) == RELEASE_KEYS and r['event'] == 'release'
                assert isinstance(r['t'], float)
            else:
                assert set(r) == FRAME_KEYS
                assert isinstance(r['t'], float) and isinstance(r['p'], float)
                assert isinstance(r['contact'], bool) and 0.0 <= r['p'] <= 1.0
        frames = frames_of(rows, name)
        t = np.array([r['t'] for r in frames])
        # One line per audio frame: (samples - frame length) / hop + 1, i.e. 100 per second.
        rate = trial.audio_rate
        length, hop = config.audio_frame_samples(rate), config.audio_hop_s * rate
        assert len(frames) == int((trial.audio.size - length) // hop) + 1
        assert len(frames) / (trial.audio.size / rate) == pytest.approx(1 / config.audio_hop_s,
                                                                        rel=0.05)
        # Absolute bag time of the frame's last sample: inside the bag, increasing, and at
        # most a few ms after the true sample time (stamps come from log times >= sample time).
        with open_reader(data['bags'] / name) as reader:
            start, end = reader.start_time * 1e-9, reader.end_time * 1e-9
        assert start <= t[0] and t[-1] <= end
        assert np.all(np.diff(t) > 0)
        true_t = trial.audio_time(length - 1 + np.arange(t.size) * hop)
        assert np.all(t - true_t > -1e-6) and np.all(t - true_t < 0.005)
        # At most one release (armed from the start, a release disarms), right after the
        # contact frame that fired it.
        assert len(releases_of(rows, name)) <= 1
        for i, r in enumerate(rows):
            if 'event' in r:
                assert i > 0 and 'p' in rows[i - 1]
                assert rows[i - 1]['t'] == r['t'] and rows[i - 1]['contact']
    assert sum(len(releases_of(all_rows, n)) for n in trials) >= N_TRIALS // 2


def test_detect_equals_the_detector_run_directly(data, all_rows):
    name = 'trial_0000'
    events = load_events(data['bags'] / name)
    detector = ContactDetector(bundle=data['bundle'], settings=DetectorSettings())
    blocks = []
    for e in events:
        if isinstance(e, AudioEvent):
            blocks.append(detector.on_audio(e.samples, stamp=e.stamp, now=e.now))
        elif isinstance(e, WrenchEvent):
            blocks.append(detector.on_wrench(t=e.t, force=e.force, torque=e.torque, now=e.now))
        elif isinstance(e, BadEvent):
            blocks.append(detector.drop(kind=e.kind, reason=e.reason, stamp=e.now))
    blocks.append(detector.flush())
    frames = frames_of(all_rows, name)
    assert np.array_equal([r['t'] for r in frames], np.concatenate([b.t for b in blocks]))
    assert np.array_equal([r['p'] for r in frames], np.concatenate([b.p for b in blocks]))
    assert np.array_equal([r['contact'] for r in frames],
                          np.concatenate([b.contact for b in blocks]))
    assert releases_of(all_rows, name) == [t for b in blocks for t in b.releases]


def test_both_models_deciding_in_detect_and_evaluate_is_the_pair_run_directly(
        data, all_rows, tmp_path):
    # model.ft_also_decides: true, as on the node: the shipped F/T-only model decides beside
    # the model; the frames stay the model's, the release is the first of either
    params = tmp_path / 'both.yaml'
    params.write_text('contact_detector_node:\n  ros__parameters:\n    model:\n'
                      '      ft_also_decides: true\n')
    rows = detect(tmp_path, data['bags'], args=['--model', data['model'], '--params', params])
    ft = load_bundle(path=default_ft_model_path())
    by_model = set()
    for name in data['trials']:
        pair = AudioFallback(
            primary=ContactDetector(bundle=data['bundle'], settings=DetectorSettings()),
            fallback=ContactDetector(bundle=ft, settings=DetectorSettings()),
            timeout_s=0.0, both_decide=True)
        releases = []
        for e in load_events(data['bags'] / name):       # message by message, as the node
            if isinstance(e, AudioEvent):
                d = pair.on_audio(e.samples, stamp=e.stamp, now=e.now)
            elif isinstance(e, WrenchEvent):
                d = pair.on_wrench(t=e.t, force=e.force, torque=e.torque, now=e.now)
            elif isinstance(e, BadEvent):
                d = pair.drop(kind=e.kind, reason=e.reason, stamp=e.now)
            else:
                continue                                    # /contact_truth
            releases += d.releases
        mine = [r for r in rows if r['bag'] == name]
        assert [r['p'] for r in frames_of(mine, name)] == [r['p'] for r in
                                                           frames_of(all_rows, name)]
        lines = [r for r in mine if 'event' in r]
        assert [r['t'] for r in lines] == releases
        if lines:
            assert lines[0]['model'] == pair.last_release_by
            by_model.add(pair.last_release_by)
        # never later than the model alone
        alone = releases_of(all_rows, name)
        assert not alone or (releases and releases[0] <= alone[0])
    assert by_model == {'audio + F/T', 'F/T-only'}
    # evaluate: forest-both beside forest; with --params, forest is the pair too
    report = tmp_path / 'report'
    assert cli_main.main(['evaluate', str(data['bags']), '--model', str(data['model']),
                          '--detector', 'forest', '--detector', 'forest-both',
                          '--report', str(report)]) == 0
    trials = json.loads((report / 'trials.json').read_text())
    both = {r['name']: r['release_t'] for r in trials['forest-both']}
    assert both == {name: (releases_of(rows, name) or [None])[0] for name in data['trials']}
    assert {r['name']: r['release_t'] for r in trials['forest']} == {
        name: (releases_of(all_rows, name) or [None])[0] for name in data['trials']}


def test_mcap_bag_gives_identical_output(data, all_rows, tmp_path):
    trial = data['trials']['trial_0001']
    bag = write_trial_bag(trial=trial, path=tmp_path / 'mcap' / trial.name, storage='mcap')
    assert list(bag.glob('*.mcap'))
    rows = detect(tmp_path, bag, args=['--model', data['model']])
    assert rows == [r for r in all_rows if r['bag'] == trial.name]


def test_detect_tells_apart_bags_of_the_same_name_from_two_folders(data, all_rows, tmp_path):
    trial = data['trials']['trial_0001']
    other = write_trial_bag(trial=trial, path=tmp_path / 'day2' / trial.name)
    rows = detect(tmp_path, data['bags'] / trial.name, other, args=['--model', data['model']])
    mine = f'{data["bags"].name}/{trial.name}'
    assert list(dict.fromkeys(r['bag'] for r in rows)) == [mine, f'day2/{trial.name}']
    # the same recording in both folders: the same lines under each name
    alone = [r for r in all_rows if r['bag'] == trial.name]
    for name in (mine, f'day2/{trial.name}'):
        assert [{**r, 'bag': trial.name} for r in rows if r['bag'] == name] == alone


def test_44k_audio_with_audio_rate(data, all_rows, tmp_path):
    name = 'trial_0000'
    ref = data['trials'][name]
    trial = simulate_trial(seed=SEED, index=ref.index, condition=ref.condition,
                           hits=ref.impacts[0].kind if ref.impacts else 'none',
                           audio_rate=44100)
    assert trial.onset_t == ref.onset_t and trial.audio.size > 2.7 * ref.audio.size
    bag = write_trial_bag(trial=trial, path=tmp_path / 'k44' / name)
    rows = detect(tmp_path, bag, args=['--model', data['model'], '--audio-rate', '44100'])
    t44 = np.array([r['t'] for r in frames_of(rows, name)])
    p44 = np.array([r['p'] for r in frames_of(rows, name)])
    frames16 = frames_of(all_rows, name)
    t16 = np.array([r['t'] for r in frames16])
    p16 = np.array([r['p'] for r in frames16])
    # Frames are defined in seconds: same count, same times within one (16 kHz) sample.
    assert t44.size == t16.size
    assert np.max(np.abs(t44 - t16)) <= 1 / 16000 + 1e-9
    assert np.corrcoef(p44, p16)[0, 1] > 0.8
    rel44, rel16 = releases_of(rows, name), releases_of(all_rows, name)
    assert len(rel44) == len(rel16) <= 1
    assert all(abs(a - b) < 0.05 for a, b in zip(rel44, rel16))
    # --audio-rate overrides audio.sample_rate of --params.
    params = write_params(tmp_path / 'rate.yaml', audio={'sample_rate': 16000.0})
    assert detect(tmp_path, bag, args=['--model', data['model'], '--params', params,
                                       '--audio-rate', '44100']) == rows


def test_odd_chunking(data, all_rows):
    name, trial = next((n, t) for n, t in data['trials'].items()
                       if t.condition == 'odd_chunking')
    sizes = np.diff(np.concatenate([[0], trial.chunk_ends]))
    assert sizes.min() < 100 and sizes.max() > 1000     # the bag really is oddly chunked
    t = np.array([r['t'] for r in frames_of(all_rows, name)])
    assert np.allclose(np.diff(t), data['bundle'].feature_config.audio_hop_s, atol=1e-3)


def test_audio_common_audio_data_bag(data, all_rows, tmp_path, capsys):
    name = 'trial_0002'
    assert AUDIO_DATA not in jazzy_typestore().fielddefs   # only the bag's definition helps
    bag = copy_bag(data['bags'] / name, tmp_path / 'ad' / name, audio_data=True)
    with open_reader(bag) as reader:
        audio = next(c for c in reader.connections if c.topic == '/audio')
        assert audio.msgtype == AUDIO_DATA and 'uint8[] data' in audio.msgdef.data
    params = write_params(tmp_path / 'ad.yaml',
                          audio={'msg_type': AUDIO_DATA, 'sample_rate': 16000.0,
                                 'wait_for_info': False})
    rows = detect(tmp_path, bag, args=['--model', data['model'], '--params', params])
    assert rows == [r for r in all_rows if r['bag'] == name]
    # The same parameters on a bag of another audio type: a clear error, not silence.
    capsys.readouterr()
    assert cli_main.main(['detect', str(data['bags'] / name), '--model', str(data['model']),
                          '--params', str(params), '--out', str(tmp_path / 'x.jsonl')]) == 1
    err = capsys.readouterr().err
    assert 'std_msgs/msg/Int16MultiArray' in err and 'audio.msg_type' in err


def test_params_file_values_take_effect(data, all_rows, tmp_path):
    name = 'trial_0000'
    params = write_params(tmp_path / 'p.yaml', release={'threshold': 0.0}, warmup_s=1.5)
    rows = detect(tmp_path, data['bags'] / name,
                  args=['--model', data['model'], '--params', params])
    frames, ref = frames_of(rows, name), frames_of(all_rows, name)
    assert [r['p'] for r in frames] == [r['p'] for r in ref]      # the forest is unchanged
    t = np.array([r['t'] for r in frames])
    warm = t >= t[0] + 1.5
    # Threshold 0: every frame after the 1.5 s warm-up is contact; the release fires as soon as
    # the model's confirmation rule allows.
    confirm = load_bundle(path=data['model']).decision_rule.confirm_frames
    assert np.array_equal([r['contact'] for r in frames], warm)
    assert releases_of(rows, name) == [float(t[warm][confirm - 1])]
    assert releases_of(rows, name) != releases_of(all_rows, name)


def test_detect_errors_are_clean(data, tmp_path, capsys):
    assert cli_main.main(['detect', str(tmp_path / 'nope'), '--model', str(data['model']),
                          '--out', str(tmp_path / 'x.jsonl')]) == 1
    assert 'no such bag' in capsys.readouterr().err
    assert cli_main.main(['detect', str(data['bags'] / 'trial_0000'), '--model',
                          str(tmp_path / 'missing.npz'), '--out',
                          str(tmp_path / 'x.jsonl')]) == 1
    assert 'missing.npz' in capsys.readouterr().err


def test_detect_warns_when_the_load_moved_while_the_carried_load_was_measured(tmp_path, capsys):
    # The shipped model compares load changes with the first 0.5 s of a recording: a recording
    # that starts during the grasp (4 N more from 0.25 s on) is named on stderr; the same
    # recording held still is not.
    trial = simulate_trial(seed=SEED, index=2, hits='none')
    moved = trial.force.copy()
    moved[trial.wrench_t >= trial.wrench_t[0] + 0.25, 2] -= 4.0
    bags = {'still': trial, 'grasping': replace(trial, force=moved)}
    for name, t in bags.items():
        write_trial_bag(trial=t, path=tmp_path / name)
    for name in bags:
        assert cli_main.main(['detect', str(tmp_path / name), '--out',
                              str(tmp_path / f'{name}.jsonl')]) == 0
        err = capsys.readouterr().err
        assert ('grasping: carried load measured over 50 F/T samples' in err) == (
            name == 'grasping')
        if name == 'grasping':
            moved_n = float(err.split('moved by ')[1].split(' N')[0])
            assert moved_n == pytest.approx(4.0, abs=0.1)
            assert 'start with the object held still' in err


# --- evaluate ------------------------------------------------------------------------------------

def test_evaluate_all_detectors_report(data, all_rows, tmp_path, capsys):
    names = ['trial_0000', 'trial_0003', 'trial_0005']
    report = tmp_path / 'report'
    assert cli_main.main(['evaluate', *[str(data['bags'] / n) for n in names], '--model',
                          str(data['model']), '--detector', 'all', '--report',
                          str(report)]) == 0
    printed = capsys.readouterr().out
    for file in ('summary.md', 'metrics.json', 'trials.json', 'latency.png'):
        assert (report / file).is_file()
    assert (report / 'latency.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    # forest-ft: the shipped F/T-only model; forest-both: it beside the model
    detectors = ('forest', 'forest-both', 'forest-ft') + BASELINES
    summary = (report / 'summary.md').read_text()
    table = [line for line in summary.splitlines() if line.startswith('| ')]
    for detector in detectors:
        rows = [line for line in table if line.startswith(f'| {detector} | ')]
        assert len(rows) == 1, detector
        assert f'| {detector} | 3 |' in printed
    metrics = json.loads((report / 'metrics.json').read_text())
    trials = json.loads((report / 'trials.json').read_text())
    assert set(metrics) == set(trials) == set(detectors)
    for detector in detectors:
        s = metrics[detector]['summary']['all']
        assert s['trials'] == 3
        assert s['detected'] + s['missed'] + s['late'] + s['premature'] == 3
        assert [o['name'] for o in trials[detector]] == names
    # The forest column is detect's output scored: same first release per trial.
    for outcome in trials['forest']:
        releases = releases_of(all_rows, outcome['name'])
        assert outcome['release_t'] == (releases[0] if releases else None)
        onset = data['trials'][outcome['name']].onset_t
        assert outcome['onset_t'] == pytest.approx(onset)
    assert metrics['forest']['frames']['contact']['support'] > 0


def test_evaluate_refuses_a_model_flag_no_chosen_detector_runs(data, tmp_path, capsys):
    # --model with only forest-ft would score the shipped F/T-only model under the user's nose
    bag, model = str(data['bags'] / 'trial_0000'), str(data['model'])
    report = tmp_path / 'report'
    for args, message in (
            (['--detector', 'forest-ft', '--model', model],
             '--detector forest-ft takes its model from --ft-model'),
            (['--detector', 'forest', '--ft-model', model],
             '--ft-model is the model of --detector forest-ft, which is not chosen')):
        with pytest.raises(SystemExit) as exit_info:
            cli_main.main(['evaluate', bag, *args, '--report', str(report)])
        assert exit_info.value.code == 2
        assert message in capsys.readouterr().err
        assert not report.exists()
    # the same model given to the detector that runs it is taken
    assert cli_main.main(['evaluate', bag, '--detector', 'forest', '--model', model]) == 0


def test_evaluate_takes_each_bags_truth_from_its_own_folder(data, tmp_path):
    # two simulated folders both have a trial_0000; each must be scored against its own onset
    trials = list(simulate_trials(n=1, seed=SEED + 1, conditions=['paper']))
    other = _write_folder(trials, tmp_path / 'other')
    report = tmp_path / 'report'
    assert cli_main.main(['evaluate', str(data['bags'] / 'trial_0000'), str(other),
                          '--model', str(data['model']), '--report', str(report)]) == 0
    rows = json.loads((report / 'trials.json').read_text())['forest']
    onsets = [data['trials']['trial_0000'].onset_t, trials[0].onset_t]
    # ... and is named by as much of its path as tells the two apart
    assert [r['name'] for r in rows] == [f'{data["bags"].name}/trial_0000', 'other/trial_0000']
    assert abs(onsets[0] - onsets[1]) > 0.05
    assert [r['onset_t'] for r in rows] == pytest.approx(onsets, rel=0, abs=1e-6)


def test_evaluate_reads_each_simulated_trials_motion_phases(tmp_path):
    # a premature release is reported with the phase it fell in (the lift, the descent, ...)
    trials = list(simulate_trials(n=1, seed=SEED + 2, conditions=['heavy']))
    _write_folder(trials, tmp_path)
    bag = tmp_path / trials[0].name
    truth = truth_for(bag, [], conditions_of([bag]))
    assert [name for name, _ in truth.phases] == [name for name, _, _ in trials[0].phases]
    lift_start = dict(truth.phases)['lift']
    assert phase_at(truth=truth, t=lift_start + 0.01) == 'lift'
    outcome = score_trial(truth=truth, releases=[lift_start + 0.2], events=[])
    assert (outcome.verdict, outcome.premature_phase) == ('premature', 'lift')


# --- metrics on hand-made truths ----------------------------------------------------------------

def test_score_trial_verdicts():
    truth = Truth(name='a', condition='paper', onset_t=10.0, contact_end_t=12.0)
    cases = [([], 'missed', None), ([9.98], 'premature', -0.02),
             ([9.995], 'detected', -0.005), ([10.1, 9.0], 'premature', -1.0),
             ([10.1], 'detected', 0.1), ([10.5], 'detected', 0.5), ([10.6], 'late', 0.6)]
    for releases, verdict, latency in cases:
        outcome = score_trial(truth=truth, releases=releases, events=releases)
        assert outcome.verdict == verdict, releases
        if latency is None:
            assert outcome.latency_s is None and outcome.release_t is None
        else:
            assert outcome.latency_s == pytest.approx(latency)
            assert outcome.release_t == min(releases)


def test_score_trial_impact_events():
    impacts = ((5.0, 'hand', True), (11.0, 'table', False), (20.0, 'hand', True))
    truth = Truth(name='a', condition='noisy', onset_t=10.0, contact_end_t=12.0,
                  impacts=impacts)
    events = [4.94,        # 60 ms before an impact: not blamed
              4.96, 5.4,   # within [-50, +500] ms of the impact at 5 s: blamed
              11.1,        # during the true contact: the contact, not the impact
              15.0,        # far from any impact: a false event, not blamed on one
              20.2]        # after lift-off, near the third impact: blamed
    outcome = score_trial(truth=truth, releases=[10.05], events=events)
    assert outcome.verdict == 'detected'
    assert outcome.impact_events == 3
    assert outcome.impacts == 3 and outcome.impacts_in_air == 2
    # Without a lift-off time the contact lasts LATE_S after the onset.
    short = Truth(name='b', condition='', onset_t=10.0, impacts=((10.6, 'hand', False),))
    assert score_trial(truth=short, releases=[], events=[10.4, 10.7]).impact_events == 1


def test_summaries_and_frame_labels():
    truths = [Truth(name=str(i), condition=c, onset_t=10.0)
              for i, c in enumerate(('paper', 'paper', 'soft', 'soft'))]
    outcomes = [score_trial(truth=tr, releases=r, events=r)
                for tr, r in zip(truths, ([10.02], [10.06], [], [9.0]))]
    s = summarize(outcomes)
    assert (s['trials'], s['detected'], s['missed'], s['premature'], s['late']) == (4, 2, 1, 1, 0)
    assert s['latency_ms_median'] == pytest.approx(40.0)
    assert s['latency_ms_max'] == pytest.approx(60.0)
    by = summarize_by_condition(outcomes)
    assert set(by) == {'all', 'paper', 'soft'}
    assert by['soft']['latency_ms_median'] is None and by['paper']['detected'] == 2
    t = np.array([9.99, 10.0, 10.05, 10.1, 10.2])
    assert frame_labels(t=t, onsets=[10.0], start_s=0.0, end_s=0.1).tolist() == [0, 1, 1, 0, 0]


# --- baselines on synthetic signals -------------------------------------------------------------

def _wrench(*, torque_y=(), force_x=(), seconds: float = 4.0, rest_ty: float = 1.2, seed=0):
    """100 Hz wrench with noise; ``torque_y``/``force_x`` are (t_rel, size, ramp_s) changes."""
    rng = np.random.default_rng(seed)
    t = 100.0 + np.arange(int(seconds * 100)) / 100
    force = np.array([8.0, 0.2, 0.1]) + rng.normal(0, 0.02, (t.size, 3))
    torque = np.array([0.1, rest_ty, 0.05]) + rng.normal(0, 0.005, (t.size, 3))
    for axis, column, changes in ((torque, 1, torque_y), (force, 0, force_x)):
        for t_rel, size, ramp in changes:
            rel = t - 100.0 - t_rel
            axis[:, column] += size * (np.clip(rel / ramp, 0, 1) if ramp else rel >= 0)
    return t, force, torque


def _run_wrench(name, t, force, torque):
    detector = make_baseline(name, wrench_rate=100.0, audio_rate=16000.0)
    events = []
    for i in range(t.size):
        d = detector.on_wrench(t=t[i:i + 1], force=force[i:i + 1], torque=torque[i:i + 1],
                               now=t[i])
        events += d.events
    return [e - 100.0 for e in events]


def test_threshold_baseline():
    step = _run_wrench('threshold', *_wrench(torque_y=[(2.0, -4.0, 0)]))
    assert step == [pytest.approx(2.0)]
    assert _run_wrench('threshold', *_wrench(torque_y=[(2.0, -2.5, 0)])) == []
    # A 4 N m ramp over 1.5 s crosses 3 N m three quarters of the way.
    ramp = _run_wrench('threshold', *_wrench(torque_y=[(2.0, -4.0, 1.5)]))
    assert ramp == [pytest.approx(3.13, abs=0.015)]
    # Relative to the rest level of the first second, whatever it is.
    assert _run_wrench('threshold', *_wrench(rest_ty=-7.0)) == []


def test_highpass_baseline():
    assert _run_wrench('highpass', *_wrench()) == []
    assert _run_wrench('highpass', *_wrench(torque_y=[(2.0, -1.0, 0)])) == [pytest.approx(2.0)]
    # A slow drift (0.2 N m/s) stays under the high-pass threshold.
    assert _run_wrench('highpass', *_wrench(torque_y=[(1.5, -0.5, 2.5)])) == []
    assert _run_wrench('highpass', *_wrench(force_x=[(2.0, 10.0, 0)])) == []   # |T| only


def test_lowpass_bandpass_baseline():
    assert _run_wrench('lowpass-bandpass', *_wrench()) == []
    slow = _run_wrench('lowpass-bandpass', *_wrench(force_x=[(2.0, 10.0, 0.5)]))
    assert len(slow) == 1 and 2.0 < slow[0] < 2.3
    assert _run_wrench('lowpass-bandpass', *_wrench(torque_y=[(2.0, -4.0, 0)])) == []  # |F|
    # A sharp collision: the band-pass observer vetoes the low-pass one while it rings, so
    # the event (if any) comes after the impulse, where the high-pass baseline fires at once.
    t, force, torque = _wrench()
    force[200:203, 0] += [15.0, -10.0, 5.0]
    torque[200:203, 1] += [1.5, -1.0, 0.5]
    assert _run_wrench('highpass', t, force, torque) == [pytest.approx(2.0)]
    assert all(e > 2.1 for e in _run_wrench('lowpass-bandpass', t, force, torque))


def test_guard_baseline():
    # |F - F_rest| >= 2 N, whatever the rest load: a 3 N step fires at once, 1.5 N never; a
    # 4 N ramp over 1 s crosses 2 N half way; any direction counts (a vector distance)
    assert _run_wrench('guard', *_wrench()) == []
    assert _run_wrench('guard', *_wrench(force_x=[(2.0, 3.0, 0)])) == [pytest.approx(2.0)]
    assert _run_wrench('guard', *_wrench(force_x=[(2.0, -3.0, 0)])) == [pytest.approx(2.0)]
    assert _run_wrench('guard', *_wrench(force_x=[(2.0, 1.5, 0)])) == []
    assert _run_wrench('guard', *_wrench(force_x=[(2.0, 4.0, 1.0)])) == [
        pytest.approx(2.5, abs=0.02)]
    t, force, torque = _wrench()
    force[:, 1] += np.where(t - 100.0 >= 2.0, 2.5, 0.0)             # sideways
    assert _run_wrench('guard', t, force + 30.0, torque) == [pytest.approx(2.0)]
    # a knock of 10 N for 20 ms fires it too: the guard cannot tell, the forests are there for it
    t, force, torque = _wrench()
    force[200:202, 2] -= 10.0
    assert _run_wrench('guard', t, force, torque) == [pytest.approx(2.0)]
    assert _run_wrench('guard', *_wrench(torque_y=[(2.0, -4.0, 0)])) == []     # F only


def test_audio_onset_baseline():
    rate = 16000

    def run(db):
        rng = np.random.default_rng(1)
        x = rng.normal(0, 100, 4 * rate)
        x[2 * rate:2 * rate + 1600] *= 10 ** (db / 20)
        x = np.clip(x, -32768, 32767).astype(np.int16)
        detector = make_baseline('audio-onset', wrench_rate=100.0, audio_rate=rate)
        events = []
        for i in range(0, x.size, 160):
            stamp = 100.0 + (i + 159) / rate
            events += detector.on_audio(x[i:i + 160], stamp=stamp, now=stamp).events
        return [e - 100.0 for e in events]
    assert run(30.0) == [pytest.approx(2.0, abs=0.035)]
    assert run(10.0) == []


def test_make_baseline_refuses_unknown_names():
    with pytest.raises(ConfigError, match='unknown detector'):
        make_baseline('magic', wrench_rate=100.0, audio_rate=16000.0)
    with pytest.raises(ConfigError, match='wrench rate'):
        make_baseline('threshold', wrench_rate=math.nan, audio_rate=16000.0)


# --- train with --labels, and without any truth ---------------------------------------------

@pytest.fixture(scope='module')
def no_truth(data):
    """Four bags without /contact_truth and without a manifest."""
    out = data['root'] / 'no_truth'
    names = ['trial_0000', 'trial_0001', 'trial_0002', 'trial_0003']
    for name in names:
        copy_bag(data['bags'] / name, out / name, drop=('/contact_truth',))
    return out, names


def test_train_with_labels_csv(data, no_truth, tmp_path):
    out, names = no_truth
    labels = tmp_path / 'labels.csv'
    lines = ['bag,onset_start,onset_end']
    lines += [f'{n},{data["trials"][n].onset_t!r},{data["trials"][n].onset_end_t!r}'
              for n in names]
    labels.write_text('\n'.join(lines) + '\n')
    model = tmp_path / 'labels.npz'
    assert train_cli.main([str(out), '--labels', str(labels), '--no-events', '--jobs', '1',
                           '--out', str(model)]) == 0
    bundle = load_bundle(path=model)
    assert bundle.training['trials'] == 4
    # The label window [onset + start, onset + end) holds one frame per 10 ms per trial.
    window = bundle.label_window['end_s'] - bundle.label_window['start_s']
    per_trial = window / 0.010
    assert 4 * (per_trial - 2) <= bundle.training['contact_frames'] <= 4 * (per_trial + 2)
    # A CSV that misses a bag is refused before any work.
    labels.write_text('\n'.join(lines[:-1]) + '\n')
    assert train_cli.main([str(out), '--labels', str(labels), '--jobs', '1', '--out',
                           str(tmp_path / 'x.npz')]) == 1


def test_bags_a_csv_does_not_name_keep_their_own_truth(data, no_truth, tmp_path, capsys):
    # A user's labelled recordings beside simulated trials: the CSV names only the recordings
    # (by path: the simulated folder holds trials of the same names).
    out, names = no_truth
    labels = tmp_path / 'labels.csv'
    labels.write_text('bag,onset_start,onset_end\n' + ''.join(
        f'{out / n},{data["trials"][n].onset_t!r},{data["trials"][n].onset_end_t!r}\n'
        for n in names))
    model = tmp_path / 'mixed.npz'
    assert train_cli.main([str(out), str(data['bags']), '--labels', str(labels), '--no-events',
                           '--jobs', '1', '--trees', '2', '--out', str(model)]) == 0
    assert (f'{N_TRIALS} bags without a row in {labels} are labelled by their own truth'
            in capsys.readouterr().out)
    bundle = load_bundle(path=model)
    assert bundle.training['trials'] == len(names) + N_TRIALS
    assert bundle.training['sources']['recordings']['labels'] == (
        f'labels.csv (--labels) for {len(names)}, the /contact_truth topic or the simulator '
        f'manifest of each bag for the other {N_TRIALS}')
    # evaluate scores the simulated trial against its manifest and the copy by its row
    simulated = data['bags'] / 'trial_0007'
    assert cli_main.main(['evaluate', str(out / names[0]), str(simulated), '--model',
                          str(data['model']), '--labels', str(labels), '--detector',
                          'threshold']) == 0
    assert '1 bags without a row' in capsys.readouterr().err
    # a bag with neither a row nor a truth of its own is refused by both, naming it
    labels.write_text(''.join(labels.read_text().splitlines(keepends=True)[:-1]))
    for command in (['train', '--no-events', '--jobs', '1', '--out', str(tmp_path / 'x.npz')],
                    ['evaluate', '--model', str(data['model'])]):
        assert cli_main.main([command[0], str(out), str(data['bags']), '--labels', str(labels),
                              *command[1:]]) == 1
        err = capsys.readouterr().err
        assert names[-1] in err and 'carry no /contact_truth or manifest.json entry' in err
    assert not (tmp_path / 'x.npz').exists()


def test_no_truth_and_no_labels_is_a_clear_error(data, no_truth, tmp_path, capsys):
    out, _ = no_truth
    result = run_cli('train', out, '--no-events', '--jobs', '1', '--out',
                     tmp_path / 'x.npz', check=False)
    assert result.returncode == 1
    assert 'Traceback' not in result.stderr
    assert '/contact_truth' in result.stderr and '--labels' in result.stderr
    assert not (tmp_path / 'x.npz').exists()
    # evaluate needs a truth too: a manifest entry or /contact_truth.
    assert cli_main.main(['evaluate', str(out / 'trial_0000'), '--model',
                          str(data['model'])]) == 1
    assert 'no manifest entry and no True on /contact_truth' in capsys.readouterr().err


def test_copy_helper_really_drops_the_truth(no_truth):
    out, names = no_truth
    with open_reader(out / names[0]) as reader:
        assert {c.topic for c in reader.connections} == {'/wrist_wrench', '/audio'}
    assert not (out / 'manifest.json').exists()


def test_train_tree_counts_and_release_rule_options(data, tmp_path, capsys):
    model = tmp_path / 'rule.npz'
    assert train_cli.main([str(data['bags']), '--no-events', '--jobs', '1', '--trees', '2,4-5',
                           '--threshold', '0.85', '--confirm-frames', '1',
                           '--sustain-frames', '10', '--sustain-threshold', '0.4',
                           '--delta-window', '2', '--delta-lag', '4', '--baseline-window', '9',
                           '--rise-frames', '3', '--change-max-frames', '7',
                           '--hold-frames', '6', '--carried-window', '30',
                           '--audio-hold-frames', '7',
                           '--carried-floor-force', '0.8', '--out', str(model)]) == 0
    bundle = load_bundle(path=model)
    # Without options, train uses the shipped features; the F/T change windows are options.
    assert data['bundle'].feature_config == recipe.DEFAULT_FEATURES
    config = bundle.feature_config
    assert (config.delta_window, config.delta_lag, config.baseline_window,
            config.rise_frames, config.change_max_frames) == (2, 4, 9, 3, 7)
    assert config.hold_frames == 6 and config.audio_hold_frames == 7
    assert (config.carried_window, config.carried_floor_force) == (30, 0.8)
    table = bundle.metrics['trial']['validation']
    assert [row['n_estimators'] for row in table] == [2, 4, 5]
    assert bundle.forest.n_estimators == bundle.metrics['trial']['best_n_estimators']
    assert bundle.decision_rule.to_dict() == {
        'threshold': 0.85, 'confirm_frames': 1, 'refractory_s': 1.0, 'average_frames': 1,
        'sustain_frames': 10, 'sustain_threshold': 0.4, 'evidence_threshold': 0.0,
        'evidence_drift': 0.5}
    # detect applies the bundle's rule, and the node's parameters override it.
    params = tmp_path / 'p.yaml'
    params.write_text('contact_detector:\n  ros__parameters:\n    release:\n'
                      '      sustain_frames: 0\n      threshold: 0.99\n')
    settings, _, _, rule = factory.settings_from_params(
        node_params.read_node_params(params), audio_rate=None)
    assert rule == {'threshold': 0.99, 'sustain_frames': 0}
    for bad in ('0', 'x', '5-3'):
        with pytest.raises(SystemExit):
            train_cli.main([str(data['bags']), '--trees', bad, '--out', str(model)])
    capsys.readouterr()


# --- sweep ------------------------------------------------------------------------------------

def test_sweep_ablation_scores_each_slow_path_threshold(data, tmp_path, capsys):
    out = tmp_path / 'ablation.md'
    bags = str(data['bags'])
    assert sweep_cli.main([bags, bags, '--grid', 'none', '--ablation', '--ablation-sustain',
                           '0.5,0.3', '--jobs', '1', '--out', str(out)]) == 0
    rows = [[cell.strip() for cell in line.strip('|').split('|')]
            for line in out.read_text().splitlines() if line.startswith('| ')][1:]
    rows = [r for r in rows if not r[0].startswith('---')]
    by_key = {(r[0], r[1], r[2]): r for r in rows}
    settings = {r[0] for r in rows}
    assert len(settings) == len(studies.ablation_settings())
    assert {r[2] for r in rows} == {'mean15>=0.5', 'mean15>=0.3'}
    for setting, condition, slow in by_key:
        if slow != 'mean15>=0.5':
            continue
        strict, loose = by_key[setting, condition, slow], by_key[setting, condition,
                                                                 'mean15>=0.3']
        # a lower slow-path threshold makes more frames contact: it can only release sooner
        released = [int(r[3].split('/')[0]) + int(r[4]) for r in (strict, loose)]
        assert int(loose[4]) >= int(strict[4]) and released[1] >= released[0]
    with pytest.raises(SystemExit):
        sweep_cli.main([bags, bags, '--grid', 'none', '--ablation', '--ablation-sustain', '2'])
    assert 'thresholds must be in [0, 1]' in capsys.readouterr().err


def test_sweep_lofo_scores_each_family_plain_and_augmented(data, tmp_path):
    out = tmp_path / 'lofo.md'
    bags = str(data['bags'])
    assert sweep_cli.main([bags, '--lofo', '--lofo-settings', 'shipped,shipped+aug',
                           '--trees', '2', '--jobs', '1', '--out', str(out)]) == 0
    worst_part, family_part = out.read_text().split('## Every family')

    def rows(text):
        return [[cell.strip() for cell in line.strip('|').split('|')]
                for line in text.splitlines() if line.startswith('| shipped')]
    families = {t.condition for t in data['trials'].values()}
    rules = {r[1] for r in rows(worst_part)}
    # per setting and rule: the worst family, and one row per family left out
    for setting in ('shipped', 'shipped+aug'):
        assert {r[1] for r in rows(worst_part) if r[0] == setting} == rules
        for rule in rules:
            assert sorted(r[2] for r in rows(family_part)
                          if r[0] == setting and r[1] == rule) == sorted(families)
    assert all(r[2] in families for r in rows(worst_part))
    # a stricter slow path only releases later: never early more often, over all families
    early = {r[1]: int(r[7].split(' / ')[1]) for r in rows(worst_part) if r[0] == 'shipped'}
    shipped = 'p>=0.95 x1 or mean15>=0.4'
    assert early['p>=0.95 x1 or mean15>=0.5'] <= early['p>=0.95 x1 or mean15>=0.45'] \
        <= early[shipped]


def test_sweep_lofo_scores_the_knocked_trials_and_a_shorter_maximum_window(data, tmp_path):
    out = tmp_path / 'lofo.md'
    assert sweep_cli.main([str(data['bags']), '--lofo', '--lofo-settings',
                           'ft-only+signed,ft-only+signed+max20,ft-only+signed+carried',
                           '--trees', '2', '--jobs', '1', '--out', str(out)]) == 0
    manifest = json.loads((data['bags'] / 'manifest.json').read_text())
    knocked = sum(any(i['kind'] == 'hand' and i['in_air'] for i in t['impacts'])
                  for t in manifest['trials'])
    assert knocked > 0
    rows = [[c.strip() for c in line.strip('|').split('|')]
            for line in out.read_text().split('## Every family')[0].splitlines()
            if line.startswith('| ft-only')]
    assert {r[0] for r in rows} == {'ft-only+signed', 'ft-only+signed+max20',
                                    'ft-only+signed+carried'}
    for r in rows:
        # the last column: the knocked trials of every family, each scored while left out
        detected, early, _ = (v.strip() for v in r[8].split(' / '))
        caught, trials = (int(v) for v in detected.split('/'))
        assert trials == knocked and caught + int(early) <= knocked
    assert studies.LOFO_CONFIG_CHANGES['ft-only+signed+max20'] == {'change_max_frames': 20}


def _lofo_shipped(data, out: Path, *options: str) -> tuple:
    """
    ``sweep --lofo`` of the ``shipped`` setting on the module's trials with ``options``.

    Returns the markdown and its per-family rows (the cells of each ``| shipped`` line of the
    section "Every family").
    """
    assert sweep_cli.main([str(data['bags']), '--lofo', '--lofo-settings', 'shipped',
                           '--jobs', '1', *options, '--out', str(out)]) == 0
    text = out.read_text()
    rows = [[c.strip() for c in line.strip('|').split('|')]
            for line in text.split('## Every family')[1].splitlines()
            if line.startswith('| shipped')]
    return text, rows


def test_sweep_lofo_pools_each_family_over_the_forest_seeds(data, tmp_path):
    tables = {}
    for seeds in ('3', '3,4'):
        _, rows = _lofo_shipped(data, tmp_path / f'lofo{seeds}.md', '--trees', '2',
                                '--seeds', seeds)
        tables[seeds] = {(r[1], r[2]): r for r in rows}
    per_family = {}
    for t in data['trials'].values():
        per_family[t.condition] = per_family.get(t.condition, 0) + 1
    assert tables['3'].keys() == tables['3,4'].keys()
    for (rule, family), row in tables['3,4'].items():
        one = tables['3'][rule, family]
        # a family's row is out of its trials once per forest; seed 3's forests are the same
        # in both runs, so the pooled row holds at least what seed 3 alone caught
        assert int(one[3].split('/')[1]) == per_family[family]
        assert int(row[3].split('/')[1]) == 2 * per_family[family]
        assert int(row[3].split('/')[0]) >= int(one[3].split('/')[0])
        assert int(row[4].split()[0]) >= int(one[4].split()[0])


def test_train_augment_is_recorded_in_the_card_and_bad_ranges_are_refused(data, tmp_path,
                                                                          capsys):
    model = tmp_path / 'aug.npz'
    bags = str(data['bags'])
    assert train_cli.main([bags, '--no-events', '--jobs', '1', '--trees', '2', '--augment',
                           '--augment-tare', '1', '--out', str(model)]) == 0
    training = load_bundle(path=model).training
    # the ranges not given are the shipped multimodal model's
    assert training['augmentation'] == {'tare_probability': 1.0, 'tare_window_s': [0.2, 0.6],
                                        'torque_scale': [0.1, 2.0], 'gain': [0.2, 1.5],
                                        'offset_probability': 0.5, 'offset_force_n': 10.0,
                                        'offset_torque_nm': 0.5, 'contact_offset_m': 0.05}
    assert data['bundle'].training['augmentation'] is None
    assert train_cli.main([bags, '--augment', '--augment-tare', '1.5',
                           '--out', str(tmp_path / 'bad.npz')]) != 0
    assert 'tare_probability' in capsys.readouterr().err
    # the lag is off unless asked for, and a range that starts at 0 is refused
    assert train_cli.main([bags, '--no-events', '--jobs', '1', '--trees', '2', '--augment',
                           '--augment-lag', '0.02,0.2', '--out', str(model)]) == 0
    assert load_bundle(path=model).training['augmentation']['lag_s'] == [0.02, 0.2]
    assert train_cli.main([bags, '--augment', '--augment-lag', '0,0.2',
                           '--out', str(tmp_path / 'bad.npz')]) != 0
    assert 'lag_s' in capsys.readouterr().err
    # the offset's size is recorded, and a negative one is refused
    assert train_cli.main([bags, '--no-events', '--jobs', '1', '--trees', '2', '--augment',
                           '--augment-offset-size', '20,1', '--out', str(model)]) == 0
    recorded = load_bundle(path=model).training['augmentation']
    assert (recorded['offset_force_n'], recorded['offset_torque_nm']) == (20.0, 1.0)
    assert train_cli.main([bags, '--augment', '--augment-offset-size=-1,1',
                           '--out', str(tmp_path / 'bad.npz')]) != 0
    assert 'offset sizes' in capsys.readouterr().err


def test_sweep_keeps_its_augmentation_defaults_while_train_takes_the_shipped_ones(capsys):
    # a sweep command written in the docs before the five augmentations were shipped must keep
    # its meaning: sweep's ranges not given stay a tare on a quarter, lever arms x0.5-2 and no
    # gain, offset or contact offset; train --augment's are the shipped model's
    for main, gain in ((sweep_cli.main, 'default 1,1'), (train_cli.main, 'default 0.2,1.5')):
        with pytest.raises(SystemExit):
            main(['--help'])
        text = ' '.join(capsys.readouterr().out.split())
        assert f'LOW,HIGH ({gain}' in text
    assert studies.STUDY_AUGMENTATION.to_dict() == {
        'tare_probability': 0.25, 'tare_window_s': [0.2, 0.6], 'torque_scale': [0.5, 2.0]}
    assert recipe.DEFAULT_AUGMENTATION.gain == (0.2, 1.5)


def _trained_with(data, model: Path, *options: str) -> tuple:
    """Train a three-tree model on the module's trials with ``options``; its bundle and card."""
    assert train_cli.main([str(data['bags']), '--no-events', '--jobs', '1', '--trees', '3',
                           *options, '--out', str(model)]) == 0
    card = json.loads(model.with_name(model.stem + '.card.json').read_text())
    return load_bundle(path=model), card


def test_train_min_samples_leaf_is_recorded_in_the_card_and_bad_values_are_refused(
        data, tmp_path, capsys):
    bags = str(data['bags'])
    bundle, card = _trained_with(data, tmp_path / 'leaf.npz', '--min-samples-leaf', '5')
    assert bundle.training['min_samples_leaf'] == card['training']['min_samples_leaf'] == 5
    assert card['forest']['params']['min_samples_leaf'] == 5
    assert data['bundle'].training['min_samples_leaf'] == 1   # the default: the paper's

    def impure_leaves(trees):
        contact = trees.value[trees.feature == -2, 1]
        return float(np.mean((contact > 1e-9) & (contact < 1 - 1e-9)))
    # fully grown trees end in pure leaves (a vote count); leaves of at least five frames
    # stop before the contact and free frames are apart, so many hold both
    assert impure_leaves(data['bundle'].trees) < 0.01 < 0.1 < impure_leaves(bundle.trees)
    for bad in ('0', '-2'):
        assert train_cli.main([bags, '--min-samples-leaf', bad,
                               '--out', str(tmp_path / 'bad.npz')]) != 0
        assert 'min_samples_leaf must be an integer >= 1' in capsys.readouterr().err
        with pytest.raises(SystemExit):
            sweep_cli.main([bags, '--lofo', '--min-samples-leaf', bad])
        assert 'min_samples_leaf must be an integer >= 1' in capsys.readouterr().err
    assert not (tmp_path / 'bad.npz').exists()


def test_train_splitter_random_grows_extremely_randomized_trees_that_detect_runs(
        data, tmp_path, capsys):
    model = tmp_path / 'extra.npz'
    bundle, card = _trained_with(data, model, '--splitter', 'random')
    assert bundle.training['splitter'] == card['training']['splitter'] == 'random'
    assert data['bundle'].training['splitter'] == 'best'   # the default: the paper's forest
    # logs and /diagnostics tell the two kinds of forest apart
    assert bundle.model_id.startswith('et') and data['bundle'].model_id.startswith('rf')
    assert bundle.model_id == card['model_id']
    # extremely randomized trees grow on every frame, a random forest on bootstrap samples
    assert card['forest']['params']['bootstrap'] is False
    assert data['bundle'].trees.params['bootstrap'] is True

    # the model file runs like any other: every trial gets frames, the decisions follow P
    out = tmp_path / 'extra.jsonl'
    run_cli('detect', data['bags'], '--model', model, '--out', out)
    rows = read_jsonl(out)
    assert {r['bag'] for r in rows} == set(data['trials'])
    assert any(r.get('event') == 'release' for r in rows)
    with pytest.raises(SystemExit):
        train_cli.main([str(data['bags']), '--splitter', 'extra',
                        '--out', str(tmp_path / 'bad.npz')])
    assert "invalid choice: 'extra'" in capsys.readouterr().err
    assert not (tmp_path / 'bad.npz').exists()


def test_sweep_lofo_passes_min_samples_leaf_to_every_forest(data, tmp_path):
    # leaves of more frames than the trials hold: every tree is its root, P(contact) is the
    # share of contact frames everywhere, far below every rule's thresholds
    text, rows = _lofo_shipped(data, tmp_path / 'lofo.md', '--trees', '2',
                               '--min-samples-leaf', '1000000')
    assert 'Forests: 2 trees, min_samples_leaf 1000000, seeds 0' in text
    assert rows and all(r[3].startswith('0/') and r[4].split()[0] == '0' for r in rows)


def test_sweep_lofo_splitter_random_trains_other_forests_and_says_so(data, tmp_path):
    tables, rows = {}, {}
    for splitter in ('best', 'random'):
        tables[splitter], rows[splitter] = _lofo_shipped(
            data, tmp_path / f'lofo_{splitter}.md', '--trees', '3', '--splitter', splitter)
    assert 'Forests: 3 trees, min_samples_leaf 1, seeds 0' in tables['best']
    assert ('Forests: 3 trees, extremely randomized trees, min_samples_leaf 1, seeds 0'
            in tables['random'])
    # other trees, other P(contact): the per-family rows differ somewhere
    assert rows['best'] and len(rows['best']) == len(rows['random'])
    assert rows['best'] != rows['random']


def test_sweep_lofo_event_weight_changes_the_forests_and_says_so(data, tmp_path, capsys):
    bags = str(data['bags'])
    families = sorted({t.condition for t in data['trials'].values()})
    tables = {}
    for weight in ('1', '20'):
        out = tmp_path / f'lofo{weight}.md'
        assert sweep_cli.main([bags, '--lofo', '--lofo-settings', 'shipped', '--trees', '3',
                               '--jobs', '1', '--lofo-event-weight', weight,
                               '--out', str(out)]) == 0
        tables[weight] = out.read_text()
    assert 'weigh' not in tables['1'].split('|')[0]
    assert 'The frames near a simulated exogenous event weigh 20 in training.' in tables['20']
    # the same trials and seeds, other weights: other forests, so other rows somewhere
    assert tables['1'].split('## Every family')[1] != tables['20'].split('## Every family')[1]
    assert len(families) >= 2
    with pytest.raises(SystemExit):
        sweep_cli.main([bags, '--lofo', '--lofo-event-weight', '0.5'])
    assert 'event_weight must be a finite number >= 1' in capsys.readouterr().err


def test_sweep_lofo_train_only_trains_the_other_folds_on_them_and_scores_none(data, tmp_path,
                                                                              capsys):
    families = sorted({t.condition for t in data['trials'].values()})
    assert len(families) >= 2
    left = families[0]
    # the train-only folder: copies of family `left`'s trials under another folder
    copies = [t for t in data['trials'].values() if t.condition == left]
    extra = _write_folder(copies, tmp_path / 'extra')
    plain, rows_plain = _lofo_shipped(data, tmp_path / 'plain.md', '--trees', '3')
    more, rows_more = _lofo_shipped(data, tmp_path / 'more.md', '--trees', '3',
                                    '--lofo-train-only', str(extra))
    assert 'never' not in plain.split('|')[0]
    assert (f'Every fold also trains on {len(copies)} trials that are never scored'
            in more.split('|')[0])
    # the same trials scored: every row counts its family's trials, no copy among them
    assert [(r[1], r[2], r[3].split('/')[1]) for r in rows_plain] == \
        [(r[1], r[2], r[3].split('/')[1]) for r in rows_more]
    # the family left out never trains on its own copies: its forest and rows are the same
    assert [r for r in rows_plain if r[2] == left] == [r for r in rows_more if r[2] == left]
    # every other fold trains on them too: other forests, other rows somewhere
    assert [r for r in rows_plain if r[2] != left] != [r for r in rows_more if r[2] != left]
    bags = str(data['bags'])
    for args, message in (([bags, '--lofo-train-only', str(extra)],
                           '--lofo-train-only needs --lofo'),
                          ([bags, '--lofo', '--lofo-train-only', bags],
                           'a folder is both scored and only trained on')):
        with pytest.raises(SystemExit):
            sweep_cli.main(args)
        assert message in capsys.readouterr().err


def test_lofo_rules_train_only_reproduces_the_sweeps_row(data, tmp_path):
    # benchmarks/lofo_rules.py --train-only, the command behind the F/T-only learning curve:
    # its shipped rule S is the sweep's shipped rule with the load paths, on the same forests
    extra = _write_folder(simulate_trials(n=6, seed=SEED + 1, conditions=['all']),
                          tmp_path / 'extra')
    out = tmp_path / 'lofo.md'
    assert sweep_cli.main([str(data['bags']), '--lofo', '--lofo-train-only', str(extra),
                           '--lofo-settings', 'ft-only+signed+carried+aug', '--augment-tare',
                           '0.5', '--augment-torque', '0.333,3', '--lofo-label-start', '0.03',
                           '--seeds', '0', '--jobs', '1', '--out', str(out),
                           '--load-threshold', '2', '--load-frames', '20', '--load-support',
                           '0.15', '--load-support-frames', '25', '--load2-threshold', '2',
                           '--load2-frames', '40', '--load2-support', '0',
                           '--load2-support-frames', '1', '--load2-direction', '-0.4',
                           '--load2-steady', '0.5']) == 0
    # per family left out: caught/trials, early, median [ms] of the shipped rule
    shipped = recipe.DEFAULT_FT_ONLY_RULE.short()
    swept = {r[2]: (r[3], int(r[4].split()[0]), r[6])
             for r in ([c.strip() for c in line.strip('|').split('|')]
                       for line in out.read_text().split('## Every family')[1].splitlines()
                       if line.startswith(f'| ft-only+signed+carried+aug | {shipped} |'))}
    assert sorted(swept) == sorted({t.condition for t in data['trials'].values()})
    scripts = Path(__file__).parents[2] / 'benchmarks'
    for extra_args, same in (([], False), (['--train-only', extra], True)):
        counts = tmp_path / 'rules.json'
        subprocess.run([sys.executable, scripts / 'lofo_rules.py', data['bags'], '--recipe',
                        'ft-only', *extra_args, '--seeds', '0', '--jobs', '1', '--json',
                        counts], check=True, capture_output=True)
        by_family = json.loads(counts.read_text())['summary']['S']['by_family']
        scored = {family: (f"{f['detected']}/{f['trials']}", f['premature'],
                           '-' if f['latency_ms_median'] is None
                           else f"{f['latency_ms_median']:.0f}")
                  for family, f in by_family.items() if family != 'all'}
        # without the training-only trials the forests differ: so do some medians
        assert (scored == swept) is same
    # a folder both scored and only trained on is refused
    refused = subprocess.run([sys.executable, scripts / 'lofo_rules.py', data['bags'],
                              '--train-only', data['bags']], capture_output=True, text=True)
    assert refused.returncode == 2
    assert 'a folder is both scored and only trained on' in refused.stderr


def test_lofo_either_takes_the_first_release_of_two_rules(data, tmp_path):
    # benchmarks/lofo_either.py, the left-out figures of two models deciding (the first release
    # of either) from lofo_rules.py --outcomes: here two rules of one recipe on one forest
    scripts = Path(__file__).parents[2] / 'benchmarks'
    outcomes, counts = tmp_path / 'outcomes.json', tmp_path / 'rules.json'
    subprocess.run([sys.executable, scripts / 'lofo_rules.py', data['bags'], '--recipe',
                    'ft-only', '--rule', 'slow:sustain_threshold=0.05', '--seeds', '0',
                    '--jobs', '1', '--json', counts, '--outcomes', outcomes],
                   check=True, capture_output=True)
    records = json.loads(outcomes.read_text())['outcomes']
    assert len(records['S']) == len(records['slow']) == len(data['trials'])
    alone = json.loads(counts.read_text())['summary']
    combined = tmp_path / 'either.json'
    subprocess.run([sys.executable, scripts / 'lofo_either.py', f'{outcomes}:S',
                    f'{outcomes}:S', f'{outcomes}:slow', '--json', combined], check=True,
                   capture_output=True)
    summary = json.loads(combined.read_text())['summary']
    # a rule beside itself is the rule alone
    assert summary['ft-only S | ft-only S'] == alone['S']
    # beside another: early where either releases before the onset, caught by the first
    either = summary['ft-only S | ft-only slow']['by_family']['all']
    by_trial = {r['trial']: r for r in records['S']}

    def release(record):
        return (record['release_t'] is None, record['release_t'] or 0.0)

    first = [min((r, by_trial[r['trial']]), key=release) for r in records['slow']]
    assert either['premature'] == sum(o['verdict'] == 'premature' for o in first)
    assert either['premature'] >= max(alone[n]['by_family']['all']['premature']
                                      for n in ('S', 'slow'))
    assert either['detected'] == sum(o['verdict'] == 'detected' for o in first)
    refused = subprocess.run([sys.executable, scripts / 'lofo_either.py', f'{outcomes}:S',
                              f'{outcomes}:nothing'], capture_output=True, text=True)
    assert refused.returncode == 1 and "has no rule 'nothing'" in refused.stderr


def test_sweep_lofo_families_leaves_only_those_out_and_refuses_unknown_ones(data, tmp_path,
                                                                            capsys):
    bags = str(data['bags'])
    families = sorted({t.condition for t in data['trials'].values()})
    assert len(families) >= 2
    out = tmp_path / 'lofo.md'
    assert sweep_cli.main([bags, '--lofo', '--lofo-settings', 'shipped,previous', '--trees',
                           '2', '--jobs', '1', '--lofo-families', families[0],
                           '--out', str(out)]) == 0
    text = out.read_text()
    assert f'Left out: only {families[0]} (a screen' in text
    family_part = text.split('## Every family')[1]
    for setting in ('shipped', 'previous'):
        rows = [[c.strip() for c in line.strip('|').split('|')]
                for line in family_part.splitlines() if line.startswith(f'| {setting} |')]
        assert rows and {r[2] for r in rows} == {families[0]}
    with pytest.raises(SystemExit):
        sweep_cli.main([bags, '--lofo', '--lofo-settings', 'shipped', '--trees', '2',
                        '--jobs', '1', '--lofo-families', 'no_such_family'])
    assert "no trials of the families ['no_such_family']" in capsys.readouterr().err
