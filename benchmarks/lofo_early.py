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
Why a left-out family releases early: the events, P(contact) and features before each release.

    .venv/bin/python benchmarks/lofo_early.py DIR... --family exogenous
        [--setting shipped] [--seeds 0,1,2] [--cache frames.pkl] [--jobs 1]
        [--setting shipped+aug --augment-tare P --augment-torque LOW,HIGH
         [--augment-gain LOW,HIGH] [--augment-offset P] [--augment-contact-offset M]
         [--augment-lag LOW,HIGH] [--augment-cache aug.pkl]] [--event-weight W]

Trains the leave-one-family-out forests of ``contact-detector sweep --lofo`` (10 trees, labels
0-0.3 s, the setting's columns of the full feature configuration) on every family but
``--family``, scores the shipped rule on that family and prints, for every release before the
onset (an early release):

- the trial, the release time relative to the onset, and the exogenous events of the 1 s
  before it (kind, time from the event's start to the release);
- P(contact) of the frames from 0.2 s before the release to the release;
- the values at the release frame of the F/T and audio features that describe a load change,
  each with its percentile among the training frames labelled *contact* (what the forest
  learnt a table looks like) and among those labelled *no contact*.

Then the same feature values for the caught trials at their release frame, as a reference.
``--cache`` keeps the computed frames (a pickle, with their feature configuration: a cache
written with another one is recomputed) for the next run on the same folders. The protocol
options are ``lofo_by_param.py``'s (the shipped protocol: ``--setting shipped+aug
--augment-tare 0.5 --augment-torque 0.1,2 --augment-gain 0.2,1.5 --augment-offset 0.5
--augment-contact-offset 0.05 --event-weight 3``); the percentiles are among the
frames the forests trained on (augmented, for ``NAME+aug``).
"""

import argparse
from pathlib import Path
import sys

from contact_detector.evaluation.metrics import frame_labels
from contact_detector.training.sweep import fit_forest
from lofo_frames import (add_protocol_arguments, add_rule_argument, left_out_decisions,
                         protocol_frames, rule_from)
import numpy as np

SHOWN = ('force_shift', 'force_shift_rel', 'force_carried_cos', 'torque_carried_cos',
         'force_change', 'force_change_max', 'force_shift_min', 'force_shift_max',
         'force_flux', 'torque_flux', 'audio_power_rel_db', 'audio_peak_rel_db',
         'audio_rise_db', 'audio_hold_db', 'ft_carried_lever')


def percentile(values: np.ndarray, x: float) -> float:
    """Return the percentage of ``values`` below ``x``."""
    return 100.0 * float(np.mean(values < x)) if len(values) else float('nan')


def main(argv=None) -> int:
    """Run the diagnostic; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('folders', nargs='+', type=Path)
    parser.add_argument('--family', default='exogenous')
    parser.add_argument('--seeds', default='0,1,2')
    parser.add_argument('--cache', type=Path, default=None)
    parser.add_argument('--jobs', type=int, default=1)
    add_rule_argument(parser)
    add_protocol_arguments(parser)
    args = parser.parse_args(argv)
    setting, frames, fit_frames, protocol = protocol_frames(args)
    config = setting.config
    names = config.feature_names
    shown = [n for n in SHOWN if n in names]
    idx = [names.index(n) for n in shown]
    fit = [f for f in fit_frames.values() if f.truth.condition != args.family]
    test = [f for f in frames.values() if f.truth.condition == args.family]
    x_fit = np.concatenate([f.x for f in fit])
    y_fit = np.concatenate([frame_labels(t=f.t, onsets=[f.truth.onset_t], start_s=0.0,
                                         end_s=0.3) for f in fit])
    pos, neg = x_fit[y_fit == 1], x_fit[y_fit == 0]
    print(f'{len(fit)} training trials{protocol} ({len(pos)} contact frames), {len(test)} '
          f'left out ({args.family}); features: {", ".join(shown)}')
    caught_rows = []
    for seed in (int(s) for s in args.seeds.split(',')):
        forest = fit_forest(frames=fit, setting=setting, n_estimators=10, seed=seed,
                            jobs=args.jobs)
        for f in test:
            p, _, releases = left_out_decisions(forest=forest, frames=f, setting=setting,
                                                rule=rule_from(args))
            rel = [float(r) for r in np.atleast_1d(releases)] if releases is not None else []
            if not rel:
                continue
            r = rel[0]
            i = int(np.searchsorted(f.t, r))
            i = min(i, len(f.t) - 1)
            if r >= f.truth.onset_t:
                caught_rows.append(f.x[i, idx])
                continue
            events = [(k, r - t) for t, k, _ in f.truth.impacts if 0.0 <= r - t <= 1.0]
            print(f'\nseed {seed} {f.truth.name}: release {1000 * (r - f.truth.onset_t):.0f} ms '
                  'before the onset; events before it: '
                  + (', '.join(f'{k} {1000 * dt:.0f} ms' for k, dt in events) or 'none'))
            window = (f.t >= r - 0.2) & (f.t <= r)
            print('  P(contact): ' + ' '.join(f'{v:.2f}' for v in p[window]))
            for n, j in zip(shown, idx):
                v = float(f.x[i, j])
                print(f'  {n:20s} {v:9.3f}  contact pct {percentile(pos[:, j], v):5.1f}  '
                      f'no-contact pct {percentile(neg[:, j], v):5.1f}')
    if caught_rows:
        med = np.median(np.array(caught_rows), axis=0)
        print('\nmedian at the release frame of the caught trials: '
              + ', '.join(f'{n} {v:.3f}' for n, v in zip(shown, med)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
