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
``contact-detector train``: train the contact forest the paper's way and write its report.

    contact-detector train BAG_OR_DIR... --out models/contact_forest.npz --report DIR
                           [--labels labels.csv]... [--with-sim N [--sim-dir DIR]]

Labels come from each bag's ``/contact_truth`` (or ``--labels FILE.csv`` with rows
``bag,onset_start,onset_end``, several rows for a recording with several contacts; a bag the
CSV does not name keeps its ``/contact_truth``, and one with neither is refused); features
from the same streaming core the node runs. ``--with-sim N`` adds N simulated trials of the
``wide`` condition sets (all twelve simulator families, at the recordings' F/T rate to 1 Hz
and audio rate, labelled by the simulator's truth) in the shipped model's proportions: N - M
with each family's own exogenous events (seed --seed) and M = N/5 rounded (120 of 600) with
any knock, touch, brush or set-down in every family (seed --seed + 1); in a temporary
directory, or in ``--sim-dir`` to keep them (``DIR/family`` and ``DIR/mixed``; a folder that
already holds those trials is reused, one that holds others is refused). The model card's
``training.sources`` records what the model was trained on. The report directory gets
``summary.md``, ``metrics.json`` and PNG figures (confusion matrix, ROC curve, feature
importance). The saved model is the trial-split forest refit on train + validation.
"""

import argparse
from datetime import datetime, timezone
import json
from pathlib import Path
import sys
import tempfile
from typing import Optional, Sequence

from contact_detector.cli.common import add_stream_arguments, discover_all
from contact_detector.cli.model_options import (add_augmentation_arguments,
                                                add_feature_arguments, augmentation_from_args,
                                                config_from_args, labels_from_args,
                                                rule_from_args, tree_counts)
from contact_detector.errors import ConfigError, ContactDetectorError
from contact_detector.evaluation.truth import conditions_of
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import Streams
from contact_detector.model.storage import save_bundle
from contact_detector.training.protocol import labels_for, SPLITTERS
from contact_detector.training.recipe import (NO_AUDIO_RATE, SIM_CONDITIONS, sim_parts,
                                              simulated_trials, train_model, training_sources)
from contact_detector.training.report import write_report
import numpy as np
from tqdm import tqdm


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector train', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', help='bag directories or folders of bags')
    parser.add_argument('--out', type=Path, default=Path('models/contact_forest.npz'),
                        help='model file; its suffix (.npz, .joblib, .skops) picks the format '
                             'unless --format is given (default models/contact_forest.npz)')
    parser.add_argument('--report', type=Path, default=None, help='report directory')
    parser.add_argument('--labels', type=Path, action='append', default=None,
                        help='CSV of bag,onset_start,onset_end (instead of /contact_truth); '
                             'several rows for a recording with several contacts; repeat it '
                             'for recordings whose rows are in several CSVs')
    parser.add_argument('--with-sim', type=int, default=0, metavar='N',
                        help='add N simulated trials of the wide condition sets (default 0): '
                             "N - round(N/5) with each family's own exogenous events (seed "
                             '--seed), round(N/5) with any knock, touch, brush or set-down in '
                             'every family (seed --seed + 1), as the shipped model')
    parser.add_argument('--sim-dir', type=Path, default=None, metavar='DIR',
                        help='keep the --with-sim trials in DIR/family and DIR/mixed (reused '
                             'if it holds them, refused if it holds others; default: a '
                             'temporary directory)')
    parser.add_argument('--format', choices=('npz', 'joblib', 'skops'), default=None,
                        help='model format (default: from the --out suffix; npz loads with '
                             'numpy alone, docs/model.md)')
    parser.add_argument('--jobs', type=int, default=1, help='parallel workers')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--augment', action='store_true',
                        help="vary each trial's wrench before its features: other lever arms "
                             'and tared sensors (docs/model.md); drawn from --seed and the '
                             'bag name')
    add_augmentation_arguments(parser)
    parser.add_argument('--trees', type=tree_counts, default=list(range(1, 11)), metavar='LIST',
                        help='candidate n_estimators, chosen by validation ROC AUC (default '
                             "1-10, the paper's; e.g. 1-10,20,50 or 50)")
    parser.add_argument('--min-samples-leaf', type=int, default=1, metavar='N',
                        help='fewest training frames in a leaf of every forest (default 1, the '
                             "paper's: fully grown trees, pure leaves)")
    parser.add_argument('--splitter', choices=SPLITTERS, default='best',
                        help="how the trees split: 'best' (default, a random forest, the "
                             "paper's) or 'random' (extremely randomized trees; "
                             'docs/model.md)')
    add_stream_arguments(parser)
    parser.add_argument('--no-events', action='store_true',
                        help='skip the event metrics on the test trials')
    add_feature_arguments(parser)
    args = parser.parse_args(argv)
    if args.with_sim < 0:
        parser.error('--with-sim must be >= 0')
    if args.sim_dir is not None and not args.with_sim:
        parser.error('--sim-dir needs --with-sim N')
    try:
        if args.with_sim and args.sim_dir is None:
            with tempfile.TemporaryDirectory(prefix='contact_detector_sim_') as tmp:
                return _train(args, sim_dir=Path(tmp))
        return _train(args, sim_dir=args.sim_dir)
    except ContactDetectorError as err:
        print(f'contact-detector train: {err}', file=sys.stderr)
        return 1


def _train(args: argparse.Namespace, *, sim_dir: Optional[Path]) -> int:
    config = config_from_args(args)
    labels = labels_from_args(args)
    rule = rule_from_args(args)
    if rule.uses_load and not config.measures_carried:
        raise ConfigError('--load-threshold and --load2-threshold need the carried load: '
                          'add a carried-load feature (e.g. force_shift_rel) to '
                          '--extra-features, or set both to 0')
    # An F/T-only model (--no-audio) trains on recordings without an audio topic too.
    found: dict[Path, Streams] = dict(discover_all(find_bags(args.bags), args=args, params={},
                                                   prog='contact-detector train',
                                                   allow_no_audio=config.ft_only))
    user_bags = list(found)
    csv_onsets = None
    if args.labels:
        labelled = labels_for(csv_paths=args.labels, bags=user_bags)
        csv_onsets = labelled.onsets
        user_bags = [b for b in user_bags if b not in labelled.left_out]
        found = {b: found[b] for b in user_bags}     # bags label could not label are left out
        if labelled.own_truth:
            csvs = ', '.join(map(str, args.labels))
            print(f'contact-detector train: {len(labelled.own_truth)} bags without a row in '
                  f'{csvs} are labelled by their own truth (/contact_truth)')
    sim = None
    if args.with_sim:
        ft_rate = float(np.round(np.median([s.wrench_rate for s in found.values()])))
        audio_rate = int(max([s.audio_rate for s in found.values() if s.has_audio],
                             default=NO_AUDIO_RATE))
        parts = sim_parts(n=args.with_sim, seed=args.seed, ft_rate=ft_rate,
                          audio_rate=audio_rate)
        mixed = parts.get('mixed', {}).get('trials', 0)
        print(f'contact-detector train: {args.with_sim} simulated trials of '
              f'{", ".join(SIM_CONDITIONS)} at {ft_rate:g} Hz F/T, {audio_rate} Hz audio: '
              f"{args.with_sim - mixed} with each family's own events, {mixed} with any event "
              'in every family')
        sim = simulated_trials(
            sim_dir=sim_dir, n=args.with_sim, seed=args.seed, ft_rate=ft_rate,
            audio_rate=audio_rate,
            progress=lambda trials, count: tqdm(trials, total=count, desc='simulate',
                                                unit='trial'))
        for name in sim.reused:
            print(f'contact-detector train: reusing {parts[name]["trials"]} simulated trials '
                  f'in {sim_dir / name}')
        found.update(discover_all(sim.bags, args=argparse.Namespace(
            wrench_topic=None, audio_topic=None, audio_rate=None, wrench_rate=None,
            audio_coding=None), params={}, prog='contact-detector train'))
    bags = list(found)
    manifest = conditions_of(bags)
    sources = training_sources(user=user_bags, csv_onsets=csv_onsets,
                               labels_paths=args.labels or (), sim=sim, sim_dir=sim_dir,
                               kept=args.sim_dir is not None, manifest=manifest)
    bars = {}

    def step(_message: str) -> None:
        if 'forests' not in bars:
            bars['forests'] = tqdm(total=2 * (len(args.trees) + 1), desc='forests', unit='step')
        bars['forests'].update(1)

    try:
        trained = train_model(
            found=found, user_bags=user_bags, csv_onsets=csv_onsets, manifest=manifest,
            sources=sources, config=config, labels=labels, rule=rule, trees=args.trees,
            seed=args.seed, jobs=args.jobs, events=not args.no_events,
            augmentation=(augmentation_from_args(args) if args.augment else None),
            min_samples_leaf=args.min_samples_leaf, splitter=args.splitter,
            created=datetime.now(timezone.utc).isoformat(timespec='seconds'),
            progress=lambda items, desc: tqdm(items, desc=desc, unit='bag'), step=step,
            log=print)
    finally:
        if 'forests' in bars:
            bars['forests'].close()
    results, bundle = trained.results, trained.bundle
    quoted, metrics, training = results['trial'], trained.metrics, trained.training
    args.out.parent.mkdir(parents=True, exist_ok=True)
    path = save_bundle(bundle=bundle, path=args.out, fmt=args.format,
                       check_frames=trained.x)
    print(f'model written to {path}')
    print(f'trial split: n_estimators={quoted.best_n}, test AUC {quoted.test_auc:.4f}, '
          f'10-fold CV accuracy {quoted.cv_mean:.5f} (SD {quoted.cv_sd:.5f})')
    print(quoted.report_text)
    if 'events_test_trials' in metrics:
        print('events on test trials:', json.dumps(metrics['events_test_trials']))
    if args.report:
        write_report(report=args.report, results=results, names=config.feature_names,
                     training=training, metrics=metrics, model_path=path)
        print(f'report written to {args.report}/summary.md')
    return 0


if __name__ == '__main__':
    sys.exit(main())
