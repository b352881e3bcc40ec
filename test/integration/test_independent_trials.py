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

"""benchmarks/independent_trials.py: its bags and labels read as a user's recordings do."""

import ast
import csv
import json
from pathlib import Path
import subprocess
import sys

from contact_detector.cli import evaluate as evaluate_cli
from contact_detector.io.bags import read_wrench
from contact_detector.io.discovery import discover_streams
import pytest

pytestmark = pytest.mark.slow   # runs the generator's 8 kHz mechanics
SCRIPT = Path(__file__).resolve().parents[2] / 'benchmarks' / 'independent_trials.py'


def test_the_generator_imports_nothing_of_the_package_it_checks():
    tree = ast.parse(SCRIPT.read_text())
    imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module or '' for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert not any(name.startswith('contact_detector') for name in imported)


def test_trials_are_labelled_bags_that_evaluate_reads(tmp_path, capsys):
    out = tmp_path / 'indep'
    subprocess.run([sys.executable, SCRIPT, out, '--trials-per-family', '1', '--seed', '7',
                    '--families', 'rigid,fixture', '--jobs', '1'], check=True,
                   capture_output=True)
    with open(out / 'labels.csv') as handle:
        rows = list(csv.DictReader(handle))
    assert sorted(r['bag'] for r in rows) == ['fixture/trial_0000', 'rigid/trial_0000']
    params = {t['bag']: t for t in json.loads((out / 'trials.json').read_text())['trials']}
    for row in rows:
        bag = out / row['bag']
        streams = discover_streams(bag)
        assert streams.has_audio
        assert streams.wrench_rate == pytest.approx(params[row['bag']]['params']['sensor']['rate'],
                                                    rel=0.02)
        t = read_wrench(bag, topic=streams.wrench_topic).t
        # the onset is inside the recording, after the object was held still
        assert t[0] + 1.0 < float(row['onset_start']) < t[-1]
    # the two bags share a name; the CSV names them by path and evaluate keeps them apart
    assert evaluate_cli.main([str(out / 'rigid'), str(out / 'fixture'), '--labels',
                              str(out / 'labels.csv'), '--detector', 'forest']) == 0
    printed = capsys.readouterr().out
    assert '| rigid/trial_0000 | 1 |' in printed and '| fixture/trial_0000 | 1 |' in printed
