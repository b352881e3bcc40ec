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
A shipped model's rules on labelled recordings of other worlds, on raw or calibrated P.

    .venv/bin/python benchmarks/generator_rules.py SET... [--recipe multimodal|ft-only]
        [--model MODEL] [--rule NAME:FIELD=VALUE[,...]]...
        [--calibrate TRAIN_DIR... [--seeds 0] [--groups 3]] [--jobs 2] [--families]
        [--early] [--json out.json]

``SET`` is a folder of labelled recordings with a ``labels.csv`` (``bag,onset_start,
onset_end``, the bags relative to the folder) and one sub-folder per family, such as an
independent generator's set (``benchmarks/independent_trials.py``,
``benchmarks/independent_robots.py``). Each recording is decoded with the streams it has (its
own audio and F/T rates; a multimodal recipe skips the recordings without audio), and its
feature frames are computed with the model's feature configuration and the load path's
columns. Every rule (the model's own, ``S``, and each ``--rule``: ``S`` with the named
fields changed, as in ``lofo_rules.py``) is scored with the **model's own forest**
(``training.sweep.score_rules``: caught within 0.5 s of the onset, early before it). A
generator's ``trials.json`` beside ``labels.csv`` gives the truth its exogenous events
(:data:`EVENT_KINDS`), so an early release is blamed on the newest one that started at most
0.5 s before it, as for simulated trials. Prints per set and over all sets one line per rule
as ``lofo_rules.py`` does (the family names are ``SET/family``). The model is the recipe's
shipped one unless ``--model`` names another; ``--early`` adds one line per
early release of ``S``: the trial, how long before the onset, and the events of the 1.5 s
before it.

``--calibrate TRAIN_DIR...`` (the simulated folders the model was trained on,
``tools/build_model.sh``'s ``data/train data/train_extra``) also scores every rule, as
``NAME~cal``, on ``g(P)``: a monotone map from P(contact) to the frequency of contact frames,
fitted as ``lofo_calibration.py`` fits it (the recipe's training families in ``--groups``
groups, each predicted by a 10-tree forest trained without it, for each ``--seeds`` seed).
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
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.training.protocol import labels_for, LabelWindow
from contact_detector.training.recipe import NO_AUDIO_RATE
from contact_detector.training.sweep import FeatureSetting, score_rules, trial_frames
from joblib import delayed, Parallel
from lofo_calibration import CalibratedForest, cross_family_calibration, curve
from lofo_rules import (parse_rule, print_rules, recipe_frames, recipe_rules, RECIPES,
                        summarise, write_json)

#: The generators' event kinds (``trials.json``) as the project's impact kinds. Speech, a door
#: slam and a temperature step put no load on the hand or the table and are not impacts.
EVENT_KINDS = {'knock_hand': 'hand', 'knock_object': 'hand', 'knock_table': 'table',
               'touch': 'touch', 'push_object': 'touch', 'push_arm': 'touch', 'brush': 'brush',
               'set_down_nearby': 'setdown', 'set_down': 'setdown'}
#: How far before an early release ``--early`` lists the events, s.
EARLY_LOOKBACK_S = 1.5


def generator_events(folder: Path) -> Dict[str, list]:
    """
    Return each trial's events from a generator's ``trials.json``, keyed by its bag's path.

    An event is ``(start time s, generator kind, before the onset)``; {} without the file.
    """
    manifest = folder / 'trials.json'
    if not manifest.is_file():
        return {}
    trials = json.loads(manifest.read_text())['trials']
    return {t['bag']: [(float(e['t_abs']), e['kind'], bool(e.get('before_onset')))
                       for e in t.get('events', [])] for t in trials}


def recording_frames(*, bag: Path, onset: float, name: str, family: str, events: list,
                     config, multimodal: bool) -> Optional[object]:
    """
    Return one labelled recording's feature frames (a ``TrialFrames``), or None.

    None: the recording has no audio topic and the recipe needs one. ``events`` are
    :func:`generator_events`' of the trial; those of :data:`EVENT_KINDS` are its impacts.
    """
    streams = discover_streams(bag, allow_no_audio=True)
    if multimodal and not streams.has_audio:
        return None
    loaded = load_events(bag, spec=stream_spec(streams, {}))
    impacts = tuple((t, EVENT_KINDS[kind], in_air) for t, kind, in_air in events
                    if kind in EVENT_KINDS)
    truth = Truth(name=name, condition=family, onset_t=float(onset), impacts=impacts)
    return trial_frames(events=loaded, truth=truth, config=config,
                        audio_rate=streams.audio_rate or NO_AUDIO_RATE,
                        wrench_rate=streams.wrench_rate)


def set_frames(*, folder: Path, config, multimodal: bool, jobs: int) -> List[object]:
    """Return the frames of every labelled recording of one set, in the order of its bags."""
    bags = find_bags(sorted(d for d in folder.iterdir() if d.is_dir()))
    onsets = labels_for(csv_paths=[folder / 'labels.csv'], bags=bags).onsets
    events = generator_events(folder)
    tasks = [(bag, onsets[bag][0], bag.relative_to(folder).as_posix()) for bag in bags
             if onsets.get(bag)]
    frames = Parallel(n_jobs=jobs)(
        delayed(recording_frames)(bag=bag, onset=onset, name=f'{folder.name}/{rel}',
                                  family=f'{folder.name}/{rel.split("/")[0]}',
                                  events=events.get(rel, []), config=config,
                                  multimodal=multimodal)
        for bag, onset, rel in tasks)
    return [f for f in frames if f is not None]


def early_lines(*, outcomes: list, frames: list) -> List[str]:
    """One line per early release: the trial, how early, the generator events before it."""
    lines = []
    for outcome, f in zip(outcomes, frames):
        if outcome.verdict != 'premature':
            continue
        before = [f'{kind} {outcome.release_t - t:.2f} s' for t, kind, _ in f.truth.impacts
                  if 0.0 <= outcome.release_t - t <= EARLY_LOOKBACK_S]
        lines.append(f'{outcome.name}: {outcome.onset_t - outcome.release_t:.2f} s before the '
                     f'onset, after {", ".join(before) or "no event"} '
                     f'(blamed: {outcome.premature_after})')
    return lines


def print_sets(outcomes: Dict[str, Dict[str, List]], *, families: bool) -> Dict[str, dict]:
    """
    Print each set's (and ``'all'``'s) rules as ``lofo_rules.py`` does; return the summaries.

    ``outcomes`` maps a set's name to each rule's outcomes; the result maps it to each rule's
    :func:`lofo_rules.summarise` (no trial is knocked on the hand in the air here).
    """
    summary = {}
    for set_name, by_rule in outcomes.items():
        print(f'== {set_name}')
        summary[set_name] = {name: summarise(outcomes=o, knocked=[])
                             for name, o in by_rule.items()}
        print_rules(summary[set_name], families=families)
    return summary


def sets_parser(description: str) -> argparse.ArgumentParser:
    """Return a screen's parser with its ``sets``: folders of labelled recordings."""
    parser = argparse.ArgumentParser(description=description,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('sets', nargs='+', type=Path,
                        help='folders of labelled recordings (labels.csv, family sub-folders)')
    return parser


def main(argv=None) -> int:
    """Run the comparison; return the exit status."""
    parser = sets_parser(__doc__)
    parser.add_argument('--model', type=Path, default=None,
                        help="the model whose forest decides (default: the recipe's shipped "
                             'model)')
    parser.add_argument('--recipe', choices=sorted(RECIPES), default='multimodal')
    parser.add_argument('--rule', action='append', default=[],
                        help="NAME:FIELD=VALUE[,...], the model's rule with those fields")
    parser.add_argument('--calibrate', nargs='+', type=Path, default=None, metavar='TRAIN_DIR',
                        help="the model's simulated training folders: also score on g(P)")
    parser.add_argument('--seeds', default='0', help="the calibration forests' seeds")
    parser.add_argument('--groups', type=int, default=3,
                        help='groups of training families the calibration predicts in turn')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--families', action='store_true', help='one line per family too')
    parser.add_argument('--early', action='store_true',
                        help="one line per early release of the model's rule")
    parser.add_argument('--json', type=Path, default=None, help='the counts, as JSON')
    args = parser.parse_args(argv)
    if args.groups < 2:
        parser.error('--groups must be at least 2')
    shipped = default_ft_model_path if RECIPES[args.recipe][2] else default_model_path
    bundle = load_bundle(path=args.model or shipped())
    rules = {'S': bundle.decision_rule}
    for text in args.rule:
        try:
            name, rule = parse_rule(text, base=bundle.decision_rule)
        except argparse.ArgumentTypeError as err:
            parser.error(f'--rule: {err}')
        rules[name] = rule
    config = bundle.feature_config.with_rule_columns()
    scored = FeatureSetting(args.recipe, config, LabelWindow(**bundle.label_window),
                            columns=bundle.feature_names)
    multimodal = not bundle.feature_config.ft_only
    sets = {folder.name: set_frames(folder=folder, config=config, multimodal=multimodal,
                                    jobs=args.jobs) for folder in args.sets}
    for name, frames in sets.items():
        print(f'{name}: {len(frames)} recordings', file=sys.stderr, flush=True)
    forest = bundle.compile()
    raw = {name: score_rules(forest=forest, frames=frames, setting=scored,
                             rules=list(rules.values())) for name, frames in sets.items()}
    names = list(rules)
    rows = {name: list(r) for name, r in raw.items()}
    curves = {}
    if args.calibrate:
        # the recipe's sweep --lofo setting, labels and augmentation, on the model's own pool
        pool = argparse.Namespace(folders=args.calibrate, jobs=args.jobs, recipe=args.recipe,
                                  rule=[])
        setting, _ = recipe_rules(pool, parser)
        keyed, fit = recipe_frames(pool, setting)
        names += [f'{name}~cal' for name in rules]
        rows = {name: [] for name in sets}
        for seed in (int(s) for s in args.seeds.split(',')):
            calibration = cross_family_calibration(frames=list(keyed.values()), fit=fit,
                                                   setting=setting, groups=args.groups,
                                                   seed=seed, jobs=args.jobs)
            curves[seed] = curve(calibration)
            print(f'seed {seed}: g(0, 0.1, ..., 1) = {curves[seed]}', file=sys.stderr,
                  flush=True)
            calibrated = CalibratedForest(forest=forest, calibration=calibration)
            for set_name, frames in sets.items():
                # the raw rows are the same for every seed: scored once, above
                rows[set_name] += raw[set_name] + score_rules(
                    forest=calibrated, frames=frames, setting=scored, rules=list(rules.values()))
    outcomes: Dict[str, Dict[str, List]] = {s: {n: [] for n in names} for s in [*sets, 'all']}
    for set_name, set_rows in rows.items():
        # with several seeds the rows repeat the names in turn: outcomes add up over seeds
        for i, row in enumerate(set_rows):
            for key in (set_name, 'all'):
                outcomes[key][names[i % len(names)]] += row.outcomes
    summary = print_sets(outcomes, families=args.families)
    if args.early:
        print('== early releases of S')
        for set_name, frames in sets.items():
            for line in early_lines(outcomes=raw[set_name][0].outcomes, frames=frames):
                print(line)
    write_json(args.json, rules=rules, summary=summary, curves=curves)
    return 0


if __name__ == '__main__':
    sys.exit(main())
