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
                           [--labels labels.csv] [--with-sim N [--sim-dir DIR]]

Labels come from each bag's ``/contact_truth`` (or ``--labels FILE.csv`` with rows
``bag,onset_start,onset_end``, several rows for a recording with several contacts); features
from the same streaming core the node runs. ``--with-sim N`` adds N simulated trials of the
``wide`` condition sets (all twelve simulator families, at the recordings' F/T rate to 1 Hz
and audio rate, labelled by the simulator's truth) to the recordings: in a temporary
directory, or in ``--sim-dir`` to keep them (a folder that already holds those N trials is
reused). The model
card's ``training.sources`` records what the model was trained on. The report directory gets
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

from contact_detector.cli.detect import add_stream_arguments, discover_all, stream_spec
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector
from contact_detector.errors import BagError, ContactDetectorError
from contact_detector.evaluation.metrics import score_onsets, score_trial, summarize, Truth
from contact_detector.features.config import (EXTRA_FEATURES, FEATURE_SCHEMA_VERSION,
                                              FeatureConfig, SHIFT_FEATURES)
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import Streams
from contact_detector.io.sensor_stream import load_events, StreamSpec
from contact_detector.model.augmentation import (scale_range, trial_seed,
                                                 WrenchAugmentation)
from contact_detector.model.bundle import (DecisionRule, ModelBundle, runtime_versions,
                                           save_bundle)
from contact_detector.model.training import (LabelWindow, read_labels_csv, run_split,
                                             trial_features, unlabelled_bags)
from contact_detector.sim.bag_writer import write_trials
from contact_detector.sim.trial import simulate_trials
import numpy as np
from tqdm import tqdm

#: Condition sets of the simulated trials ``--with-sim`` adds.
SIM_CONDITIONS = ('wide',)
#: Recordings (and simulated trials) the split by recording needs: one per set at least.
MIN_RECORDINGS = 3

#: The defaults chosen by leave-one-family-out (docs/generalisation.md): a 0.64 s F/T window
#: updated at every sample with its mean removed; audio loudness relative to the room (dB above
#: the noise floor, its recent peak, rise and gap); the change of |F| and |T| against a median
#: baseline and its recent maximum; the orientation- and tare-free length of the force and
#: torque vector change with its 0.1 s minimum and 0.5 s maximum. Labels cover the first 0.3 s
#: of the contact; release at the first frame where every tree says contact (p >= 0.95 with 10
#: trees; 0.9 was as safe on every left-out simulator family but released early 3 times in 48
#: on the real_sounds family kept out of the choice), or when the mean P(contact) of the last
#: 15 frames reaches 0.3.
DEFAULT_FEATURES = FeatureConfig(ft_window=64, ft_hop=1, ft_detrend='mean',
                                 delta_window=1, delta_lag=5, rise_frames=2,
                                 change_max_frames=50, shift_min_frames=10, shift_lag=20,
                                 shift_window=40,
                                 extra_features=('audio_power_rel_db', 'audio_peak_rel_db',
                                                 'audio_rise_db', 'audio_peak_gap_db',
                                                 'force_change', 'torque_change',
                                                 'force_change_max', 'torque_change_max',
                                                 'force_shift', 'torque_shift',
                                                 'force_shift_min', 'torque_shift_min',
                                                 'force_shift_max', 'torque_shift_max'))
#: The extra features of an F/T-only model (``--no-audio``): the vector shift features, which
#: do not depend on the sensor's orientation, tare or sign convention, and the signed changes
#: of |F| and |T| with their recent maxima, which tell a knock on the hand from a touch
#: (chosen by leaving each family out: docs/offline.md, "Robots without a microphone").
DEFAULT_FT_ONLY_EXTRA = SHIFT_FEATURES + ('force_change', 'torque_change', 'force_change_max',
                                          'torque_change_max')
#: Audio rate assumed for recordings without an audio topic (an F/T-only model reads none), Hz.
NO_AUDIO_RATE = 16000
DEFAULT_LABELS = LabelWindow(start_s=0.0, end_s=0.3)
DEFAULT_RULE = DecisionRule(threshold=0.95, confirm_frames=1, refractory_s=1.0,
                            sustain_frames=15, sustain_threshold=0.3)


def add_feature_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the feature/label/rule options shared by train and sweep."""
    d = DEFAULT_FEATURES
    parser.add_argument('--ft-window', type=int, default=d.ft_window,
                        help=f'F/T DFT window, samples (default {d.ft_window})')
    parser.add_argument('--ft-hop', type=int, default=d.ft_hop,
                        help=f'F/T feature hop, samples (default {d.ft_hop})')
    parser.add_argument('--ft-detrend', choices=('none', 'mean'), default=d.ft_detrend,
                        help=f"remove each F/T window's mean (default {d.ft_detrend})")
    parser.add_argument('--ft-window-fn', choices=('rect', 'hann'), default=d.ft_window_fn)
    for field, text in (('delta_window', 'F/T change features: newest samples averaged'),
                        ('delta_lag', 'F/T change features: samples back to the reference'),
                        ('baseline_window',
                         'samples in the median baseline of the *_change features'),
                        ('rise_frames', 'audio frames back to the reference of audio_rise_db'),
                        ('change_max_frames',
                         'F/T feature frames over which the *_change_max and *_shift_max '
                         'features take the maximum'),
                        ('shift_min_frames',
                         'F/T feature frames over which the *_shift_min features take the '
                         'minimum'),
                        ('shift_lag', 'F/T samples from the newest to the end of the '
                                      '*_shift baseline'),
                        ('shift_window', 'F/T samples in the median baseline of *_shift')):
        default = getattr(d, field)
        parser.add_argument('--' + field.replace('_', '-'), type=int, default=default,
                            help=f'{text} (default {default})')
    parser.add_argument('--extra-features', default=None,
                        help='comma-separated extra features, from '
                             f"{', '.join(EXTRA_FEATURES)} (default "
                             f"{','.join(d.extra_features)}; with --no-audio "
                             f"{','.join(DEFAULT_FT_ONLY_EXTRA)})")
    parser.add_argument('--no-audio', action='store_true',
                        help='an F/T-only model (robots without a microphone): no audio '
                             'column, one frame per F/T feature frame')
    parser.add_argument('--label-start', type=float, default=DEFAULT_LABELS.start_s,
                        help='label window start after the onset, s')
    parser.add_argument('--label-end', type=float, default=DEFAULT_LABELS.end_s,
                        help='label window end after the onset, s')
    parser.add_argument('--threshold', type=float, default=DEFAULT_RULE.threshold)
    parser.add_argument('--confirm-frames', type=int, default=DEFAULT_RULE.confirm_frames)
    parser.add_argument('--refractory', type=float, default=DEFAULT_RULE.refractory_s)
    parser.add_argument('--average-frames', type=int, default=DEFAULT_RULE.average_frames,
                        help='compare the mean P(contact) of this many frames with --threshold')
    parser.add_argument('--sustain-frames', type=int, default=DEFAULT_RULE.sustain_frames,
                        help='slow path: also contact when the mean P(contact) of this many '
                             'frames >= --sustain-threshold (0 = off)')
    parser.add_argument('--sustain-threshold', type=float,
                        default=DEFAULT_RULE.sustain_threshold)
    parser.add_argument('--evidence-threshold', type=float,
                        default=DEFAULT_RULE.evidence_threshold,
                        help='evidence path: also contact when the sum of P(contact) - '
                             '--evidence-drift over consecutive frames reaches this (0 = off)')
    parser.add_argument('--evidence-drift', type=float, default=DEFAULT_RULE.evidence_drift)


def tree_counts(text: str) -> list:
    """Parse ``1-10,20,50`` into sorted distinct tree counts (argparse type)."""
    counts = set()
    try:
        for part in text.split(','):
            low, _, high = part.strip().partition('-')
            counts.update(range(int(low), int(high or low) + 1))
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'not a list of tree counts: {text!r}') from err
    if not counts or min(counts) < 1:
        raise argparse.ArgumentTypeError(f'tree counts must be >= 1: {text!r}')
    return sorted(counts)


def rule_from_args(args: argparse.Namespace) -> DecisionRule:
    """Build the DecisionRule from parsed options."""
    return DecisionRule(threshold=args.threshold, confirm_frames=args.confirm_frames,
                        refractory_s=args.refractory, average_frames=args.average_frames,
                        sustain_frames=args.sustain_frames,
                        sustain_threshold=args.sustain_threshold,
                        evidence_threshold=args.evidence_threshold,
                        evidence_drift=args.evidence_drift)


def config_from_args(args: argparse.Namespace) -> FeatureConfig:
    """Build the FeatureConfig from parsed options."""
    no_audio = bool(getattr(args, 'no_audio', False))
    if args.extra_features is None:
        extra = DEFAULT_FT_ONLY_EXTRA if no_audio else DEFAULT_FEATURES.extra_features
    else:
        extra = tuple(e for e in args.extra_features.split(',') if e)
    return FeatureConfig(audio=not no_audio, ft_window=args.ft_window, ft_hop=args.ft_hop,
                         ft_detrend=args.ft_detrend, ft_window_fn=args.ft_window_fn,
                         delta_window=args.delta_window, delta_lag=args.delta_lag,
                         baseline_window=args.baseline_window, rise_frames=args.rise_frames,
                         change_max_frames=args.change_max_frames,
                         shift_min_frames=args.shift_min_frames, shift_lag=args.shift_lag,
                         shift_window=args.shift_window, extra_features=extra)


def conditions_of(bags: Sequence[Path]) -> dict:
    """
    Map bag path -> its manifest entry, from manifests beside the bags, where there are any.

    Keyed by path, not name: two simulated folders both have a ``trial_0000``.
    """
    out = {}
    for parent in {b.parent for b in bags}:
        manifest = parent / 'manifest.json'
        if manifest.exists():
            for trial in json.loads(manifest.read_text()).get('trials', []):
                out[parent / trial['name']] = trial
    return out


def write_figures(*, report: Path, split, names: Sequence[str]) -> None:
    """Confusion matrix, ROC curve and feature importance of a split's test set as PNGs."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from sklearn.metrics import roc_curve

    fig, ax = plt.subplots(figsize=(4, 3.5))
    cm = np.array(split.confusion)
    ax.imshow(cm, cmap='Blues')
    for (i, j), v in np.ndenumerate(cm):
        ax.text(j, i, str(v), ha='center', va='center',
                color='white' if v > cm.max() / 2 else 'black')
    ax.set_xticks([0, 1], ['not contact', 'contact'])
    ax.set_yticks([0, 1], ['not contact', 'contact'])
    ax.set_xlabel('predicted')
    ax.set_ylabel('true')
    ax.set_title(f'Confusion matrix ({split.name} split, test)')
    fig.tight_layout()
    fig.savefig(report / 'confusion_matrix.png', dpi=120)
    plt.close(fig)

    fpr, tpr, _ = roc_curve(split.y_test, split.p_test)
    fig, ax = plt.subplots(figsize=(4, 3.5))
    ax.plot(fpr, tpr, label=f'AUC = {split.test_auc:.4f}')
    ax.plot([0, 1], [0, 1], 'k--', lw=0.8)
    ax.set_xlabel('false positive rate')
    ax.set_ylabel('true positive rate')
    ax.set_title(f'ROC ({split.name} split, test)')
    ax.legend(loc='lower right')
    fig.tight_layout()
    fig.savefig(report / 'roc.png', dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5, 3.5))
    importance = split.forest.feature_importances_
    ax.barh(range(len(names)), importance)
    ax.set_yticks(range(len(names)), names)
    ax.invert_yaxis()
    ax.set_xlabel('importance (mean decrease in impurity)')
    ax.set_title('Feature importance')
    fig.tight_layout()
    fig.savefig(report / 'feature_importance.png', dpi=120)
    plt.close(fig)


def n_table_markdown(split) -> str:
    """Return the paper's Table 1 for one split as markdown."""
    lines = ['| n_estimators | accuracy | AUC |', '|---|---|---|']
    for row in split.n_table:
        mark = '**' if row['n_estimators'] == split.best_n else ''
        lines.append(f"| {mark}{row['n_estimators']}{mark} | {row['accuracy']:.5f} | "
                     f"{row['auc']:.5f} |")
    return '\n'.join(lines)


def event_metrics(*, bundle: ModelBundle, bags: Sequence[Path], spec: StreamSpec,
                  audio_rate: float, wrench_rate: float, manifest: dict,
                  found: Optional[dict] = None, labels: Optional[dict] = None) -> dict:
    """
    Run the full detector on held-out bags; return the event summary.

    ``found`` (bag -> discovered Streams) replaces ``spec`` and the rates per bag; ``labels``
    (bag name -> onsets) is the truth of the bags it names, every onset scored
    (:func:`score_onsets`); other bags are scored against their manifest entry.
    """
    outcomes = []
    for bag in bags:
        streams = (found or {}).get(bag)
        if streams is not None:
            spec = stream_spec(streams, {})
            audio_rate = streams.audio_rate or NO_AUDIO_RATE
            wrench_rate = streams.wrench_rate
        events = load_events(bag, spec=spec)
        detector = ContactDetector(bundle=bundle, settings=DetectorSettings(
            audio_rate=audio_rate, wrench_rate=wrench_rate))
        run = run_detector(events, detector=detector)
        if bag.name in (labels or {}):
            outcomes.extend(score_onsets(name=bag.name, condition='recordings',
                                         onsets=labels[bag.name], events=run.events))
            continue
        info = manifest.get(bag)
        if info is None:
            continue
        truth = Truth(name=bag.name, condition=info.get('condition', ''),
                      onset_t=info['onset_t'], contact_end_t=info.get('contact_end_t'),
                      impacts=tuple((i['t'], i['kind'], i['in_air'])
                                    for i in info.get('impacts', [])))
        outcomes.append(score_trial(truth=truth, releases=run.releases, events=run.events))
    return summarize(outcomes)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector train', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', help='bag directories or folders of bags')
    parser.add_argument('--out', type=Path, default=Path('models/contact_forest.npz'),
                        help='model file; its suffix (.npz, .joblib, .skops) picks the format '
                             'unless --format is given (default models/contact_forest.npz)')
    parser.add_argument('--report', type=Path, default=None, help='report directory')
    parser.add_argument('--labels', type=Path, default=None,
                        help='CSV of bag,onset_start,onset_end (instead of /contact_truth); '
                             'several rows for a recording with several contacts')
    parser.add_argument('--with-sim', type=int, default=0, metavar='N',
                        help='add N simulated trials of the wide condition sets (default 0)')
    parser.add_argument('--sim-dir', type=Path, default=None, metavar='DIR',
                        help='keep the --with-sim trials in DIR (reused if it holds them; '
                             'default: a temporary directory)')
    parser.add_argument('--format', choices=('npz', 'joblib', 'skops'), default=None,
                        help='model format (default: from the --out suffix; npz loads with '
                             'numpy alone, docs/model.md)')
    parser.add_argument('--jobs', type=int, default=1, help='parallel workers')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--augment', action='store_true',
                        help="vary each trial's wrench before its features: other lever arms "
                             'and tared sensors (docs/model.md); drawn from --seed and the '
                             'bag name')
    parser.add_argument('--augment-tare', type=float,
                        default=WrenchAugmentation.tare_probability,
                        help='augmentation: probability of a tared sensor (default '
                             f'{WrenchAugmentation.tare_probability})')
    parser.add_argument('--augment-torque', type=scale_range,
                        default=WrenchAugmentation.torque_scale,
                        help='augmentation: torque scale range LOW,HIGH, log-uniform '
                             '(default 1/3,3)')
    parser.add_argument('--trees', type=tree_counts, default=list(range(1, 11)), metavar='LIST',
                        help='candidate n_estimators, chosen by validation ROC AUC (default '
                             "1-10, the paper's; e.g. 1-10,20,50 or 50)")
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


def simulated_trials(*, sim_dir: Path, n: int, seed: int, ft_rate: float,
                     audio_rate: int) -> tuple[list, dict]:
    """
    Write (or reuse) ``n`` simulated trials of :data:`SIM_CONDITIONS` in ``sim_dir``.

    Returns
    -------
    (list of Path, dict)
        The trial bags and the manifest's settings.

    Raises
    ------
    BagError
        ``sim_dir`` holds other simulator output (other trials, seed or audio rate, or an F/T
        rate more than 1 % away: one recording more or less moves the median a little).

    """
    settings = {'seed': seed, 'trials': n, 'start_index': 0,
                'conditions': list(SIM_CONDITIONS), 'storage': 'sqlite3',
                'audio_rate': audio_rate, 'ft_rate': ft_rate, 'chunk_size': None,
                'label_window_s': 0.1}
    manifest = sim_dir / 'manifest.json'
    if manifest.exists():
        held = json.loads(manifest.read_text())
        have = dict(held.get('settings', {}))
        same_rate = abs(float(have.pop('ft_rate', 0.0)) / ft_rate - 1.0) <= 0.01
        if not same_rate or have != {k: v for k, v in settings.items() if k != 'ft_rate'}:
            raise BagError(f'{sim_dir} holds other simulated trials ({held.get("settings")}); '
                           'give an empty or new --sim-dir')
        print(f'contact-detector train: reusing {n} simulated trials in {sim_dir}')
        return [sim_dir / t['bag'] for t in held['trials']], held['settings']
    trials = simulate_trials(n=n, seed=seed, conditions=SIM_CONDITIONS, audio_rate=audio_rate,
                             ft_rate=ft_rate)
    records, _ = write_trials(trials=tqdm(trials, total=n, desc='simulate', unit='trial'),
                              out_dir=sim_dir, settings=settings)
    return [sim_dir / r['bag'] for r in records], settings


def training_sources(*, user: Sequence[Path], csv_onsets: Optional[dict],
                     labels_path: Optional[Path], sim: Sequence[Path], sim_settings: dict,
                     sim_dir: Optional[Path], kept: bool, manifest: dict) -> dict:
    """Return what the model was trained on, for the model card (``training.sources``)."""
    sources = {}
    if user:
        contacts = sum(len(csv_onsets[b.name]) for b in user) if csv_onsets else len(user)
        sources['recordings'] = {
            'count': len(user), 'contacts': contacts, 'bags': sorted(b.name for b in user),
            'labels': f'{labels_path.name} (--labels)' if labels_path else
            'the /contact_truth topic or the simulator manifest of each bag'}
    if sim:
        sources['simulated'] = {
            'trials': len(sim),
            'families': sorted({manifest.get(b, {}).get('condition', '') for b in sim}),
            'seed': sim_settings['seed'], 'ft_rate': sim_settings['ft_rate'],
            'audio_rate': sim_settings['audio_rate'],
            'labels': 'simulator truth (/contact_truth)',
            'kept_in': str(sim_dir) if kept else 'a temporary directory (deleted)'}
    return sources


def _train(args: argparse.Namespace, *, sim_dir: Optional[Path]) -> int:
    from joblib import delayed, Parallel  # training only: scikit-learn's dependency

    config = config_from_args(args)
    labels = LabelWindow(start_s=args.label_start, end_s=args.label_end)
    rule = rule_from_args(args)
    # An F/T-only model (--no-audio) trains on recordings without an audio topic too.
    found: dict[Path, Streams] = dict(discover_all(find_bags(args.bags), args=args, params={},
                                                   prog='contact-detector train',
                                                   allow_no_audio=config.ft_only))
    user_bags = list(found)
    csv_onsets = read_labels_csv(args.labels) if args.labels else None
    if csv_onsets is not None:
        skipped = unlabelled_bags(args.labels)
        user_bags = [b for b in user_bags if b.name in csv_onsets or b.name not in skipped]
        found = {b: found[b] for b in user_bags}     # bags label could not label are left out
        missing = [b.name for b in user_bags if b.name not in csv_onsets]
        if missing:
            print(f'contact-detector train: {args.labels} has no onset for {missing[:5]}',
                  file=sys.stderr)
            return 1
    sim_bags, sim_settings = [], {}
    if args.with_sim:
        ft_rate = float(np.round(np.median([s.wrench_rate for s in found.values()])))
        audio_rate = int(max([s.audio_rate for s in found.values() if s.has_audio],
                             default=NO_AUDIO_RATE))
        print(f'contact-detector train: {args.with_sim} simulated trials of '
              f'{", ".join(SIM_CONDITIONS)} at {ft_rate:g} Hz F/T, {audio_rate} Hz audio')
        sim_bags, sim_settings = simulated_trials(sim_dir=sim_dir, n=args.with_sim,
                                                  seed=args.seed, ft_rate=ft_rate,
                                                  audio_rate=audio_rate)
        found.update(discover_all(sim_bags, args=argparse.Namespace(
            wrench_topic=None, audio_topic=None, audio_rate=None, wrench_rate=None,
            audio_coding=None), params={}, prog='contact-detector train'))
    bags = list(found)
    if len(bags) < MIN_RECORDINGS:
        raise BagError(f'train splits by recording into training, validation and test sets and '
                       f'needs at least {MIN_RECORDINGS} recordings, got {len(bags)}: add '
                       'recordings, cut a long one into one bag per contact '
                       '(tools/split_recording.py) or add simulated trials (--with-sim N)')
    manifest = conditions_of(bags)
    user = set(user_bags)

    augmentation = (WrenchAugmentation(tare_probability=args.augment_tare,
                                       torque_scale=tuple(args.augment_torque))
                    if args.augment else None)

    def one(bag):
        streams = found[bag]
        return trial_features(bag=bag, config=config, spec=stream_spec(streams, {}),
                              audio_rate=streams.audio_rate or NO_AUDIO_RATE,
                              wrench_rate=streams.wrench_rate, label_window=labels,
                              onsets=csv_onsets[bag.name] if csv_onsets and bag in user
                              else None,
                              condition=manifest.get(bag, {}).get('condition', ''),
                              augmentation=augmentation,
                              augment_seed=trial_seed(seed=args.seed, name=bag.name))

    trials = Parallel(n_jobs=args.jobs)(
        delayed(one)(bag) for bag in tqdm(bags, desc='features', unit='bag'))
    x = np.concatenate([t.x for t in trials])
    y = np.concatenate([t.y for t in trials])
    groups = np.concatenate([np.full(t.y.size, i) for i, t in enumerate(trials)])
    # Names tell the trials apart in the split: a recording and a trial may share one.
    names = [t.name if b in user else f'sim/{t.name}' for b, t in zip(bags, trials)]
    print(f'{len(trials)} trials, {y.size} frames, {int(y.sum())} labelled contact')
    results = {}
    with tqdm(total=2 * (len(args.trees) + 1), desc='forests', unit='step') as bar:
        for kind in ('sample', 'trial'):
            results[kind] = run_split(kind=kind, x=x, y=y, groups=groups, trial_names=names,
                                      seed=args.seed, jobs=args.jobs, n_range=args.trees,
                                      progress=lambda _msg: bar.update(1))
    quoted = results['trial']
    metrics = {kind: {'best_n_estimators': r.best_n, 'validation': r.n_table,
                      'cv_accuracy_mean': r.cv_mean, 'cv_accuracy_sd': r.cv_sd,
                      'test_auc': r.test_auc, 'test_report': r.report,
                      'confusion_matrix': r.confusion}
               for kind, r in results.items()}
    training = {'trials': len(trials), 'frames': int(y.size), 'contact_frames': int(y.sum()),
                'conditions': sorted({t.condition for t in trials}),
                'test_trials': quoted.test_trials, 'seed': args.seed,
                'augmentation': augmentation.to_dict() if augmentation else None,
                'audio_rate': sorted({s.audio_rate for s in found.values()}),
                'wrench_rate': sorted({round(s.wrench_rate, 3) for s in found.values()}),
                'sources': training_sources(user=user_bags, csv_onsets=csv_onsets,
                                            labels_path=args.labels, sim=sim_bags,
                                            sim_settings=sim_settings, sim_dir=sim_dir,
                                            kept=args.sim_dir is not None,
                                            manifest=manifest)}
    bundle = ModelBundle(
        forest=quoted.forest, feature_config=config, feature_names=config.feature_names,
        feature_schema_version=FEATURE_SCHEMA_VERSION, label_window=labels.to_dict(),
        decision_rule=rule,
        versions=runtime_versions(),
        training=training, metrics=metrics,
        created=datetime.now(timezone.utc).isoformat(timespec='seconds'))
    if not args.no_events:
        test_bags = [b for b, n in zip(bags, names) if n in set(quoted.test_trials)]
        metrics['events_test_trials'] = event_metrics(
            bundle=bundle, bags=tqdm(test_bags, desc='events', unit='bag'), spec=StreamSpec(),
            audio_rate=16000.0, wrench_rate=100.0, manifest=manifest, found=found,
            labels={b.name: csv_onsets[b.name] for b in test_bags if b in user}
            if csv_onsets else None)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    path = save_bundle(bundle=bundle, path=args.out, fmt=args.format, check_frames=x)
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


def write_report(*, report: Path, results: dict, names, training: dict, metrics: dict,
                 model_path: Path) -> None:
    """Write summary.md, metrics.json and the figures of the trial split."""
    report.mkdir(parents=True, exist_ok=True)
    write_figures(report=report, split=results['trial'], names=names)
    (report / 'metrics.json').write_text(json.dumps(
        {'training': training, 'metrics': metrics}, indent=2, default=float))
    lines = [f'# Training report: {model_path.name}', '',
             f"{training['trials']} trials ({', '.join(training['conditions']) or 'unlabelled'}"
             f"), {training['frames']} frames, {training['contact_frames']} labelled contact.",
             '', 'The paper split frames at random (**sample** split); neighbouring frames of '
             'one trial then sit in training and test alike. The **trial** split keeps whole '
             'trials apart and is the one we quote.', '']
    for kind in ('trial', 'sample'):
        r = results[kind]
        lines += [f'## {kind.capitalize()} split', '',
                  "n_estimators by validation ROC AUC (the paper's Table 1):", '',
                  n_table_markdown(r), '',
                  f'Stratified 10-fold cross-validation accuracy: {100 * r.cv_mean:.2f}% '
                  f'(SD {100 * r.cv_sd:.2f}%).', '',
                  "Test set classification report (the paper's Table 2):", '', '```',
                  r.report_text.rstrip(), '```', '']
    if 'events_test_trials' in metrics:
        lines += ['## Events on the test trials (full detector, trial split)', '', '```',
                  json.dumps(metrics['events_test_trials'], indent=2), '```', '']
    lines += ['![confusion matrix](confusion_matrix.png) ![ROC](roc.png) '
              '![feature importance](feature_importance.png)', '']
    (report / 'summary.md').write_text('\n'.join(lines))


if __name__ == '__main__':
    sys.exit(main())
