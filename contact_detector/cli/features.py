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
``contact-detector features``: run the streaming feature core on a generated signal.

A quick look at the feature core with no robot and no data: a synthetic 5 s recording (a
held load, a contact-like load drop with a ring-down and an impact sound at 3 s) goes through
:class:`~contact_detector.features.StreamingFeatureExtractor` in 10 ms chunks, and the features
around the event are printed as a table.
"""

import argparse
import sys
from typing import Optional, Sequence

from contact_detector.features import FeatureConfig, FeatureFrames, StreamingFeatureExtractor
from contact_detector.sim.synthetic import synthetic_recording
import numpy as np


def run_stream(*, config: FeatureConfig, recording: dict, audio_rate: int, ft_rate: float,
               chunk: int) -> FeatureFrames:
    """Push the recording through the streaming core in chunks, in arrival order."""
    extractor = StreamingFeatureExtractor(config=config, audio_rate=audio_rate,
                                          ft_input_rate=ft_rate)
    audio, ft_t = recording['audio'], recording['ft_t']
    t0 = recording['t0']
    out, f = [], 0
    for start in range(0, audio.size, chunk):
        end = min(start + chunk, audio.size)
        stamp = t0 + (end - 1) / audio_rate
        f_end = int(np.searchsorted(ft_t, stamp, side='right'))
        if f_end > f:
            out.append(extractor.push_wrench(t=ft_t[f:f_end], force=recording['force'][f:f_end],
                                             torque=recording['torque'][f:f_end]))
            f = f_end
        out.append(extractor.push_audio(audio[start:end], stamp=stamp))
    out.append(extractor.flush())
    return FeatureFrames.concat(out, config.feature_names)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector features', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--audio-rate', type=int, default=16000, help='Hz (default 16000)')
    parser.add_argument('--ft-rate', type=float, default=100.0, help='Hz (default 100)')
    parser.add_argument('--ft-window', type=int, default=32, help='DFT window, F/T samples')
    parser.add_argument('--ft-hop', type=int, default=1, help='F/T feature hop, samples')
    args = parser.parse_args(argv)
    config = FeatureConfig(ft_window=args.ft_window, ft_hop=args.ft_hop)
    recording = synthetic_recording(audio_rate=args.audio_rate, ft_rate=args.ft_rate)
    frames = run_stream(config=config, recording=recording, audio_rate=args.audio_rate,
                        ft_rate=args.ft_rate, chunk=args.audio_rate // 100)
    rel = frames.t - recording['t0']
    print(f'{len(frames)} audio frames ({frames.valid.mean():.0%} with fresh F/T features); '
          f'event at 3.000 s')
    print('   t [s]  ' + '  '.join(f'{n:>15}' for n in frames.names))
    for i in np.flatnonzero((rel > 2.95) & (rel < 3.12))[::2]:
        print(f'{rel[i]:8.3f}  ' + '  '.join(f'{v:15.6g}' for v in frames.x[i]))
    return 0


if __name__ == '__main__':
    sys.exit(main())
