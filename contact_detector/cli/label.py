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
``contact-detector label BAG_OR_DIR... --out labels.csv [--plots DIR]``: propose contact onsets.

For each recording, :func:`contact_detector.evaluation.labelling.propose_onset` proposes the
contact onset with hindsight (the largest lasting change of the F/T vector, refined back to
where it leaves its baseline and to the contact sound's onset). The CSV has one row per bag,
``bag,onset_start,onset_end,confidence,reason``: the format ``train --labels`` reads. A bag
that cannot be labelled gets empty onsets, confidence 0 and the reason; readers skip it with a
warning. ``--plots DIR`` writes a review figure per bag (|F|, |T|, the vector shift, the audio
power and the proposed onset). Like the other commands it prints what discovery found: topics,
audio format and F/T rate, with their sources and warnings.

The F/T samples are read as ``detect`` reads them (:func:`contact_detector.io.bags.read_wrench`):
messages with an invalid stamp, NaN/Inf values, or a stamp that repeats or goes back are left
out and counted, and the counts are printed. A bag whose F/T rate ``detect`` refuses (outside
[50, 10000] Hz) or whose ``--wrench-topic`` is not a WrenchStamped is unreadable: its row has
no onset and says why.
"""

import argparse
import csv
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.errors import BagError, ConfigError, ContactDetectorError
from contact_detector.evaluation.labelling import Proposal, propose_onset
from contact_detector.features.resample import check_input_rate
from contact_detector.io.bags import (find_bags, manifest_entry, read_wrench,
                                      recording_names, topic_types)
from contact_detector.io.discovery import (discover_streams, find_wrench_topic,
                                           measure_wrench_rate, PROBE_MESSAGES, Streams,
                                           summary_lines)
from contact_detector.io.sensor_stream import read_audio_series, StreamSpec
import numpy as np
from tqdm import tqdm

PROG = 'contact-detector label'
#: Columns of the CSV (the first three are what every labels reader needs).
HEADER = ('bag', 'onset_start', 'onset_end', 'confidence', 'reason')


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser."""
    parser = argparse.ArgumentParser(
        prog=PROG, description='Propose the contact onset of each recording (hindsight) and '
                               'write a labels CSV for train/evaluate --labels.')
    parser.add_argument('bags', nargs='+', metavar='BAG_OR_DIR',
                        help='rosbag2 directories, ROS 1 .bag files or directories of them')
    parser.add_argument('--out', required=True, type=Path, metavar='CSV')
    parser.add_argument('--plots', type=Path, default=None, metavar='DIR',
                        help='write a review figure per bag here')
    parser.add_argument('--label-length', type=float, default=0.1, metavar='S',
                        help='onset_end = onset_start + this (default 0.1 s)')
    parser.add_argument('--no-audio', action='store_true', help='use the F/T only')
    parser.add_argument('--wrench-topic', default=None)
    parser.add_argument('--audio-topic', default=None)
    parser.add_argument('--audio-rate', type=float, default=None, metavar='HZ')
    return parser


def label_bag(bag: Path, *,
              args: argparse.Namespace) -> tuple[Proposal, dict, Optional[Streams]]:
    """
    Read one bag and propose its onset.

    Returns the proposal, the arrays for a figure (and ``wrench``, the
    :class:`~contact_detector.io.bags.WrenchSeries` with its drop counts) and what discovery
    found (None when it failed and the bag is labelled from the F/T alone).

    Raises
    ------
    BagError
        The wrench topic is missing, ambiguous or of another type, has no usable message, or
        its F/T rate is one ``detect`` refuses.
    ConfigError
        A flag's value is refused (``--audio-rate``).

    """
    entry = manifest_entry(bag) or {}
    audio = rate = audio_t0 = streams = None
    # a wrong wrench topic is no reason to fall back to the F/T alone: it is the F/T
    wrench_topic = find_wrench_topic(bag, types=topic_types(bag), given=args.wrench_topic)
    # first: a bag without usable F/T is unreadable whatever its audio
    wrench = read_wrench(bag, topic=wrench_topic)
    try:
        streams = discover_streams(bag, wrench_topic=args.wrench_topic,
                                   audio_topic=args.audio_topic, audio_rate=args.audio_rate,
                                   param_audio_rate=entry.get('audio_rate'),
                                   allow_no_audio=True)
        if not streams.has_audio and not args.no_audio:
            # its other warnings are printed with the summary
            note = f'; {streams.audio_note}' if streams.audio_note else ''
            print(f'{PROG}: warning: {bag.name}: F/T only (no audio topic{note})',
                  file=sys.stderr)
        if streams.has_audio and not args.no_audio:
            series = read_audio_series(bag, spec=StreamSpec(
                wrench_topic=streams.wrench_topic, audio_topic=streams.audio_topic,
                audio_msg_type=streams.audio_msg_type, channels=streams.channels,
                coding=streams.coding, audio_rate=streams.audio_rate))
            rate = float(streams.audio_rate)
            audio, audio_t0 = series.samples, series.t0(rate)
    except ConfigError:
        raise       # a flag's value: the same for every bag, not an audio problem of this one
    except ContactDetectorError as err:
        print(f'{PROG}: warning: {bag.name}: F/T only ({err})', file=sys.stderr)
    if streams is not None:
        w_rate, source = streams.wrench_rate, 'measured from the header stamps'
    else:
        # discovery failed before measuring it: measure as it does, on the samples kept
        try:
            w_rate = measure_wrench_rate(stamps=wrench.t[:PROBE_MESSAGES], path=bag,
                                         topic=wrench_topic)
        except BagError as err:     # its advice (--wrench-rate) is no flag of label
            raise BagError(f'cannot measure the F/T rate of {wrench_topic}: fewer than two '
                           f'usable samples ({wrench.describe_drops() or "one message"})'
                           ) from err
        source = 'measured from the header stamps kept'
    try:
        check_input_rate(rate=w_rate)       # what detect's resampler refuses
    except ConfigError as err:
        raise BagError(f'{err} ({wrench_topic}, {source})') from err
    t, force, torque = wrench.t, wrench.force, wrench.torque
    proposal = propose_onset(ft_t=t, force=force, torque=torque, audio=audio,
                             audio_rate=rate, audio_t0=audio_t0)
    return proposal, {'t': t, 'force': force, 'torque': torque, 'audio': audio, 'rate': rate,
                      'audio_t0': audio_t0, 'truth': entry.get('onset_t'),
                      'wrench': wrench}, streams


def plot_proposal(*, bag: Path, proposal: Proposal, data: dict, output: Path) -> Path:
    """Review figure: |F|, |T|, the vector shift, the audio power and the proposed onset."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    t = data['t']
    t_ref = float(t[0])
    panels = 4 if data['audio'] is not None else 3
    fig, axes = plt.subplots(panels, 2, figsize=(12, 2.2 * panels), sharex='col')
    centre = proposal.onset_t if proposal.onset_t is not None else None
    for col in range(2):
        ax_f, ax_t, ax_s = axes[0, col], axes[1, col], axes[2, col]
        ax_f.plot(t - t_ref, np.linalg.norm(data['force'], axis=1), 'k', lw=0.8)
        ax_f.set_ylabel('|F| (N)')
        ax_t.plot(t - t_ref, np.linalg.norm(data['torque'], axis=1), 'k', lw=0.8)
        ax_t.set_ylabel('|T| (N m)')
        ax_s.plot(proposal.shift_t - t_ref, proposal.shift, 'tab:blue', lw=0.8)
        ax_s.set_ylabel('vector shift\n(noise units)')
        if panels == 4:
            ax_a = axes[3, col]
            x = np.asarray(data['audio'], dtype=float)
            rate = data['rate']
            fl = max(1, int(round(0.002 * rate)))
            n = len(x) // fl
            power = np.mean(x[:n * fl].reshape(n, fl) ** 2, axis=1)
            ta = data['audio_t0'] - t_ref + (np.arange(n) + 1) * fl / rate
            ax_a.semilogy(ta, np.maximum(power, 1e-12), 'tab:red', lw=0.6)
            ax_a.set_ylabel('audio power\n(2 ms)')
        for ax in axes[:, col]:
            if proposal.onset_t is not None:
                ax.axvline(proposal.onset_t - t_ref, color='g', lw=1.2)
            if proposal.ft_onset_t is not None:
                ax.axvline(proposal.ft_onset_t - t_ref, color='g', ls=':', lw=1.0)
            if data.get('truth') is not None:
                ax.axvline(data['truth'] - t_ref, color='k', ls='--', alpha=0.6)
        if col == 1 and centre is not None:
            axes[0, 1].set_xlim(centre - t_ref - 0.15, centre - t_ref + 0.15)
    axes[0, 0].set_title('whole recording', fontsize=9)
    axes[0, 1].set_title('around the proposed onset (green; dotted: F/T, dashed: truth)',
                         fontsize=9)
    axes[-1, 0].set_xlabel(f'time (s) from {t_ref:.3f}')
    what = (f'onset {proposal.onset_t:.4f} s ({proposal.source}), confidence '
            f'{proposal.confidence:.2f}' if proposal.onset_t is not None
            else f'no onset: {proposal.reason}')
    fig.suptitle(f'{bag.name}: {what}', fontsize=10)
    fig.tight_layout()
    output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(output, dpi=100)
    plt.close(fig)
    return output


def row_for(name: str, proposal: Proposal, *, length: float) -> list:
    """One CSV row (see :data:`HEADER`) of the bag called ``name``."""
    if proposal.onset_t is None:
        return [name, '', '', '0.0', proposal.reason]
    return [name, f'{proposal.onset_t:.6f}', f'{proposal.onset_t + length:.6f}',
            f'{proposal.confidence:.3f}', '']


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; return the exit status (0 ok, 1 error, 2 usage)."""
    args = build_parser().parse_args(argv)
    try:
        bags = find_bags(args.bags)
    except ContactDetectorError as err:
        print(f'{PROG}: error: {err}', file=sys.stderr)
        return 1
    rows = []
    found = []
    # the file name, or as much of the path as tells apart bags that share it
    names = recording_names(bags)
    for bag in tqdm(bags, desc='label', unit='bag', disable=len(bags) < 2):
        try:
            proposal, data, streams = label_bag(bag, args=args)
            if streams is not None:
                found.append((bag, streams))
        except ConfigError as err:
            print(f'{PROG}: error: {err}', file=sys.stderr)
            return 1
        except ContactDetectorError as err:
            print(f'{PROG}: {names[bag]}: {err}', file=sys.stderr)
            rows.append([names[bag], '', '', '0.0', f'unreadable: {err}'.replace(',', ';')])
            continue
        rows.append(row_for(names[bag], proposal, length=args.label_length))
        drops = data['wrench'].describe_drops()
        if drops:
            print(f'{PROG}: warning: {names[bag]}: {drops}', file=sys.stderr)
        print(f'{PROG}: {names[bag]}: ' + (
            f'onset {proposal.onset_t:.4f} ({proposal.source}) confidence '
            f'{proposal.confidence:.2f}' if proposal.onset_t is not None
            else f'no onset ({proposal.reason})'))
        if args.plots is not None:
            plot_proposal(bag=bag, proposal=proposal, data=data,
                          output=args.plots / f'{names[bag]}.png')
    # what discovery found, as the other commands print it (after the bars: once per run)
    for line in summary_lines(found):
        print(f'{PROG}: {line}')
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, 'w', newline='') as handle:
        writer = csv.writer(handle)
        writer.writerow(HEADER)
        writer.writerows(rows)
    print(f'wrote {args.out} ({sum(1 for r in rows if r[1])}/{len(rows)} labelled)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
