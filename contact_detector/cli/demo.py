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
``contact-detector demo``: the whole detector, live, on a laptop with no robot.

    contact-detector demo [--trials 6] [--seed 7] [--out DIR] [--model M]

1. simulates a handful of paper-like trials with exogenous hits on the hand and on the table;
2. starts ``contact_detector_node`` as its own process (DDS on loopback);
3. replays each trial into it in real time, as live sensors would publish (header stamps moved
   to now), arming the release before each trial as a placing routine would;
4. collects ``contact``, ``contact_probability`` and ``release`` and prints one row per trial
   (true onset, release, latency, exogenous hits, verdict) and a summary line;
5. writes a figure of one trial with the detections marked.

Exits non-zero if the node fails, a release comes before the glass touches (premature), or a
contact is missed. The run is :func:`contact_detector.ros.demo_run.run_demo`; the trials, scores,
table and figure are :mod:`contact_detector.evaluation.demo`.
"""

import argparse
from pathlib import Path
import sys
import tempfile
from typing import Optional, Sequence

from contact_detector.model.shipped import default_model_path


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the demo; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector demo', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--trials', type=int, default=6)
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--out', type=Path, default=None,
                        help='keep bags, node log and figure here (default: a temp folder, '
                             'figure in ./demo_trial.png)')
    parser.add_argument('--model', type=Path, default=None)
    args = parser.parse_args(argv)
    from contact_detector.ros.demo_run import run_demo

    model = args.model or default_model_path()
    with tempfile.TemporaryDirectory(prefix='contact_detector_demo_') as tmp:
        out = args.out or Path(tmp)
        figure = (args.out / 'demo_trial.png') if args.out else Path('demo_trial.png')
        return run_demo(trials=args.trials, seed=args.seed, out=out, model=model,
                        figure=figure)


if __name__ == '__main__':
    sys.exit(main())
