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
from pathlib import Path

from contact_detector.cli.plot import main as plot_main
from contact_detector.cli.simulate import main as simulate_main
from contact_detector.errors import BagError, ConfigError
from contact_detector.io.bags import (iter_messages, jazzy_typestore, read_audio, read_manifest,
                                      read_truth, read_wrench)
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.conditions import (CONDITION_SETS, get_condition, ranges_markdown,
                                             resolve_conditions)
from contact_detector.sim.trial import (G, PHASES, simulate_trial, simulate_trials,
                                        STOP_TORQUE_NM)
import numpy as np
import pytest
from rosbags.highlevel import AnyReader

SEED = 5
ALL = tuple(CONDITION_SETS)


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
    assert base == pytest.approx(entry['params']['derived']['baseline_ty_nm'], abs=1e-9)
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
        assert fired == pytest.approx(tr.stop_t, abs=1e-9)
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


def test_manifest_schema(manifest):
    entry = manifest['trials'][0]
    for key in ('name', 'bag', 'condition', 'seed', 'index', 'start_time', 'end_time',
                'onset_t', 'onset_end_t', 'contact_end_t', 'stop_t', 'phases', 'impacts',
                'params'):
        assert key in entry
    json.dumps(manifest, allow_nan=False)
    assert manifest['format'] == 'contact_detector.sim.manifest'


def test_plot_writes_png(sim_dir, tmp_path):
    out = tmp_path / 'fig.png'
    assert plot_main([str(sim_dir / 'trial_0000'), '-o', str(out)]) == 0
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert plot_main([str(sim_dir), '-o', str(out)]) == 1  # six bags: ambiguous


def test_docs_table_matches_the_ranges():
    docs = Path(__file__).resolve().parent.parent / 'docs' / 'simulator.md'
    assert ranges_markdown() in docs.read_text(encoding='utf-8')
