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
Write a labels CSV from a contact signal a recording already carries.

    tools/labels_from_topic.py BAG_OR_DIR... --topic T --field F --out labels.csv

Many recordings hold their own contact labels: a boolean from the robot's own detector, a key
pressed by the person holding the tool. An onset is the header stamp (else the log time) of
each message whose ``--field`` turns on: from off (false, 0, '0' or empty) to anything else.
The rows are ``bag,onset_start,onset_end`` (``onset_end`` = ``onset_start``: the signal gives
one instant), the CSV ``contact-detector train --labels`` and ``evaluate --labels`` read.
A bag whose signal never turns on gets no row, and is named on stderr.

Examples (docs/your-robot.md)::

    tools/labels_from_topic.py learn_placing/ --topic contact --field in_contact
    tools/labels_from_topic.py cucumber_test1_0.bag --topic /key_continuous --field data.data
"""

import argparse
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.errors import ContactDetectorError
from contact_detector.io.bags import find_bags, iter_messages

OFF = (False, 0, '0', '', 'false', 'False')


def onsets(bag: Path, *, topic: str, field: str) -> list:
    """Return the times (s) at which ``field`` of ``topic`` turns on (module docstring)."""
    out, was_on = [], False
    for message in iter_messages(bag, topics=[topic]):
        value = message.msg
        for part in field.split('.'):
            value = getattr(value, part)
        on = value not in OFF
        if on and not was_on:
            stamp = getattr(getattr(message.msg, 'header', None), 'stamp', None)
            out.append(stamp.sec + stamp.nanosec * 1e-9 if stamp is not None
                       else message.log_time_ns * 1e-9)
        was_on = on
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the script; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', help='bags or folders of bags')
    parser.add_argument('--topic', required=True, help='topic holding the contact signal')
    parser.add_argument('--field', required=True,
                        help='message field, dotted (e.g. in_contact, data.data)')
    parser.add_argument('--out', type=Path, required=True, help='CSV to write')
    args = parser.parse_args(argv)
    rows = ['bag,onset_start,onset_end']
    try:
        for bag in find_bags(args.bags):
            times = onsets(bag, topic=args.topic, field=args.field)
            if not times:
                print(f'{bag.name}: {args.field} of {args.topic} never turns on; no row',
                      file=sys.stderr)
            rows += [f'{bag.name},{t:.6f},{t:.6f}' for t in times]
    except (ContactDetectorError, AttributeError) as err:
        print(f'labels_from_topic: {err}', file=sys.stderr)
        return 1
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text('\n'.join(rows) + '\n')
    print(f'{len(rows) - 1} onsets -> {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
