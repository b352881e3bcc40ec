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
One labels CSV to train on simulated folders and an independent generator's trials together.

    .venv/bin/python benchmarks/training_set_labels.py OUT.csv DIR... [--events]

``contact-detector train --labels`` wants an onset for every bag it reads. This script writes
that CSV for two kinds of folder:

- a ``contact-detector simulate`` folder (it holds ``manifest.json``): one row per trial,
  from ``onset_t`` to ``onset_end_t``;
- an output folder of ``independent_trials.py`` or ``independent_robots.py`` (it holds
  ``labels.csv`` and ``trials.json``): one row per labelled bag.

Bag cells are written relative to the CSV's folder. The script prints the bag folders to pass
to ``train``: each simulated folder, and each generator family folder.

``--events`` also writes a ``manifest.json`` into each generator family folder. Its
``impacts`` are the generator's exogenous events (``t_abs``, ``kind``), so ``train
--event-weight W`` weighs their no-contact frames as it weighs the simulator's. The
decision notes 2026-11-25-train-on-a-second-world.md and
2026-11-25-second-world-with-its-events.md trained with it:

    .venv/bin/python benchmarks/training_set_labels.py ALL.csv data/train data/train_extra
        A3301 A3303 A3304 A3305 [--events]
    .venv/bin/contact-detector train <the printed folders> --labels ALL.csv --augment ...
"""

import argparse
import csv
import json
import os
from pathlib import Path
import sys
from typing import Dict, List, Sequence, Tuple

from contact_detector.io.bags import read_manifest


def simulated_rows(folder: Path) -> List[Tuple[Path, str, str]]:
    """Bag path, onset start and end (s, as written) of each trial of a simulate folder."""
    return [(folder / t['bag'], f"{t['onset_t']:.6f}", f"{t['onset_end_t']:.6f}")
            for t in read_manifest(folder)['trials']]


def generator_rows(folder: Path) -> List[Tuple[Path, str, str]]:
    """Bag path, onset start and end (s, as written) of each row of a generator's labels.csv."""
    with open(folder / 'labels.csv', newline='') as handle:
        return [(folder / r['bag'], r['onset_start'], r['onset_end'])
                for r in csv.DictReader(handle)]


def write_event_manifests(folder: Path) -> None:
    """
    Write ``manifest.json`` into each family folder of a generator's output.

    Each trial's entry has ``name``, ``bag``, ``condition`` (the family), ``onset_t`` and
    ``impacts``: the generator's events as ``{'t': t_abs, 'kind': kind}``, t in s of bag time.
    """
    trials = json.loads((folder / 'trials.json').read_text())['trials']
    families: Dict[str, list] = {}
    for trial in trials:
        family, name = Path(trial['bag']).parts[-2:]
        impacts = [{'t': float(e['t_abs']), 'kind': str(e['kind'])}
                   for e in trial.get('events') or () if 't_abs' in e]
        families.setdefault(family, []).append({
            'name': name, 'bag': name, 'condition': family, 'onset_t': float(trial['onset']),
            'impacts': impacts})
    for family, entries in families.items():
        (folder / family / 'manifest.json').write_text(json.dumps({'trials': entries}))


def main(argv: Sequence[str] | None = None) -> int:
    """Write the CSV and print the folders to train on; 1 for a folder of neither kind."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('out', type=Path, help='the labels CSV to write')
    parser.add_argument('folders', type=Path, nargs='+',
                        help='simulate folders and generator output folders')
    parser.add_argument('--events', action='store_true',
                        help="write each generator family folder's manifest.json with its "
                        'events')
    args = parser.parse_args(argv)
    rows: List[Tuple[Path, str, str]] = []
    train_on: List[Path] = []
    for folder in args.folders:
        # a generator's family folders get a manifest.json with --events: labels.csv decides
        if (folder / 'labels.csv').is_file() and (folder / 'trials.json').is_file():
            labelled = generator_rows(folder)
            rows += labelled
            train_on += sorted({bag.parent for bag, _, _ in labelled})
            if args.events:
                write_event_manifests(folder)
        elif (folder / 'manifest.json').is_file():
            rows += simulated_rows(folder)
            train_on.append(folder)
        else:
            print(f'{folder}: neither a simulate folder (manifest.json) nor a generator output '
                  '(labels.csv and trials.json)', file=sys.stderr)
            return 1
    base = args.out.resolve().parent
    base.mkdir(parents=True, exist_ok=True)
    with open(args.out, 'w', newline='') as handle:
        writer = csv.writer(handle)
        writer.writerow(['bag', 'onset_start', 'onset_end'])
        writer.writerows((os.path.relpath(bag.resolve(), base), start, end)
                         for bag, start, end in rows)
    print(f'{len(rows)} bags labelled in {args.out}; train on:', file=sys.stderr)
    print(' '.join(str(f) for f in train_on))
    return 0


if __name__ == '__main__':
    sys.exit(main())
