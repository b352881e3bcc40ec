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
The stream options and discovery messages of detect, evaluate and train (not a command).

Command modules import this module, :mod:`.model_options` and the layers below, never each
other.
"""

import argparse
from pathlib import Path
from typing import Sequence

from contact_detector.io.bags import manifest_entry
from contact_detector.io.discovery import discover_streams, summary_lines


def add_stream_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options that override what discovery finds in a bag."""
    parser.add_argument('--wrench-topic', default=None,
                        help='wrench topic (default: the one WrenchStamped topic)')
    parser.add_argument('--audio-topic', default=None,
                        help='audio topic (default: the one topic of a supported audio type)')
    parser.add_argument('--audio-rate', type=float, default=None, metavar='HZ',
                        help='audio sample rate (default: from AudioInfo / AudioStamped, '
                             'else audio.sample_rate of --params, else estimated)')
    parser.add_argument('--wrench-rate', type=float, default=None, metavar='HZ',
                        help='F/T rate (default: measured from the header stamps)')
    parser.add_argument('--audio-coding', choices=('pcm', 'mp3'), default=None,
                        help='AudioData payload (default: from AudioInfo, else pcm)')


def discover_all(bags: Sequence[Path], *, args: argparse.Namespace, params: dict,
                 prog: str, allow_no_audio: bool = False) -> list:
    """
    Discover every bag's streams (flags override); print what was found; return the list.

    ``allow_no_audio``: the caller decides recordings without an audio topic with an F/T-only
    model, so such a bag is no error (its :class:`Streams` has ``audio_topic`` None).

    Returns
    -------
    list of (Path, Streams)

    """
    msg_type = params.get('audio.msg_type')
    found = []
    for bag in bags:
        # A simulator manifest beside the bag knows its rate; a parameter file is the robot's.
        entry = manifest_entry(bag)
        hint = (entry['audio_rate'], 'manifest') if entry and 'audio_rate' in entry else (
            params.get('audio.sample_rate'), 'parameters')
        found.append((bag, discover_streams(
            bag, wrench_topic=args.wrench_topic, audio_topic=args.audio_topic,
            audio_msg_type=msg_type or None, audio_rate=args.audio_rate,
            wrench_rate=getattr(args, 'wrench_rate', None),
            param_audio_rate=hint[0], param_source=hint[1],
            channels=int(params['audio.channels']) if 'audio.channels' in params else None,
            coding=getattr(args, 'audio_coding', None), allow_no_audio=allow_no_audio)))
    for line in summary_lines(found):
        print(f'{prog}: {line}')
    return found
