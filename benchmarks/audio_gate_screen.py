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
Screen a release that waits for confirmation only when no impact sound came.

    .venv/bin/python benchmarks/audio_gate_screen.py lofo DIR... [--seeds 0]
        [the protocol options of lofo_early.py] [--cache F --augment-cache F]
    .venv/bin/python benchmarks/audio_gate_screen.py bags DIR... --labels L.csv
        [--model M]

The gate acts on the frames the shipped rule calls *contact*. A contact frame releases when
``audio_rise_db`` reached ``X`` dB in one of the last ``K`` frames (an impact sound), or when
the frame ends a run of more than ``M`` contact frames. Otherwise it waits. With ``M = 0``
every contact frame releases, which is the shipped rule. The point is to tell a push on the
object, which makes no sound, from a table, which does; the cost falls on quiet contacts.

- ``lofo``: the leave-one-family-out forests of ``lofo_early.py`` (10 trees, the shipped
  protocol's options) on the simulator's folders, every family left out in turn.
- ``bags``: the shipped model (or ``--model``) on labelled bags, such as an independent
  generator's output, read as ``contact-detector evaluate`` reads them.

Per gate, it prints trials caught within 500 ms, early releases and the median latency, the
worst family by ``(caught - early) / trials``, and each family's caught / early / median.
Then how loud the contacts are: the largest ``audio_rise_db`` from 50 ms before the onset to
300 ms after it, its median and how often it stays below 6 dB.
"""

import argparse
from pathlib import Path
import sys
from typing import Dict, List, Optional, Sequence

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.factory import stream_spec
from contact_detector.detection.offline import run_detector, run_features
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import discover_streams
from contact_detector.io.sensor_stream import load_events
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.training.protocol import match_labels, read_labels_csv
from contact_detector.training.sweep import fit_forest
from lofo_frames import (add_protocol_arguments, add_rule_argument, left_out_decisions,
                         protocol_frames, rule_from)
import numpy as np

FEATURE = 'audio_rise_db'
#: (X dB, K frames, M frames); M = 0 is the shipped rule
GATES = [(0.0, 20, 0)] + [(x, 20, m) for x in (3.0, 6.0, 10.0) for m in (5, 10, 20)]


def gated_release(*, t: np.ndarray, contact: np.ndarray, rise: np.ndarray, x_db: float,
                  k: int, m: int) -> Optional[float]:
    """
    Return the time of the first frame the gate releases at, or None.

    Parameters
    ----------
    t, contact, rise : np.ndarray, shape (n,)
        Frame times (s), the shipped rule's contact decision and ``audio_rise_db`` (dB).
    x_db, k, m : float, int, int
        Release at a contact frame if ``max(rise[i-k+1 .. i]) >= x_db``, or if it ends a run
        of more than ``m`` contact frames; ``m = 0`` releases at every contact frame.

    """
    if m == 0:
        hits = np.flatnonzero(contact)
    else:
        padded = np.concatenate([np.full(k - 1, -np.inf), rise])
        sound = np.lib.stride_tricks.sliding_window_view(padded, k).max(axis=1) >= x_db
        run = np.zeros(contact.size, dtype=int)
        count = 0
        for i, c in enumerate(contact.tolist()):
            count = count + 1 if c else 0
            run[i] = count
        hits = np.flatnonzero(contact & (sound | (run > m)))
    return float(t[hits[0]]) if hits.size else None


def table(trials: List[dict]) -> None:
    """Print one line per gate (see the module docstring)."""
    for x_db, k, m in GATES:
        fams: Dict[str, list] = {}
        for tr in trials:
            rel = gated_release(t=tr['t'], contact=tr['contact'], rise=tr['rise'], x_db=x_db,
                                k=k, m=m)
            f = fams.setdefault(tr['family'], [0, 0, 0, []])
            f[2] += 1
            if rel is not None and rel < tr['onset']:
                f[1] += 1
            elif rel is not None and rel <= tr['onset'] + 0.5:
                f[0] += 1
                f[3].append(1000.0 * (rel - tr['onset']))
        caught, early, n = (sum(v[i] for v in fams.values()) for i in range(3))
        lat = [v for f in fams.values() for v in f[3]]
        worst = min(fams, key=lambda name: (fams[name][0] - fams[name][1]) / fams[name][2])
        name = 'shipped rule' if m == 0 else f'rise >= {x_db:g} dB in {k}, else > {m} frames'
        print(f'{name:34s} {caught}/{n} caught, {early} early, median '
              f'{np.median(lat) if lat else float("nan"):.0f} ms; worst {worst} '
              f'{fams[worst][0]}/{fams[worst][2]}, {fams[worst][1]} early | '
              + ', '.join(f'{fam} {v[0]}/{v[1]}/{np.median(v[3]) if v[3] else 0:.0f}'
                          for fam, v in sorted(fams.items())), flush=True)


def loudness(trials: List[dict]) -> None:
    """Print how loud the contacts are: the largest rise from 50 ms before to 300 ms after."""
    peaks: Dict[str, list] = {}
    for tr in trials:
        near = (tr['t'] > tr['onset'] - 0.05) & (tr['t'] < tr['onset'] + 0.3)
        peaks.setdefault(tr['family'], []).append(
            float(tr['rise'][near].max()) if near.any() else float('nan'))
    every = np.array([v for values in peaks.values() for v in values])
    print(f'largest {FEATURE} from -50 to +300 ms around the onset: median '
          f'{np.nanmedian(every):.1f} dB, below 6 dB in {np.mean(every < 6):.0%} of trials | '
          + ', '.join(f'{fam} {np.nanmedian(v):.1f} dB, {np.mean(np.array(v) < 6):.0%}'
                      for fam, v in sorted(peaks.items())))


def lofo_trials(args: argparse.Namespace) -> List[dict]:
    """Return, every family left out in turn, the shipped rule's contact frames and the rise."""
    setting, frames, fit_frames, _ = protocol_frames(args)
    names = setting.config.feature_names
    rise = names.index(FEATURE)
    out = []
    for family in sorted({f.truth.condition for f in frames.values()}):
        fit = [f for f in fit_frames.values() if f.truth.condition != family]
        for seed in (int(s) for s in args.seeds.split(',')):
            forest = fit_forest(frames=fit, setting=setting, n_estimators=10, seed=seed,
                                jobs=args.jobs)
            for f in (f for f in frames.values() if f.truth.condition == family):
                _, contact, _ = left_out_decisions(forest=forest, frames=f, setting=setting,
                                                   rule=rule_from(args))
                out.append({'family': family, 't': f.t, 'contact': contact,
                            'rise': f.x[:, rise], 'onset': f.truth.onset_t})
        print(f'left out: {family}', file=sys.stderr, flush=True)
    return out


def bag_trials(args: argparse.Namespace) -> List[dict]:
    """Return the model's contact frames and the rise feature on each labelled bag."""
    bundle = load_bundle(path=args.model or default_model_path())
    bags = find_bags(args.folders)
    onsets = match_labels(rows=read_labels_csv(args.labels), bags=bags, csv_path=args.labels)
    out = []
    for bag in bags:
        streams = discover_streams(bag)
        events = load_events(bag, spec=stream_spec(streams, {}))
        run = run_detector(events, detector=ContactDetector(bundle=bundle, settings=(
            DetectorSettings(audio_rate=streams.audio_rate, wrench_rate=streams.wrench_rate))))
        frames = run_features(events, extractor=StreamingFeatureExtractor(
            config=bundle.feature_config, audio_rate=streams.audio_rate,
            ft_input_rate=streams.wrench_rate))
        at = np.clip(np.searchsorted(frames.t, run.t), 0, max(len(frames.t) - 1, 0))
        out.append({'family': bag.parent.name, 't': run.t, 'contact': run.contact,
                    'rise': frames.x[at, frames.names.index(FEATURE)],
                    'onset': float(onsets[bag][0])})
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the screen; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='mode', required=True)
    lofo = sub.add_parser('lofo')
    lofo.add_argument('folders', nargs='+', type=Path)
    lofo.add_argument('--seeds', default='0')
    lofo.add_argument('--cache', type=Path, default=None)
    lofo.add_argument('--jobs', type=int, default=1)
    add_rule_argument(lofo)
    add_protocol_arguments(lofo)
    bags = sub.add_parser('bags')
    bags.add_argument('folders', nargs='+', type=Path)
    bags.add_argument('--labels', type=Path, required=True)
    bags.add_argument('--model', type=Path, default=None)
    args = parser.parse_args(argv)
    trials = lofo_trials(args) if args.mode == 'lofo' else bag_trials(args)
    table(trials)
    loudness(trials)
    return 0


if __name__ == '__main__':
    sys.exit(main())
