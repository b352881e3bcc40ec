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
Digest of a simulated data set: one SHA-256 per bag (every message) and one of the manifest.

    .venv/bin/contact-detector simulate /tmp/a --trials 24 --seed 3 --conditions wide
    .venv/bin/python tools/sim_digest.py /tmp/a > a.txt
    ... change the simulator, simulate into /tmp/b the same way ...
    .venv/bin/python tools/sim_digest.py /tmp/b --compare a.txt

A bag's digest covers, in log-time order, each message's topic, type, log time (ns) and raw
serialised bytes; the manifest's covers ``manifest.json`` byte for byte (every parameter,
derived fact, phase and impact) but for its ``simulator`` fingerprint of the code, which
changes with any edit: the digest is of the manifest written again without it, the bytes of a
manifest from before the fingerprint. Two data sets with equal digests hold the same trials bit
for bit. Exit status 1 when ``--compare`` finds a difference.
"""

import argparse
import hashlib
import json
from pathlib import Path
import sys
from typing import Sequence

from rosbags.rosbag2 import Reader


def bag_digest(path: Path) -> str:
    """Return the SHA-256 of every message of a rosbag2 directory, in log-time order."""
    sha = hashlib.sha256()
    with Reader(path) as reader:
        for conn, log_ns, raw in reader.messages():
            sha.update(f'{conn.topic}\0{conn.msgtype}\0{int(log_ns)}\0'.encode())
            sha.update(bytes(raw))
    return sha.hexdigest()


def digests(folder: Path) -> dict[str, str]:
    """Return ``{name: sha256}`` of ``manifest.json`` and of every bag directory in ``folder``."""
    manifest = json.loads((folder / 'manifest.json').read_text(encoding='utf-8'))
    manifest.pop('simulator', None)     # the code's fingerprint, not the trials
    # as contact_detector.sim.bag_writer.write_manifest writes it
    text = json.dumps(manifest, indent=1, allow_nan=False) + '\n'
    out = {'manifest.json': hashlib.sha256(text.encode('utf-8')).hexdigest()}
    for bag in sorted(p for p in folder.iterdir() if (p / 'metadata.yaml').is_file()):
        out[bag.name] = bag_digest(bag)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Print the digests of a simulated folder, or compare them with a saved listing."""
    parser = argparse.ArgumentParser(prog='sim_digest.py', description=__doc__.split('\n')[1])
    parser.add_argument('folder', type=Path, help='output folder of contact-detector simulate')
    parser.add_argument('--compare', type=Path, default=None, metavar='FILE',
                        help='a listing printed before; report every difference')
    args = parser.parse_args(argv)
    now = digests(args.folder)
    if args.compare is None:
        for name, digest in now.items():
            print(f'{digest}  {name}')
        return 0
    before = {}
    for line in args.compare.read_text(encoding='utf-8').splitlines():
        digest, name = line.split(maxsplit=1)
        before[name] = digest
    differ = sorted(n for n in set(now) | set(before) if now.get(n) != before.get(n))
    for name in differ:
        print(f'differs: {name}')
    print(f'{len(now) - len(differ)} of {len(now)} digests equal, {len(differ)} differ')
    return 1 if differ else 0


if __name__ == '__main__':
    sys.exit(main())
