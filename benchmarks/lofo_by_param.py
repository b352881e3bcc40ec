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
Which trials a left-out family loses, by one of the simulator's parameters.

    .venv/bin/python benchmarks/lofo_by_param.py DIR... --family geometry --param tared
        [--setting shipped] [--seeds 0,1,2] [--cache frames.pkl] [--jobs 1] [--trials]
        [--setting shipped+aug --augment-tare P --augment-torque LOW,HIGH
         [--augment-gain LOW,HIGH] [--augment-offset P] [--augment-contact-offset M]
         [--augment-lag LOW,HIGH] [--augment-cache aug.pkl]] [--event-weight W]

Trains the leave-one-family-out forests of ``contact-detector sweep --lofo`` (10 trees, labels
0-0.3 s, the setting's columns of the full feature configuration) on every family but
``--family``, scores the shipped rule on that family and counts, per value of ``--param``
(a family parameter in the manifests' ``params.family``, else a trial parameter in
``params``; numbers are cut at their quartiles), the left-out trials caught within 500 ms,
early and not caught, over the forests of ``--seeds``. ``--trials`` also prints every trial.
``--cache`` keeps the computed frames for the next run on the same folders. A setting named
``NAME+aug`` trains the forests on the other families' wrenches augmented by the
``--augment-*`` options, as ``sweep --lofo --lofo-settings NAME+aug`` does with the same ones,
and with sweep's defaults (the shipped protocol: ``--setting shipped+aug --augment-tare 0.5
--augment-torque 0.1,2 --augment-gain 0.2,1.5 --augment-offset 0.5 --augment-contact-offset
0.05 --event-weight 3``); the left-out family is never augmented. ``--augment-cache`` keeps
those frames. ``--event-weight W`` weighs the training frames near a simulated event as ``sweep
--lofo-event-weight W`` does (default 1).
"""

import argparse
import json
from pathlib import Path
import sys

from contact_detector.evaluation.metrics import score_trial
from contact_detector.training.sweep import fit_forest
from lofo_frames import (add_protocol_arguments, add_rule_argument, left_out_decisions,
                         protocol_frames, rule_from)
import numpy as np

# score_trial's verdicts, as sweep --lofo counts them
VERDICTS = {'detected': 'caught', 'premature': 'early', 'late': 'missed', 'missed': 'missed'}


def param_of(trial: dict, name: str) -> object:
    """Return a trial's family parameter ``name``, else its trial parameter, else None."""
    params = trial.get('params', {})
    family = params.get('family', {})
    return family[name] if name in family else params.get(name)


def groups(values: list) -> list:
    """Return one label per value: the value itself, or its quartile range for numbers."""
    numbers = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if len(numbers) != len(values) or len(set(numbers)) <= 4:
        return [str(v) for v in values]
    edges = np.quantile(numbers, [0.25, 0.5, 0.75])
    bins = np.searchsorted(edges, numbers, side='right')
    bounds = [min(numbers), *edges, max(numbers)]
    return [f'{bounds[b]:.3g}-{bounds[b + 1]:.3g}' for b in bins]


def main(argv=None) -> int:
    """Run the breakdown; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('folders', nargs='+', type=Path)
    parser.add_argument('--family', default='geometry')
    parser.add_argument('--param', default='tared')
    parser.add_argument('--seeds', default='0,1,2')
    parser.add_argument('--cache', type=Path, default=None)
    parser.add_argument('--jobs', type=int, default=1)
    add_rule_argument(parser)
    parser.add_argument('--trials', action='store_true')
    add_protocol_arguments(parser)
    args = parser.parse_args(argv)
    setting, frames, fit_frames, protocol = protocol_frames(args)
    manifests = [{t['name']: t for t in json.loads((f / 'manifest.json').read_text())['trials']}
                 for f in args.folders]
    fit = [f for f in fit_frames.values() if f.truth.condition != args.family]
    test = {k: f for k, f in frames.items() if f.truth.condition == args.family}
    results = {k: [] for k in test}
    for seed in (int(s) for s in args.seeds.split(',')):
        forest = fit_forest(frames=fit, setting=setting, n_estimators=10, seed=seed,
                            jobs=args.jobs)
        for key, f in test.items():
            _, _, releases = left_out_decisions(forest=forest, frames=f, setting=setting,
                                                rule=rule_from(args))
            outcome = score_trial(truth=f.truth, releases=releases, events=())
            results[key].append(VERDICTS[outcome.verdict])
    keys = sorted(test)
    values = []
    for key in keys:
        tag, name = key.split('/', 1)
        values.append(param_of(manifests[int(tag)].get(name, {}), args.param))
    labels = groups(values)
    print(f'{len(fit)} training trials{protocol}, {len(test)} left out ({args.family}), '
          f'setting {args.setting}, forests of seeds {args.seeds}; by {args.param}:\n')
    print(f'| {args.param} | trials | caught | early | not caught |')
    print('|---|---|---|---|---|')
    for label in sorted(set(labels)):
        got = [v for key, lab in zip(keys, labels) if lab == label for v in results[key]]
        print(f'| {label} | {sum(lab == label for lab in labels)} | '
              f'{got.count("caught")}/{len(got)} | {got.count("early")} | '
              f'{got.count("missed")} |')
    if args.trials:
        print()
        for key, value in zip(keys, values):
            print(f'{args.folders[int(key.split("/")[0])]}/{key.split("/", 1)[1]}: '
                  f'{args.param}={value}: {" ".join(results[key])}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
