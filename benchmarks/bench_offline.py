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
Offline tools: real-time factor of ``detect``, and the forest against the baselines.

(a) **Real-time factor** of ``contact-detector detect`` in one process on one core: simulated
trials (every condition set) are written as bags, then each bag is decoded and run through a
fresh detector exactly as ``detect`` does (:func:`contact_detector.detection.factory.detect_bag`):
in blocks, and once more message by message (the node's path) to check that both give the
same output and to measure the ratio in the same run.
Per bag, RTF = bag duration / processing time; the median over bags is reported (wall time and
CPU time of this process), with the split into bag decoding (rosbags + message adapters) and the
detector (feature core + forest + release logic), and the whole ``detect`` command over the
folder (interpreter start, model load, discovery and JSONL writing included); with
``--profile N``, the N functions that take the most time in that per-bag work. The target
(issue #15) is >= 300x per bag, decoding included, at 44.1 kHz in 1024-sample chunks
(``--audio-rate 44100 --chunk-size 1024``).

(b) **Forest vs baselines** on a held-out simulated set of every condition (a seed the model
was not trained on): ``evaluate --detector all`` scores every detector on the same trials; the
comparison table and the detected / premature counts by condition are printed, and the full
report (summary.md, metrics.json, trials.json, latency.png) is written to ``WORK/report``.

Uses the shipped ``models/contact_forest.npz`` if present, else ``--model``. Prints markdown.

Usage::

    python benchmarks/bench_offline.py [--model M] [--rtf-trials 16] [--trials 60]
                                       [--seed 1000] [--work DIR] [--skip-rtf] [--skip-compare]
                                       [--audio-rate HZ] [--chunk-size N] [--storage S]
                                       [--profile N]
"""

import argparse
from datetime import datetime, timezone
import os
from pathlib import Path
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from typing import List, Optional, Sequence

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from contact_detector.detection import factory  # noqa: E402
from contact_detector.detection.offline import run_detector  # noqa: E402
from contact_detector.errors import ContactDetectorError  # noqa: E402
from contact_detector.evaluation import compare, report  # noqa: E402
from contact_detector.evaluation.baselines import BASELINES  # noqa: E402
from contact_detector.io.bags import find_bags, open_reader  # noqa: E402
from contact_detector.io.sensor_stream import load_events, StreamSpec  # noqa: E402
from contact_detector.model.shipped import default_model_path  # noqa: E402
from contact_detector.sim.bag_writer import (manifest_entry, write_manifest,  # noqa: E402
                                             write_trial_bag)
from contact_detector.sim.trial import simulate_trials  # noqa: E402
import numpy as np  # noqa: E402

#: Real-time factor per bag, decoding included, that ``detect`` must reach (issue #15).
TARGET_RTF = 300.0


def emit(*lines: str) -> None:
    """Print each argument on a line of its own ('' = an empty line)."""
    print(*lines, sep='\n', flush=True)


def cpu_name() -> str:
    """Return the CPU model name from /proc/cpuinfo, else the platform's."""
    try:
        for line in Path('/proc/cpuinfo').read_text().splitlines():
            if line.startswith('model name'):
                return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def simulate(*, out: Path, n: int, seed: int, storage: str, audio_rate: int,
             chunk_size: Optional[int] = None) -> List[Path]:
    """Write ``n`` trials of every condition set as bags plus a manifest; return the bags."""
    records = []
    for trial in simulate_trials(n=n, seed=seed, conditions=['all'], audio_rate=audio_rate,
                                 chunk_size=chunk_size):
        write_trial_bag(trial=trial, path=out / trial.name, storage=storage)
        records.append(manifest_entry(trial))
    write_manifest(trials=records, out_dir=out, settings={'seed': seed, 'trials': n})
    return find_bags([out])


def bag_duration(bag: Path) -> float:
    """Bag duration in seconds: last minus first log time."""
    with open_reader(bag) as reader:
        return (reader.end_time - reader.start_time) * 1e-9


def _clock() -> tuple:
    return time.perf_counter(), time.process_time()


def real_time_factor(*, bags: Sequence[Path], model: Path, audio_rate: float) -> dict:
    """Time detect's per-bag work; return the per-bag figures and their medians."""
    make, stream = factory.build_detector_factory(model=model, params_file=None,
                                                  audio_rate=audio_rate)
    spec = StreamSpec(**stream)
    make()                                   # warm caches (compiled forest, FFT plans)
    rows = []
    for bag in bags:
        duration = bag_duration(bag)
        w0, c0 = _clock()
        run = factory.detect_bag(bag=bag, make_detector=make, spec=spec)
        w1, c1 = _clock()
        events = load_events(bag, spec=spec)
        w2, c2 = _clock()
        blocks = run_detector(events, detector=make())
        w3, _ = _clock()
        single = run_detector(events, detector=make(), in_blocks=False)
        w4, _ = _clock()
        same = all(np.array_equal(getattr(blocks, k), getattr(single, k))
                   for k in ('t', 'p', 'contact', 'valid')) and (
            blocks.releases, blocks.events, blocks.counts) == (
            single.releases, single.events, single.counts)
        rows.append({'bag': bag.name, 'duration_s': duration, 'frames': len(run.t),
                     'wall_s': w1 - w0, 'cpu_s': c1 - c0, 'decode_s': w2 - w1,
                     'decode_cpu_s': c2 - c1,
                     'detector_s': w3 - w2, 'per_message_s': w4 - w3, 'same': same})
    med = {key: statistics.median(r['duration_s'] / r[key] for r in rows)
           for key in ('wall_s', 'cpu_s', 'decode_s', 'decode_cpu_s', 'detector_s',
                       'per_message_s')}
    return {'rows': rows, 'median_rtf': med,
            'speedup': statistics.median(r['per_message_s'] / r['detector_s'] for r in rows),
            'identical': sum(r['same'] for r in rows),
            'frames_per_s': statistics.median(r['frames'] / r['wall_s'] for r in rows)}


#: Stages of detect's per-bag work: (label, file, function) whose time with callees is shown.
STAGES = (
    ('bag decoding (reader, CDR, message adapters)', 'io/sensor_stream.py', 'sensor_events'),
    ('detector, in blocks', 'detection/blocks.py', 'run_blocks'),
    ('- per-message checks and audio rate check', 'detection/blocks.py', '_scan'),
    ('- audio time anchors', 'detection/blocks.py', '_anchors'),
    ('- audio frame powers', 'detection/blocks.py', '_frame_powers'),
    ('- audio levels (noise floor, peak, rise)', 'features/audio.py', 'rows'),
    ('- F/T features (spectra, medians, maxima)', 'features/force_torque.py', 'push'),
    ('- forest', 'model/compiled_forest.py', 'predict_proba'),
    ('- release logic', 'detection/release.py', 'step'),
)


def profile_tables(*, bags: Sequence[Path], model: Path, audio_rate: float,
                   top: int) -> tuple:
    """
    Profile detect's per-bag work (cProfile): the time of each stage and the ``top`` functions.

    Decoding and detector together, as :func:`real_time_factor` times them. The profiler adds
    a fixed cost to every Python call, so Python-heavy functions look dearer than they are:
    read the shares and the ranking, not the absolute times.

    Returns
    -------
    (str, str)
        Markdown tables: the stages of :data:`STAGES`, and the functions with the most own
        time.

    """
    import cProfile
    import pstats

    make, stream = factory.build_detector_factory(model=model, params_file=None,
                                                  audio_rate=audio_rate)
    spec = StreamSpec(**stream)
    make()
    profile = cProfile.Profile()
    profile.enable()
    for bag in bags:
        factory.detect_bag(bag=bag, make_detector=make, spec=spec)
    profile.disable()
    stats = pstats.Stats(profile).stats     # (file, line, name) -> (cc, calls, own, cum, _)
    n = len(bags)
    whole = next(row[3] for (file, _, name), row in stats.items()
                 if name == 'detect_bag' and file.endswith('detection/factory.py'))
    stages = ['| stage | function | ms per bag (profiled) | share of the per-bag work |',
              '|---|---|---|---|']
    for label, suffix, function in STAGES:
        cum = sum(row[3] for (file, _, name), row in stats.items()
                  if name == function and file.endswith(suffix))
        stages.append(f'| {label} | `{suffix} {function}` | {cum / n * 1e3:.2f} | '
                      f'{100 * cum / whole:.0f} % |')
    total = sum(row[2] for row in stats.values())
    root = Path(__file__).resolve().parents[1]
    functions = ['| function | calls per bag | own time per bag (ms) | share | '
                 'with callees (ms) |', '|---|---|---|---|---|']
    for (file, line, name), (_, calls, own, cum, _) in sorted(
            stats.items(), key=lambda item: -item[1][2])[:top]:
        path = Path(file)
        where = (f'{path.relative_to(root)}:{line} {name}' if path.is_relative_to(root)
                 else f'{path.name}:{line} {name}' if line else re.sub(r' at 0x\w+', '', name))
        functions.append(f'| `{where}` | {calls / n:.0f} | {own / n * 1e3:.2f} | '
                         f'{100 * own / total:.0f} % | {cum / n * 1e3:.2f} |')
    return '\n'.join(stages), '\n'.join(functions)


def whole_command(*, folder: Path, model: Path, out: Path) -> float:
    """Wall time of ``contact-detector detect FOLDER`` (interpreter start, model load, JSONL)."""
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, '-m', 'contact_detector.cli.main', 'detect',
                           str(folder), '--model', str(model), '--out', str(out)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f'detect failed: {done.stderr}')
    return time.perf_counter() - t0


def by_condition_table(results: dict) -> str:
    """Return detected / premature counts per condition set (rows) and detector (columns)."""
    detectors = list(results)
    conditions = [c for c in results[detectors[0]]['summary'] if c != 'all'] + ['all']
    lines = ['| condition | ' + ' | '.join(detectors) + ' |',
             '|---|' + '---|' * len(detectors)]
    for condition in conditions:
        cells = []
        for name in detectors:
            s = results[name]['summary'][condition]
            cells.append(f"{s['detected']}/{s['trials']} ({s['premature']})")
        lines.append(f'| {condition} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog='bench_offline', description=__doc__.split('\n')[1])
    parser.add_argument('--model', type=Path, default=None,
                        help='model bundle (default: the shipped models/contact_forest.npz)')
    parser.add_argument('--rtf-trials', type=int, default=16, help='bags timed for (a)')
    parser.add_argument('--trials', type=int, default=60, help='held-out trials for (b)')
    parser.add_argument('--seed', type=int, default=1000,
                        help='simulator seed of the held-out set (not a training seed)')
    parser.add_argument('--storage', choices=('sqlite3', 'mcap', 'ros1'), default='sqlite3')
    parser.add_argument('--audio-rate', type=int, default=16000)
    parser.add_argument('--chunk-size', type=int, default=None,
                        help='audio samples per message (default: the condition sets '
                             'chunking, 10 ms or odd)')
    parser.add_argument('--work', type=Path, default=None,
                        help='keep bags and the report here (default: a temporary directory)')
    parser.add_argument('--profile', type=int, default=0, metavar='N',
                        help='after (a), profile the same per-bag work and print the N '
                             'functions with the most own time')
    parser.add_argument('--skip-rtf', action='store_true')
    parser.add_argument('--skip-compare', action='store_true')
    args = parser.parse_args(argv)
    try:
        model = args.model or default_model_path()
    except ContactDetectorError as err:
        print(f'bench_offline: {err}; train one and pass --model', file=sys.stderr)
        return 1
    tmp = None
    if args.work is None:
        tmp = tempfile.TemporaryDirectory(prefix='bench_offline_')
        work = Path(tmp.name)
    else:
        work = args.work
        work.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()
    emit('# bench_offline', '')
    emit(f'{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, {cpu_name()}, '
         f'{os.cpu_count()} cores, load {load[0]:.2f}, Python {platform.python_version()}; '
         f'model `{model}`; {args.storage} bags, {args.audio_rate} Hz audio'
         + (f' in {args.chunk_size}-sample chunks' if args.chunk_size else '') + '.', '')

    if not args.skip_rtf:
        folder = work / 'rtf'
        bags = simulate(out=folder, n=args.rtf_trials, seed=args.seed + 1,
                        storage=args.storage, audio_rate=args.audio_rate,
                        chunk_size=args.chunk_size)
        rtf = real_time_factor(bags=bags, model=model, audio_rate=args.audio_rate)
        total_s = sum(r['duration_s'] for r in rtf['rows'])
        command_s = whole_command(folder=folder, model=model, out=work / 'rtf.jsonl')
        m = rtf['median_rtf']
        emit(f'## (a) detect real-time factor ({len(bags)} bags, {total_s:.0f} s of '
             'recordings, one process)', '',
             '| figure | median over bags |', '|---|---|',
             f"| RTF, decoding + detector (wall) | {m['wall_s']:.1f}x |",
             f"| RTF, decoding + detector (CPU of this process) | {m['cpu_s']:.1f}x |",
             f"| RTF, bag decoding only | {m['decode_s']:.1f}x |",
             f"| RTF, bag decoding only (CPU of this process) | {m['decode_cpu_s']:.1f}x |",
             f"| RTF, detector only, in blocks (what detect runs) | {m['detector_s']:.1f}x |",
             f"| RTF, detector only, message by message (the node's path) | "
             f"{m['per_message_s']:.1f}x |",
             '| blocks vs message by message, same bag (median ratio) | '
             f"{rtf['speedup']:.1f}x faster; identical output on {rtf['identical']}/"
             f"{len(rtf['rows'])} bags |",
             f"| audio frames per second of processing | {rtf['frames_per_s']:.0f} |",
             f'| whole `detect` command over the folder (wall) | {total_s / command_s:.1f}x '
             f'({command_s:.1f} s) |', '',
             f'Target >= {TARGET_RTF:.0f}x per bag: '
             f"{'met' if m['wall_s'] >= TARGET_RTF else 'NOT met'} (wall), "
             f"{'met' if m['cpu_s'] >= TARGET_RTF else 'NOT met'} (CPU).", '')
        if args.profile:
            stages, functions = profile_tables(bags=bags, model=model,
                                               audio_rate=args.audio_rate, top=args.profile)
            emit(f'Where the time goes: cProfile of the same per-bag work ({len(bags)} bags; '
                 'the profiler inflates Python calls, so read the shares and the ranking):', '',
                 stages, '', functions, '')

    if not args.skip_compare:
        folder = work / 'heldout'
        bags = simulate(out=folder, n=args.trials, seed=args.seed, storage=args.storage,
                        audio_rate=args.audio_rate)
        make, stream = factory.build_detector_factory(model=model, params_file=None,
                                                      audio_rate=args.audio_rate)
        probe = make()
        t0 = time.perf_counter()
        results = compare.evaluate(
            bags=bags, detectors=['forest', *BASELINES],
            make_forest=make,
            spec=StreamSpec(**stream), audio_rate=probe.settings.audio_rate,
            wrench_rate=probe.settings.wrench_rate, label_window=probe.bundle.label_window)
        elapsed = time.perf_counter() - t0
        report.write_report(report=work / 'report', results=results)
        emit(f'## (b) forest vs baselines ({len(bags)} held-out trials, seed {args.seed}, '
             f'every condition set; {elapsed:.0f} s)', '')
        emit(report.comparison_table(results), '')
        emit('Detected / trials (premature) by condition:', '')
        emit(by_condition_table(results), '')
        emit(f"Report: `{work / 'report' / 'summary.md'}`"
             + (' (temporary)' if tmp else ''), '')
    if tmp is not None:
        tmp.cleanup()
    return 0


if __name__ == '__main__':
    sys.exit(main())
