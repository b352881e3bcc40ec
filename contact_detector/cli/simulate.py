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
``contact-detector simulate OUT_DIR --trials N --seed S``: write simulated trials as rosbag2.

One bag per trial (``OUT_DIR/trial_0000``, ...) plus ``OUT_DIR/manifest.json`` with each
trial's true contact onset, stop time, phases, exogenous impacts and every randomised
parameter. Deterministic for a seed: the same command writes the same messages.
"""

import argparse
from pathlib import Path
import shutil
import sys
from typing import Sequence

from contact_detector.errors import BagError, ContactDetectorError
from contact_detector.sim.bag_writer import held_trials, STORAGES, write_trials
from contact_detector.sim.conditions import (ALIASES, BRUSH_MODES, CONDITION_SETS,
                                             CONTACT_SOUND_MODES, EVENT_MODES,
                                             resolve_conditions, TARED_MODES)
from contact_detector.sim.trial import HIT_KINDS, simulate_trial, simulate_trials
from tqdm import tqdm

PROG = 'contact-detector simulate'


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser."""
    sets = '; '.join(f'{c.name}: {c.description}' for c in CONDITION_SETS.values())
    parser = argparse.ArgumentParser(
        prog=PROG,
        description='Write simulated glass-placing trials (wrist F/T, microphone, ground truth) '
                    'as rosbag2 plus a JSON manifest.',
        epilog=f'Condition sets: {sets}. Aliases: all: the six original sets (paper to '
               f'odd_chunking); families: the six families (geometry to quiet_contact); wide: '
               f'those twelve; no alias includes real_sounds or slow_partial. real_sounds '
               f'(recorded sounds) needs tools/fetch_sounds.sh first. Trial i uses condition '
               f'i mod len(conditions); within a set the exogenous hits cycle hand, table, '
               f'none (exogenous: mixed, touch, brush, setdown); with --events everywhere '
               f'the other sets add mixed (any of hand, table, touch, brush, setdown per '
               f'event).')
    parser.add_argument('out_dir', metavar='OUT_DIR', type=Path,
                        help='directory for the bags and manifest.json (created)')
    parser.add_argument('--trials', type=int, default=6, metavar='N',
                        help='number of trials (default 6)')
    parser.add_argument('--seed', type=int, default=0, metavar='S',
                        help='random seed (default 0); trial i uses default_rng([S, i])')
    parser.add_argument('--storage', choices=sorted(STORAGES), default='sqlite3',
                        help='rosbag2 storage plugin, or ros1 for ROS 1 .bag files '
                             '(default sqlite3)')
    parser.add_argument('--audio-rate', type=int, default=16000, metavar='HZ',
                        help='microphone sample rate (default 16000)')
    parser.add_argument('--ft-rate', type=float, default=100.0, metavar='HZ',
                        help='wrist F/T rate (default 100, the HSR; e.g. 1000)')
    parser.add_argument('--chunk-size', type=int, default=None, metavar='SAMPLES',
                        help='fixed audio samples per /audio message (default: 10 ms, or '
                             'random sizes for the odd_chunking set)')
    parser.add_argument('--label-window', type=float, default=0.1, metavar='S',
                        help='length of the labelled onset window (default 0.1 s)')
    parser.add_argument('--conditions', nargs='+', default=['paper'], metavar='SET',
                        help='condition sets or aliases, space or comma separated '
                             f'(default paper; known: {", ".join([*CONDITION_SETS, *ALIASES])})')
    parser.add_argument('--start-index', type=int, default=0, metavar='I',
                        help='index of the first trial (default 0)')
    parser.add_argument('--events', choices=EVENT_MODES, default='family',
                        help='family (default): touches, brushes and set-downs only in the '
                             'exogenous set; everywhere: in every set')
    parser.add_argument('--tared', choices=TARED_MODES, default='family',
                        help='F/T sensors tared (zeroed at rest before the lift, so they read '
                             'the change of the load since then): family (default): only the '
                             'geometry and slow_partial sets draw it (tared or not, equal '
                             'odds); everywhere: every set draws it; all: every sensor is '
                             'tared; none: no sensor is (the same trials otherwise)')
    parser.add_argument('--contact-sound', choices=CONTACT_SOUND_MODES, default='family',
                        help="the contact sound's level: family (default): as each set draws "
                             'it (quieter only in quiet_contact and real_sounds); everywhere: '
                             'every other set changes it by -24 to 0 dB')
    parser.add_argument('--brushes', choices=BRUSH_MODES, default='lifting',
                        help='how a brush pushes on the object: lifting (default): mostly up, '
                             'against the motion; friction: the friction against the motion '
                             'plus the sideways push that makes it (friction coefficient '
                             '0.2-1.0)')
    parser.add_argument('--sensor-offset', type=_offset_pair, default=None, metavar='N,NM',
                        help='untared sensors read a constant offset of up to N newtons and NM '
                             'newton metres (vector lengths, uniform): a sensor never zeroed. '
                             "Default: each set's own, up to 3 N and 0.3 N m (zeroed with "
                             'the empty hand, then drifting); the same trials otherwise')
    parser.add_argument('--hits', choices=HIT_KINDS, default=None,
                        help='give every trial this kind of exogenous event instead of the '
                             "set's cycle (mixed: any of hand, table, touch, brush, setdown "
                             'per event)')
    parser.add_argument('--overwrite', action='store_true',
                        help='replace existing trial_* bags and manifest.json in OUT_DIR')
    parser.add_argument('--reuse', action='store_true',
                        help='keep OUT_DIR as it is if its manifest.json says these very '
                             'trials (every setting above the same) and every bag it lists '
                             'is there; other trials in OUT_DIR are an error, or replaced '
                             'with --overwrite')
    parser.add_argument('--quiet', action='store_true', help='no progress bar or summary')
    return parser


def _offset_pair(text: str) -> tuple[float, float]:
    """Parse ``N,NM`` (checked by the simulator: ConfigError -> usage error)."""
    try:
        force, torque = (float(v) for v in text.split(','))
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'expected N,NM (two numbers), got {text!r}') from err
    return force, torque


def _prepare(out_dir: Path, *, overwrite: bool) -> None:
    existing = sorted(out_dir.glob('trial_*')) + sorted(out_dir.glob('manifest.json'))
    if existing and not overwrite:
        raise ContactDetectorError(f'{out_dir} already holds simulator output '
                                   f'({existing[0].name}, ...); use --overwrite')
    for path in existing:
        if path.is_dir():
            shutil.rmtree(path)
        else:
            path.unlink()
    out_dir.mkdir(parents=True, exist_ok=True)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; return the exit status (0 ok, 1 error, 2 usage)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.trials < 1:
        parser.error('--trials must be >= 1')
    if args.seed < 0 or args.start_index < 0:
        parser.error('--seed and --start-index must be >= 0')
    try:
        conditions = resolve_conditions(args.conditions)
    except ContactDetectorError as err:
        parser.error(str(err))
    try:
        # validate the arguments before touching OUT_DIR
        simulate_trial(seed=args.seed, index=args.start_index, condition=conditions[0],
                       audio_rate=args.audio_rate, ft_rate=args.ft_rate,
                       chunk_size=args.chunk_size, label_window_s=args.label_window,
                       events=args.events, tared=args.tared, hits=args.hits,
                       contact_sound=args.contact_sound, brushes=args.brushes,
                       sensor_offset=args.sensor_offset)
    except ContactDetectorError as err:
        parser.error(str(err))
    settings = {'seed': args.seed, 'trials': args.trials, 'start_index': args.start_index,
                'conditions': list(conditions), 'storage': args.storage,
                'audio_rate': args.audio_rate, 'ft_rate': args.ft_rate,
                'chunk_size': args.chunk_size, 'label_window_s': args.label_window,
                'events': args.events, 'tared': args.tared, 'hits': args.hits}
    if args.contact_sound != 'family':
        # older manifests have no such key: 'family' is their mode
        settings['contact_sound'] = args.contact_sound
    if args.brushes != 'lifting':
        settings['brushes'] = args.brushes
    if args.sensor_offset is not None:
        settings['sensor_offset'] = list(args.sensor_offset)
    try:
        if args.reuse:
            try:
                held, other = held_trials(out_dir=args.out_dir, settings=settings)
            except BagError:
                if not args.overwrite:
                    raise
                held, other = None, ()   # unreadable: --overwrite replaces it with the rest
            if held is not None and not other:
                if not args.quiet:
                    print(f'{args.out_dir} already holds these {args.trials} trials; reused')
                return 0
            if other and not args.overwrite:
                raise ContactDetectorError(
                    f'{args.out_dir} holds other simulated trials (other {", ".join(other)}); '
                    'use --overwrite or another OUT_DIR')
        _prepare(args.out_dir, overwrite=args.overwrite)
        trials = simulate_trials(n=args.trials, seed=args.seed, conditions=conditions,
                                 start_index=args.start_index, audio_rate=args.audio_rate,
                                 ft_rate=args.ft_rate, chunk_size=args.chunk_size,
                                 label_window_s=args.label_window, events=args.events,
                                 tared=args.tared, hits=args.hits,
                                 contact_sound=args.contact_sound, brushes=args.brushes,
                                 sensor_offset=args.sensor_offset)
        records, manifest = write_trials(
            trials=tqdm(trials, total=args.trials, desc='simulate', unit='trial',
                        disable=args.quiet),
            out_dir=args.out_dir, storage=args.storage, settings=settings)
    except ContactDetectorError as err:
        print(f'{PROG}: error: {err}', file=sys.stderr)
        return 1
    if not args.quiet:
        hits = sum(len(r['impacts']) for r in records)
        in_air = sum(i['in_air'] for r in records for i in r['impacts'])
        print(f'wrote {len(records)} bags ({args.storage}) and {manifest}; '
              f'{hits} exogenous impacts, {in_air} while the object was in the air')
    return 0


if __name__ == '__main__':
    sys.exit(main())
