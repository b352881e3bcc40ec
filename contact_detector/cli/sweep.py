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
``contact-detector sweep``: choose features, label window and decision rule by measurement.

    contact-detector sweep TRAIN_DIR HELDOUT_DIR [--grid quick|full] [--jobs 2] [--out FILE.md]
    contact-detector sweep DIR... --lofo [--lofo-settings shipped,invariant]
        [--lofo-families exogenous,heavy] [--out FILE.md]
    contact-detector sweep DIR... --model M [--own-test TRAIN_DIR] [--knocks] [--out FILE.md]

With ``--lofo`` every trial of every folder is pooled and grouped by family (its condition set
in the manifest); for each family a forest is trained on all the others and every candidate
rule is scored on the family left out. The table gives one row per family and, per feature
setting and rule, the *worst* family: the figure to choose by. ``--lofo-families`` leaves
only the families named out (each forest still trains on all the others): a cheap screen of a
candidate, not a conclusion.

Trains the paper's forest (10 trees, max_features = sqrt) per feature setting and label window
on the training trials, then scores every decision rule on the held-out trials: detections,
misses, premature releases, latency, contact events blamed on exogenous impacts, frame
precision/recall. With ``--ablation`` it also trains on all condition sets but one and tests on
the one left out (heavy, soft, noisy, gain), for the settings that are meant to generalise.
``--seeds 0,1,2,3`` trains one forest per seed for the grid and the ablation and sums the
counts over the seeds (latency: the median of the per-seed medians); with ``--lofo`` every fold
trains one forest per seed and each family's row pools their outcomes: a 10-tree forest is a
noisy estimator, and one forest cannot tell two close settings apart.

With ``--model`` no forest is trained: the rules (the model's own, the threshold x
confirmation grid, single-frame paths with a slow path) are scored with that model's features,
labels and trees on every trial of the folders, and with ``--own-test`` also on the model's own
trial-split test trials found in TRAIN_DIR: the check of a rule on the model that ships.
``--knocks`` adds, per folder, the trials with a knock on the hand while the object is in the
air (the F/T-only model's safety figure).
"""

import argparse
import json
from pathlib import Path
import sys
from typing import List, Optional, Sequence

from contact_detector.cli.common import add_stream_arguments, discover_all
from contact_detector.cli.model_options import (add_augmentation_arguments,
                                                add_load_path_arguments,
                                                augmentation_from_args)
from contact_detector.errors import ConfigError, ContactDetectorError
from contact_detector.evaluation.truth import knocked_in_air
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import common_rates
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.rule import DecisionRule, LOAD2_FIELDS, LOAD_FIELDS, STEADY_FRAMES
from contact_detector.model.storage import load_bundle
from contact_detector.training.augmentation import AUGMENTED
from contact_detector.training.protocol import check_min_samples_leaf, LabelWindow, SPLITTERS
from contact_detector.training.recipe import DEFAULT_FT_ONLY_RULE, DEFAULT_RULE, NO_AUDIO_RATE
from contact_detector.training.studies import (ablation_study, feature_grid, grid_study,
                                               LOFO_SETTINGS, lofo_study, model_study, STATE,
                                               STUDY_AUGMENTATION)
from contact_detector.training.sweep import decode_bags, rows_markdown, seed_rows_markdown
from tqdm import tqdm


def thresholds(text: str) -> List[float]:
    """Parse ``0.5,0.4`` into thresholds in [0, 1] (argparse type)."""
    try:
        values = [float(v) for v in text.split(',') if v.strip()]
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'not a list of numbers: {text!r}') from err
    if not values or any(not 0.0 <= v <= 1.0 for v in values):
        raise argparse.ArgumentTypeError(f'thresholds must be in [0, 1], got {text!r}')
    return values


def seed_list(text: str) -> List[int]:
    """Parse ``0,1,2,3`` into forest seeds (argparse type)."""
    try:
        seeds = [int(v) for v in text.split(',') if v.strip()]
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'not a list of seeds: {text!r}') from err
    if not seeds:
        raise argparse.ArgumentTypeError(f'no seed in {text!r}')
    return seeds


def discover(folders: Sequence[tuple], args: argparse.Namespace, *,
             allow_no_audio: bool = False) -> tuple[dict, float, float]:
    """
    Find the streams of every folder's bags (flags override); print one line per folder.

    ``folders`` holds ``(name, bags)`` pairs (:func:`folder_bags`). Returns ``({name: {bag:
    Streams}}, audio_rate, wrench_rate)``, the rates shared by all the bags
    (:func:`~contact_detector.io.discovery.common_rates`). ``allow_no_audio``: an F/T-only
    model decides, so recordings without an audio topic are read (their audio rate is unused).
    """
    found = {name: dict(discover_all(bags, args=args, params={},
                                     prog=f'contact-detector sweep: {name}',
                                     allow_no_audio=allow_no_audio))
             for name, bags in folders}
    audio_rate, wrench_rate = common_rates([item for streams in found.values()
                                            for item in streams.items()],
                                           allow_no_audio=allow_no_audio)
    return found, audio_rate or NO_AUDIO_RATE, wrench_rate


def folder_bags(folders: Sequence) -> list:
    """``(folder, its bags)`` for each folder given on the command line."""
    return [(folder, find_bags([folder])) for folder in folders]


def decode(found, tag):
    """Decode every bag once, with a progress bar: 'tag/name' -> (events, truth)."""
    return decode_bags(bags=list(found), spec=StreamSpec(), found=found, tag=tag,
                       progress=lambda b: tqdm(b, desc=f'decode {tag}', unit='bag'))


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector sweep', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+',
                        help='TRAIN_DIR HELDOUT_DIR, or with --lofo any number of folders')
    parser.add_argument('--lofo', action='store_true',
                        help='leave-one-family-out: pool the folders, leave each family out')
    parser.add_argument('--lofo-settings', default=','.join(LOFO_SETTINGS),
                        help=f'feature settings compared with --lofo (from {list(LOFO_SETTINGS)}'
                             f'; NAME{AUGMENTED}: the forests train on augmented wrenches, '
                             'see --augment-tare; the left-out family is never augmented)')
    parser.add_argument('--lofo-families', default=None, metavar='LIST',
                        help='--lofo: leave out only these families, comma-separated (e.g. '
                             'exogenous,heavy), each forest still trained on all the others: '
                             'a cheap screen; a conclusion needs every family (the default)')
    parser.add_argument('--lofo-train-only', action='append', default=[], metavar='DIR',
                        help='--lofo: every fold also trains on the trials of DIR (except '
                             'those of the family left out) and none of them is scored: a '
                             'learning curve on the same scored trials (repeatable)')
    parser.add_argument('--trees', type=int, default=10, help='trees per forest')
    parser.add_argument('--min-samples-leaf', type=int, default=1, metavar='N',
                        help='--lofo: fewest training frames in a leaf of every forest '
                             "(default 1, the paper's fully grown trees)")
    parser.add_argument('--splitter', choices=SPLITTERS, default='best',
                        help="--lofo: how the trees split: 'best' (default, random forests) "
                             "or 'random' (extremely randomized trees)")
    add_augmentation_arguments(parser, defaults=STUDY_AUGMENTATION)
    parser.add_argument('--lofo-label-start', type=float, default=STATE.start_s,
                        help='--lofo: frames from this long after the onset are labelled '
                             f'contact, s (default {STATE.start_s})')
    parser.add_argument('--lofo-label-end', type=float, default=STATE.end_s,
                        help='--lofo: frames up to this long after the onset are labelled '
                             f'contact, s (default {STATE.end_s})')
    parser.add_argument('--lofo-label-ignore', type=float, default=0.0, metavar='S',
                        help='--lofo: leave the frames up to S s after the label window out '
                             'of training (default 0: they are labelled no contact)')
    parser.add_argument('--lofo-label-ignore-lead', action='store_true',
                        help='--lofo: leave the frames from the onset to --lofo-label-start out '
                             'of training (default: they are labelled no contact)')
    parser.add_argument('--lofo-event-weight', type=float, default=1.0, metavar='W',
                        help='--lofo: weight of the no-contact frames from 20 ms before to '
                             '0.8 s after a simulated knock, touch, brush or set-down starts '
                             '(default 1: as every other frame)')
    parser.add_argument('--grid', choices=('compare', 'focus', 'full', 'none'),
                        default='compare', help='feature grid (none: only --ablation)')
    parser.add_argument('--ablation', action='store_true')
    parser.add_argument('--ablation-sustain', type=thresholds,
                        default=[DEFAULT_RULE.sustain_threshold],
                        help='slow-path thresholds scored in the ablation, comma-separated '
                             f'(default {DEFAULT_RULE.sustain_threshold})')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--seeds', type=seed_list, default=None, metavar='LIST',
                        help='forest seeds, comma-separated: grid and ablation summed over '
                             'one forest per seed, --lofo pools each family over them '
                             '(default: --seed alone)')
    parser.add_argument('--model', type=Path, default=None,
                        help='score the rules with this trained model instead of training')
    parser.add_argument('--own-test', type=Path, default=None, metavar='TRAIN_DIR',
                        help="--model: also score the model's own test trials in TRAIN_DIR")
    parser.add_argument('--knocks', action='store_true',
                        help='--model: also score, per folder, the trials with a knock on the '
                             'hand while the object is in the air (simulator manifests)')
    add_stream_arguments(parser)
    add_load_path_arguments(
        parser, field='load', defaults=DecisionRule(),
        help_text="also score the shipped rule (--lofo) or the model's rule (--model) with the "
                  'load path: contact when the force stayed N from the carried load for '
                  '--load-frames frames and the mean P(contact) of --load-support-frames '
                  'frames >= --load-support')
    add_load_path_arguments(
        parser, field='load2', defaults=DecisionRule(),
        help_text='with --load-threshold: the scored rule also has the second load path, the '
                  'same test with its own --load2-* distance, frames, backing and direction '
                  'gate')
    parser.add_argument('--load2-steady', type=float, default=DecisionRule().load2_steady,
                        metavar='S',
                        help='with --load2-threshold: the second load path also needs the '
                             f'distances of the newest {STEADY_FRAMES} frames within max - min '
                             '<= S x their median (0 = off, the default; the shipped F/T-only '
                             f'model: {DEFAULT_FT_ONLY_RULE.load2_steady:g})')
    parser.add_argument('--out', type=Path, default=None, help='markdown table file')
    parser.add_argument('--json', type=Path, default=None, help='all rows as JSON')
    args = parser.parse_args(argv)
    if (args.own_test is not None or args.knocks) and args.model is None:
        parser.error('--own-test and --knocks need --model')
    try:
        args.load = load_fields(args)
    except ContactDetectorError as err:
        parser.error(str(err))
    if args.model is not None:
        try:
            output = with_model(args)
        except ContactDetectorError as err:
            print(f'contact-detector sweep: {err}', file=sys.stderr)
            return 1
        print(output)
        if args.out:
            args.out.write_text(output)
        return 0
    if args.lofo_train_only and not args.lofo:
        parser.error('--lofo-train-only needs --lofo')
    both = {str(Path(f).resolve()) for f in args.bags} & {
        str(Path(f).resolve()) for f in args.lofo_train_only}
    if both:
        parser.error(f'a folder is both scored and only trained on: {sorted(both)}')
    if args.lofo:
        try:
            augmentation = augmentation_from_args(args, defaults=STUDY_AUGMENTATION)
            check_min_samples_leaf(args.min_samples_leaf)
            label = LabelWindow(args.lofo_label_start, args.lofo_label_end,
                                args.lofo_label_ignore, args.lofo_event_weight,
                                args.lofo_label_ignore_lead)
            found, audio_rate, wrench_rate = discover(
                folder_bags(args.bags + args.lofo_train_only), args)
        except ContactDetectorError as err:
            parser.error(str(err))
        trials, train_only = {}, {}
        for i, folder in enumerate(args.bags):
            trials.update(decode(found[folder], f'{i}'))
        for i, folder in enumerate(args.lofo_train_only):
            train_only.update(decode(found[folder], f'train-only-{i}'))
        families = ([f.strip() for f in args.lofo_families.split(',') if f.strip()]
                    if args.lofo_families else None)
        try:
            output = lofo_study(
                trials=trials, settings=args.lofo_settings.split(','),
                label=label, trees=args.trees, seed=args.seed, seeds=args.seeds or (),
                augmentation=augmentation, min_samples_leaf=args.min_samples_leaf,
                splitter=args.splitter, families=families, audio_rate=audio_rate,
                wrench_rate=wrench_rate, jobs=args.jobs, load=args.load,
                train_only=train_only,
                progress=lambda items: tqdm(items, desc='lofo', unit='setting'))
        except ContactDetectorError as err:
            parser.error(str(err))
        print(output)
        if args.out:
            args.out.write_text(output)
        return 0
    if len(args.bags) != 2:
        parser.error('give TRAIN_DIR and HELDOUT_DIR (or --lofo with any folders)')
    try:
        found, audio_rate, wrench_rate = discover(folder_bags(args.bags), args)
    except ContactDetectorError as err:
        parser.error(str(err))
    train = decode(found[args.bags[0]], 'train')
    heldout = decode(found[args.bags[1]], 'heldout')
    rows, best_rows, totals = grid_study(
        train=train, heldout=heldout, settings=feature_grid(args.grid), seeds=args.seeds,
        seed=args.seed, audio_rate=audio_rate, wrench_rate=wrench_rate, jobs=args.jobs,
        progress=lambda items: tqdm(items, desc='settings', unit='setting'))
    text = []
    if totals:
        text += ['## Every rule, summed over the forest seeds (held-out trials)', '',
                 seed_rows_markdown(totals, seeds=args.seeds), '']
    if rows:
        text += ['## Best rule per setting (held-out trials)', '', rows_markdown(best_rows), '',
                 '## Every rule', '', rows_markdown(rows), '']
    if args.ablation:
        text += ['## Ablation: train on the other condition sets, test on the one left out',
                 '', ablation_study(
                     trials={**train, **heldout}, sustain=args.ablation_sustain,
                     seeds=args.seeds or [args.seed], audio_rate=audio_rate,
                     wrench_rate=wrench_rate, jobs=args.jobs,
                     progress=lambda items: tqdm(items, desc='ablation', unit='setting')),
                 '']
    output = '\n'.join(text)
    print(output)
    if args.out:
        args.out.write_text(output)
    if args.json:
        args.json.write_text(json.dumps([r.__dict__ for r in rows], indent=2, default=str))
    return 0


def with_model(args) -> str:
    """Decode the model's own test trials (``--own-test``) and the folders; score the rules."""
    bundle = load_bundle(path=args.model)
    folders = folder_bags(args.bags)
    own_name = f'{args.own_test} (own test trials)'
    if args.own_test is not None:
        test = set(bundle.training.get('test_trials', []))
        # the card names a test trial by its bag, or by folder and bag where two bags share a
        # name (training.recipe), with sim/ for simulated trials
        own = [b for b in find_bags([args.own_test])
               if test & {b.name, f'sim/{b.name}', f'{b.parent.name}/{b.name}',
                          f'sim/{b.parent.name}/{b.name}'}]
        folders.insert(0, (own_name, own))
    found, audio_rate, wrench_rate = discover(folders, args,
                                              allow_no_audio=bundle.feature_config.ft_only)
    groups = []
    if args.own_test is not None:
        groups.append((f'own {len(found[own_name])} test trials',
                       decode(found[own_name], 'own')))
    for i, folder in enumerate(args.bags):
        trials = decode(found[folder], f'{i}')
        groups.append((f'{Path(folder).name}: {len(trials)} trials', trials))
        if args.knocks:
            knocked = {name: trial for name, trial in trials.items() if knocked_in_air(trial[1])}
            groups.append((f'{Path(folder).name}: {len(knocked)} trials with a knock on the hand '
                           'in the air', knocked))
    return model_study(bundle=bundle, groups=groups,
                       title=f'## Rules scored with {args.model.name} ({bundle.model_id})',
                       audio_rate=audio_rate, wrench_rate=wrench_rate, jobs=args.jobs,
                       load=args.load)


def load_fields(args: argparse.Namespace) -> Optional[dict]:
    """Return the load paths' DecisionRule fields from the options (validated), or None."""
    if args.load2_steady > 0 and args.load2_threshold <= 0:
        raise ConfigError('--load2-steady needs --load2-threshold: it is a condition of the '
                          'second load path')
    if args.load_threshold <= 0:
        if args.load2_threshold > 0:
            raise ConfigError('--load2-threshold needs --load-threshold: the scored rule '
                              'adds both load paths')
        return None
    fields = {name: getattr(args, name) for name in LOAD_FIELDS + LOAD2_FIELDS}
    fields['load2_steady'] = args.load2_steady
    DecisionRule(**fields)          # ConfigError naming a bad value
    return fields


if __name__ == '__main__':
    sys.exit(main())
