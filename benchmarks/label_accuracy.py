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
Accuracy of ``contact-detector label`` on simulated trials with known onsets.

    .venv/bin/python benchmarks/label_accuracy.py --trials 120 --conditions wide [--dir DIR]

Simulates the trials as bags (``contact-detector simulate``, the condition sets cycled), runs
``contact-detector label`` on them and compares each proposed onset with the manifest's
``onset_t``: per family the median, 99th percentile and largest |error| in ms and the share
within 20 ms, then the same over all trials. An unlabelled bag counts as an infinite error.
``--list-over MS`` then lists each trial whose |error| exceeds MS ms (bag, family, signed
error: negative = proposed before the truth), ``--list-family NAME`` every trial of a family.
"""

import argparse
import csv
import json
from pathlib import Path
import subprocess
import sys
import tempfile

import numpy as np


def command(*args: str) -> None:
    """Run ``contact-detector ARGS...`` as its own process; exit if it fails."""
    done = subprocess.run([sys.executable, '-m', 'contact_detector.cli.main', *args])
    if done.returncode != 0:
        raise SystemExit(f'contact-detector {args[0]} failed')


def main() -> int:
    """Run the benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--trials', type=int, default=120)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--conditions', nargs='+', default=['wide'])
    parser.add_argument('--ft-rate', type=float, default=100.0)
    parser.add_argument('--dir', type=Path, default=None,
                        help='keep the bags here (default: a temporary directory)')
    parser.add_argument('--list-over', type=float, default=None, metavar='MS',
                        help='list the trials whose |error| exceeds MS ms')
    parser.add_argument('--list-family', default=None, metavar='NAME',
                        help="list every trial of this family (e.g. 'soft')")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = args.dir or Path(tmp)
        if not (out / 'manifest.json').exists():
            command('simulate', str(out), '--trials', str(args.trials), '--seed',
                    str(args.seed), '--ft-rate', str(args.ft_rate), '--quiet',
                    '--conditions', *args.conditions)
        # the labels go to the temporary directory: --dir may be shared, read-only data
        command('label', str(out), '--out', str(Path(tmp) / 'labels.csv'))
        trials = json.loads((out / 'manifest.json').read_text())['trials']
        with open(Path(tmp) / 'labels.csv') as handle:
            rows = {r['bag']: r for r in csv.DictReader(handle)}
    by_family: dict[str, list[float]] = {}
    listed = []
    for trial in trials:
        row = rows.get(Path(trial['bag']).name)
        signed = (float(row['onset_start']) - trial['onset_t']) * 1e3 \
            if row and row['onset_start'] else np.inf
        err = abs(signed)
        by_family.setdefault(trial['condition'], []).append(err)
        if ((args.list_over is not None and err > args.list_over)
                or trial['condition'] == args.list_family):
            listed.append((Path(trial['bag']).name, trial['condition'], signed))
    every = [e for errs in by_family.values() for e in errs]
    print('| family | trials | median ms | p99 ms | max ms | within 20 ms |')
    print('|---|---|---|---|---|---|')
    for name, errs in [*by_family.items(), ('all', every)]:
        e = np.asarray(errs)
        ok = int(np.sum(e <= 20))
        print(f'| {name} | {len(e)} | {np.median(e):.1f} | {np.percentile(e, 99):.1f} | '
              f'{e.max():.1f} | {100 * ok / len(e):.1f} % ({ok}/{len(e)}) |')
    if listed:
        print('\n| trial | family | error ms |\n|---|---|---|')
        for name, family, signed in listed:
            print(f'| {name} | {family} | {signed:+.1f} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
