#!/usr/bin/env python3

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
Cut a ROS 1 recording with several labelled contacts into one bag per contact.

    tools/split_recording.py BAG.bag --labels labels.csv --out DIR

``contact-detector train`` splits its data by recording (no recording sits in training and
test alike), so one long recording of many contacts can be neither split nor left out in
parts. This cuts it: piece ``k`` holds every message logged in ``[(o_{k-1} + o_k) / 2,
(o_k + o_{k+1}) / 2)`` (open at the recording's ends), ``o_k`` the labelled onsets, and is
written as ``DIR/<stem>_cK.bag`` with the original connections and raw message bytes (an mp3
audio stream is cut at a message boundary, which is a frame boundary for audio_common).
``DIR/labels.csv`` gets one row per piece, in the format ``--labels`` reads.
"""

import argparse
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.training.protocol import read_labels_csv
from rosbags.rosbag1 import Reader, Writer


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the script; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bag', type=Path, help='ROS 1 .bag file')
    parser.add_argument('--labels', type=Path, required=True, help='labels CSV')
    parser.add_argument('--out', type=Path, required=True, help='directory for the pieces')
    args = parser.parse_args(argv)
    onsets = sorted(read_labels_csv(args.labels).get(args.bag.name, []))
    if not onsets:
        print(f'split_recording: {args.labels} has no onset for {args.bag.name}',
              file=sys.stderr)
        return 1
    cuts = [-float('inf')] + [(a + b) / 2 for a, b in zip(onsets, onsets[1:])] + [float('inf')]
    args.out.mkdir(parents=True, exist_ok=True)
    rows = ['bag,onset_start,onset_end']
    with Reader(args.bag) as reader:
        for k, onset in enumerate(onsets):
            lo, hi = cuts[k] * 1e9, cuts[k + 1] * 1e9
            name = f'{args.bag.stem}_c{k + 1}.bag'
            path = args.out / name
            if path.exists():
                path.unlink()
            with Writer(path) as writer:
                conns = {c.id: writer.add_connection(
                    c.topic, c.msgtype, msgdef=c.msgdef.data, md5sum=c.digest,
                    callerid=c.ext.callerid, latching=c.ext.latching)
                    for c in reader.connections}
                for conn, t_ns, raw in reader.messages():
                    if lo <= t_ns < hi:
                        writer.write(conns[conn.id], t_ns, raw)
            rows.append(f'{name},{onset:.6f},{onset:.6f}')
    (args.out / 'labels.csv').write_text('\n'.join(rows) + '\n')
    print(f'{len(onsets)} pieces and labels.csv -> {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
