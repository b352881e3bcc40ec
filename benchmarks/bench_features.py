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
Feature-core cost per audio frame and real-time factor (one core).

Streams a synthetic recording through StreamingFeatureExtractor the way the node receives it
(audio in 10 ms chunks, one wrench sample per message) and the way offline tools do (1 s
chunks), at 16/44.1 kHz audio with 100 Hz/1 kHz F/T. Prints a markdown table of medians.

    python benchmarks/bench_features.py [--seconds 30] [--repeats 5]
                                        [--configs default,shipped,shipped+load]
                                        [--noise-jumps 15,0]

``--configs``: ``default`` is ``FeatureConfig()`` (the paper's seven on a sliding window),
``shipped`` the shipped multimodal model's, ``shipped+load`` that with the load path's column
(``force_carried_shift``), which the detector computes beside the columns of every model that
measures the carried load. With several, their runs alternate (one of each in turn) so that
they share the machine's load, and the table has one row per configuration.
``--noise-jumps``: the F/T stream's noise check (``noise_jump_n``, N; 0 = off, the default 15
N), one row per value and configuration, alternating in the same way.
"""

import argparse
import statistics
import time

from contact_detector.features import FeatureConfig, StreamingFeatureExtractor
from contact_detector.features.config import LOAD_FEATURE
from contact_detector.features.noise import NOISE_JUMP_N
from contact_detector.sim.synthetic import synthetic_recording
import numpy as np


def run_once(*, config, recording, audio_rate, ft_rate, audio_chunk, ft_chunk,
             noise_jump_n=NOISE_JUMP_N):
    extractor = StreamingFeatureExtractor(config=config, audio_rate=audio_rate,
                                          ft_input_rate=ft_rate, noise_jump_n=noise_jump_n)
    audio, ft_t, force, torque = (recording['audio'], recording['ft_t'], recording['force'],
                                  recording['torque'])
    t0 = recording['t0']
    frames, f = 0, 0
    start = time.perf_counter()
    for a in range(0, audio.size, audio_chunk):
        end = min(a + audio_chunk, audio.size)
        stamp = t0 + (end - 1) / audio_rate
        f_end = int(np.searchsorted(ft_t, stamp, side='right'))
        while f < f_end:
            g = min(f + ft_chunk, f_end)
            frames += len(extractor.push_wrench(t=ft_t[f:g], force=force[f:g],
                                                torque=torque[f:g]))
            f = g
        frames += len(extractor.push_audio(audio[a:end], stamp=stamp))
    frames += len(extractor.flush())
    return time.perf_counter() - start, frames


#: The configurations --configs names.
CONFIGS = {'default': FeatureConfig(), 'shipped': FeatureConfig.shipped(),
           'shipped+load': FeatureConfig.shipped().with_extra((LOAD_FEATURE,))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--seconds', type=float, default=30.0)
    parser.add_argument('--repeats', type=int, default=5)
    parser.add_argument('--configs', default='default',
                        help=f'comma-separated, from {sorted(CONFIGS)} (default: default)')
    parser.add_argument('--noise-jumps', default=f'{NOISE_JUMP_N:g}',
                        help='comma-separated noise_jump_n values, N (0 = the check off)')
    args = parser.parse_args()
    unknown = sorted(set(args.configs.split(',')) - set(CONFIGS))
    if unknown:
        parser.error(f'unknown configurations {unknown}; known: {sorted(CONFIGS)}')
    try:
        jumps = [float(v) for v in args.noise_jumps.split(',')]
    except ValueError as err:
        parser.error(f'--noise-jumps: {err}')
    names = [(name, jump) for name in args.configs.split(',') for jump in jumps]
    print(f'feature core, {args.seconds:.0f} s of input, median of {args.repeats} runs\n')
    print('| configuration | audio | F/T | delivery | us / audio frame | real-time factor |')
    print('|---|---|---|---|---|---|')
    for audio_rate in (16000, 44100):
        for ft_rate in (100.0, 1000.0):
            recording = synthetic_recording(audio_rate=audio_rate, ft_rate=ft_rate,
                                            seconds=args.seconds)
            for label, audio_chunk, ft_chunk in (
                    ('live: 10 ms audio, 1 wrench/msg', audio_rate // 100, 1),
                    ('offline: 1 s chunks', audio_rate, int(ft_rate))):
                runs = {name: [] for name in names}
                for _ in range(args.repeats):
                    for name, jump in names:
                        runs[name, jump].append(run_once(
                            config=CONFIGS[name], recording=recording, audio_rate=audio_rate,
                            ft_rate=ft_rate, audio_chunk=audio_chunk, ft_chunk=ft_chunk,
                            noise_jump_n=jump))
                for name, jump in names:
                    seconds = statistics.median(r[0] for r in runs[name, jump])
                    frames = runs[name, jump][0][1]
                    row = name if len(jumps) == 1 else f'{name}, noise_jump {jump:g} N'
                    print(f'| {row} | {audio_rate / 1000:g} kHz | {ft_rate:g} Hz | {label} | '
                          f'{1e6 * seconds / frames:.1f} | {args.seconds / seconds:.0f}x |')


if __name__ == '__main__':
    main()
