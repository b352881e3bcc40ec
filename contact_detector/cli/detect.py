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
``contact-detector detect``: run the node's processing on bags, in bag time.

    contact-detector detect BAG_OR_DIR... [--model M] [--params P] [--wrench-topic T]
                            [--audio-topic T] [--audio-rate HZ] [--wrench-rate HZ]
                            [--audio-coding pcm|mp3] --out FILE.jsonl

Bags are rosbag2 directories (sqlite3, mcap) or ROS 1 ``.bag`` files. The wrench and audio
topics, the audio format and the F/T rate are found in each bag
(:mod:`contact_detector.io.discovery`) and printed; the options override what is found.

Writes one JSON object per line: for every audio frame
``{"bag": NAME, "t": T, "p": P, "contact": B}`` and for every release
``{"bag": NAME, "t": T, "event": "release"}`` (with ``"model": "F/T-only"`` or ``"audio +
F/T"`` when two models decide); NAME is the bag directory's (or file's) name,
with as much of its path as tells apart bags of the same name from different folders
(``day1/trial_0000``, as ``evaluate`` names them), T the absolute
bag time in seconds of the last audio sample the decision used (of the last F/T sample with an
F/T-only model). Each bag starts a fresh detector, armed. With ``model.ft_also_decides: true``
in ``--params``, as on the node, a multimodal model decides together with the shipped F/T-only
model and the first release of either is the release; the frames written are the multimodal
model's. A recording without the audio topic is decided by
the shipped F/T-only model unless ``--model`` (or ``model.path``) names one; the command prints
which models it used. ``--params`` reads the node's YAML parameter file (the
``contact_detector_node: ros__parameters:`` section), so offline runs use the robot's settings;
its ``audio.sample_rate`` serves bags that do not describe their audio, and ``--audio-rate``
overrides both.
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.cli.common import add_stream_arguments, discover_all
from contact_detector.detection.factory import build_detector_factory, detect_bag, stream_spec
from contact_detector.detection.parameters import read_param_file
from contact_detector.errors import ContactDetectorError
from contact_detector.io.bags import find_bags, recording_names
from tqdm import tqdm


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector detect', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', help='bag directories or folders of bags')
    parser.add_argument('--model', type=Path, default=None,
                        help='model bundle (default: model.path from --params, else the '
                             'shipped model; for a recording without the audio topic, or '
                             'with audio.enabled false in --params, the shipped F/T-only '
                             'model)')
    parser.add_argument('--params', type=Path, default=None, help='node parameter YAML')
    add_stream_arguments(parser)
    parser.add_argument('--out', type=Path, required=True, help='JSONL output file')
    args = parser.parse_args(argv)
    try:
        return _detect(args)
    except ContactDetectorError as err:
        print(f'contact-detector detect: {err}', file=sys.stderr)
        return 1


def _detect(args: argparse.Namespace) -> int:
    make, stream = build_detector_factory(model=args.model, params_file=args.params,
                                          audio_rate=args.audio_rate)
    params = read_param_file(args.params) if args.params else {}
    found = discover_all(find_bags(args.bags), args=args, params=params,
                         prog='contact-detector detect',
                         allow_no_audio=make.decides_without_audio)
    bags = [bag for bag, _ in found]
    names = recording_names(bags)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    frames = releases = 0
    used = set()
    with args.out.open('w') as out:
        for bag, streams in tqdm(found, desc='detect', unit='bag', disable=len(bags) < 2):
            if streams.has_audio not in used:
                used.add(streams.has_audio)
                where = 'with' if streams.has_audio else 'without'
                print(f'model for recordings {where} an audio topic: '
                      f'{make.describe(has_audio=streams.has_audio)}')
            run = detect_bag(bag=bag, make_detector=make, spec=stream_spec(streams, stream),
                             streams=streams)
            name = names[bag]
            rows = [(float(t), 0, {'bag': name, 't': float(t), 'p': float(p),
                                   'contact': bool(c)})
                    for t, p, c in zip(run.t, run.p, run.contact)]
            by = {'model': run.released_by} if run.released_by else {}
            rows += [(float(t), 1, {'bag': name, 't': float(t), 'event': 'release', **by})
                     for t in run.releases]
            # A release line follows the frame that fired it.
            lines = [json.dumps(row) for _, _, row in sorted(rows, key=lambda r: r[:2])]
            out.write('\n'.join(lines) + ('\n' if lines else ''))
            frames += len(run.t)
            releases += len(run.releases)
            if run.carried is not None and not run.carried.steady:
                print(f'{name}: {run.carried.describe()}: the recording should start with '
                      'the object held still in the hand', file=sys.stderr)
            problem = run.input_problem()
            if problem:
                print(f'{name}: {problem}', file=sys.stderr)
            if run.counts.get('audio_dropped') or run.counts.get('wrench_dropped'):
                print(f'{name}: dropped {run.counts["audio_dropped"]} audio and '
                      f'{run.counts["wrench_dropped"]} wrench messages', file=sys.stderr)
    print(f'{len(bags)} bags, {frames} frames, {releases} releases -> {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
