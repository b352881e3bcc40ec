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

r"""
Compare extra-feature sets, F/T change windows and release rules over several forest seeds.

A 10-tree forest is a noisy estimator: the same recipe trained with another random seed moves
the count of premature releases on 360 held-out trials by several, so one trained forest cannot
tell two feature sets apart. For each feature setting and each seed this script trains the
paper's forest (10 trees, ``max_features='sqrt'``) on all training trials and scores the rules
on the held-out folders, summed over the seeds. It is how the extras, the change windows and
the rule in docs/sweep.md were chosen.

``--compare features`` (round 2): subsets of the eight extras with round 2's change windows,
features computed once.
``--compare deltas`` (round 3): the shipped features with other ``delta_window`` /
``delta_lag`` (the F/T change is the newest ``delta_window`` samples against the samples
``delta_lag`` earlier), features computed once per setting.
``--compare sustain`` (rounds 3 and 4): the shipped features, the slow path's threshold and
length.
``--compare audio`` (round 4): round 3's features with and without the audio onset features
``audio_rise_db`` / ``audio_peak_gap_db`` (and ``rise_frames``), features computed once per
``rise_frames``.
``--compare changemax`` (round 5): round 4's features with and without ``force_change_max`` /
``torque_change_max`` (and ``change_max_frames``), features computed once per
``change_max_frames``; round 4's rule with the slow path at 0.5 (its default), 0.4 and 0.3.
``--compare conditions`` (round 5): held-out *conditions* over several seeds (the one-forest
ablation of ``sweep --ablation`` cannot tell one or two trials apart). For each of heavy, soft,
noisy and gain, train on the other condition sets of the training folder and the *first*
held-out folder, and test on that condition's trials of the *other* held-out folders; round 4's
features against the shipped ones, slow path at 0.5 and 0.3.

    python benchmarks/feature_check.py data/train data/heldout22 data/heldout33 \
        data/heldout55 --seeds 0,1,2,3 --jobs 2 [--compare deltas]
"""

import argparse
from dataclasses import replace
from typing import Dict, List

from contact_detector.features.config import FeatureConfig, PAPER_FEATURES
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.rule import DecisionRule
from contact_detector.training.recipe import DEFAULT_FEATURES, DEFAULT_LABELS
from contact_detector.training.sweep import compute_frames, FeatureSetting, fit_forest, score_rules
from contact_detector.training.sweep import decode_bags
import numpy as np

BEFORE = ('audio_power_rel_db', 'audio_peak_rel_db', 'force_delta', 'torque_delta')
CHANGE = ('force_change', 'torque_change', 'ft_change_angle')
#: The eight extras of rounds 2 and 3 (round 4 added the two audio onset features).
EIGHT = BEFORE + ('ft_delta_angle',) + CHANGE
ONSET = ('audio_rise_db', 'audio_peak_gap_db')
#: Round 5's F/T features: the recent maximum of the two changes.
CHANGE_MAX = ('force_change_max', 'torque_change_max')
#: The shipped rule since round 2, written out: the tables in docs/sweep.md do not move with
#: DEFAULT_RULE.
ROUND2_RULE = DecisionRule(threshold=0.95, confirm_frames=1, refractory_s=1.0,
                           sustain_frames=15, sustain_threshold=0.5)
#: Its fast path without unanimity: 9 of the 10 trees.
FAST_RULE = replace(ROUND2_RULE, threshold=0.9)
#: Round 3's features (the eight extras, the shortened change windows).
ROUND3 = replace(DEFAULT_FEATURES, extra_features=EIGHT)
#: Round 2's change windows (round 3 shortened them); ``--compare features`` reproduces round 2.
ROUND2 = replace(ROUND3, delta_window=3, delta_lag=10)


def feature_settings() -> List[FeatureSetting]:
    """Feature subsets of round 2's configuration, named by what they add."""
    def subset(name: str, extras: tuple) -> FeatureSetting:
        return FeatureSetting(name, ROUND2, DEFAULT_LABELS,
                              columns=PAPER_FEATURES + extras)
    return [
        subset('four extras (the previous default)', BEFORE),
        subset('four extras + ft_delta_angle', BEFORE + ('ft_delta_angle',)),
        subset('median-baseline changes instead of the deltas', BEFORE[:2] + CHANGE),
        subset('all eight extras (round 2)', EIGHT),
    ]


def feature_rules() -> List[DecisionRule]:
    """Return the round-1 default, the shipped rule and its faster and stricter neighbours."""
    slow = {'sustain_frames': 15, 'sustain_threshold': 0.5}
    return [DecisionRule(threshold=0.7, confirm_frames=2),
            DecisionRule(threshold=0.85, **slow),
            DecisionRule(threshold=0.95),
            ROUND2_RULE]


def sustain_rules() -> List[DecisionRule]:
    """Return the slow path (quiet contacts) with lower thresholds and a longer mean."""
    return [replace(ROUND2_RULE, sustain_threshold=0.5),
            replace(ROUND2_RULE, sustain_threshold=0.4),
            replace(ROUND2_RULE, sustain_threshold=0.3),
            replace(ROUND2_RULE, sustain_frames=20, sustain_threshold=0.4)]


def delta_configs() -> List[tuple]:
    """(name, config): the round-2 windows, round 3's and their neighbours (eight extras)."""
    def windows(window: int, lag: int) -> FeatureConfig:
        return replace(ROUND3, delta_window=window, delta_lag=lag)
    return [('delta_window 3, delta_lag 10 (round 2)', windows(3, 10)),
            ('delta_window 2, delta_lag 10', windows(2, 10)),
            ('delta_window 1, delta_lag 10', windows(1, 10)),
            ('delta_window 1, delta_lag 5 (round 3, shipped)', windows(1, 5)),
            ('delta_window 1, delta_lag 3', windows(1, 3))]


def audio_settings(rise_frames: int) -> List[FeatureSetting]:
    """Round 3's features, plus one or both audio onset features, at one ``rise_frames``."""
    config = replace(DEFAULT_FEATURES, extra_features=EIGHT + ONSET, rise_frames=rise_frames)
    shipped = rise_frames == DEFAULT_FEATURES.rise_frames

    def subset(name: str, extras: tuple) -> FeatureSetting:
        return FeatureSetting(name, config, DEFAULT_LABELS, columns=PAPER_FEATURES + extras)
    if not shipped:
        return [subset(f'+ both, rise_frames {rise_frames}', EIGHT + ONSET)]
    return [subset('round 3 (eight extras)', EIGHT),
            subset(f'+ audio_rise_db (rise_frames {rise_frames})', EIGHT + ONSET[:1]),
            subset('+ audio_peak_gap_db', EIGHT + ONSET[1:]),
            subset(f'+ both (shipped, rise_frames {rise_frames})', EIGHT + ONSET)]


def changemax_settings(frames: int) -> List[FeatureSetting]:
    """Round 4's features, with the two ``*_change_max`` features at one window."""
    config = replace(DEFAULT_FEATURES, extra_features=EIGHT + ONSET + CHANGE_MAX,
                     change_max_frames=frames)

    def subset(name: str, extras: tuple) -> FeatureSetting:
        return FeatureSetting(name, config, DEFAULT_LABELS, columns=PAPER_FEATURES + extras)
    if frames != DEFAULT_FEATURES.change_max_frames:
        return [subset(f'+ *_change_max, change_max_frames {frames}',
                       EIGHT + ONSET + CHANGE_MAX)]
    return [subset('round 4 (ten extras)', EIGHT + ONSET),
            subset(f'+ *_change_max (shipped, change_max_frames {frames})',
                   EIGHT + ONSET + CHANGE_MAX)]


def _frames(folders: List[str], config: FeatureConfig, jobs: int) -> list:
    spec = StreamSpec()
    frames = {}
    for k, folder in enumerate(folders):
        frames.update(compute_frames(
            events_by_trial=decode_bags(bags=find_bags([folder]), spec=spec, tag=f'set{k}'),
            config=config,
            audio_rate=16000.0, wrench_rate=100.0, jobs=jobs))
    return list(frames.values())


def _rows(setting: FeatureSetting, train: list, heldout: list, rules: List[DecisionRule],
          seeds: List[int], jobs: int) -> None:
    totals: Dict[str, dict] = {}
    for seed in seeds:
        forest = fit_forest(frames=train, setting=setting, n_estimators=10, seed=seed,
                            jobs=jobs)
        for row in score_rules(forest=forest, frames=heldout, setting=setting, rules=rules):
            s = row.summary
            t = totals.setdefault(row.rule, {'detected': 0, 'trials': 0, 'miss': 0,
                                             'premature': 0, 'impact': 0, 'medians': []})
            t['detected'] += s['detected']
            t['trials'] += s['trials']
            t['miss'] += s['missed'] + s['late']
            t['premature'] += s['premature']
            t['impact'] += s['impact_events']
            if s['latency_ms_median'] is not None:
                t['medians'].append(s['latency_ms_median'])
    for rule, t in totals.items():
        m = np.array(t['medians'])
        latency = f'{np.median(m):.0f} ({m.min():.0f}-{m.max():.0f})' if m.size else '-'
        print(f"| {setting.name} | {rule} | {t['detected']}/{t['trials']} | {t['miss']} | "
              f"{t['premature']} | {t['impact']} | {latency} |", flush=True)


def _groups(groups: List[List[FeatureSetting]], rules: List[DecisionRule],
            args: argparse.Namespace, seeds: List[int]) -> None:
    # Each group shares one feature configuration: its features are computed once.
    for settings in groups:
        config = settings[0].config
        train = _frames([args.train], config, args.jobs)
        heldout = _frames(args.heldout, config, args.jobs)
        for setting in settings:
            _rows(setting, train, heldout, rules, seeds, args.jobs)


def main() -> int:
    """Run the comparison; print one markdown table."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('train', help='training folder')
    parser.add_argument('heldout', nargs='+', help='held-out folders')
    parser.add_argument('--seeds', default='0,1,2,3', help='forest seeds, comma-separated')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--compare',
                        choices=('features', 'deltas', 'sustain', 'audio', 'changemax',
                                 'conditions'),
                        default='features')
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(',')]
    print(f'forest seeds {seeds}; sums over the seeds, latency = median of the per-seed '
          'medians (range)\n')
    print('| features | rule | detected | missed+late | premature | impact events | '
          'latency median [ms] |')
    print('|---|---|---|---|---|---|---|')
    if args.compare == 'features':
        train = _frames([args.train], ROUND2, args.jobs)
        heldout = _frames(args.heldout, ROUND2, args.jobs)
        for setting in feature_settings():
            _rows(setting, train, heldout, feature_rules(), seeds, args.jobs)
        return 0
    if args.compare == 'sustain':
        setting = FeatureSetting('shipped', DEFAULT_FEATURES, DEFAULT_LABELS)
        _rows(setting, _frames([args.train], DEFAULT_FEATURES, args.jobs),
              _frames(args.heldout, DEFAULT_FEATURES, args.jobs), sustain_rules(), seeds,
              args.jobs)
        return 0
    if args.compare == 'audio':
        _groups([audio_settings(r) for r in (DEFAULT_FEATURES.rise_frames, 1, 3)],
                [ROUND2_RULE, FAST_RULE], args, seeds)
        return 0
    if args.compare == 'conditions':
        rules = [replace(ROUND2_RULE, sustain_threshold=th) for th in (0.5, 0.3)]
        pool = _frames([args.train, args.heldout[0]], DEFAULT_FEATURES, args.jobs)
        test = _frames(args.heldout[1:], DEFAULT_FEATURES, args.jobs)
        for condition in ('heavy', 'soft', 'noisy', 'gain'):
            fit = [f for f in pool if f.truth.condition != condition]
            left_out = [f for f in test if f.truth.condition == condition]
            for name, extras in (('round 4', EIGHT + ONSET),
                                 ('shipped (round 5)', EIGHT + ONSET + CHANGE_MAX)):
                setting = FeatureSetting(f'{name}, {condition} left out', DEFAULT_FEATURES,
                                         DEFAULT_LABELS, columns=PAPER_FEATURES + extras)
                _rows(setting, fit, left_out, rules, seeds, args.jobs)
        return 0
    if args.compare == 'changemax':
        _groups([changemax_settings(k) for k in (DEFAULT_FEATURES.change_max_frames, 30, 80)],
                [replace(ROUND2_RULE, sustain_threshold=th) for th in (0.5, 0.4, 0.3)],
                args, seeds)
        return 0
    for name, config in delta_configs():
        setting = FeatureSetting(name, config, DEFAULT_LABELS)
        _rows(setting, _frames([args.train], config, args.jobs),
              _frames(args.heldout, config, args.jobs), [ROUND2_RULE, FAST_RULE], seeds,
              args.jobs)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
