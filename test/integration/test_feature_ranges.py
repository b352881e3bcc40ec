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


def _labelled_early(folder: Path, labels: Path) -> Path:
    """Write a labels CSV that puts every simulated trial's onset 1 s before its true one."""
    manifest = json.loads((folder / 'manifest.json').read_text())
    with labels.open('w', newline='') as f:
        out = csv.writer(f)
        out.writerow(['bag', 'onset_start', 'onset_end'])
        for trial in manifest['trials']:
            out.writerow([trial['name'], trial['onset_t'] - 1.0, trial['onset_t'] - 1.0])
    return labels


def test_a_window_that_is_not_the_contact_is_flagged(sets, tmp_path):
    # labelled 1 s early, the recordings' "contact" frames are the approach: their load change
    # is far below any simulated contact's, which is what the table is there to show
    labels = _labelled_early(sets / 'recordings', tmp_path / 'early.csv')
    rows = _table(str(sets / 'recordings'), '--reference', str(sets / 'reference'),
                  '--labels', str(labels), '--model', str(default_ft_model_path()),
                  '--augmented')
    assert rows['force_shift'][0] >= 80


SWAP = SCRIPT.with_name('modality_swap.py')


def _swap_table(*args: str) -> dict:
    """Return modality_swap.py's rows: label -> [(mean P, share %), ...] per window."""
    done = subprocess.run([sys.executable, str(SWAP), *args], capture_output=True, text=True,
                          check=True)
    rows = {}
    for line in done.stdout.splitlines():
        cells = [c.strip() for c in line.strip('|').split('|')]
        if line.startswith('| ') and cells[0] not in ('frames', '---'):
            rows[cells[0]] = [(float(c.split(',')[0]), float(c.split(',')[1].split('%')[0]))
                              for c in cells[1:]]
    return rows


def test_modality_swap_of_the_reference_itself_changes_nothing_it_scores(sets):
    rows = _swap_table(str(sets / 'reference'), '--reference', str(sets / 'reference'))
    assert list(rows) == ['reference', 'recordings', 'recordings, reference audio',
                          'recordings, reference F/T']
    assert rows['recordings'] == rows['reference']      # the same frames, scored alike
    assert all(0.0 <= mean <= 1.0 for r in rows.values() for mean, _ in r)


def test_modality_swap_finds_the_contact_in_the_swapped_force_torque(sets, tmp_path):
    # labelled 1 s early, the recordings' frames after the "onset" are the approach: the F/T-only
    # model is sure there is no contact, until the reference contacts' F/T features are swapped in
    labels = _labelled_early(sets / 'recordings', tmp_path / 'early.csv')
    rows = _swap_table(str(sets / 'recordings'), '--reference', str(sets / 'reference'),
                       '--labels', str(labels), '--model', str(default_ft_model_path()))
    assert list(rows) == ['reference', 'recordings', 'recordings, reference F/T']  # no audio
    late = {label: r[2][0] for label, r in rows.items()}     # mean P 60-120 ms
    assert late['recordings'] < 0.2 < late['reference'] - 0.3
    assert abs(late['recordings, reference F/T'] - late['reference']) < 0.2


def test_swapped_takes_only_the_named_columns_from_the_reference(monkeypatch):
    monkeypatch.syspath_prepend(str(SCRIPT.parent))
    import modality_swap
    import numpy as np
    frames = np.zeros((4, 3))
    reference = np.array([[1.0, 2.0, 3.0]])
    out = modality_swap.swapped(frames=frames, reference=reference, columns=[0, 2],
                                rng=np.random.default_rng(0))
    assert out.tolist() == [[1.0, 0.0, 3.0]] * 4 and not frames.any()
