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
Start-up cost of the node and of ``detect``: import, shipped-model load, detector build.

Each run is a fresh ``python`` process (so nothing is cached in ``sys.modules``) that imports
the entry module (``contact_detector.ros.node`` or ``contact_detector.cli.detect``), loads the
shipped model with ``load_bundle(path=default_model_path())`` and compiles its forest
(``bundle.compile()``, what building the detector costs). It reports the median over
``--runs`` runs of each phase, of import + load (the issue's target: <= 1 s) and of the whole
process (interpreter start to exit), and whether scikit-learn, joblib, rosbags or matplotlib
were imported. ``--model PATH`` times another model file instead (e.g. a legacy ``.joblib``,
which imports scikit-learn).

Usage::

    python benchmarks/bench_startup.py [--runs 5] [--model PATH]
"""

import argparse
import json
from pathlib import Path
import statistics
import subprocess
import sys
import time
from typing import Optional, Sequence

REPO = Path(__file__).resolve().parents[1]
TARGETS = {'node': 'contact_detector.ros.node', 'detect': 'contact_detector.cli.detect'}
WATCHED = ('sklearn', 'joblib', 'rosbags', 'matplotlib')

_CHILD = """
import json, sys, time
t0 = time.perf_counter()
import {module}  # noqa: F401
t1 = time.perf_counter()
from contact_detector.model import default_model_path, load_bundle
bundle = load_bundle(path={model} or default_model_path())
t2 = time.perf_counter()
bundle.compile()
t3 = time.perf_counter()
print(json.dumps({{'import_s': t1 - t0, 'load_s': t2 - t1, 'compile_s': t3 - t2,
                  'imported': [m for m in {watched!r} if m in sys.modules]}}))
"""


def run_once(*, module: str, model: Optional[str]) -> dict:
    """One fresh process; return its phase times (s) and the watched modules it imported."""
    code = _CHILD.format(module=module, model=repr(model), watched=WATCHED)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, '-c', code], cwd=REPO, capture_output=True,
                          text=True, check=True)
    result = json.loads(done.stdout)
    result['process_s'] = time.perf_counter() - start
    return result


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the benchmark and print a markdown table."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--runs', type=int, default=5)
    parser.add_argument('--model', default=None, help='model file (default: the shipped one)')
    args = parser.parse_args(argv)
    print(f'Python {sys.version.split()[0]}, model '
          f'{args.model or "shipped (default_model_path)"}, median of {args.runs} fresh '
          'processes\n')
    print('| entry | import (s) | load_bundle (s) | import + load (s) | compile (s) | '
          'whole process (s) | imported |')
    print('|---|---|---|---|---|---|---|')
    for name, module in TARGETS.items():
        runs = [run_once(module=module, model=args.model) for _ in range(args.runs)]

        def med(key: str, runs: list = runs) -> float:
            return statistics.median(r[key] for r in runs)

        both = statistics.median(r['import_s'] + r['load_s'] for r in runs)
        imported = sorted({m for r in runs for m in r['imported']})
        print(f'| {name} (`{module}`) | {med("import_s"):.3f} | {med("load_s"):.3f} | '
              f'{both:.3f} | {med("compile_s"):.3f} | {med("process_s"):.3f} | '
              f'{", ".join(imported) or "none of " + "/".join(WATCHED)} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
