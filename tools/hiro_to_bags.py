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
Turn the real HIRO snap-assembly recordings into labelled rosbag2 bags.

    tools/hiro_to_bags.py SRC OUT [--quiet-audio] [--storage sqlite3|mcap] [--torque-scale S]

``SRC`` is a clone of https://github.com/HongminWu/HIRO_SA_DATA (docs/your-robot.md says how
to fetch it). A real HIRO arm holds a plastic part with snap clips, lowers it slowly onto its
mate fixed on the table until they touch, then turns, snaps and mates it. Each trial folder of
``REAL_HIRO_ONE_SA_SUCCESS`` and ``REAL_HIRO_ONE_SA_ERROR_CHARAC`` holds ``R_Torques.dat``
(whitespace text, one row per sample: ``t`` in s, then Fx Fy Fz in N and Mx My Mz in N m, the
wrist sensor's wrench with its bias removed, at 200 Hz) and ``R_State.dat`` (the start times of
the task's phases, s: approach, rotation, insertion, mating).

Writes ``OUT/success/<trial>`` and ``OUT/error/<trial>`` (rosbag2 directories: every row as a
``geometry_msgs/msg/WrenchStamped`` on ``/wrist_wrench``, stamped and logged at ``EPOCH_S +
t``) and ``OUT/labels.csv`` with one onset per trial, in the format ``--labels`` reads.

**The onset.** The second phase time ``S`` is the controller's own contact detection, which
ends the guarded approach; it comes after the force has risen by 1-3 N. The onset is where
that rise began: with ``F_rest`` the mean force vector over ``[S - 1.5, S - 0.6]`` s and
``d_k = |F_k - F_rest|``, the band is ``max(0.3 N, 4 std(d))`` over that interval, and the
onset is the first sample of the run of samples above the band that ends at ``S`` (``S``
itself if ``d`` is inside the band there). A trial without a contact phase is not converted
(its folder is named on stderr).

``--quiet-audio`` adds a microphone that hears nothing of the contact: 16 kHz
``std_msgs/msg/Int16MultiArray`` chunks of 1024 samples of white noise with a standard
deviation of 3 LSB (about -80 dBFS), so the multimodal model decides.

``--torque-scale S`` multiplies every torque by ``S`` (default 1): the forces as recorded, with
the torques of a contact ``S`` times farther off the sensor's axis. The part is pressed close to
that axis, so its torque barely moves; this asks whether that is what a model misses
(docs/decisions/2026-12-07-ft-only-label-start.md).
"""

import argparse
from pathlib import Path
import sys
from typing import List, Optional, Sequence, Tuple

from contact_detector.io.bags import (AUDIO_TOPIC, AUDIO_TYPE, jazzy_typestore, WRENCH_TOPIC,
                                      WRENCH_TYPE)
from contact_detector.sim.bag_writer import int16_multiarray_cdr, wrench_cdr
import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

#: The folders of real trials, and the sub-folder of OUT each goes to.
GROUPS = {'REAL_HIRO_ONE_SA_SUCCESS': 'success', 'REAL_HIRO_ONE_SA_ERROR_CHARAC': 'error'}
#: Stamps are ``EPOCH_S + t``: the files' clocks start at 0.
EPOCH_S = 1_700_000_000
#: The rest before the controller's contact detection, s before it.
REST_S = (1.5, 0.6)
#: The smallest band around the rest, N, and its width in standard deviations.
BAND_N, BAND_SD = 0.3, 4.0
AUDIO_RATE, AUDIO_CHUNK, AUDIO_LSB = 16000, 1024, 3.0
STORAGES = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}


def contact_onset(*, t: np.ndarray, force: np.ndarray, detected_s: float) -> float:
    """
    Return where the force began the rise the controller detected at ``detected_s``, s.

    Parameters
    ----------
    t : np.ndarray, shape (n,)
        Sample times, s, increasing.
    force : np.ndarray, shape (n, 3)
        Force vectors, N.
    detected_s : float
        The controller's contact detection, s.

    Returns
    -------
    float
        The time of the first sample of the run above ``max(0.3 N, 4 std(d))`` that ends at
        ``detected_s``, ``d = |F - F_rest|``, ``F_rest`` the mean over ``[detected_s - 1.5,
        detected_s - 0.6]``; ``detected_s``'s sample if ``d`` is inside the band there.

    Raises
    ------
    ValueError
        Fewer than two samples in the rest interval.

    """
    rest = (t >= detected_s - REST_S[0]) & (t <= detected_s - REST_S[1])
    if rest.sum() < 2:
        raise ValueError(f'fewer than 2 samples {REST_S[0]}-{REST_S[1]} s before the contact '
                         f'detection at {detected_s:.3f} s')
    d = np.linalg.norm(force - force[rest].mean(axis=0), axis=1)
    band = max(BAND_N, BAND_SD * float(d[rest].std()))
    k = int(np.searchsorted(t, detected_s, side='right')) - 1
    while k > 0 and d[k - 1] > band and d[k] > band:
        k -= 1
    return float(t[k])


def write_bag(*, path: Path, t: np.ndarray, wrench: np.ndarray, storage: str,
              audio: Optional[np.random.Generator]) -> None:
    """
    Write one trial's wrench (``wrench``: shape (n, 6), N and N m) as a rosbag2 directory.

    With ``audio`` (the noise's generator), a quiet microphone track covers the recording.
    """
    stamps = EPOCH_S * 10**9 + np.round(t * 1e9).astype(np.int64)
    raw = wrench_cdr(stamp_ns=stamps, force=wrench[:, :3], torque=wrench[:, 3:])
    messages: List[Tuple[int, int, int]] = [(int(s), 0, i) for i, s in enumerate(stamps)]
    noise = np.zeros(0, np.int16)
    if audio is not None:
        chunks = int((t[-1] - t[0]) * AUDIO_RATE) // AUDIO_CHUNK
        noise = np.round(audio.normal(0.0, AUDIO_LSB, chunks * AUDIO_CHUNK)).astype(np.int16)
        # each chunk logged when its last sample has been heard
        messages += [(int(stamps[0] + round((k + 1) * AUDIO_CHUNK / AUDIO_RATE * 1e9)), 1, k)
                     for k in range(chunks)]
    typestore = jazzy_typestore()
    with Writer(path, version=9, storage_plugin=STORAGES[storage]) as writer:
        wrench_conn = writer.add_connection(WRENCH_TOPIC, WRENCH_TYPE, typestore=typestore)
        audio_conn = (writer.add_connection(AUDIO_TOPIC, AUDIO_TYPE, typestore=typestore)
                      if audio is not None else None)
        for stamp, kind, i in sorted(messages):
            if kind == 0:
                writer.write(wrench_conn, stamp, raw[i].tobytes())
            else:
                chunk = noise[i * AUDIO_CHUNK:(i + 1) * AUDIO_CHUNK]
                writer.write(audio_conn, stamp, int16_multiarray_cdr(chunk))


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the script; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('src', type=Path, help='a clone of HongminWu/HIRO_SA_DATA')
    parser.add_argument('out', type=Path, help='directory for the bags and labels.csv')
    parser.add_argument('--quiet-audio', action='store_true',
                        help='add a microphone track that hears nothing of the contact')
    parser.add_argument('--storage', choices=sorted(STORAGES), default='sqlite3')
    parser.add_argument('--torque-scale', type=float, default=1.0, metavar='S',
                        help='multiply every torque by S > 0 (default 1: as recorded)')
    args = parser.parse_args(argv)
    if not (np.isfinite(args.torque_scale) and args.torque_scale > 0):
        parser.error(f'--torque-scale must be a finite number > 0, got {args.torque_scale}')
    trials = [(d, family) for group, family in GROUPS.items() if (args.src / group).is_dir()
              for d in sorted((args.src / group).iterdir()) if (d / 'R_Torques.dat').is_file()]
    if not trials:
        print(f'hiro_to_bags: no trial folder with R_Torques.dat under {args.src}/'
              f'{{{",".join(GROUPS)}}}', file=sys.stderr)
        return 1
    rng = np.random.default_rng(0) if args.quiet_audio else None
    rows, skipped, unreadable = ['bag,onset_start,onset_end'], [], []
    for folder, family in trials:
        states = (folder / 'R_State.dat').read_text().split() if (
            folder / 'R_State.dat').is_file() else []
        try:
            table = np.loadtxt(folder / 'R_Torques.dat', ndmin=2)
            detected_s = float(states[1]) if len(states) >= 2 else None
        except ValueError as err:
            print(f'hiro_to_bags: {folder.name}: not a table of numbers: {err}',
                  file=sys.stderr)
            unreadable.append(folder.name)
            continue
        if detected_s is None:
            skipped.append(folder.name)
            continue
        if table.shape[1] < 7 or len(table) < 2:
            print(f'hiro_to_bags: {folder.name}: R_Torques.dat needs rows of t and 6 wrench '
                  f'values, got {table.shape[1]} columns and {len(table)} rows', file=sys.stderr)
            unreadable.append(folder.name)
            continue
        t, wrench = table[:, 0], table[:, 1:7] * ([1.0] * 3 + [args.torque_scale] * 3)
        try:
            onset = contact_onset(t=t, force=wrench[:, :3], detected_s=detected_s)
        except ValueError as err:
            print(f'hiro_to_bags: {folder.name}: {err}', file=sys.stderr)
            unreadable.append(folder.name)
            continue
        bag = args.out / family / folder.name
        if bag.exists():
            print(f'hiro_to_bags: {bag} exists; give an empty OUT', file=sys.stderr)
            return 1
        bag.parent.mkdir(parents=True, exist_ok=True)
        write_bag(path=bag, t=t, wrench=wrench, storage=args.storage, audio=rng)
        stamp = EPOCH_S + onset
        rows.append(f'{family}/{folder.name},{stamp:.6f},{stamp:.6f}')
    (args.out / 'labels.csv').write_text('\n'.join(rows) + '\n')
    if skipped:
        print(f'hiro_to_bags: no contact phase, not converted: {", ".join(skipped)}',
              file=sys.stderr)
    print(f'{len(rows) - 1} bags and labels.csv -> {args.out}'
          + (f'; {len(unreadable)} trial folders not converted (above)' if unreadable else ''))
    return 0


if __name__ == '__main__':
    sys.exit(main())
