"""Compare extra-feature sets and release rules over several forest seeds.

A 10-tree forest is a noisy estimator: the same recipe trained with another random seed moves
the count of premature releases on 360 held-out trials by several, so one trained forest cannot
tell two feature sets apart. This script computes every feature once (the shipped
configuration, which includes all the extras), then for each feature subset and each seed trains
the paper's forest (10 trees, ``max_features='sqrt'``) on all training trials and scores the
rules on the held-out folders, summed over the seeds. It is how the extras and the rule in
docs/sweep.md were chosen.

    python benchmarks/feature_check.py data/train data/heldout22 data/heldout33 \\
        data/heldout55 --seeds 0,1,2,3 --jobs 2
"""

import argparse
from typing import Dict, List

import numpy as np

from contact_detector.cli.sweep import decode
from contact_detector.cli.train import DEFAULT_FEATURES, DEFAULT_LABELS, DEFAULT_RULE
from contact_detector.features.config import PAPER_FEATURES
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.bundle import DecisionRule
from contact_detector.model.sweep import (compute_frames, FeatureSetting, fit_forest,
                                          score_rules)

BEFORE = ('audio_power_rel_db', 'audio_peak_rel_db', 'force_delta', 'torque_delta')
CHANGE = ('force_change', 'torque_change', 'ft_change_angle')


def settings() -> List[FeatureSetting]:
    """Feature subsets of the shipped configuration, named by what they add."""
    def subset(name: str, extras: tuple) -> FeatureSetting:
        return FeatureSetting(name, DEFAULT_FEATURES, DEFAULT_LABELS,
                              columns=PAPER_FEATURES + extras)
    return [
        subset('four extras (the previous default)', BEFORE),
        subset('four extras + ft_delta_angle', BEFORE + ('ft_delta_angle',)),
        subset('median-baseline changes instead of the deltas', BEFORE[:2] + CHANGE),
        subset('all eight extras (shipped)', DEFAULT_FEATURES.extra_features),
    ]


def rules() -> List[DecisionRule]:
    """The previous default, the shipped rule and its faster and stricter neighbours."""
    slow = {'sustain_frames': 15, 'sustain_threshold': 0.5}
    return [DecisionRule(threshold=0.7, confirm_frames=2),
            DecisionRule(threshold=0.85, **slow),
            DecisionRule(threshold=0.95),
            DEFAULT_RULE]


def main() -> int:
    """Run the comparison; print one markdown table."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('train', help='training folder')
    parser.add_argument('heldout', nargs='+', help='held-out folders')
    parser.add_argument('--seeds', default='0,1,2,3', help='forest seeds, comma-separated')
    parser.add_argument('--jobs', type=int, default=2)
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(',')]
    spec = StreamSpec()
    train = compute_frames(events_by_trial=decode(find_bags([args.train]), spec, 'train'),
                           config=DEFAULT_FEATURES, audio_rate=16000.0, wrench_rate=100.0,
                           jobs=args.jobs)
    heldout = {}
    for k, folder in enumerate(args.heldout):
        heldout.update(compute_frames(
            events_by_trial=decode(find_bags([folder]), spec, f'heldout{k}'),
            config=DEFAULT_FEATURES, audio_rate=16000.0, wrench_rate=100.0, jobs=args.jobs))
    train_frames, heldout_frames = list(train.values()), list(heldout.values())
    print(f'{len(train_frames)} training trials, {len(heldout_frames)} held-out trials, '
          f'forest seeds {seeds}; sums over the seeds, latency = median of the per-seed '
          'medians (range)\n')
    print('| features | rule | detected | missed+late | premature | impact events | '
          'latency median [ms] |')
    print('|---|---|---|---|---|---|---|')
    for setting in settings():
        totals: Dict[str, dict] = {}
        for seed in seeds:
            forest = fit_forest(frames=train_frames, setting=setting, n_estimators=10,
                                seed=seed, jobs=args.jobs)
            for row in score_rules(forest=forest, frames=heldout_frames, setting=setting,
                                   rules=rules()):
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
            latency = (f'{np.median(m):.0f} ({m.min():.0f}-{m.max():.0f})' if m.size else '-')
            print(f"| {setting.name} | {rule} | {t['detected']}/{t['trials']} | {t['miss']} | "
                  f"{t['premature']} | {t['impact']} | {latency} |", flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
