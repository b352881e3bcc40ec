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
How rough the force is after a contact, a brush or a touch, in the simulator and elsewhere.

    .venv/bin/python benchmarks/force_roughness_events.py DIR... [--after 0.1,0.2]

For every recording of each folder, the F/T path of the feature core
(:class:`~contact_detector.features.force_torque.ForceTorqueStream`, the shipped
configuration with ``force_roughness`` and ``force_roughness_rel``) runs over the wrench, and
the two values are read ``--after`` seconds after each event's start:

- a contact: its onset, from the simulator's ``manifest.json`` or from a ``labels.csv`` one
  folder up (the generators' folders: ``bag,onset_start,onset_end``, bag named
  ``family/trial``);
- a brush or a touch of the simulator that starts in the air, at least 0.3 s before the
  contact.

Printed per folder and kind: the count and the 10th, 50th and 90th percentiles, the first
``--after`` giving the decision a release 0.1 s after the onset would have had. This is the
figure of docs/decisions/2026-11-28-force-roughness.md: whether a brush is rougher than a
table contact in worlds other than the simulator's.
"""

import argparse
import csv
from pathlib import Path
import sys

from contact_detector.features.config import FeatureConfig, ROUGH_FEATURES
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.io.bags import find_bags, read_manifest, read_wrench
from contact_detector.io.discovery import discover_streams
import numpy as np


def _events(folder: Path) -> dict:
    """Bag path -> [(kind, start time s)] of the folder's contacts and in-air brushes, touches."""
    out = {}
    if (folder / 'manifest.json').is_file():
        for trial in read_manifest(folder)['trials']:
            onset = trial['onset_t']
            found = [('contact', onset)]
            found += [(hit['kind'], hit['t']) for hit in trial.get('impacts', [])
                      if hit['kind'] in ('brush', 'touch') and hit['t'] < onset - 0.3]
            out[folder / trial['bag']] = found
        return out
    labels = folder.parent / 'labels.csv'
    with labels.open(encoding='utf-8') as f:
        for row in csv.DictReader(f):
            family, _, name = row['bag'].partition('/')
            if family == folder.name:
                out[folder / name] = [('contact', float(row['onset_start']))]
    return out


def _values(bag: Path, config: FeatureConfig) -> tuple[np.ndarray, np.ndarray]:
    streams = discover_streams(bag)
    wrench = read_wrench(bag, topic=streams.wrench_topic)
    stream = ForceTorqueStream(config=config, input_rate=streams.wrench_rate)
    t, x = stream.push(t=wrench.t, force=wrench.force, torque=wrench.torque)
    columns = [stream.columns.index(name) for name in ROUGH_FEATURES]
    return t, x[:, columns]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('folders', nargs='+', type=Path)
    parser.add_argument('--after', default='0.1,0.2',
                        help='seconds after the event start to read the values at')
    args = parser.parse_args(argv)
    after = [float(a) for a in args.after.split(',')]
    config = FeatureConfig.shipped().with_extra(ROUGH_FEATURES)
    print('| folder | kind | after [s] | n | force_roughness [N] p10 / p50 / p90 '
          '| force_roughness_rel p10 / p50 / p90 |')
    print('|---|---|---|---|---|---|')
    for folder in args.folders:
        bags = set(find_bags([folder]))
        values = {}
        for bag, events in sorted(_events(folder).items()):
            if bag not in bags:
                continue
            t, x = _values(bag, config)
            for kind, start in events:
                for a in after:
                    i = int(np.searchsorted(t, start + a))
                    if i < len(t):
                        values.setdefault((kind, a), []).append(x[i])
        for (kind, a), rows in sorted(values.items()):
            v = np.array(rows)
            cells = [' / '.join(f'{q:.2f}' for q in np.percentile(v[:, k], (10, 50, 90)))
                     for k in range(2)]
            print(f'| {folder.name} | {kind} | {a:g} | {len(v)} | {cells[0]} | {cells[1]} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
