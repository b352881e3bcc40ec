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
Why the F/T-only model is slower on trials with a knock on the hand: latency per knocked trial.

    .venv/bin/python benchmarks/knock_latency.py DIR... --model models/contact_forest_ft.npz
        [--pool] [--trials] [--jobs 2]

Scores the model's own rule on every simulated trial of the folders (the same frames,
P(contact) and release logic as ``contact-detector sweep --model M --knocks``) and prints

- per condition set: trials and median latency of the caught trials, with and without a
  knock on the hand in the air (a within-condition comparison: the knocked trials are not
  spread evenly over the condition sets);
- the trials by the time from their newest knock to the onset (inside the shipped 0.5 s
  window of ``*_change_max`` / ``*_shift_max``, inside the 0.64 s F/T window, or older):
  caught, early, median latency, the median excess over the trial's condition set's median
  without a knock, how many the slow path and the load path released, and the largest
  ``force_change_max`` in the 50 ms before the onset;
- with ``--trials``, one line per knocked trial: condition, knock-to-onset time, latency, the
  path that released (fast: P >= threshold; slow: the mean of the last frames; load: the load
  path, the force held from the carried load with the forest behind it) and the highest
  P(contact) in the first 50 ms after the onset.

Latency is release - onset of the caught trials (``detected``); the medians are over those.
``--pool`` reports the trials of every folder together.
"""

import argparse
from collections import defaultdict
from pathlib import Path
import sys

from contact_detector.evaluation.metrics import score_trial
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.storage import load_bundle
from contact_detector.training.sweep import compute_frames, decide_trial, decode_bags
import numpy as np

WARMUP_S = 0.5


def median_ms(values) -> str:
    """Median of latencies in s as a string in ms, '-' for none."""
    return f'{1000 * float(np.median(values)):.0f}' if len(values) else '-'


def newest_knock_before(truth) -> float:
    """Time from the newest knock on the hand in the air before the onset to the onset, s."""
    gaps = [truth.onset_t - t for t, kind, in_air in truth.impacts
            if kind == 'hand' and in_air and t < truth.onset_t]
    return min(gaps) if gaps else float('nan')


def frames_config(bundle):
    """Return the model's feature configuration with the columns its rule reads."""
    return bundle.feature_config.with_rule_columns()


def release_path(*, rule, p: np.ndarray, i: int) -> str:
    """Which path released at frame ``i``: fast (p >= threshold), slow (the mean), else load."""
    if p[i] >= rule.threshold:
        return 'fast'
    k = rule.sustain_frames
    if k and i + 1 >= k and float(np.mean(p[i + 1 - k:i + 1])) >= rule.sustain_threshold:
        return 'slow'
    return 'load' if rule.uses_load else 'slow'


def trial_rows(*, bundle, frames) -> list:
    """One dict per trial: condition, knock, latency, verdict, path, features at onset."""
    forest = bundle.compile()
    rule = bundle.decision_rule
    names = frames_config(bundle).feature_names
    n_model = bundle.feature_config.n_features
    col = names.index('force_change_max') if 'force_change_max' in names else None
    rows = []
    for name, f in sorted(frames.items()):
        p = forest.predict_proba(f.x[:, :n_model]) if f.x.shape[0] else np.zeros(0)
        _, releases, events = decide_trial(frames=f, p=p, rule=rule, names=names,
                                           warmup_s=WARMUP_S)
        out = score_trial(truth=f.truth, releases=releases, events=events)
        onset = f.truth.onset_t
        path = '-'
        if out.release_t is not None:
            i = int(np.searchsorted(f.t, out.release_t))
            i = min(i, p.size - 1)
            path = release_path(rule=rule, p=p, i=i)
        after = (f.t >= onset) & (f.t < onset + 0.05)
        before = (f.t < onset) & (f.t >= onset - 0.05)
        rows.append({
            'name': name, 'condition': f.truth.condition, 'verdict': out.verdict,
            'latency': out.latency_s, 'knock_gap': newest_knock_before(f.truth),
            'knocked': any(k == 'hand' and a for _, k, a in f.truth.impacts),
            'path': path,
            'p_max_50ms': float(p[after].max()) if after.any() else float('nan'),
            'change_max_before': (float(f.x[before, col].max())
                                  if col is not None and before.any() else float('nan')),
        })
    return rows


def report(rows: list, *, per_trial: bool) -> str:
    """Markdown tables of :func:`trial_rows`."""
    text = ['| condition | trials | knocked | caught, knocked | median knocked [ms] | '
            'caught, not knocked | median not knocked [ms] |', '|---|---|---|---|---|---|---|']
    by_cond = defaultdict(list)
    for r in rows:
        by_cond[r['condition']].append(r)
    for cond in sorted(by_cond) + ['all']:
        rs = rows if cond == 'all' else by_cond[cond]
        kn = [r['latency'] for r in rs if r['knocked'] and r['verdict'] == 'detected']
        no = [r['latency'] for r in rs if not r['knocked'] and r['verdict'] == 'detected']
        text.append(f'| {cond} | {len(rs)} | {sum(r["knocked"] for r in rs)} | {len(kn)} | '
                    f'{median_ms(kn)} | {len(no)} | {median_ms(no)} |')
    cond_median = {c: np.median([r['latency'] for r in rs
                                 if not r['knocked'] and r['verdict'] == 'detected'] or [np.nan])
                   for c, rs in by_cond.items()}
    text += ['', '| newest knock on the hand before the onset [s] | trials | caught | early | '
             "median [ms] | median of latency minus its condition set's median without a "
             'knock [ms] | released by the slow path / the load path | median '
             'force_change_max, 50 ms before the onset [N] |', '|---|---|---|---|---|---|---|---|']
    # 0.5 s: the shipped change_max_frames; 0.65 s: the 0.64 s F/T window and the 0.6 s
    # shift baseline, the longest memory of a feature
    bins = [(0.0, 0.3), (0.3, 0.5), (0.5, 0.65), (0.65, 1.0), (1.0, 2.0), (2.0, np.inf)]
    groups = [(f'{lo:.2f}-{hi:.2f}' if np.isfinite(hi) else f'>= {lo:.2f}',
               [r for r in rows if r['knocked'] and lo <= r['knock_gap'] < hi])
              for lo, hi in bins]
    groups += [('knocked, none before the onset',
                [r for r in rows if r['knocked'] and np.isnan(r['knock_gap'])]),
               ('knocked, none in the last 1.00 s before the onset',
                [r for r in rows if r['knocked'] and not r['knock_gap'] < 1.0]),
               ('every knocked trial', [r for r in rows if r['knocked']]),
               ('no knock', [r for r in rows if not r['knocked']])]
    for label, rs in groups:
        caught = [r for r in rs if r['verdict'] == 'detected']
        excess = [r['latency'] - cond_median[r['condition']] for r in caught]
        excess_ms = '-' if not excess else f'{1000 * float(np.nanmedian(excess)):+.0f}'
        cm = [r['change_max_before'] for r in rs if not np.isnan(r['change_max_before'])]
        text.append(f'| {label} | {len(rs)} | {len(caught)} | '
                    f'{sum(r["verdict"] == "premature" for r in rs)} | '
                    f'{median_ms([r["latency"] for r in caught])} | '
                    f'{excess_ms} | '
                    f'{sum(r["path"] == "slow" for r in caught)} / '
                    f'{sum(r["path"] == "load" for r in caught)} | '
                    f'{(float(np.median(cm)) if cm else float("nan")):.2f} |')
    if per_trial:
        text += ['', '| trial | condition | knock before onset [s] | verdict | latency [ms] | '
                 'path | max P, first 50 ms | force_change_max before [N] |',
                 '|---|---|---|---|---|---|---|---|']
        knocked = [r for r in rows if r['knocked']]
        for r in sorted(knocked, key=lambda r: (np.nan_to_num(r['knock_gap'], nan=99.0))):
            lat = '-' if r['latency'] is None else f'{1000 * r["latency"]:.0f}'
            text.append(f'| {r["name"]} | {r["condition"]} | {r["knock_gap"]:.2f} | '
                        f'{r["verdict"]} | {lat} | {r["path"]} | {r["p_max_50ms"]:.2f} | '
                        f'{r["change_max_before"]:.2f} |')
    return '\n'.join(text)


def main() -> int:
    """Run the diagnostic and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('folders', nargs='+', type=Path)
    parser.add_argument('--model', type=Path, default=Path('models/contact_forest_ft.npz'))
    parser.add_argument('--trials', action='store_true', help='one line per knocked trial')
    parser.add_argument('--pool', action='store_true',
                        help='one report over the trials of every folder')
    parser.add_argument('--jobs', type=int, default=2)
    args = parser.parse_args()
    bundle = load_bundle(path=args.model)
    config = frames_config(bundle)
    rows = {}
    for i, folder in enumerate(args.folders):
        trials = decode_bags(bags=find_bags([folder]), spec=StreamSpec(), tag=str(i))
        frames = compute_frames(events_by_trial=trials, config=config, audio_rate=16000.0,
                                wrench_rate=100.0, jobs=args.jobs)
        rows[str(folder)] = trial_rows(bundle=bundle, frames=frames)
    if args.pool:
        rows = {' + '.join(rows): [r for rs in rows.values() for r in rs]}
    for name, rs in rows.items():
        print(f'## {name} ({bundle.model_id}, rule {bundle.decision_rule.short()})\n')
        print(report(rs, per_trial=args.trials))
        print()
    return 0


if __name__ == '__main__':
    sys.exit(main())
