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
The carried load at the start of recordings, and how far it moved while it was measured.

    .venv/bin/python benchmarks/carried_load.py DIR_OR_BAG... [--model M] [--list]

For every recording, the first ``carried_window`` F/T samples (at the model's feature rate)
are measured as the detector measures them after a start
(:func:`~contact_detector.features.carried.measure_carried_load`): the load, and ``moved``,
how far the median of the second half lies from the first half's. Prints per folder how many
recordings are ``steady``, ``moved`` (the node and ``detect`` warn) or ``below-floor`` (a tared
sensor or an empty hand), and the percentiles of the force's ``moved``: how close a recording
that starts as it should comes to the warning. ``--list`` prints every recording that is not
``steady``.
"""

import argparse
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.detection.factory import stream_spec
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import discover_streams
from contact_detector.io.sensor_stream import sensor_events, WrenchEvent
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
import numpy as np


def first_carried_load(bag: Path, *, config):
    """Return the carried load of a recording's start, or None if it is too short."""
    streams = discover_streams(bag, allow_no_audio=True)
    ft = ForceTorqueStream(config=config, input_rate=streams.wrench_rate)
    for event in sensor_events(bag, spec=stream_spec(streams, {})):
        if isinstance(event, WrenchEvent):
            ft.push(t=event.t, force=event.force, torque=event.torque)
            if ft.carried_load is not None:
                return ft.carried_load
    return None


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Print the table; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('paths', nargs='+', type=Path, help='folders of bags, or bags')
    parser.add_argument('--model', type=Path, default=None,
                        help='model whose feature configuration to use (default: shipped)')
    parser.add_argument('--list', action='store_true', help='print every recording not steady')
    args = parser.parse_args(argv)
    config = load_bundle(path=args.model or default_model_path()).feature_config
    if not ForceTorqueStream(config=config, input_rate=config.ft_rate_hz).uses_carried:
        parser.error('the model has no carried-load feature: it measures no carried load')
    print('| recordings | steady | moved | below-floor | too short | moved |F| p50 / p90 / '
          'p99 / max [N] |')
    print('|---|---|---|---|---|---|')
    for path in args.paths:
        counts = {'steady': 0, 'moved': 0, 'below-floor': 0, 'too short': 0}
        moved, listed = [], []
        for bag in find_bags([path]):
            carried = first_carried_load(bag, config=config)
            if carried is None:
                counts['too short'] += 1
                continue
            counts[carried.status] += 1
            moved.append(float(carried.moved[0]))
            if carried.status != 'steady':
                listed.append(f'  {bag.name}: {carried.describe()}')
        p = (' / '.join(f'{v:.2f}' for v in np.percentile(moved, [50, 90, 99, 100]))
             if moved else '-')
        print(f'| {path.name} ({sum(counts.values())}) | {counts["steady"]} | '
              f'{counts["moved"]} | {counts["below-floor"]} | {counts["too short"]} | {p} |')
        if args.list:
            print('\n'.join(listed), file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
