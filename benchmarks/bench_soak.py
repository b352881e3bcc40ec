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
Soak: many simulated minutes of input through the node's processing at full speed; memory.

Runs :mod:`contact_detector.ros.soak` (``detector``: :class:`ContactDetector` directly;
``node``: the real node's callbacks in this process) and prints one row per simulated minute
(resident set size, ``tracemalloc`` current and peak), then first / last / max and the
least-squares slope over minutes 1.. (minute 0 includes imports and warm-up).

    python benchmarks/bench_soak.py [--minutes 30] [--mode detector|node|both]
                                    [--pool 24] [--model PATH] [--no-tracemalloc]
                                    [--json out.json]

The model is the shipped ``models/contact_forest.npz`` unless ``--model`` is given.
"""

import argparse
import json
from pathlib import Path
import sys
from typing import List, Optional

from contact_detector.model.storage import load_bundle
from contact_detector.ros.soak import make_pool, run_soak, Sample, summary

SHIPPED_MODEL = Path(__file__).resolve().parents[1] / 'models' / 'contact_forest.npz'


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--minutes', type=float, default=30.0,
                        help='simulated minutes per mode (default 30)')
    parser.add_argument('--mode', choices=('detector', 'node', 'both'), default='both')
    parser.add_argument('--model', default=str(SHIPPED_MODEL),
                        help='model file (default: the shipped one)')
    parser.add_argument('--no-tracemalloc', action='store_true',
                        help='RSS only (tracemalloc slows Python down about 2x)')
    parser.add_argument('--pool', type=int, default=24,
                        help='distinct simulated trials, played in turn (default 24)')
    parser.add_argument('--json', default='', help='also write the samples here')
    args = parser.parse_args(argv)

    model = Path(args.model)
    bundle = load_bundle(path=model)
    print(f'model {bundle.model_id} ({model})', flush=True)
    pool = make_pool(n=args.pool)
    seconds = sum(events[-1][0] - events[0][0] for _, events in pool)
    print(f'{len(pool)} trials simulated ({seconds:.0f} s), played in turn', flush=True)
    modes = ('detector', 'node') if args.mode == 'both' else (args.mode,)
    results = []
    for mode in modes:
        def progress(s: Sample, mode=mode) -> None:
            print(f'  {mode} minute {s.minute:5.1f}: RSS {s.rss_mb:7.1f} MB, traced '
                  f'{s.traced_mb:7.3f} MB (peak {s.traced_peak_mb:7.3f}), wall {s.wall_s:6.1f} s',
                  flush=True)
        result = run_soak(bundle=bundle, minutes=args.minutes, mode=mode, pool=pool,
                          trace=not args.no_tracemalloc, progress=progress)
        results.append(result)
        print(summary(result), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps([{
            'mode': r.mode, 'trials': r.trials, 'counts': r.counts,
            'samples': [s.__dict__ for s in r.samples]} for r in results], indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(main())
