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

"""``train --no-torque``: a model for a wrist that reads force alone (docs/model.md)."""

from dataclasses import replace
import json
from pathlib import Path

from contact_detector.cli import main as cli_main
from contact_detector.features.config import TORQUE_FEATURES
from contact_detector.model.storage import load_bundle
from contact_detector.sim import simulate_trials
from contact_detector.sim.bag_writer import manifest_entry, write_manifest, write_trial_bag
import numpy as np
import pytest

pytestmark = pytest.mark.slow   # simulates bags, trains, runs detect


def _write(trials: list, out: Path) -> Path:
    for trial in trials:
        write_trial_bag(trial=trial, path=out / trial.name)
    write_manifest(trials=[manifest_entry(t) for t in trials], out_dir=out)
    return out


def _releases(path: Path) -> list:
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    return [(r['bag'], r['t']) for r in rows if r.get('event') == 'release']


def test_a_force_only_model_decides_the_same_when_the_sensor_reads_no_torque(tmp_path, capsys):
    trials = list(simulate_trials(n=10, seed=8, conditions=('wide',)))
    sensor = _write(trials, tmp_path / 'six_axis')
    # a 3-axis sensor: the same force, its driver publishing the torque as zero
    force_only = _write([replace(t, torque=np.zeros_like(t.torque)) for t in trials],
                        tmp_path / 'three_axis')
    model = tmp_path / 'force.npz'
    assert cli_main.main(['train', str(sensor), '--no-torque', '--jobs', '1', '--trees', '3',
                          '--out', str(model)]) == 0
    bundle = load_bundle(path=model)
    assert not set(bundle.feature_names) & set(TORQUE_FEATURES)
    assert bundle.model_id.startswith('rf3-paper4+audio_power_rel_db')
    assert bundle.feature_config.to_dict()['torque'] is False
    capsys.readouterr()
    decided = {}
    for folder in (sensor, force_only):
        out = tmp_path / f'{folder.name}.jsonl'
        assert cli_main.main(['detect', str(folder), '--model', str(model), '--out',
                              str(out)]) == 0
        decided[folder.name] = _releases(out)
    assert decided['six_axis'] == decided['three_axis'] and len(decided['six_axis']) >= 5
    # a torque feature asked for by name is refused, with the reason
    assert cli_main.main(['train', str(sensor), '--no-torque', '--extra-features',
                          'force_shift,torque_shift', '--out', str(tmp_path / 'x.npz')]) != 0
    assert 'torque is false' in capsys.readouterr().err
