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
Two models deciding, each family left out: the first release of either, per trial.

    .venv/bin/python benchmarks/lofo_either.py MULTIMODAL.json:RULE FT_ONLY.json:RULE...
        [--families] [--json out.json]

Each argument is an ``--outcomes`` file of ``benchmarks/lofo_rules.py`` (the same folders and
forest seeds, one file per recipe) and the name of one of its rules (``S``: the shipped one).
Per trial and seed the combined outcome is the outcome of the earlier release, as the node
decides with ``model.ft_also_decides`` (the first release of either model, once per arming):
early if that release is early, caught if it is within 500 ms, missed if neither model
released. Several ``FT_ONLY.json:RULE`` arguments print one line each: the first argument's
rule beside that one, as ``lofo_rules.py`` prints its rules.
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Dict, List, Tuple

from contact_detector.evaluation.metrics import Outcome
from lofo_rules import print_rules, summarise, write_json

KEYS = ('seed', 'trial', 'knocked')


def read_outcomes(text: str) -> Tuple[str, Dict[tuple, dict]]:
    """
    Return ``(label, records)`` of ``FILE.json:RULE``: the rule's records by (seed, trial).

    Exits with a message if the file or the rule is not there.
    """
    path, _, rule = text.rpartition(':')
    if not path:
        sys.exit(f'lofo_either: expected FILE.json:RULE, got {text!r}')
    data = json.loads(Path(path).read_text())
    if rule not in data['outcomes']:
        sys.exit(f'lofo_either: {path} has no rule {rule!r}; it has {sorted(data["outcomes"])}')
    return (f"{data['recipe']} {rule}",
            {(r['seed'], r['trial']): r for r in data['outcomes'][rule]})


def earlier(a: dict, b: dict) -> dict:
    """Return the record whose release comes first (no release comes last)."""
    inf = float('inf')
    first = (a['release_t'] if a['release_t'] is not None else inf,
             b['release_t'] if b['release_t'] is not None else inf)
    return a if first[0] <= first[1] else b


def either(first: Dict[tuple, dict], second: Dict[tuple, dict]
           ) -> Tuple[List[Outcome], List[Outcome]]:
    """Return the combined outcomes of every trial and those knocked on the hand in the air."""
    if first.keys() != second.keys():
        sys.exit('lofo_either: the two files do not hold the same trials and seeds')
    outcomes, knocked = [], []
    for key in sorted(first):
        record = earlier(first[key], second[key])
        outcome = Outcome(**{k: v for k, v in record.items() if k not in KEYS})
        outcomes.append(outcome)
        if record['knocked']:
            knocked.append(outcome)
    return outcomes, knocked


def main(argv=None) -> int:
    """Print the combined figures; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('first', metavar='MULTIMODAL.json:RULE')
    parser.add_argument('second', nargs='+', metavar='FT_ONLY.json:RULE')
    parser.add_argument('--families', action='store_true', help='one line per family too')
    parser.add_argument('--json', type=Path, default=None, help='the counts, as JSON')
    args = parser.parse_args(argv)
    label, first = read_outcomes(args.first)
    summary = {}
    for text in args.second:
        other, second = read_outcomes(text)
        outcomes, knocked = either(first, second)
        summary[f'{label} | {other}'] = summarise(outcomes=outcomes, knocked=knocked)
    print_rules(summary, families=args.families)
    write_json(args.json, rules={}, summary=summary)
    return 0


if __name__ == '__main__':
    sys.exit(main())
