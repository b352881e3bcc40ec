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
    .venv/bin/python benchmarks/label_accuracy.py --dir DIR DIR...     # sets pooled

Simulates the trials as bags (``contact-detector simulate``, the condition sets cycled), runs
``contact-detector label`` on them and compares each proposed onset with the manifest's
``onset_t``: per family the median, 99th percentile and largest |error| in ms and the share
within 20 ms, then the same over all trials. An unlabelled bag counts as an infinite error.
Several ``--dir`` (each already simulated) are labelled one by one and pooled; the share
within 20 ms of each set is printed under the table. The ``all`` row's share carries its
95 % Wilson interval, since one trial moves a 240-trial set's share by 0.4 points:
``(p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)``, z = 1.96.
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


def wilson(*, hits: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval of a share ``hits / n``, as fractions (see the module doc)."""
    p = hits / n
    centre = p + z * z / (2 * n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return (centre - half) / (1 + z * z / n), (centre + half) / (1 + z * z / n)


def errors(*, out: Path, labels: Path) -> list[tuple[str, str, float]]:
    """Label the bags in ``out`` into ``labels``; (bag, family, signed error ms) per trial."""
    # the labels go to the temporary directory: --dir may be shared, read-only data
    command('label', str(out), '--out', str(labels))
    trials = json.loads((out / 'manifest.json').read_text())['trials']
    with open(labels) as handle:
        rows = {r['bag']: r for r in csv.DictReader(handle)}
    found = []
    for trial in trials:
        row = rows.get(Path(trial['bag']).name)
        signed = (float(row['onset_start']) - trial['onset_t']) * 1e3 \
            if row and row['onset_start'] else np.inf
        found.append((Path(trial['bag']).name, trial['condition'], signed))
    return found


def main() -> int:
    """Run the benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--trials', type=int, default=120)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--conditions', nargs='+', default=['wide'])
    parser.add_argument('--ft-rate', type=float, default=100.0)
    parser.add_argument('--dir', type=Path, nargs='+', default=None,
                        help='keep the bags here (default: a temporary directory); '
                             'several: simulated sets to pool')
    parser.add_argument('--list-over', type=float, default=None, metavar='MS',
                        help='list the trials whose |error| exceeds MS ms')
    parser.add_argument('--list-family', default=None, metavar='NAME',
                        help="list every trial of this family (e.g. 'soft')")
    args = parser.parse_args()
    if args.dir and len(args.dir) > 1:
        missing = [str(d) for d in args.dir if not (d / 'manifest.json').exists()]
        if missing:
            parser.error(f'pooled sets must be simulated first: {", ".join(missing)}')
    per_set = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, out in enumerate(args.dir or [Path(tmp)]):
            if not (out / 'manifest.json').exists():
                command('simulate', str(out), '--trials', str(args.trials), '--seed',
                        str(args.seed), '--ft-rate', str(args.ft_rate), '--quiet',
                        '--conditions', *args.conditions)
            per_set.append((out, errors(out=out, labels=Path(tmp) / f'labels{i}.csv')))
    by_family: dict[str, list[float]] = {}
    listed = []
    for out, found in per_set:
        for name, family, signed in found:
            by_family.setdefault(family, []).append(abs(signed))
            if ((args.list_over is not None and abs(signed) > args.list_over)
                    or family == args.list_family):
                shown = name if len(per_set) == 1 else f'{out.name}/{name}'
                listed.append((shown, family, signed))
    every = [e for errs in by_family.values() for e in errs]
    print('| family | trials | median ms | p99 ms | max ms | within 20 ms |')
    print('|---|---|---|---|---|---|')
    for name, errs in [*by_family.items(), ('all', every)]:
        e = np.asarray(errs)
        ok = int(np.sum(e <= 20))
        interval = ''
        if name == 'all':
            low, high = wilson(hits=ok, n=len(e))
            interval = f', 95 % {100 * low:.1f}-{100 * high:.1f} %'
        print(f'| {name} | {len(e)} | {np.median(e):.1f} | {np.percentile(e, 99):.1f} | '
              f'{e.max():.1f} | {100 * ok / len(e):.1f} % ({ok}/{len(e)}{interval}) |')
    if len(per_set) > 1:
        print()
        for out, found in per_set:
            ok = sum(abs(signed) <= 20 for _, _, signed in found)
            print(f'{out}: {ok}/{len(found)} within 20 ms ({100 * ok / len(found):.1f} %)')
    if listed:
        print('\n| trial | family | error ms |\n|---|---|---|')
        for name, family, signed in listed:
            print(f'| {name} | {family} | {signed:+.1f} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
