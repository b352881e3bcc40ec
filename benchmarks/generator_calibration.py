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
A shipped model's rules on raw and calibrated P, on labelled recordings of other worlds.

    .venv/bin/python benchmarks/generator_calibration.py TRAIN_DIR... --sets SET...
        [--model models/contact_forest.npz] [--recipe multimodal|ft-only]
        [--rule NAME:FIELD=VALUE[,...]]... [--seeds 0] [--groups 3] [--jobs 2]
        [--families] [--json out.json]

``TRAIN_DIR`` are the simulated folders the model was trained on (``tools/build_model.sh``'s
``data/train data/train_extra``). On them a monotone map ``g`` from P(contact) to the
frequency of contact frames is fitted as ``lofo_calibration.py`` fits it: the recipe's
training families in ``--groups`` groups, each predicted by a 10-tree forest (the recipe's
setting, augmentation and label window; each ``--seeds`` seed in turn) trained without it.

``SET`` is a folder of labelled recordings with a ``labels.csv`` (``bag,onset_start,
onset_end``, the bags relative to the folder) and one sub-folder per family, such as an
independent generator's set (``benchmarks/independent_trials.py``,
``benchmarks/independent_robots.py``). Each recording is decoded with the streams it has (its
own audio and F/T rates; a multimodal recipe skips the recordings without audio), its feature
frames computed with the model's feature configuration and the load path's columns, and every
rule (the recipe's shipped rule ``S`` and each ``--rule``) is scored with the **model's own
forest** on P and, as ``NAME~cal``, on ``g(P)`` (``training.sweep.score_rules``: caught within
0.5 s of the onset, early before it). Prints per set and over all sets one line per rule as
``lofo_rules.py`` does (the family names are ``SET/family``).
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Dict, List, Optional

from contact_detector.detection.factory import stream_spec
from contact_detector.evaluation.metrics import Truth
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import discover_streams
from contact_detector.io.sensor_stream import load_events
from contact_detector.model.storage import load_bundle
from contact_detector.training.protocol import labels_for, LabelWindow
from contact_detector.training.sweep import FeatureSetting, trial_frames
from joblib import delayed, Parallel
from lofo_calibration import cross_family_calibration, curve, score_raw_and_calibrated
from lofo_rules import (add_arguments, print_rules, recipe_frames, recipe_rules, RECIPES,
                        summarise)


def recording_frames(*, bag: Path, onset: float, name: str, family: str, config,
                     multimodal: bool) -> Optional[object]:
    """
    Return one labelled recording's feature frames (a ``TrialFrames``), or None.

    None: the recording has no audio topic and the recipe needs one.
    """
    streams = discover_streams(bag, allow_no_audio=True)
    if multimodal and not streams.has_audio:
        return None
    events = load_events(bag, spec=stream_spec(streams, {}))
    truth = Truth(name=name, condition=family, onset_t=float(onset))
    return trial_frames(events=events, truth=truth, config=config,
                        audio_rate=streams.audio_rate or 16000.0,
                        wrench_rate=streams.wrench_rate)


def set_frames(*, folder: Path, config, multimodal: bool, jobs: int) -> List[object]:
    """Return the frames of every labelled recording of one set, in the order of its bags."""
    bags = find_bags(sorted(d for d in folder.iterdir() if d.is_dir()))
    onsets = labels_for(csv_path=folder / 'labels.csv', bags=bags).onsets
    tasks = [(bag, onsets[bag][0], f'{folder.name}/{bag.relative_to(folder)}',
              f'{folder.name}/{bag.relative_to(folder).parts[0]}')
             for bag in bags if onsets.get(bag)]
    frames = Parallel(n_jobs=jobs)(
        delayed(recording_frames)(bag=bag, onset=onset, name=name, family=family,
                                  config=config, multimodal=multimodal)
        for bag, onset, name, family in tasks)
    return [f for f in frames if f is not None]


def main(argv=None) -> int:
    """Run the screen; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    parser.add_argument('--sets', nargs='+', type=Path, required=True,
                        help='folders of labelled recordings (labels.csv, family sub-folders)')
    parser.add_argument('--model', type=Path, default=Path('models/contact_forest.npz'),
                        help="the shipped model whose forest decides (the recipe's)")
    parser.add_argument('--groups', type=int, default=3,
                        help='groups of training families the calibration predicts in turn')
    args = parser.parse_args(argv)
    if args.groups < 2:
        parser.error('--groups must be at least 2')
    setting, rules = recipe_rules(args, parser)
    bundle = load_bundle(path=args.model)
    if bundle.decision_rule != rules['S']:
        print(f"note: {args.model}'s rule differs from the recipe's shipped rule; S is the "
              "recipe's", file=sys.stderr)
    config = bundle.feature_config.with_rule_columns()
    scored = FeatureSetting(args.recipe, config, LabelWindow(**bundle.label_window),
                            columns=bundle.feature_names)
    multimodal = not RECIPES[args.recipe][2]
    sets = {folder.name: set_frames(folder=folder, config=config, multimodal=multimodal,
                                    jobs=args.jobs) for folder in args.sets}
    for name, frames in sets.items():
        print(f'{name}: {len(frames)} recordings', file=sys.stderr, flush=True)
    keyed, fit = recipe_frames(args, setting)
    forest = bundle.compile()
    names = list(rules) + [f'{name}~cal' for name in rules]
    outcomes: Dict[str, Dict[str, List]] = {s: {n: [] for n in names} for s in [*sets, 'all']}
    curves = {}
    for seed in (int(s) for s in args.seeds.split(',')):
        calibration = cross_family_calibration(frames=list(keyed.values()), fit=fit,
                                               setting=setting, groups=args.groups, seed=seed,
                                               jobs=args.jobs)
        curves[seed] = curve(calibration)
        print(f'seed {seed}: g(0, 0.1, ..., 1) = {curves[seed]}', file=sys.stderr, flush=True)
        for set_name, frames in sets.items():
            rows = score_raw_and_calibrated(forest=forest, calibration=calibration,
                                            frames=frames, setting=scored, rules=rules)
            for name, row in zip(names, rows):
                outcomes[set_name][name] += row.outcomes
                outcomes['all'][name] += row.outcomes
    summary = {}
    for set_name, by_rule in outcomes.items():
        print(f'== {set_name}')
        summary[set_name] = {name: summarise(outcomes=o, knocked=[])
                             for name, o in by_rule.items()}
        print_rules(summary[set_name], families=args.families)
    if args.json:
        args.json.write_text(json.dumps({'rules': {n: r.to_dict() for n, r in rules.items()},
                                         'curves': curves, 'summary': summary}, indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(main())
