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
    contact-detector sweep DIR... --lofo [--lofo-settings shipped,invariant] [--out FILE.md]

With ``--lofo`` every trial of every folder is pooled and grouped by family (its condition set
in the manifest); for each family a forest is trained on all the others and every candidate
rule is scored on the family left out. The table gives one row per family and, per feature
setting and rule, the *worst* family: the figure to choose by.

Trains the paper's forest (10 trees, max_features = sqrt) per feature setting and label window
on the training trials, then scores every decision rule on the held-out trials: detections,
misses, premature releases, latency, contact events blamed on exogenous impacts, frame
precision/recall. With ``--ablation`` it also trains on all condition sets but one and tests on
the one left out (heavy, soft, noisy, gain), for the settings that are meant to generalise.
"""

import argparse
from dataclasses import replace
import json
from pathlib import Path
import sys
from typing import List, Optional, Sequence

from contact_detector.cli.evaluate import truth_for
from contact_detector.cli.train import conditions_of, DEFAULT_FEATURES, DEFAULT_RULE
from contact_detector.features.config import FeatureConfig
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import load_events, StreamSpec
from contact_detector.model.augmentation import (AUGMENTED, scale_range,
                                                 WrenchAugmentation)
from contact_detector.model.bundle import DecisionRule
from contact_detector.model.sweep import (best_row, compute_frames, FeatureSetting,
                                          fit_forest, leave_one_family_out, rows_markdown,
                                          score_rules, worst_family)
from contact_detector.model.training import LabelWindow
from tqdm import tqdm

EXTRAS = ('audio_power_rel_db', 'audio_peak_rel_db', 'force_delta', 'torque_delta')
#: The audio features measured against the tracked noise floor, and the two of round 4.
ONSET_AUDIO = ('audio_rise_db', 'audio_peak_gap_db')
RELATIVE_AUDIO = ('audio_power_rel_db', 'audio_peak_rel_db') + ONSET_AUDIO
#: The two F/T features of round 5.
CHANGE_MAX = ('force_change_max', 'torque_change_max')
ONSET = LabelWindow(0.0, 0.1)
STATE = LabelWindow(0.0, 0.3)


def feature_grid(name: str) -> List[FeatureSetting]:
    """Return the feature settings to try: 'compare', 'focus' or 'full' (both)."""
    paper = FeatureConfig(ft_window=160, ft_hop=128)
    base = FeatureConfig(ft_window=32, ft_hop=1)
    ours = FeatureConfig(ft_detrend='mean', extra_features=EXTRAS)
    compare = [
        FeatureSetting('paper W160 H128, onset labels', paper, ONSET),
        FeatureSetting('W32 H1, onset labels', base, ONSET),
        FeatureSetting('W32 H1, state labels', base, STATE),
        FeatureSetting('W32 H1 detrend, state labels', FeatureConfig(ft_detrend='mean'), STATE),
        FeatureSetting('W32 H1 detrend+extras, onset labels', ours, ONSET),
        FeatureSetting('W32 H1 detrend+extras, state labels', ours, STATE),
    ]
    focus = [
        FeatureSetting('detrend+extras, state labels, delta lag 5',
                       replace(ours, delta_lag=5), STATE),
        FeatureSetting('detrend+extras, state labels, delta lag 3',
                       replace(ours, delta_lag=3, delta_window=2), STATE),
        FeatureSetting('detrend+extras, labels 0-0.2 s', ours, LabelWindow(0.0, 0.2)),
        FeatureSetting('detrend+extras, labels 0-0.5 s', ours, LabelWindow(0.0, 0.5)),
        FeatureSetting('W16 H1 detrend+extras, state labels', replace(ours, ft_window=16),
                       STATE),
        FeatureSetting('W64 H1 detrend+extras, state labels', replace(ours, ft_window=64),
                       STATE),
        FeatureSetting('W32 H4 detrend+extras, state labels', replace(ours, ft_hop=4), STATE),
        FeatureSetting('audio 16 ms / 5 ms, detrend+extras, state labels',
                       replace(ours, audio_frame_s=0.016, audio_hop_s=0.005), STATE),
    ]
    return {'compare': compare, 'focus': focus, 'full': compare + focus, 'none': []}[name]


def rule_grid() -> List[DecisionRule]:
    """Thresholds x confirmation frames."""
    return [DecisionRule(threshold=th, confirm_frames=k, refractory_s=1.0)
            for th in (0.3, 0.5, 0.7, 0.9) for k in (1, 2, 3, 5)]


def ablation_settings() -> List[FeatureSetting]:
    """Return the settings compared on held-out condition sets (the shipped window, W64)."""
    full = DEFAULT_FEATURES
    paper7 = replace(full, ft_detrend='none', extra_features=())
    return [
        FeatureSetting('paper 7 features, no detrend', paper7, STATE),
        FeatureSetting('paper 7, detrend', replace(paper7, ft_detrend='mean'), STATE),
        FeatureSetting('detrend + extras (shipped)', full, STATE),
        FeatureSetting('shipped, without the vector shifts', full, STATE,
                       columns=tuple(n for n in full.feature_names if n not in _SHIFT)),
        FeatureSetting('shipped, without raw audio power', full, STATE,
                       columns=tuple(n for n in full.feature_names if n != 'audio_power')),
        FeatureSetting('shipped, without the *_change_max features (round 4)', full, STATE,
                       columns=tuple(n for n in full.feature_names if n not in CHANGE_MAX)),
        FeatureSetting('shipped, without the audio onset features', full, STATE,
                       columns=tuple(n for n in full.feature_names if n not in ONSET_AUDIO)),
        FeatureSetting('shipped, without the dB-above-floor features', full, STATE,
                       columns=tuple(n for n in full.feature_names
                                     if n not in RELATIVE_AUDIO)),
        FeatureSetting('audio only (power, dB above floor, its peak, rise and gap)', full, STATE,
                       columns=('audio_power',) + RELATIVE_AUDIO),
        FeatureSetting('F/T only', full, STATE,
                       columns=tuple(n for n in full.feature_names
                                     if not n.startswith('audio'))),
        FeatureSetting('reduced: dB above floor, recent peak, torque centroid/spread, shifts',
                       full, STATE,
                       columns=('audio_power_rel_db', 'audio_peak_rel_db', 'torque_centroid',
                                'torque_spread', 'force_shift', 'torque_shift',
                                'force_shift_min')),
    ]


def thresholds(text: str) -> List[float]:
    """Parse ``0.5,0.4`` into thresholds in [0, 1] (argparse type)."""
    try:
        values = [float(v) for v in text.split(',') if v.strip()]
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'not a list of numbers: {text!r}') from err
    if not values or any(not 0.0 <= v <= 1.0 for v in values):
        raise argparse.ArgumentTypeError(f'thresholds must be in [0, 1], got {text!r}')
    return values


def decode(bags, spec, tag):
    """Decode every bag once: 'tag/name' -> (events, truth)."""
    manifest = conditions_of(bags)
    out = {}
    for bag in tqdm(bags, desc=f'decode {tag}', unit='bag'):
        events = load_events(bag, spec=spec)
        out[f'{tag}/{bag.name}'] = (events, truth_for(bag, events, manifest))
    return out


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
    parser.add_argument('--trees', type=int, default=10, help='trees per forest')
    parser.add_argument('--augment-tare', type=float,
                        default=WrenchAugmentation.tare_probability,
                        help='augmentation: probability of a tared sensor (default '
                             f'{WrenchAugmentation.tare_probability})')
    parser.add_argument('--augment-torque', type=scale_range,
                        default=WrenchAugmentation.torque_scale,
                        help='augmentation: torque scale range LOW,HIGH, log-uniform '
                             '(default 1/3,3)')
    parser.add_argument('--lofo-label-start', type=float, default=STATE.start_s,
                        help='--lofo: frames from this long after the onset are labelled '
                             f'contact, s (default {STATE.start_s})')
    parser.add_argument('--lofo-label-end', type=float, default=STATE.end_s,
                        help='--lofo: frames up to this long after the onset are labelled '
                             f'contact, s (default {STATE.end_s})')
    parser.add_argument('--grid', choices=('compare', 'focus', 'full', 'none'),
                        default='compare', help='feature grid (none: only --ablation)')
    parser.add_argument('--ablation', action='store_true')
    parser.add_argument('--ablation-sustain', type=thresholds,
                        default=[DEFAULT_RULE.sustain_threshold],
                        help='slow-path thresholds scored in the ablation, comma-separated '
                             f'(default {DEFAULT_RULE.sustain_threshold})')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--audio-rate', type=float, default=16000.0)
    parser.add_argument('--wrench-rate', type=float, default=100.0)
    parser.add_argument('--out', type=Path, default=None, help='markdown table file')
    parser.add_argument('--json', type=Path, default=None, help='all rows as JSON')
    args = parser.parse_args(argv)
    spec = StreamSpec()
    if args.lofo:
        output = lofo(args, spec)
        print(output)
        if args.out:
            args.out.write_text(output)
        return 0
    if len(args.bags) != 2:
        parser.error('give TRAIN_DIR and HELDOUT_DIR (or --lofo with any folders)')
    train = decode(find_bags([args.bags[0]]), spec, 'train')
    heldout = decode(find_bags([args.bags[1]]), spec, 'heldout')
    rules = rule_grid()
    rows, best_rows = [], []
    cache = {}
    for setting in tqdm(feature_grid(args.grid), desc='settings', unit='setting'):
        key = setting.config
        if key not in cache:
            cache = {key: (compute_frames(events_by_trial=train, config=key,
                                          audio_rate=args.audio_rate,
                                          wrench_rate=args.wrench_rate, jobs=args.jobs),
                           compute_frames(events_by_trial=heldout, config=key,
                                          audio_rate=args.audio_rate,
                                          wrench_rate=args.wrench_rate, jobs=args.jobs))}
        train_frames, heldout_frames = cache[key]
        forest = fit_forest(frames=list(train_frames.values()), setting=setting,
                            n_estimators=10, seed=args.seed, jobs=args.jobs)
        scored = score_rules(forest=forest, frames=list(heldout_frames.values()),
                             setting=setting, rules=rules)
        rows += scored
        best_rows.append(best_row(scored))
    text = []
    if rows:
        text += ['## Best rule per setting (held-out trials)', '', rows_markdown(best_rows), '',
                 '## Every rule', '', rows_markdown(rows), '']
    if args.ablation:
        text += ['## Ablation: train on the other condition sets, test on the one left out',
                 '', ablation(train, heldout, args), '']
    output = '\n'.join(text)
    print(output)
    if args.out:
        args.out.write_text(output)
    if args.json:
        args.json.write_text(json.dumps([r.__dict__ for r in rows], indent=2, default=str))
    return 0


_SPECTRAL = ('force_centroid', 'force_spread', 'force_flux', 'torque_centroid', 'torque_spread',
             'torque_flux')
_SHIFT = ('force_shift', 'torque_shift', 'force_shift_min', 'torque_shift_min',
          'force_shift_max', 'torque_shift_max')
_SIGNED = ('force_change', 'torque_change', 'force_change_max', 'torque_change_max')
#: The feature settings --lofo compares: name -> columns (None: the shipped model's).
LOFO_SETTINGS = {
    'shipped': None,
    'round5': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + (
        'force_delta', 'torque_delta', 'ft_delta_angle', 'force_change', 'torque_change',
        'ft_change_angle', 'force_change_max', 'torque_change_max'),
    'invariant': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + _SHIFT,
    'invariant-no-raw-power': _SPECTRAL + RELATIVE_AUDIO + _SHIFT,
    'invariant+signed': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + _SHIFT + _SIGNED,
    'ft-only': _SPECTRAL + _SHIFT,
    'ft-only+signed': _SPECTRAL + _SHIFT + _SIGNED,
}


def lofo_rules() -> List[DecisionRule]:
    """Return the rules --lofo scores: the shipped rule, faster, slower and evidence paths."""
    rules = [DEFAULT_RULE]
    rules += [replace(DEFAULT_RULE, threshold=th) for th in (0.8, 0.9)]
    # Slower and safer (the F/T-only model against knocks on the hand): confirmation frames
    # and a stricter slow path.
    rules += [replace(DEFAULT_RULE, confirm_frames=cf) for cf in (2, 3)]
    rules += [replace(DEFAULT_RULE, confirm_frames=cf, sustain_threshold=0.4) for cf in (1, 3)]
    rules += [replace(DEFAULT_RULE, threshold=th, sustain_threshold=0.4) for th in (0.8, 0.9)]
    rules += [replace(DEFAULT_RULE, sustain_threshold=0.4, evidence_threshold=h,
                      evidence_drift=0.3) for h in (1.0, 1.5)]
    rules += [replace(DEFAULT_RULE, evidence_threshold=h, evidence_drift=d)
              for d in (0.3, 0.4, 0.5) for h in (0.5, 1.0, 1.5, 2.5)]
    return rules


def lofo(args, spec) -> str:
    """Leave-one-family-out over the pooled folders; per setting and rule the worst family."""
    from contact_detector.features.config import EXTRA_FEATURES
    config = replace(DEFAULT_FEATURES, extra_features=EXTRA_FEATURES)
    trials = {}
    for i, folder in enumerate(args.bags):
        trials.update(decode(find_bags([folder]), spec, f'{i}'))
    frames = list(compute_frames(events_by_trial=trials, config=config,
                                 audio_rate=args.audio_rate, wrench_rate=args.wrench_rate,
                                 jobs=args.jobs).values())
    # SETTING+aug: the forests train on the same trials with augmented wrenches.
    fit_frames = None
    if any(name.endswith(AUGMENTED) for name in args.lofo_settings.split(',')):
        fit_frames = list(compute_frames(
            events_by_trial=trials, config=config, audio_rate=args.audio_rate,
            wrench_rate=args.wrench_rate, jobs=args.jobs,
            augmentation=WrenchAugmentation(tare_probability=args.augment_tare,
                                            torque_scale=tuple(args.augment_torque)),
            seed=args.seed).values())
    rules = lofo_rules()
    worst_lines = ['| setting | rule | worst family | detected | premature | median [ms] | '
                   'p95 [ms] | all families: detected / premature |',
                   '|---|---|---|---|---|---|---|---|']
    family_lines = ['| setting | rule | family | detected | premature | impact events | '
                    'median [ms] | p95 [ms] |', '|---|---|---|---|---|---|---|---|']
    labels = LabelWindow(args.lofo_label_start, args.lofo_label_end)
    for name in tqdm(args.lofo_settings.split(','), desc='lofo', unit='setting'):
        base = name.removesuffix(AUGMENTED)
        fit = fit_frames if name.endswith(AUGMENTED) else None
        columns = LOFO_SETTINGS[base] or DEFAULT_FEATURES.feature_names
        setting = FeatureSetting(name, config, labels,
                                 columns=tuple(columns))
        folds = leave_one_family_out(frames=frames, setting=setting, rules=rules,
                                     n_estimators=args.trees, seed=args.seed, jobs=args.jobs,
                                     fit_frames=fit)
        for k, rule in enumerate(rules):
            summaries = []
            for fold in folds:
                s = dict(fold.rows[k].summary, family=fold.family)
                summaries.append(s)
                family_lines.append(f'| {name} | {rule.short()} | {fold.family} | '
                                    f"{s['detected']}/{s['trials']} | {s['premature']} | "
                                    f"{s['impact_events']} | {_ms(s['latency_ms_median'])} | "
                                    f"{_ms(s['latency_ms_p95'])} |")
            w = worst_family(summaries)
            if w is None:
                continue
            total = sum(s['detected'] for s in summaries)
            trials_n = sum(s['trials'] for s in summaries)
            early = sum(s['premature'] for s in summaries)
            worst_lines.append(f"| {name} | {rule.short()} | {w['family']} | "
                               f"{w['detected']}/{w['trials']} | {w['premature']} | "
                               f"{_ms(w['latency_ms_median'])} | {_ms(w['latency_ms_p95'])} | "
                               f'{total}/{trials_n} / {early} |')
    return '\n'.join(['## Leave one family out: the worst family per setting and rule', '',
                      *worst_lines, '', '## Every family', '', *family_lines, ''])


def _ms(value) -> str:
    return '-' if value is None else f'{value:.0f}'


def ablation(train, heldout, args) -> str:
    """Leave-one-condition-out table for the ablation settings (the default rule)."""
    everything = {**train, **heldout}
    rules = [replace(DEFAULT_RULE, sustain_threshold=th) for th in args.ablation_sustain]
    lines = [f'Rule: {DEFAULT_RULE.short()} (slow-path thresholds '
             f"{', '.join(str(th) for th in args.ablation_sustain)}); forest of 10 trees "
             'trained on every trial of the other condition sets.', '',
             '| setting | held-out condition | slow path | detected | premature | '
             'impact events | latency median [ms] |', '|---|---|---|---|---|---|---|']
    cache = {}
    for setting in tqdm(ablation_settings(), desc='ablation', unit='setting'):
        if setting.config not in cache:
            cache = {setting.config: compute_frames(
                events_by_trial=everything, config=setting.config,
                audio_rate=args.audio_rate, wrench_rate=args.wrench_rate, jobs=args.jobs)}
        frames = cache[setting.config]
        for condition in ('heavy', 'soft', 'noisy', 'gain'):
            fit = [f for f in frames.values() if f.truth.condition != condition]
            test = [f for f in frames.values() if f.truth.condition == condition]
            if not test:
                continue
            forest = fit_forest(frames=fit, setting=setting, n_estimators=10, seed=args.seed,
                                jobs=args.jobs)
            scored = score_rules(forest=forest, frames=test, setting=setting, rules=rules)
            for rule, row in zip(rules, scored):
                s = row.summary
                median = ('-' if s['latency_ms_median'] is None
                          else f"{s['latency_ms_median']:.0f}")
                slow = f'mean{rule.sustain_frames}>={rule.sustain_threshold}'
                lines.append(f'| {setting.name} | {condition} | {slow} | '
                             f"{s['detected']}/{s['trials']} | {s['premature']} | "
                             f"{s['impact_events']} | {median} |")
    return '\n'.join(lines)


if __name__ == '__main__':
    sys.exit(main())
