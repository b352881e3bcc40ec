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

"""Tests of the simulator: determinism, truth, stop rule, phases, bags, hits, condition sets."""

import json
import os
from pathlib import Path
import shutil

from contact_detector.cli.plot import main as plot_main
from contact_detector.cli.simulate import main as simulate_main
from contact_detector.errors import BagError, ConfigError
from contact_detector.io.bags import (iter_messages, jazzy_typestore, read_audio, read_manifest,
                                      read_truth, read_wrench)
from contact_detector.sim import bag_writer, sound_bank
from contact_detector.sim.bag_writer import differing_settings, write_trial_bag
from contact_detector.sim.conditions import (CONDITION_SETS, FAMILY_SETS, get_condition,
                                             LATER_SETS, ORIGINAL_SETS, ranges_markdown,
                                             REAL_SOUND_SETS, resolve_conditions, TARED_MODES)
from contact_detector.sim.hits import friction_brush, Hit
from contact_detector.sim.loads import G, STOP_TORQUE_NM
from contact_detector.sim.trial import PHASES, simulate_trial, simulate_trials
import numpy as np
import pytest
from rosbags.highlevel import AnyReader

SEED = 5
ALL = ORIGINAL_SETS


@pytest.fixture(scope='module')
def sim_dir(tmp_path_factory) -> Path:
    """Six trials, one per condition set, written by the command line tool."""
    out = tmp_path_factory.mktemp('sim') / 'run'
    assert simulate_main([str(out), '--trials', '6', '--seed', str(SEED), '--conditions', 'all',
                          '--quiet']) == 0
    return out


@pytest.fixture(scope='module')
def manifest(sim_dir) -> dict:
    return read_manifest(sim_dir)


def _trials(manifest):
    return {t['name']: t for t in manifest['trials']}


# ---------------------------------------------------------------------------------- determinism


def test_same_seed_same_trial_and_other_seed_differs():
    a = simulate_trial(seed=3, index=4, condition='noisy')
    b = simulate_trial(seed=3, index=4, condition='noisy')
    for field in ('wrench_t', 'force', 'torque', 'audio', 'chunk_ends', 'chunk_log_t'):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert a.params == b.params and a.impacts == b.impacts and a.phases == b.phases
    c = simulate_trial(seed=4, index=4, condition='noisy')
    assert c.onset_t != a.onset_t
    assert not np.array_equal(c.audio[:1000], a.audio[:1000])


@pytest.mark.slow
def test_cli_is_deterministic(tmp_path):
    runs = []
    for name in ('a', 'b'):
        out = tmp_path / name
        assert simulate_main([str(out), '--trials', '2', '--seed', '9', '--conditions',
                              'paper,odd_chunking', '--quiet']) == 0
        msgs = [(m.topic, m.log_time_ns, repr(m.msg)) for bag in sorted(out.glob('trial_*'))
                for m in iter_messages(bag)]
        runs.append((msgs, read_manifest(out)))
    assert runs[0][0] == runs[1][0]
    assert runs[0][1] == runs[1][1]


def test_hit_kind_changes_nothing_else():
    a = simulate_trial(seed=1, index=2, hits='none')
    b = simulate_trial(seed=1, index=2, hits='hand')
    assert not a.impacts and b.impacts
    assert a.onset_t == b.onset_t
    pa = {k: v for k, v in a.params.items() if k != 'derived'}
    pb = {k: v for k, v in b.params.items() if k != 'derived'}
    assert pa == pb


# ---------------------------------------------------------------------------- truth and phases


def test_truth_topic_matches_manifest(sim_dir, manifest):
    assert len(manifest['trials']) == 6
    for trial in manifest['trials']:
        truth = read_truth(sim_dir / trial['bag'])
        assert [v for _, v in truth] == [True, False]
        assert truth[0][0] == pytest.approx(trial['onset_t'], abs=1e-6)
        assert truth[1][0] == pytest.approx(trial['onset_end_t'], abs=1e-6)
        assert trial['onset_end_t'] - trial['onset_t'] == pytest.approx(0.1, abs=1e-6)


@pytest.mark.parametrize('condition', ALL)
def test_phases_in_order(condition):
    tr = simulate_trial(seed=SEED, index=11, condition=condition)
    assert tuple(p[0] for p in tr.phases) == PHASES
    assert tr.phases[0][1] == tr.start_time
    for (_, _, end), (_, start, _) in zip(tr.phases, tr.phases[1:]):
        assert end == start
    for name, a, b in tr.phases:
        assert b > a, name
    by_name = {name: (a, b) for name, a, b in tr.phases[1:-1]}
    assert by_name['push'][0] == tr.onset_t
    assert by_name['settle'][0] == tr.stop_t
    assert by_name['retreat'][0] < tr.contact_end_t < by_name['retreat'][1]
    assert tr.phases[0][2] - tr.phases[0][1] >= 0.8
    assert tr.phases[-1][2] - tr.phases[-1][1] >= 0.8
    assert 7.0 < tr.end_time - tr.start_time < 13.0
    assert tr.wrench_t[-1] <= tr.end_time < tr.wrench_t[-1] + 1 / tr.ft_rate
    assert tr.audio_time(len(tr.audio)) <= tr.end_time + 1e-9


def test_ego_noise_while_moving():
    louder = 0
    for index in range(4):
        tr = simulate_trial(seed=SEED, index=index, condition='paper', hits='none')
        x = tr.audio.astype(float)
        rest = x[:int(0.8 * tr.audio_rate)]
        a, b = [(p[1], p[2]) for p in tr.phases if p[0] == 'descend'][0]
        i0, i1 = int((a - tr.start_time) * tr.audio_rate), int((b - tr.start_time - 0.2)
                                                               * tr.audio_rate)
        louder += np.sqrt(np.mean(x[i0:i1] ** 2)) > 1.2 * np.sqrt(np.mean(rest ** 2))
    assert louder == 4


def test_contact_sound_audible_in_paper_set():
    ratios = []
    for index in range(6):
        tr = simulate_trial(seed=SEED, index=index, condition='paper', hits='none')
        x = tr.audio.astype(float)
        i = int((tr.onset_t - tr.start_time) * tr.audio_rate)
        before = np.mean(x[i - 3200:i - 160] ** 2)
        after = np.mean(x[i:i + 512] ** 2)
        ratios.append(after / before)
    assert np.median(ratios) > 3.0


def test_soft_and_noisy_make_the_contact_harder_to_hear():
    paper = simulate_trial(seed=SEED, index=3, condition='paper')
    soft = simulate_trial(seed=SEED, index=3, condition='soft')
    noisy = simulate_trial(seed=SEED, index=3, condition='noisy')
    assert soft.params['derived']['contact_peak_fs'] < 0.3 * paper.params['derived'][
        'contact_peak_fs']
    assert noisy.params['bg_rms_fs'] > 2 * paper.params['bg_rms_fs']
    # the soft surface takes the load more slowly
    assert soft.params['derived']['k_eff_npm'] < paper.params['derived']['k_eff_npm']


# ------------------------------------------------------------------------------------ the F/T


def test_force_at_rest_is_the_held_weight():
    for condition in ('paper', 'heavy'):
        tr = simulate_trial(seed=SEED, index=2, condition=condition)
        m = tr.params['derived']['object_total_kg'] + tr.params['hand_mass_kg']
        rest = np.linalg.norm(tr.force[:int(0.8 * tr.ft_rate)].mean(axis=0))
        assert abs(rest - m * G) <= tr.params['force_bias_n'] + 0.5


def _stop_check(*, t, torque, entry):
    """Apply the robot's stop rule to the measured torque; return the firing time."""
    a, b = entry['params']['derived']['baseline_window']
    base = torque[(t >= a - 1e-9) & (t < b - 1e-9), 1].mean()
    assert base == pytest.approx(entry['params']['derived']['baseline_ty_nm'], abs=1e-6)
    armed = t >= b - 1e-9
    over = armed & (np.abs(torque[:, 1] - base) >= STOP_TORQUE_NM)
    return t[np.argmax(over)], base


def test_stop_rule_in_bags(sim_dir, manifest):
    for entry in manifest['trials']:
        w = read_wrench(sim_dir / entry['bag'])
        fired, base = _stop_check(t=w.t, torque=w.torque, entry=entry)
        assert fired == pytest.approx(entry['stop_t'], abs=1e-6)
        assert fired > entry['onset_t']


@pytest.mark.parametrize('condition', ALL)
def test_stop_rule_reached_and_push_stops(condition):
    for index in range(3):
        tr = simulate_trial(seed=SEED + 1, index=index, condition=condition)
        entry = {'params': tr.params}
        fired, base = _stop_check(t=tr.wrench_t, torque=tr.torque, entry=entry)
        assert fired == pytest.approx(tr.stop_t, abs=1e-6)
        assert tr.onset_t < tr.stop_t < tr.onset_t + 3.5
        # the arm stops pushing: |dT_y| does not keep growing during 'settle'
        settle = [p for p in tr.phases if p[0] == 'settle'][0]
        dty = np.abs(tr.torque[:, 1] - base)
        late = (tr.wrench_t > settle[2] - 0.15) & (tr.wrench_t < settle[2])
        early = (tr.wrench_t > settle[1] + 0.1) & (tr.wrench_t < settle[1] + 0.15)
        assert dty[late].mean() <= dty[early].mean() + 0.3
        assert dty[late].mean() < 2 * STOP_TORQUE_NM
        # and the load returns after lift-off
        assert abs(tr.torque[-20:, 1].mean() - base) < 0.5


# -------------------------------------------------------------------------------------- bags


def test_bags_readable_with_anyreader(sim_dir, manifest):
    store = jazzy_typestore()
    for entry in manifest['trials']:
        with AnyReader([sim_dir / entry['bag']], default_typestore=store) as reader:
            topics = {c.topic: c.msgtype for c in reader.connections}
            assert topics == {'/wrist_wrench': 'geometry_msgs/msg/WrenchStamped',
                              '/audio': 'std_msgs/msg/Int16MultiArray',
                              '/contact_truth': 'std_msgs/msg/Bool'}
            assert all(c.msgdef.data for c in reader.connections)  # embedded definitions
            last = 0
            for conn, log_ns, raw in reader.messages():
                assert log_ns >= last
                last = log_ns
        meta = (sim_dir / entry['bag'] / 'metadata.yaml').read_text()
        assert 'storage_identifier: sqlite3' in meta and 'version: 9' in meta


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_bag_content_matches_trial(tmp_path, storage):
    tr = simulate_trial(seed=2, index=3, condition='odd_chunking', ft_rate=1000.0,
                        audio_rate=44100)
    bag = write_trial_bag(trial=tr, path=tmp_path / tr.name, storage=storage)
    w = read_wrench(bag)
    assert w.frame_id == 'wrist_ft_sensor_frame'
    assert np.allclose(w.t, tr.wrench_t, atol=1e-6, rtol=0)
    assert np.allclose(np.diff(w.t), 1e-3, atol=1e-6)
    assert np.array_equal(w.force, tr.force) and np.array_equal(w.torque, tr.torque)
    a = read_audio(bag)
    assert np.array_equal(a.samples, tr.audio)
    assert np.array_equal(a.chunk_ends, tr.chunk_ends)
    sizes = np.diff(np.concatenate(([0], a.chunk_ends)))
    assert sizes.min() < 50 and sizes.max() > 1000  # random chunking
    last_sample_t = tr.audio_time(a.chunk_ends - 1)
    jitter = a.log_t - last_sample_t
    assert jitter.min() >= -1e-6 and jitter.max() <= 0.02 + 1e-6
    assert np.all(np.diff(a.log_t) >= 0)
    assert a.t0(tr.audio_rate) == pytest.approx(tr.start_time, abs=0.02)
    with pytest.raises(BagError):
        write_trial_bag(trial=tr, path=bag, storage=storage)
    with pytest.raises(ConfigError):
        write_trial_bag(trial=tr, path=tmp_path / 'x', storage='rosbag1')


def test_default_chunking_and_fixed_chunk_size():
    tr = simulate_trial(seed=1, index=0)
    assert np.all(np.diff(np.concatenate(([0], tr.chunk_ends))) == 160)
    jitter = tr.chunk_log_t - tr.audio_time(tr.chunk_ends - 1)
    assert jitter.min() >= -1e-6 and jitter.max() <= 0.003 + 1e-6
    tr = simulate_trial(seed=1, index=0, chunk_size=512, condition='odd_chunking')
    assert np.all(np.diff(np.concatenate(([0], tr.chunk_ends))) == 512)


# -------------------------------------------------------------------------------------- hits


@pytest.mark.slow
def test_hit_placement_across_sets():
    trials = list(simulate_trials(n=36, seed=SEED, conditions=['all']))
    kinds = {c: [] for c in ALL}
    air_moving = total = 0
    for tr in trials:
        hit_kinds = {i.kind for i in tr.impacts}
        kinds[tr.condition].append(hit_kinds.pop() if hit_kinds else 'none')
        assert len(hit_kinds) == 0  # one kind per trial
        if tr.impacts:
            assert 1 <= len(tr.impacts) <= 3
        times = [i.t for i in tr.impacts]
        assert times == sorted(times)
        assert all(b - a >= 0.2 for a, b in zip(times, times[1:]))
        for hit in tr.impacts:
            assert tr.start_time < hit.t < tr.end_time
            assert abs(hit.t - tr.onset_t) >= 0.2
            assert hit.in_air == (not tr.onset_t <= hit.t < tr.contact_end_t)
            assert hit.amplitude > 0
            total += 1
            air_moving += tr.phase_at(hit.t) in ('accelerate', 'descend')
    for condition in ALL:
        assert sorted(kinds[condition]) == ['hand', 'hand', 'none', 'none', 'table', 'table']
    assert air_moving >= 0.35 * total  # many while the object is still in the air


def _first_hit(tr, kind, in_air):
    return next((h for h in tr.impacts if h.kind == kind and h.in_air == in_air
                 and h.t < tr.onset_t), None)


@pytest.mark.slow
def test_hand_hit_makes_sound_and_ft_pulse():
    checked = 0
    for index in range(8):
        hit = simulate_trial(seed=SEED, index=index, hits='hand')
        none = simulate_trial(seed=SEED, index=index, hits='none')
        h = _first_hit(hit, 'hand', True)
        if h is None:
            continue
        j = (hit.wrench_t >= h.t) & (hit.wrench_t < h.t + 0.06)
        assert np.abs(hit.force[j] - none.force[j]).max() > 0.5
        i = int((h.t - hit.start_time) * hit.audio_rate)
        diff = hit.audio[i:i + 1600].astype(float) - none.audio[i:i + 1600]
        assert np.abs(diff).max() > 0.02 * 32767 * hit.params['mic_gain'] * 0.5
        checked += 1
    assert checked >= 2


@pytest.mark.slow
def test_table_hit_in_air_has_no_ft_only_sound():
    checked = 0
    for index in range(8):
        hit = simulate_trial(seed=SEED, index=index, hits='table')
        none = simulate_trial(seed=SEED, index=index, hits='none')
        h = _first_hit(hit, 'table', True)
        if h is None:
            continue
        before = hit.wrench_t < hit.onset_t
        assert np.array_equal(hit.force[before], none.force[before])
        assert np.array_equal(hit.torque[before], none.torque[before])
        i = int((h.t - hit.start_time) * hit.audio_rate)
        assert np.any(hit.audio[i:i + 1600] != none.audio[i:i + 1600])
        checked += 1
    assert checked >= 2


def test_table_hit_on_resting_object_is_a_tiny_vibration():
    found = False
    for index in range(30):
        tr = simulate_trial(seed=SEED, index=index, hits='table')
        details = [d for d in tr.params['derived']['hit_details'] if not d['in_air']]
        if not details:
            continue
        assert all(0 < d['vib_n'] < 0.2 for d in details)
        found = True
        break
    assert found


# ---------------------------------------------------------------------------- condition sets


def test_every_condition_set_generated(sim_dir, manifest):
    trials = _trials(manifest)
    assert sorted(t['condition'] for t in trials.values()) == sorted(ALL)
    by_cond = {t['condition']: t for t in trials.values()}
    p = {c: t['params'] for c, t in by_cond.items()}
    assert p['heavy']['derived']['object_total_kg'] >= 0.7
    assert p['paper']['derived']['object_total_kg'] <= 0.6
    assert p['soft']['surface'] in ('cloth', 'mat', 'towel')
    assert p['paper']['surface'] in ('wood', 'stone', 'laminate')
    assert p['noisy']['babble_rms_fs'] > 0 and p['paper']['babble_rms_fs'] == 0
    assert p['odd_chunking']['chunking'] == 'random'
    sizes = np.diff(np.concatenate(([0], read_audio(sim_dir / by_cond['odd_chunking']['bag'])
                                    .chunk_ends)))
    assert len(set(sizes.tolist())) > 10
    for entry in trials.values():
        assert set(get_condition(entry['condition']).ranges) <= set(entry['params'])
    assert manifest['settings']['conditions'] == list(ALL)


@pytest.mark.slow
def test_parameters_stay_in_documented_ranges():
    for condition in ALL:
        cond = get_condition(condition)
        for index in range(3):
            params = simulate_trial(seed=7, index=index, condition=condition).params
            for name, spec in cond.ranges.items():
                value = params[name]
                if hasattr(spec, 'low'):
                    assert spec.low - 1e-12 <= value <= spec.high + 1e-12, name
                else:
                    assert (tuple(value) if isinstance(value, list) else value) in spec.options


def test_gain_set_clips_sometimes():
    clipped = [simulate_trial(seed=SEED, index=i, condition='gain').params['derived'][
        'clipped_samples'] > 0 for i in range(12)]
    assert any(clipped) and not all(clipped)


def test_condition_names():
    assert resolve_conditions(['all']) == ALL
    assert resolve_conditions(['soft,paper', 'soft']) == ('soft', 'paper')
    with pytest.raises(ConfigError):
        resolve_conditions(['kitchen'])
    with pytest.raises(ConfigError):
        simulate_trial(seed=0, index=0, condition='kitchen')
    with pytest.raises(ConfigError):
        simulate_trial(seed=-1, index=0)
    with pytest.raises(ConfigError):
        simulate_trial(seed=0, index=0, ft_rate=10.0)
    table = ranges_markdown()
    assert all(f'`{name}`' in table for name in CONDITION_SETS['paper'].ranges)


# ---------------------------------------------------------------------------------- commands


def test_simulate_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / 'run'
    assert simulate_main([str(out), '--trials', '1', '--quiet']) == 0
    assert simulate_main([str(out), '--trials', '1', '--quiet']) == 1
    assert 'overwrite' in capsys.readouterr().err
    assert simulate_main([str(out), '--trials', '1', '--quiet', '--overwrite',
                          '--storage', 'mcap']) == 0
    assert (out / 'trial_0000' / 'trial_0000.mcap').is_file()
    with pytest.raises(SystemExit):
        simulate_main([str(out), '--conditions', 'kitchen'])


def test_simulate_reuse_keeps_the_same_trials_and_refuses_others(tmp_path, capsys):
    out = tmp_path / 'run'
    args = [str(out), '--trials', '2', '--seed', '3', '--conditions', 'paper']
    assert simulate_main([*args, '--quiet']) == 0
    bag = out / 'trial_0001'
    written = {p: p.stat().st_mtime_ns for p in sorted(out.rglob('*'))}
    capsys.readouterr()

    # the same command with --reuse: nothing simulated, nothing touched
    assert simulate_main([*args, '--reuse']) == 0
    assert 'already holds these 2 trials; reused' in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in sorted(out.rglob('*'))} == written

    # other trials (another seed): refused, and OUT_DIR left as it was
    assert simulate_main([*args[:-4], '--seed', '4', '--conditions', 'paper', '--reuse',
                          '--quiet']) == 1
    assert 'holds other simulated trials (other seed)' in capsys.readouterr().err
    assert read_manifest(out)['settings']['seed'] == 3

    # a bag its manifest lists is gone: refused, then simulated again with --overwrite
    shutil.rmtree(bag)
    assert simulate_main([*args, '--reuse', '--quiet']) == 1
    assert '(other bags)' in capsys.readouterr().err
    assert simulate_main([*args, '--reuse', '--overwrite', '--quiet']) == 0
    assert bag.is_dir()
    # and with --overwrite other trials are replaced
    assert simulate_main([*args[:-4], '--seed', '4', '--conditions', 'paper', '--reuse',
                          '--overwrite', '--quiet']) == 0
    assert read_manifest(out)['settings']['seed'] == 4
    # an unreadable manifest: a clear error, or replaced with --overwrite
    (out / 'manifest.json').write_text('{')
    assert simulate_main([*args, '--reuse', '--quiet']) == 1
    assert 'cannot read manifest' in capsys.readouterr().err
    assert simulate_main([*args, '--reuse', '--overwrite', '--quiet']) == 0
    assert read_manifest(out)['settings']['seed'] == 3


def test_reuse_refuses_trials_of_another_simulator_code(tmp_path, capsys):
    # the manifest records the simulator's fingerprint: trials simulated before an edit to
    # the simulator (or before the fingerprint existed) are not reused as if they were new
    out = tmp_path / 'run'
    args = [str(out), '--trials', '2', '--seed', '3', '--conditions', 'paper']
    assert simulate_main([*args, '--quiet']) == 0
    assert read_manifest(out)['simulator'] == bag_writer.simulator_fingerprint()
    manifest = json.loads((out / 'manifest.json').read_text())
    for held in ('0123456789abcdef', None):
        if held is None:
            manifest.pop('simulator')
        else:
            manifest['simulator'] = held
        (out / 'manifest.json').write_text(json.dumps(manifest))
        capsys.readouterr()
        assert simulate_main([*args, '--reuse', '--quiet']) == 1
        assert '(other simulator)' in capsys.readouterr().err
        assert simulate_main([*args, '--reuse', '--overwrite', '--quiet']) == 0
        assert read_manifest(out)['simulator'] == bag_writer.simulator_fingerprint()
        manifest = json.loads((out / 'manifest.json').read_text())


def test_the_simulator_fingerprint_follows_every_edit_of_its_code(tmp_path, monkeypatch):
    sim = Path(bag_writer.__file__).resolve().parent
    for source in sim.glob('*.py'):
        shutil.copy(source, tmp_path / source.name)
    fingerprint = bag_writer.simulator_fingerprint.__wrapped__
    monkeypatch.setattr(bag_writer, '__file__', str(tmp_path / 'bag_writer.py'))
    assert fingerprint() == bag_writer.simulator_fingerprint()
    with open(tmp_path / 'loads.py', 'a') as handle:
        handle.write('# an edit\n')
    edited = fingerprint()
    assert edited != bag_writer.simulator_fingerprint() and len(edited) == 16


def test_settings_left_out_by_older_manifests_take_their_defaults():
    wanted = {'seed': 1, 'trials': 4, 'ft_rate': 100.0, 'tared': 'family', 'hits': None}
    older = {'seed': 1, 'trials': 4, 'ft_rate': 100.0, 'hits': None}   # before --tared
    assert differing_settings(held=older, wanted=wanted) == ()
    assert differing_settings(held=older, wanted={**wanted, 'tared': 'all'}) == ('tared',)
    assert differing_settings(held={**older, 'brushes': 'lifting'}, wanted=wanted) == ()
    assert differing_settings(held={**older, 'brushes': 'friction'}, wanted=wanted) == (
        'brushes',)
    # F/T rates: equal by default, within a relative tolerance when one is given
    assert differing_settings(held={**older, 'ft_rate': 100.5}, wanted=wanted) == ('ft_rate',)
    assert differing_settings(held={**older, 'ft_rate': 100.5}, wanted=wanted,
                              ft_rate_tolerance=0.01) == ()
    assert differing_settings(held={**older, 'seed': 2, 'ft_rate': 'x'}, wanted=wanted) == (
        'ft_rate', 'seed')


def test_manifest_schema(manifest):
    entry = manifest['trials'][0]
    for key in ('name', 'bag', 'condition', 'seed', 'index', 'start_time', 'end_time',
                'onset_t', 'onset_end_t', 'contact_end_t', 'stop_t', 'phases', 'impacts',
                'params'):
        assert key in entry
    json.dumps(manifest, allow_nan=False)
    assert manifest['format'] == 'contact_detector.sim.manifest'
    assert manifest['settings']['events'] == 'family'
    assert manifest['settings']['tared'] == 'family'


@pytest.mark.slow
def test_plot_writes_png(sim_dir, tmp_path):
    out = tmp_path / 'fig.png'
    assert plot_main([str(sim_dir / 'trial_0000'), '-o', str(out)]) == 0
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert plot_main([str(sim_dir), '-o', str(out)]) == 1  # six bags: ambiguous


def test_docs_table_matches_the_ranges():
    docs = Path(__file__).resolve().parents[3] / 'docs' / 'simulator.md'
    assert ranges_markdown() in docs.read_text(encoding='utf-8')


# ------------------------------------------------------------------------------------ families


def _load_along_up(tr):
    """Measured force change along world up against the pre-approach baseline, N (= N(t))."""
    d = tr.params['derived']
    return (tr.force - np.asarray(d['baseline_force_n'])) @ np.asarray(d['up_in_sensor'])


def _window_mean(tr, x, t0, t1):
    sel = (tr.wrench_t >= t0) & (tr.wrench_t < t1)
    return np.mean(x[sel], axis=0)


def test_aliases_keep_all_as_the_original_six():
    assert resolve_conditions(['all']) == ORIGINAL_SETS
    assert resolve_conditions(['families']) == FAMILY_SETS
    assert resolve_conditions(['wide']) == ORIGINAL_SETS + FAMILY_SETS
    assert set(CONDITION_SETS) == set(ORIGINAL_SETS + FAMILY_SETS + REAL_SOUND_SETS + LATER_SETS)
    # the original sets draw no family parameters: their trials are those of before
    paper = simulate_trial(seed=SEED, index=0, condition='paper')
    assert 'family' not in paper.params and 'stop_rule' not in paper.params['derived']


@pytest.mark.parametrize('condition', FAMILY_SETS)
def test_family_deterministic_and_onset_is_first_touch(condition):
    a = simulate_trial(seed=SEED, index=3, condition=condition)
    b = simulate_trial(seed=SEED, index=3, condition=condition)
    for name in ('force', 'torque', 'audio', 'chunk_ends', 'wrench_log_t'):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert a.params == b.params and a.impacts == b.impacts and a.onset_t == b.onset_t
    c = simulate_trial(seed=SEED + 1, index=3, condition=condition)
    assert not np.array_equal(a.force[:100], c.force[:100])
    assert set(a.params['family']) == set(get_condition('paper').family) | set(
        a.params['family'])
    # the load moves to the table from onset_t on, not before: compare the 40 ms before the
    # onset with the descent before it, and the load at the stop
    tr = simulate_trial(seed=SEED, index=3, condition=condition, hits='none')
    n = _load_along_up(tr)
    noise = tr.params['force_noise_n']
    before = _window_mean(tr, n, tr.onset_t - 0.04, tr.onset_t)
    descent = _window_mean(tr, n, tr.onset_t - 0.4, tr.onset_t - 0.1)
    assert abs(before - descent) < 0.25 + 2 * noise
    settled = _window_mean(tr, n, tr.stop_t + 0.05, tr.stop_t + 0.2)
    assert settled > before + 0.8
    assert tr.onset_t < tr.stop_t < tr.contact_end_t


def test_geometry_gravity_along_many_axes_tared_and_lever_arms():
    axes, levers, tared, untared = set(), [], 0, 0
    for index in range(10):
        tr = simulate_trial(seed=SEED, index=index, condition='geometry', hits='none')
        d, fam = tr.params['derived'], tr.params['family']
        up = np.asarray(d['up_in_sensor'])
        axes.add((int(np.argmax(np.abs(up))), bool(up[np.argmax(np.abs(up))] > 0)))
        levers.append(float(np.linalg.norm(d['lever_contact_m'])))
        assert fam['frame'] in ('axis', 'random') and d['stop_rule'] in ('force', 'wrench')
        rest = _window_mean(tr, tr.force, tr.start_time + 0.2, tr.phases[1][1] - 0.2)
        weight = (d['object_total_kg'] + tr.params['hand_mass_kg']) * G
        if fam['tared']:
            tared += 1
            assert np.linalg.norm(rest) < 0.1  # starts near zero
        else:
            untared += 1
            # the static load points along -up (gravity), up to the sensor's bias
            assert np.linalg.norm(rest + weight * up) <= tr.params['force_bias_n'] + 0.5
        # the stop rule: |F - F_base| or |T - T_base| (30 ms average) crossed its threshold
        j = int(np.searchsorted(tr.wrench_t, tr.stop_t))
        df = np.linalg.norm(tr.force[j - 2:j + 1].mean(axis=0) - d['baseline_force_n'])
        dt = np.linalg.norm(tr.torque[j - 2:j + 1].mean(axis=0) - d['baseline_torque_nm'])
        assert df >= d['stop_threshold_n'] - 1e-9 or (
            d['stop_rule'] == 'wrench' and dt >= d['stop_threshold_torque_nm'] - 1e-9)
    assert len({a for a, _ in axes}) == 3 and len(axes) >= 4  # gravity along x, y and z
    assert tared and untared
    assert 0.02 <= min(levers) and max(levers) <= 0.30 + 0.5 * 0.14
    assert max(levers) / min(levers) > 3


def test_spring_load_passes_through_the_weight_or_stops_partway():
    partial = beyond = crossed_zero = 0
    for index in range(10):
        tr = simulate_trial(seed=SEED, index=index, condition='spring', hits='none')
        d, fam = tr.params['derived'], tr.params['family']
        assert fam['contact_model'] == 'spring' and d['stop_rule'] == 'load'
        n = _load_along_up(tr)
        weight = d['object_total_kg'] * G
        at_stop = float(np.interp(tr.stop_t, tr.wrench_t, n))
        assert at_stop >= 0.7 * d['stop_threshold_n']
        settled = _window_mean(tr, n, tr.stop_t + 0.1, tr.stop_t + 0.25)
        if fam['stop_load_frac'] < 0.6:
            partial += settled < weight
        elif fam['stop_load_frac'] > 1.5:
            beyond += settled > 1.2 * weight
            if fam['tool_compensated']:
                # the measured load (the object's weight alone) reverses through zero
                f_up = tr.force @ np.asarray(d['up_in_sensor'])
                base = float(np.asarray(d['baseline_force_n']) @ d['up_in_sensor'])
                crossed_zero += base < 0 < _window_mean(tr, f_up, tr.stop_t + 0.1,
                                                        tr.stop_t + 0.25)
    assert partial >= 1 and beyond >= 1 and crossed_zero >= 1


@pytest.mark.slow
def test_slow_partial_moves_part_of_the_weight_slowly():
    partial, tared = 0, set()
    for index in range(6):
        tr = simulate_trial(seed=SEED, index=index, condition='slow_partial', hits='none')
        d, fam = tr.params['derived'], tr.params['family']
        assert fam['contact_model'] == 'compliant' and d['stop_rule'] == 'load'
        assert 0.1 <= d['weight_transfer_s'] <= 1.1
        n = _load_along_up(tr)
        weight = d['object_total_kg'] * G
        assert weight <= 0.4 * G
        # slow: under a third of the weight on the table 60 ms after the onset
        assert _window_mean(tr, n, tr.onset_t + 0.04, tr.onset_t + 0.06) < weight / 3
        # the arm stops with part of the weight (or about all of it) on the table, never
        # pressing on as 'compliant' does
        settled = _window_mean(tr, n, tr.stop_t + 0.3, tr.stop_t + 0.4)
        assert 0.3 * weight <= settled <= 1.3 * weight
        partial += settled < 0.85 * weight
        tared.add(fam['tared'])
    assert partial >= 1 and tared == {False, True}


@pytest.mark.slow
def test_compliant_transfer_is_slow_and_approach_speeds_vary():
    for index in range(4):
        tr = simulate_trial(seed=SEED, index=index, condition='compliant', hits='none')
        d = tr.params['derived']
        assert 0.08 <= d['weight_transfer_s'] <= 0.55
        n = _load_along_up(tr)
        weight = d['object_total_kg'] * G
        # the measured load has not reached the weight 60 ms after the onset
        assert _window_mean(tr, n, tr.onset_t + 0.04, tr.onset_t + 0.06) < weight
    speeds, decel = [], 0
    for index in range(8):
        tr = simulate_trial(seed=SEED, index=index, condition='approach', hits='none')
        d, p = tr.params['derived'], tr.params
        speeds.append(d['contact_speed_mps'])
        if tr.params['family']['decel']:
            decel += 1
            assert 0.005 <= d['contact_speed_mps'] < p['descent_speed_mps']
        else:
            assert d['contact_speed_mps'] == p['descent_speed_mps']
    assert decel >= 1 and min(speeds) < 0.02 < max(speeds)


@pytest.mark.slow
def test_exogenous_events_in_the_air():
    trials = list(simulate_trials(n=8, seed=SEED, conditions=['exogenous']))
    kinds = {i.kind for tr in trials for i in tr.impacts}
    assert {'touch', 'brush', 'setdown'} <= kinds
    assert [tr.params['derived']['hits'] for tr in trials[:4]] == [
        'mixed', 'touch', 'brush', 'setdown']
    moving = [i for tr in trials for i in tr.impacts
              if i.in_air and tr.phase_at(i.t) in ('accelerate', 'descend')]
    assert {i.kind for i in moving} >= {'touch', 'brush'}
    checked = set()
    for index in range(8):
        if len(checked) == 3:
            break
        none = simulate_trial(seed=SEED, index=index, condition='exogenous', hits='none')
        for kind in sorted({'touch', 'brush', 'setdown'} - checked):
            tr = simulate_trial(seed=SEED, index=index, condition='exogenous', hits=kind)
            details = [h for h in tr.params['derived']['hit_details'] if h['in_air']
                       and tr.phase_at(h['t']) in ('accelerate', 'descend')]
            if not details:
                continue
            h = details[0]
            sel = (tr.wrench_t >= h['t']) & (tr.wrench_t < h['t'] + h.get('duration_s', 0.1))
            df = np.abs(tr.force[sel] - none.force[sel]).max()
            if kind == 'setdown':
                # a sound, no load change at the sensor while the object is in the air
                assert df == 0.0
                i0 = int((h['t'] - tr.start_time) * tr.audio_rate)
                seg = slice(i0, i0 + int(0.05 * tr.audio_rate))
                assert np.abs(tr.audio[seg].astype(float) - none.audio[seg]).max() > 100
            elif kind == 'brush' or h['on_object']:
                assert df > 0.2  # the wrist feels the push or the friction
            else:
                continue  # a touch on the arm: look for one on the object
            checked.add(kind)
    assert checked == {'touch', 'brush', 'setdown'}


@pytest.mark.slow
def test_events_everywhere_puts_touches_brushes_and_setdowns_in_every_family():
    n = 96  # two rounds of the four-kind cycle over the twelve sets
    family = list(simulate_trials(n=n, seed=SEED, conditions=['wide']))
    everywhere = list(simulate_trials(n=n, seed=SEED, conditions=['wide'], events='everywhere'))
    assert get_condition('paper').cycle(events='everywhere') == ('hand', 'table', 'none',
                                                                 'mixed')
    assert get_condition('exogenous').cycle(events='everywhere') == \
        get_condition('exogenous').hit_cycle
    same = 0
    for a, b in zip(family, everywhere):
        assert a.condition == b.condition and a.onset_t == b.onset_t
        if a.params['derived']['hits'] == b.params['derived']['hits']:
            # a trial of the same kind is the trial '--events family' gives
            same += 1
            assert a.impacts == b.impacts
            assert np.array_equal(a.force, b.force) and np.array_equal(a.audio, b.audio)
    assert same >= n // 3
    assert sum(tr.params['derived']['hits'] == 'mixed' for tr in everywhere
               if tr.condition != 'exogenous') == 2 * 11
    others = [tr for tr in everywhere if tr.condition != 'exogenous']
    kinds = {i.kind for tr in others for i in tr.impacts}
    assert {'touch', 'brush', 'setdown'} <= kinds
    assert {i.kind for tr in family if tr.condition != 'exogenous'
            for i in tr.impacts} <= {'hand', 'table'}
    with_brush = {tr.condition for tr in others if any(i.kind == 'brush' for i in tr.impacts)}
    assert len(with_brush) >= 4  # not one family's quirk


@pytest.mark.slow
def test_cli_hits_gives_every_trial_that_kind_and_the_manifest_says_so(tmp_path):
    out = tmp_path / 'mixed'
    assert simulate_main([str(out), '--trials', '3', '--seed', '4', '--conditions', 'paper',
                          '--events', 'everywhere', '--hits', 'mixed', '--quiet']) == 0
    manifest = read_manifest(out)
    assert manifest['settings']['events'] == 'everywhere'
    assert manifest['settings']['hits'] == 'mixed'
    assert [t['params']['derived']['hits'] for t in manifest['trials']] == ['mixed'] * 3
    # without --hits the set's cycle gives hand, table, none
    assert simulate_main([str(tmp_path / 'x'), '--trials', '3', '--seed', '4', '--conditions',
                          'paper', '--quiet']) == 0
    cycled = read_manifest(tmp_path / 'x')['trials']
    assert [t['params']['derived']['hits'] for t in cycled] == ['hand', 'table', 'none']


@pytest.mark.parametrize('option', ['events', 'tared'])
def test_unknown_event_or_tare_mode_is_refused(tmp_path, capsys, option):
    with pytest.raises(ConfigError, match=f'{option} must be one of'):
        simulate_trial(seed=1, index=0, **{option: 'sometimes'})
    with pytest.raises(SystemExit) as exc:
        simulate_main([str(tmp_path / 'x'), f'--{option}', 'sometimes'])
    assert exc.value.code == 2
    assert 'invalid choice' in capsys.readouterr().err
    assert not (tmp_path / 'x').exists()


def _rest_wrench(tr):
    """Force (N) and torque (N m) samples at rest before the lift (the tare window)."""
    sel = (tr.wrench_t >= tr.start_time + 0.2) & (tr.wrench_t < tr.phases[1][1] - 0.2)
    return tr.force[sel], tr.torque[sel]


def test_tared_all_zeroes_every_sensor_at_rest_and_changes_nothing_else():
    n = len(resolve_conditions(['wide']))
    family = list(simulate_trials(n=n, seed=SEED, conditions=['wide'], hits='none'))
    tared = list(simulate_trials(n=n, seed=SEED, conditions=['wide'], hits='none',
                                 tared='all'))
    assert TARED_MODES == ('family', 'everywhere', 'all', 'none')
    for a, b in zip(family, tared):
        assert b.params['family']['tared'] is True, b.condition
        if a.condition == 'geometry':
            # geometry's other family draws stay what 'family' drew
            assert {k: v for k, v in a.params['family'].items() if k != 'tared'} == \
                {k: v for k, v in b.params['family'].items() if k != 'tared'}
        else:
            assert 'family' not in a.params or a.params['family']['tared'] is False
        (fa, _), (fb, tb) = _rest_wrench(a), _rest_wrench(b)
        # the tared sensor reads noise around 0 at rest; the untared one the held load
        rest_a, rest_b = np.linalg.norm(fa, axis=1).mean(), np.linalg.norm(fb, axis=1).mean()
        assert rest_b < 0.5 and rest_b * 10 < rest_a, (a.condition, rest_a, rest_b)
        assert np.linalg.norm(fb.mean(axis=0)) < 0.05 and np.linalg.norm(tb.mean(axis=0)) < 0.01
        # a tare subtracts a constant: up to one quantisation step, the same wrench
        j = int(np.searchsorted(a.wrench_t, a.onset_t))
        q = a.params['force_quant_n']
        assert np.ptp(b.force[:j] - a.force[:j], axis=0).max() <= q + 1e-9
        assert a.onset_t == b.onset_t and a.phases[:5] == b.phases[:5]


def test_tared_none_unzeroes_the_sensors_a_family_tares_and_changes_nothing_else(tmp_path):
    # slow_partial and geometry draw tared or not: 'none' gives the untared twin of each trial
    n = 8
    family = list(simulate_trials(n=n, seed=SEED, conditions=['slow_partial', 'geometry'],
                                  hits='none'))
    untared = list(simulate_trials(n=n, seed=SEED, conditions=['slow_partial', 'geometry'],
                                   hits='none', tared='none'))
    assert {a.params['family']['tared'] for a in family} == {False, True}
    for a, b in zip(family, untared):
        assert b.params['family']['tared'] is False, b.condition
        assert {k: v for k, v in a.params['family'].items() if k != 'tared'} == \
            {k: v for k, v in b.params['family'].items() if k != 'tared'}
        fb, _ = _rest_wrench(b)
        # the untared sensor reads the held load at rest (hand and object: several newtons)
        assert np.linalg.norm(fb, axis=1).mean() > 2.0, b.condition
        if a.params['family']['tared']:
            # the same wrench up to the tare (a constant) and one quantisation step
            j = int(np.searchsorted(a.wrench_t, a.onset_t))
            q = a.params['force_quant_n']
            assert np.ptp(b.force[:j] - a.force[:j], axis=0).max() <= q + 1e-9
            assert a.onset_t == b.onset_t and np.array_equal(a.audio, b.audio)
        else:
            assert np.array_equal(a.force, b.force) and np.array_equal(a.audio, b.audio)
    # the command line takes it and records it
    assert simulate_main([str(tmp_path / 'x'), '--trials', '1', '--conditions', 'slow_partial',
                          '--tared', 'none', '--quiet']) == 0
    manifest = read_manifest(tmp_path / 'x')
    assert manifest['settings']['tared'] == 'none'
    assert manifest['trials'][0]['params']['family']['tared'] is False


def test_sensor_offset_scales_the_never_zeroed_offset_and_changes_nothing_else(tmp_path):
    n = 6
    base = list(simulate_trials(n=n, seed=SEED, conditions=['paper', 'slow_partial'],
                                hits='none', tared='none'))
    big = list(simulate_trials(n=n, seed=SEED, conditions=['paper', 'slow_partial'],
                               hits='none', tared='none', sensor_offset=(30.0, 1.5)))
    for a, b in zip(base, big):
        # the same quantile of [0, 30] N as of the set's [0, 3] N: ten times the length
        assert b.params['force_bias_n'] == pytest.approx(10 * a.params['force_bias_n'])
        assert b.params['torque_bias_nm'] == pytest.approx(5 * a.params['torque_bias_nm'])
        assert a.onset_t == b.onset_t and np.array_equal(a.audio, b.audio)
        # before the contact the wrench differs by a constant vector of nine times the
        # set's offset, up to one quantisation step
        j = int(np.searchsorted(a.wrench_t, a.onset_t))
        diff = b.force[:j] - a.force[:j]
        assert np.ptp(diff, axis=0).max() <= a.params['force_quant_n'] + 1e-9
        assert np.linalg.norm(diff.mean(axis=0)) == pytest.approx(
            9 * a.params['force_bias_n'], abs=a.params['force_quant_n'] * 2)
    # a tared sensor reads no offset either way
    tared = list(simulate_trials(n=2, seed=SEED, conditions=['paper'], tared='all',
                                 sensor_offset=(30.0, 1.5)))
    for trial in tared:
        fb, _ = _rest_wrench(trial)
        assert np.linalg.norm(fb, axis=1).mean() < 1.0
    with pytest.raises(ConfigError, match='sensor_offset'):
        simulate_trial(seed=SEED, index=0, sensor_offset=(-1.0, 0.1))
    # the command line takes it and records it
    assert simulate_main([str(tmp_path / 'x'), '--trials', '1', '--tared', 'none',
                          '--sensor-offset', '30,1.5', '--quiet']) == 0
    manifest = read_manifest(tmp_path / 'x')
    assert manifest['settings']['sensor_offset'] == [30.0, 1.5]
    assert 0.0 <= manifest['trials'][0]['params']['force_bias_n'] <= 30.0


@pytest.mark.slow
def test_tared_everywhere_draws_both_and_an_untared_draw_is_the_family_trial():
    n = 48  # four trials of each of the twelve sets
    family = list(simulate_trials(n=n, seed=SEED, conditions=['wide']))
    everywhere = list(simulate_trials(n=n, seed=SEED, conditions=['wide'], tared='everywhere'))
    drawn = {}
    for a, b in zip(family, everywhere):
        assert a.condition == b.condition and a.onset_t == b.onset_t
        is_tared = b.params['family']['tared']
        drawn.setdefault(b.condition, set()).add(is_tared)
        if not is_tared or b.condition == 'geometry':
            # an untared draw (and every geometry trial) is the trial 'family' gives
            assert a.impacts == b.impacts and a.stop_t == b.stop_t
            for name in ('force', 'torque', 'audio', 'chunk_ends', 'wrench_log_t'):
                assert np.array_equal(getattr(a, name), getattr(b, name)), (b.condition, name)
            assert {k: v for k, v in a.params.items() if k != 'family'} == \
                {k: v for k, v in b.params.items() if k != 'family'}
        else:
            force, _ = _rest_wrench(b)
            assert np.linalg.norm(force.mean(axis=0)) < 0.05
    others = {name: kinds for name, kinds in drawn.items() if name != 'geometry'}
    assert len(others) == 11 and set().union(*others.values()) == {False, True}
    assert sum(kinds == {False, True} for kinds in others.values()) >= 5  # not one set's quirk


@pytest.mark.parametrize('flag, mode', [('tared', 'all'), ('contact-sound', 'everywhere'),
                                        ('brushes', 'friction')])
def test_cli_mode_is_in_the_manifest(tmp_path, flag, mode):
    out = tmp_path / 'set'
    assert simulate_main([str(out), '--trials', '2', '--seed', '4', '--conditions', 'paper',
                          f'--{flag}', mode, '--quiet']) == 0
    manifest = read_manifest(out)
    assert manifest['settings'][flag.replace('-', '_')] == mode
    family = [t['params'].get('family', {}) for t in manifest['trials']]
    if flag == 'tared':
        assert [f['tared'] for f in family] == [True, True]
        force = read_wrench(out / 'trial_0000').force
        assert np.linalg.norm(force[20:60].mean(axis=0)) < 0.05  # tared at rest
    elif flag == 'contact-sound':
        assert all(-24.0 <= f['contact_sound_db'] <= 0.0 for f in family)


def test_a_friction_brush_pushes_sideways_and_rubs_against_the_motion():
    rng = np.random.default_rng(3)
    ratios = []
    for seed in range(200):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # any sensor orientation
        world = np.array([rng.normal() * 0.7, rng.normal() * 0.7, 1.0])
        planned = Hit(kind='brush', anchor='abs', t=1.0, sound_amp=0.01, force_n=2.0,
                      direction=tuple(q @ (world / np.linalg.norm(world))), seed=seed)
        brush = friction_brush(planned, R=q)
        force = brush.force_n * (q.T @ np.asarray(brush.direction))  # N, world frame
        # the planned force is the friction along the motion (up: the arm moves down) ...
        assert force[2] == pytest.approx(2.0)
        side = force[:2]
        # ... made by a push along the planned sideways direction, with mu in 0.2-1.0
        assert np.dot(side, world[:2]) == pytest.approx(np.linalg.norm(side)
                                                        * np.linalg.norm(world[:2]))
        ratios.append(force[2] / np.linalg.norm(side))
        assert brush.t == planned.t and brush.seed == planned.seed
    assert 0.2 <= min(ratios) < 0.3 and 0.8 < max(ratios) <= 1.0
    assert friction_brush(planned, R=q) == brush  # a stream of the brush's own


def test_friction_brushes_change_only_the_brushes():
    changed = 0
    for index in range(3):
        a = simulate_trial(seed=SEED, index=index, condition='exogenous', hits='brush')
        b = simulate_trial(seed=SEED, index=index, condition='exogenous', hits='brush',
                           brushes='friction')
        assert a.onset_t == b.onset_t and a.impacts == b.impacts
        assert np.array_equal(a.audio, b.audio)  # the same scraping sound
        first = min(i.t for i in a.impacts if i.kind == 'brush')
        j = int((first - a.start_time) * a.ft_rate)
        assert np.array_equal(a.force[:j], b.force[:j])  # nothing changes before the brush
        changed += not np.allclose(a.force[j:j + 20], b.force[j:j + 20])
    assert changed == 3
    with pytest.raises(ConfigError, match='brushes'):
        simulate_trial(seed=SEED, index=0, brushes='sticky')


def test_contact_sound_everywhere_only_quietens_the_contact():
    quieter = 0
    for index in range(4):
        a = simulate_trial(seed=SEED, index=index, condition='paper', hits='none')
        b = simulate_trial(seed=SEED, index=index, condition='paper', hits='none',
                           contact_sound='everywhere')
        db = b.params['family']['contact_sound_db']
        assert -24.0 <= db <= 0.0
        assert a.onset_t == b.onset_t
        for name in ('force', 'torque', 'chunk_ends'):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
        onset = int((a.onset_t - a.start_time) * a.audio_rate)
        # the microphone hears the same room up to the contact, then a quieter contact
        assert np.array_equal(a.audio[:onset], b.audio[:onset])
        after = slice(onset, onset + a.audio_rate // 20)
        loud, soft = (float(np.sqrt(np.mean(np.square(x[after], dtype=float))))
                      for x in (a.audio, b.audio))
        assert soft <= loud * 1.001
        quieter += soft < 0.9 * loud
    assert quieter >= 2
    # a family that draws its own contact level keeps it
    fam = simulate_trial(seed=SEED, index=0, condition='quiet_contact', hits='none')
    same = simulate_trial(seed=SEED, index=0, condition='quiet_contact', hits='none',
                          contact_sound='everywhere')
    assert np.array_equal(fam.audio, same.audio)
    with pytest.raises(ConfigError, match='contact_sound'):
        simulate_trial(seed=SEED, index=0, contact_sound='loud')


def test_quiet_contact_and_ego_noise_families():
    families, noise_only = set(), 0
    for index in range(8):
        tr = simulate_trial(seed=SEED, index=index, condition='quiet_contact', hits='none')
        fam, d = tr.params['family'], tr.params['derived']
        families.add(fam['ego_family'])
        loud = tr.params['contact_amp_fs'] * tr.params['hardness'] * (
            d['contact_speed_mps'] / 0.04)
        assert d['contact_peak_fs'] <= loud * 10 ** (-15 / 20) + 1e-12
        if fam['mic_mode'] == 'noise_only':
            noise_only += 1
            # the audio carries nothing of the contact: no power jump after the onset
            i0 = int((tr.onset_t - tr.start_time) * tr.audio_rate)
            n = int(0.1 * tr.audio_rate)
            pre = np.mean(tr.audio[i0 - n:i0].astype(float) ** 2)
            post = np.mean(tr.audio[i0:i0 + n].astype(float) ** 2)
            assert post < 2 * pre
        if fam['ego_family'] == 'servo':
            assert d['ego_servo_bursts']
    assert noise_only >= 1 and len(families) >= 3


# ---------------------------------------------------------------------- real recorded sounds


@pytest.fixture(scope='module')
def real_bank():
    """Return the fetched sound bank; skip (outside CI) when it has not been fetched."""
    if not sound_bank.bank_available():
        why = (f'the real sound bank is not in {sound_bank.bank_dir()}: run '
               f'{sound_bank.FETCH_COMMAND} (tools/setup.sh does; needs apt-get)')
        if os.environ.get('CI'):
            pytest.fail(why + ' -- CI must have it')
        pytest.skip(why)
    return sound_bank.load_bank()


def _lag_of(audio: np.ndarray, clip: np.ndarray, expect: int, search: int) -> int:
    """Lag (samples, relative to ``expect``) where ``clip`` best matches ``audio``."""
    seg = audio[expect - search:expect + search + len(clip)].astype(float)
    corr = np.correlate(seg - seg.mean(), clip, mode='valid')
    energy = np.sqrt(np.convolve(seg ** 2, np.ones(len(clip)), mode='valid'))
    return int(np.argmax(corr / np.maximum(energy, 1e-9))) - search


def test_real_sounds_without_bank_is_a_clear_config_error(tmp_path, monkeypatch):
    monkeypatch.setenv(sound_bank.SOUNDS_ENV, str(tmp_path / 'none'))
    with pytest.raises(ConfigError, match='tools/fetch_sounds.sh'):
        simulate_trial(seed=SEED, index=0, condition='real_sounds')
    # the other sets never need it
    simulate_trial(seed=SEED, index=0, condition='quiet_contact')


def test_real_sounds_deterministic_and_ft_is_the_simulators(real_bank):
    a = simulate_trial(seed=SEED, index=2, condition='real_sounds')
    b = simulate_trial(seed=SEED, index=2, condition='real_sounds')
    for name in ('force', 'torque', 'audio', 'chunk_ends', 'wrench_log_t'):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert a.params == b.params and a.impacts == b.impacts
    d = a.params['derived']
    assert d['sound_bank'] == real_bank.fingerprint
    assert d['real_clips'][0]['clip'].startswith('contact__')
    assert d['real_room_clip'].startswith('room__') and d['real_ego_clip'].startswith('ego__')
    c = simulate_trial(seed=SEED + 1, index=2, condition='real_sounds')
    assert not np.array_equal(a.audio[:4000], c.audio[:4000])
    # the hit plan changes only the hits: same contact recording, same F/T before any hit
    quiet = simulate_trial(seed=SEED, index=2, condition='real_sounds', hits='none')
    assert quiet.params['derived']['real_clips'][0] == d['real_clips'][0]
    assert quiet.onset_t == a.onset_t and quiet.stop_t == a.stop_t


@pytest.mark.parametrize('audio_rate', [16000, 44100])
def test_real_contact_starts_at_the_onset_and_knocks_where_the_impacts_say(
        real_bank, audio_rate):
    checked_contacts = checked_knocks = 0
    for index in range(8):
        tr = simulate_trial(seed=SEED, index=index, condition='real_sounds',
                            audio_rate=audio_rate)
        d = tr.params['derived']
        rate, delay = tr.audio_rate, d['sound_delay_s']
        clips = {c.name: c for role in sound_bank.ROLES for c in real_bank.clips[role]}
        contact = d['real_clips'][0]
        assert contact['t'] == pytest.approx(tr.onset_t - tr.start_time + delay, abs=1e-6)
        knocks = [c for c in d['real_clips'][1:] if c['role'] in ('hand', 'table')]
        # knocks are where the impacts list says (plus the sound's delay)
        hand_table = [im for im in tr.impacts if im.kind in ('hand', 'table')]
        assert [k['t'] for k in knocks] == pytest.approx(
            [im.t - tr.start_time + delay for im in hand_table], abs=1e-6)
        assert [k['role'] for k in knocks] == [im.kind for im in hand_table]
        for item in [contact] + knocks:
            data, onset = real_bank.at_rate(clips[item['clip']], rate)
            expect = int(round(item['t'] * rate)) - onset
            window = data[:int(0.04 * rate)]
            if item['peak_fs'] < 0.05:
                continue  # too close to the noise floor to locate by correlation
            assert abs(_lag_of(tr.audio, window, expect, int(0.02 * rate))) <= 1, item
            if item is contact:
                checked_contacts += 1
            else:
                checked_knocks += 1
    assert checked_contacts >= 3 and checked_knocks >= 3


def test_real_sound_levels_are_sane(real_bank):
    for index in range(6):
        tr = simulate_trial(seed=SEED, index=index, condition='real_sounds', hits='none')
        d = tr.params['derived']
        x = tr.audio.astype(float) - tr.params['mic_dc_lsb']
        rest = x[:int(0.8 * tr.audio_rate)] / 32767.0
        room = tr.params['family']['real_room_rms_fs'] * tr.params['mic_gain']
        # the room background near its drawn level (a recording is not stationary: a 0.8 s
        # piece of it has 0.5-2x its RMS over the whole recording)
        assert 0.5 * room < np.sqrt(np.mean(rest ** 2)) < 2.0 * room
        # no clipping (the family keeps the paper's microphone gain) and the contact peak
        # within its drawn level plus the background
        assert d['clipped_samples'] == 0 and np.abs(tr.audio).max() < 32767
        i = int(round(d['real_clips'][0]['t'] * tr.audio_rate))
        peak = np.abs(x[i:i + int(0.1 * tr.audio_rate)]).max() / 32767.0
        gain = tr.params['mic_gain']
        assert 0.6 * d['contact_peak_fs'] * gain < peak
        assert peak < 1.3 * d['contact_peak_fs'] * gain + 6 * room + 0.03


def test_sound_bank_cache_is_kept_when_complete_and_refused_when_not(real_bank, tmp_path):
    copy = tmp_path / 'bank'
    shutil.copytree(real_bank.folder, copy)
    stamps = {f.name: f.stat().st_mtime_ns for f in copy.iterdir()}
    # a complete cache: fetch neither downloads nor rewrites anything
    assert sound_bank.fetch(dest=copy, quiet=True) == copy
    assert {f.name: f.stat().st_mtime_ns for f in copy.iterdir()} == stamps
    assert sound_bank.load_bank(folder=copy).fingerprint == real_bank.fingerprint
    # a missing recording: the bank is unavailable, with the fetch command in the error
    next(copy.glob('contact__*.wav')).unlink()
    assert not sound_bank.bank_available(folder=copy)
    with pytest.raises(ConfigError, match='tools/fetch_sounds.sh'):
        sound_bank.load_bank(folder=copy)


def test_sound_bank_clips_are_aligned_and_normalised(real_bank):
    assert sum(len(real_bank.clips[r]) for r in sound_bank.ROLES) == sum(
        len(v) for v in sound_bank.BANK.values())
    for role in sound_bank.IMPULSE_ROLES:
        for clip in real_bank.clips[role]:
            x = np.abs(clip.data)
            assert x.max() == pytest.approx(1.0)
            # the onset is the first sample at 20 % of the peak, 1 ms into the clip at most
            assert x[clip.onset] >= sound_bank.ONSET_FRACTION - 1e-9
            assert np.all(x[:clip.onset] < sound_bank.ONSET_FRACTION)
            assert clip.onset <= round(sound_bank.PRE_ROLL_S * clip.rate)
            data, onset = real_bank.at_rate(clip, 16000)
            assert onset == round(clip.onset * 16000 / clip.rate)
            assert len(data) == pytest.approx(len(clip.data) * 16000 / clip.rate, abs=2)
    for role in sound_bank.LOOP_ROLES:
        for clip in real_bank.clips[role]:
            assert np.sqrt(np.mean(clip.data ** 2)) == pytest.approx(1.0)
            assert len(clip.data) / clip.rate >= 1.0
