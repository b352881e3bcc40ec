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
Detection quality of the shipped models at each F/T rate: the same trials at every rate.

    .venv/bin/python benchmarks/ft_rate_quality.py OUT_DIR [--rates 100,51,125,200,500,1000]
        [--trials 120] [--seed 4545] [--quiet-rates 100,200] [--quiet-trials 48]
        [--quiet-seed 4546] [--jobs 2]

For every rate R it runs the commands a user types (as ``python -m contact_detector.cli.main``):

- ``contact-detector simulate OUT_DIR/rR --trials 120 --seed 4545 --conditions wide
  --ft-rate R --quiet`` (skipped when ``OUT_DIR/rR/manifest.json`` exists): the same seed
  gives the same trials at every rate (checked: every trial's condition, random parameters
  and onset agree with the first rate's; what the simulated arm does after it senses the
  contact, its stop and retreat, follows the sampled F/T and may differ by a few samples);
- ``contact-detector evaluate OUT_DIR/rR --detector forest --detector forest-ft --report
  OUT_DIR/eval_rR`` (the multimodal and the F/T-only shipped models; the rate is measured
  from the stamps);
- ``contact-detector sweep OUT_DIR/rR --model models/contact_forest_ft.npz --knocks
  --wrench-rate R --out OUT_DIR/sweep_rR.md --jobs J`` (the F/T-only model's own rule on the trials
  with a knock on the hand in the air; ``sweep`` measures the rate as ``evaluate`` does,
  ``--wrench-rate`` gives it the rate simulated all the same);

and with ``--quiet-rates`` the multimodal model on ``--conditions quiet_contact`` trials
(``OUT_DIR/qR``: a microphone that hears nothing of the contact).

It prints, per rate and model: caught within 500 ms (``detected``), early (premature), missed
or late, latency median and p95 (ms), and the median of the per-trial latency difference to
the first rate over the trials caught at both (paired: the noise of a median over different
trials left out). For the F/T-only model it also gives the median (and largest) time from a
release's frame to the stamp of the first wrench sample at or after it: a check that the
frame is timed at the sample that completed it (0; a frame on the resampler's grid, at a rate
that is no integer multiple of 100 Hz, is computed when the first sample at or after its grid
point arrives, and is timed there, docs/features.md). Then how far ``force_change`` at each rate
lags the first rate's around the onset, on the F/T-only model's F/T frames and on the
multimodal model's audio frames (:func:`feature_lag`), and, per family, the rows where a rate's
caught or early count differs from the first rate's or its paired shift exceeds 10 ms.
"""

import argparse
import json
from pathlib import Path
import subprocess
import sys
import time

from contact_detector.io.sensor_stream import load_events, StreamSpec, WrenchEvent
import numpy as np

MODEL = Path(__file__).resolve().parent.parent / 'models' / 'contact_forest.npz'
FT_MODEL = MODEL.with_name('contact_forest_ft.npz')
MODELS = (('forest', 'multimodal'), ('forest-ft', 'F/T-only'))


def run(*argv) -> None:
    """Run ``contact-detector ARGV...``, its output swallowed; raise if it fails."""
    done = subprocess.run([sys.executable, '-m', 'contact_detector.cli.main', *map(str, argv)],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode:
        raise SystemExit(f'failed: contact-detector {" ".join(map(str, argv))}\n'
                         + done.stderr[-2000:])


def completion_wait(folder: Path, outcomes) -> str:
    """Median ms from each release's frame time to the wrench sample that completed it."""
    waits = []
    for o in outcomes:
        if o['release_t'] is None:
            continue
        events = load_events(folder / o['name'], spec=StreamSpec())
        stamps = np.concatenate([e.t for e in events if isinstance(e, WrenchEvent)])
        i = min(int(np.searchsorted(stamps, o['release_t'] - 1e-9)), stamps.size - 1)
        waits.append(1000 * (stamps[i] - o['release_t']))
    return f'{np.median(waits):.0f} (max {np.max(waits):.1f})' if waits else '-'


def feature_lag(*, folders, model: Path, feature: str = 'force_change', every: int = 5) -> list:
    """
    Median lag, ms, of ``feature`` at each folder's rate behind the first folder's, per trial.

    For every ``every``-th trial whose feature moves by >= 0.5 in [-50, 200] ms of the onset,
    the lag ``L`` (whole ms in [-10, 40]) minimising ``sum (x_R(t + L) - x_1(t))^2`` over that
    span, both linearly interpolated on a 1 ms grid; the valid frames of the model's
    extractor (F/T frames for an F/T-only model, audio frames for the multimodal one).
    """
    from contact_detector.detection.offline import run_features
    from contact_detector.features.streaming import StreamingFeatureExtractor
    from contact_detector.model.storage import load_bundle

    config = load_bundle(path=model).feature_config
    col = list(config.feature_names).index(feature)
    trials = json.loads((folders[0][1] / 'manifest.json').read_text())['trials'][::every]
    span = np.arange(-0.05, 0.2, 0.001)

    def frames(rate, folder, trial):
        extractor = StreamingFeatureExtractor(config=config, audio_rate=trial['audio_rate'],
                                              ft_input_rate=rate)
        got = run_features(load_events(folder / trial['bag'], spec=StreamSpec()),
                           extractor=extractor)
        return got.t[got.valid] - trial['onset_t'], got.x[got.valid, col]

    lags = [[] for _ in folders]
    for trial in trials:
        ref = np.interp(span, *frames(folders[0][0], folders[0][1], trial))
        if np.ptp(ref) < 0.5:
            continue
        for k, (rate, folder) in enumerate(folders):
            t, x = frames(rate, folder, trial)
            lags[k].append(min(range(-10, 41), key=lambda lag: float(np.sum(
                (np.interp(span + lag / 1000, t, x) - ref) ** 2))))
    return [(float(np.median(v)) if v else float('nan'), len(v)) for v in lags]


def check_paired(dirs) -> None:
    """Every trial's condition, parameters and onset agree across the folders."""
    first = json.loads((dirs[0] / 'manifest.json').read_text())['trials']
    for d in dirs[1:]:
        other = json.loads((d / 'manifest.json').read_text())['trials']
        for a, b in zip(first, other, strict=True):
            pa = {k: v for k, v in a['params'].items() if k != 'derived'}
            pb = {k: v for k, v in b['params'].items() if k != 'derived'}
            before = [i for i in a['impacts'] if i['t'] < a['onset_t']]
            same = (a['condition'] == b['condition'] and a['onset_t'] == b['onset_t']
                    and pa == pb and before == [i for i in b['impacts'] if i['t'] < a['onset_t']])
            if not same:
                raise SystemExit(f'{d.name}/{b["name"]} is not the same trial as in {dirs[0]}')


def ms(value) -> str:
    """Milliseconds as text, '-' for none."""
    return '-' if value is None else f'{value:.0f}'


def paired_shift(base, outcomes) -> str:
    """Median latency difference (ms) to ``base`` over the trials caught in both."""
    lat0 = {o['name']: o['latency_s'] for o in base if o['verdict'] == 'detected'}
    diff = [1000 * (o['latency_s'] - lat0[o['name']]) for o in outcomes
            if o['verdict'] == 'detected' and o['name'] in lat0]
    return f'{np.median(diff):+.0f}' if diff else '-'


def knock_row(path: Path) -> str:
    """Return the model's own rule on the knocked trials (the knock table's first row)."""
    for line in path.read_text().splitlines():
        if 'with a knock on the hand' in line:
            cells = [c.strip() for c in line.strip('|').split('|')]
            return f'{cells[2]} caught, {cells[4]} early, median {cells[5]} ms'
    return '-'


def main(argv=None) -> int:
    """Run the measurement; print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('out', type=Path)
    parser.add_argument('--rates', default='100,51,125,200,500,1000')
    parser.add_argument('--trials', type=int, default=120)
    parser.add_argument('--seed', type=int, default=4545)
    parser.add_argument('--quiet-rates', default='100,200')
    parser.add_argument('--quiet-trials', type=int, default=48)
    parser.add_argument('--quiet-seed', type=int, default=4546)
    parser.add_argument('--jobs', type=int, default=2, help='processes of sweep (default 2)')
    args = parser.parse_args(argv)
    rates = [r for r in args.rates.split(',') if r]
    quiet = [r for r in args.quiet_rates.split(',') if r]
    steps = 3 * len(rates) + 2 * len(quiet) + 1
    done = [0]
    start = time.monotonic()

    def step(text):
        done[0] += 1
        print(f'[{done[0]}/{steps} {time.monotonic() - start:5.0f} s] {text}', file=sys.stderr,
              flush=True)

    def simulate(folder, rate, trials, seed, conditions):
        step(f'simulate {folder.name}')
        if not (folder / 'manifest.json').exists():
            run('simulate', folder, '--trials', trials, '--seed', seed, '--conditions',
                conditions, '--ft-rate', rate, '--quiet')

    results, knocks = {}, {}
    for rate in rates:
        simulate(args.out / f'r{rate}', rate, args.trials, args.seed, 'wide')
    check_paired([args.out / f'r{r}' for r in rates])
    for rate in rates:
        step(f'evaluate r{rate}')
        report = args.out / f'eval_r{rate}'
        run('evaluate', args.out / f'r{rate}', '--detector', 'forest', '--detector',
            'forest-ft', '--report', report)
        results[rate] = (json.loads((report / 'metrics.json').read_text()),
                         json.loads((report / 'trials.json').read_text()))
        step(f'sweep --knocks r{rate}')
        out = args.out / f'sweep_r{rate}.md'
        run('sweep', args.out / f'r{rate}', '--model', FT_MODEL, '--knocks', '--wrench-rate',
            rate, '--out', out, '--jobs', args.jobs)
        knocks[rate] = knock_row(out)
    step('feature lag')
    folders = [(float(r), args.out / f'r{r}') for r in rates]
    lag = {key: feature_lag(folders=folders, model=path) for key, path in
           (('forest', MODEL), ('forest-ft', FT_MODEL))}
    quiet_results = {}
    for rate in quiet:
        simulate(args.out / f'q{rate}', rate, args.quiet_trials, args.quiet_seed,
                 'quiet_contact')
    if len(quiet) > 1:
        check_paired([args.out / f'q{r}' for r in quiet])
    for rate in quiet:
        step(f'evaluate q{rate}')
        report = args.out / f'eval_q{rate}'
        run('evaluate', args.out / f'q{rate}', '--detector', 'forest', '--report', report)
        quiet_results[rate] = (json.loads((report / 'metrics.json').read_text()),
                               json.loads((report / 'trials.json').read_text()))

    head = ('| F/T rate [Hz] | model | caught | early | missed+late | median [ms] | p95 [ms] '
            f'| paired shift vs {rates[0]} Hz [ms] | frame -> completing sample [ms] |')
    rule = '\n|---|---|---|---|---|---|---|---|---|'
    print(f'## {args.trials} trials, --conditions wide --seed {args.seed}\n')
    print(head + rule)
    for rate in rates:
        metrics, trials = results[rate]
        for key, label in MODELS:
            s = metrics[key]['summary']['all']
            wait = (completion_wait(args.out / f'r{rate}', trials[key]) if key == 'forest-ft'
                    else '')
            print(f"| {rate} | {label} | {s['detected']}/{s['trials']} | {s['premature']} | "
                  f"{s['missed'] + s['late']} | {ms(s['latency_ms_median'])} | "
                  f"{ms(s['latency_ms_p95'])} | "
                  f'{paired_shift(results[rates[0]][1][key], trials[key])} | {wait} |')
    print(f'\nforce_change lag behind {rates[0]} Hz, median over trials [ms] (trials):')
    for key, label in MODELS:
        frames = 'audio frames' if key == 'forest' else 'F/T frames'
        print(f'  {label} ({frames}): ' + ', '.join(
            f'{r} Hz {v:+.1f} ({n})' for r, (v, n) in zip(rates, lag[key])))
    print('\nF/T-only model, own rule, trials with a knock on the hand in the air (sweep):')
    for rate in rates:
        print(f'  {rate} Hz: {knocks[rate]}')
    print(f'\n## Families where a rate differs from {rates[0]} Hz (caught, early, or a paired '
          'shift > 10 ms)\n')
    print('| model | family | ' + ' | '.join(f'{r} Hz' for r in rates) + ' |')
    print('|---|---|' + '---|' * len(rates))
    for key, label in MODELS:
        for family in results[rates[0]][0][key]['summary']:
            if family == 'all':
                continue
            cells = [results[r][0][key]['summary'][family] for r in rates]
            shifts = [paired_shift([o for o in results[rates[0]][1][key]
                                    if o['condition'] == family],
                                   [o for o in results[r][1][key] if o['condition'] == family])
                      for r in rates]
            base = cells[0]
            if any(c['detected'] != base['detected'] or c['premature'] != base['premature']
                   or (shift != '-' and abs(int(shift)) > 10)
                   for c, shift in zip(cells[1:], shifts[1:])):
                text = [f"{c['detected']}/{c['trials']}, {c['premature']} early, "
                        f"{ms(c['latency_ms_median'])} ms ({shift})"
                        for c, shift in zip(cells, shifts)]
                print(f'| {label} | {family} | ' + ' | '.join(text) + ' |')
    if quiet:
        print(f'\n## {args.quiet_trials} trials, --conditions quiet_contact --seed '
              f'{args.quiet_seed}, multimodal model\n')
        print(head + rule)
        for rate in quiet:
            metrics, trials = quiet_results[rate]
            s = metrics['forest']['summary']['all']
            print(f"| {rate} | multimodal | {s['detected']}/{s['trials']} | {s['premature']} | "
                  f"{s['missed'] + s['late']} | {ms(s['latency_ms_median'])} | "
                  f"{ms(s['latency_ms_p95'])} | "
                  f"{paired_shift(quiet_results[quiet[0]][1]['forest'], trials['forest'])} | |")
    return 0


if __name__ == '__main__':
    sys.exit(main())
