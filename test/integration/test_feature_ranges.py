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

"""``benchmarks/feature_ranges.py``: where recordings' features sit against simulated trials."""

import csv
import json
from pathlib import Path
import subprocess
import sys

from contact_detector.cli import simulate as simulate_cli
from contact_detector.model.shipped import default_ft_model_path
from contact_detector.model.storage import load_bundle
import pytest

pytestmark = pytest.mark.slow   # simulates bags

SCRIPT = Path(__file__).resolve().parents[2] / 'benchmarks' / 'feature_ranges.py'


def _table(*args: str) -> dict:
    done = subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True,
                          check=True)
    rows = {}
    for line in done.stdout.splitlines():
        cells = [c.strip() for c in line.strip('|').split('|')]
        if line.startswith('| ') and cells[0] not in ('feature', '---'):
            below, above = (float(part.split()[0]) for part in cells[-1].split('/'))
            rows[cells[0]] = (below, above)
    return rows


@pytest.fixture(scope='module')
def sets(tmp_path_factory):
    root = tmp_path_factory.mktemp('ranges')
    for name, seed, trials in (('reference', 50, 6), ('recordings', 51, 3)):
        assert simulate_cli.main([str(root / name), '--trials', str(trials), '--seed',
                                  str(seed), '--conditions', 'paper', '--quiet']) == 0
    return root


def test_trials_like_the_reference_sit_inside_its_range(sets):
    model = str(default_ft_model_path())
    rows = _table(str(sets / 'recordings'), '--reference', str(sets / 'reference'),
                  '--model', model)
    assert list(rows) == list(load_bundle(path=Path(model)).feature_names)
    below, above = rows['force_shift']
    assert below <= 30 and above <= 30


def test_a_window_that_is_not_the_contact_is_flagged(sets, tmp_path):
    # labelled 1 s early, the recordings' "contact" frames are the approach: their load change
    # is far below any simulated contact's, which is what the table is there to show
    manifest = json.loads((sets / 'recordings' / 'manifest.json').read_text())
    labels = tmp_path / 'early.csv'
    with labels.open('w', newline='') as f:
        out = csv.writer(f)
        out.writerow(['bag', 'onset_start', 'onset_end'])
        for trial in manifest['trials']:
            out.writerow([trial['name'], trial['onset_t'] - 1.0, trial['onset_t'] - 1.0])
    rows = _table(str(sets / 'recordings'), '--reference', str(sets / 'reference'),
                  '--labels', str(labels), '--model', str(default_ft_model_path()),
                  '--augmented')
    assert rows['force_shift'][0] >= 80
