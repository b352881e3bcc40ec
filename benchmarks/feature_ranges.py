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
Where your recordings' features sit against the simulated trials a model is trained on.

    .venv/bin/python benchmarks/feature_ranges.py RECORDINGS... --reference data/train \
        [--labels LABELS.csv] [--model M] [--reference-trials 96] [--augmented]

When a model misses the contacts of your robot, this says which features look unlike the
training trials. Every bag of the reference folders (simulated, with their own truth) and of
the recordings (with their ``--labels`` rows, as ``train`` and ``evaluate`` read them, or
their own truth) goes through the model's feature core, as recorded. Two windows of frames are
compared, relative to each bag's onset: *before* (the approach: from 1.5 s to 0.3 s before
it) and *contact* (from 50 ms to 300 ms after it). For every feature the table gives the
reference's 5th, 50th and 95th percentiles in both windows, the recordings' medians, and the
share of the recordings' contact frames outside the reference contact frames' 5-95 % range
(below / above). A feature whose contact frames mostly lie below the reference's 5th
percentile is one the forest has not seen take such values at a contact. The reference is the
simulated trials as recorded; ``--augmented`` varies their wrenches as the model's training
did (the augmentation and seed its card records), which widens the ranges the forest saw.
"""

import argparse
from pathlib import Path
import sys
from typing import Dict, List, Optional, Sequence, Tuple

from contact_detector.detection.factory import stream_spec
from contact_detector.features.config import FeatureConfig
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import discover_streams
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.training.augmentation import trial_seed, WrenchAugmentation
from contact_detector.training.protocol import labels_for, LabelWindow, trial_features
from contact_detector.training.recipe import NO_AUDIO_RATE
import numpy as np

#: The two windows, s relative to the onset: (start, end).
WINDOWS = {'before': (-1.5, -0.3), 'contact': (0.05, 0.3)}


def window_frames(*, bags: Sequence[Path], config: FeatureConfig,
                  onsets: Dict[Path, List[float]],
                  augmentation: Optional[WrenchAugmentation] = None,
                  seed: int = 0, windows: Optional[Dict[str, Tuple[float, float]]] = None
                  ) -> Tuple[Dict[str, np.ndarray], List[str]]:
    """
    Return the feature frames of the bags in each window of ``windows`` (:data:`WINDOWS`).

    Parameters
    ----------
    bags : sequence of Path
        Bags, each with its onsets in ``onsets`` or a truth of its own.
    config : FeatureConfig
        The model's feature contract.
    onsets : dict
        Bag -> onsets, s (a labels CSV); a bag not in it uses its own truth.
    augmentation : WrenchAugmentation or None
        Vary each bag's wrench as training does (drawn with ``trial_seed(seed, bag name)``);
        None = as recorded.
    seed : int
        The training seed the draws follow.
    windows : dict or None
        Window name -> (start, end), s relative to the onset, frames with ``start <= t - onset
        < end``; None: :data:`WINDOWS`.

    Returns
    -------
    dict
        Window name -> frames, shape (n_frames, n_features); only the first onset of a bag is
        used, and a window is cut at the bag's next onset.
    list of str
        The feature names, in column order.

    """
    windows = WINDOWS if windows is None else windows
    out: Dict[str, List[np.ndarray]] = {name: [] for name in windows}
    names: List[str] = []
    for bag in bags:
        streams = discover_streams(bag, allow_no_audio=not config.audio)
        data = trial_features(bag=bag, config=config, spec=stream_spec(streams, {}),
                              audio_rate=streams.audio_rate or NO_AUDIO_RATE,
                              wrench_rate=streams.wrench_rate, label_window=LabelWindow(),
                              onsets=onsets.get(bag), augmentation=augmentation,
                              augment_seed=trial_seed(seed=seed, name=bag.name))
        names = list(config.feature_names)
        first = min(data.onsets)
        dt = data.t - first
        for name, (start, end) in windows.items():
            out[name].append(data.x[(dt >= start) & (dt < end)])
    width = len(names)
    return ({name: (np.concatenate(frames) if frames else np.empty((0, width)))
             for name, frames in out.items()}, names)


def range_table(*, reference: Dict[str, np.ndarray], recordings: Dict[str, np.ndarray],
                names: Sequence[str]) -> str:
    """
    Tabulate each feature of the recordings against the reference's range.

    Parameters
    ----------
    reference, recordings : dict
        Window name -> frames, shape (n_frames, n_features) (:func:`window_frames`).
    names : sequence of str
        Feature names, in column order.

    Returns
    -------
    str
        A markdown table: per feature the reference's p5 / p50 / p95 before the onset and at
        the contact, the recordings' medians, and the share of the recordings' contact frames
        below the reference contact p5 and above its p95.

    """
    lines = ['| feature | reference before p5 / p50 / p95 | reference contact p5 / p50 / p95 '
             '| recordings before p50 | recordings contact p50 | recordings contact below '
             'p5 / above p95 |',
             '|---|---|---|---|---|---|']
    for i, name in enumerate(names):
        before = np.percentile(reference['before'][:, i], [5, 50, 95])
        contact = np.percentile(reference['contact'][:, i], [5, 50, 95])
        mine = recordings['contact'][:, i]
        below = float(np.mean(mine < contact[0])) if mine.size else float('nan')
        above = float(np.mean(mine > contact[2])) if mine.size else float('nan')
        mine_before = recordings['before'][:, i]
        lines.append(
            f'| {name} | {" / ".join(f"{v:.3g}" for v in before)} | '
            f'{" / ".join(f"{v:.3g}" for v in contact)} | '
            f'{np.median(mine_before) if mine_before.size else float("nan"):.3g} | '
            f'{np.median(mine) if mine.size else float("nan"):.3g} | '
            f'{100 * below:.0f} % / {100 * above:.0f} % |')
    return '\n'.join(lines)


def reference_parser(description: str, *, reference_trials: int) -> argparse.ArgumentParser:
    """Return a parser of recordings, ``--reference``, ``--labels``, ``--model`` and a count."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument('recordings', nargs='+', type=Path, help='folders of bags, or bags')
    parser.add_argument('--reference', nargs='+', type=Path, required=True,
                        help='folders of simulated trials (e.g. the training set)')
    parser.add_argument('--labels', type=Path, action='append', default=None,
                        help="CSV of the recordings' onsets (contact-detector label writes "
                             'one; repeat it for several); bags no CSV names use their own '
                             'truth')
    parser.add_argument('--model', type=Path, default=None,
                        help='the model whose features to compute (default: the shipped '
                             'multimodal model)')
    parser.add_argument('--reference-trials', type=int, default=reference_trials,
                        help=f'use the first N reference bags (default {reference_trials})')
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Print the table; return the exit status."""
    parser = reference_parser(__doc__.split('\n\n')[0], reference_trials=96)
    parser.add_argument('--augmented', action='store_true',
                        help="vary the reference trials' wrenches as the model's training did")
    args = parser.parse_args(argv)
    bundle = load_bundle(path=args.model or default_model_path())
    config = bundle.feature_config
    augmentation, seed = None, 0
    if args.augmented:
        recorded = bundle.training.get('augmentation')
        if not recorded:
            parser.error('the model card records no augmentation')
        augmentation = WrenchAugmentation(**{k: tuple(v) if isinstance(v, list) else v
                                             for k, v in recorded.items()})
        seed = int(bundle.training.get('seed', 0))
    reference_bags = find_bags(args.reference)[:args.reference_trials]
    bags = find_bags(args.recordings)
    onsets: Dict[Path, List[float]] = {}
    if args.labels is not None:
        labels = labels_for(csv_paths=args.labels, bags=bags)
        onsets = labels.onsets
        bags = [b for b in bags if b not in labels.left_out]
    reference, names = window_frames(bags=reference_bags, config=config, onsets={},
                                     augmentation=augmentation, seed=seed)
    mine, _ = window_frames(bags=bags, config=config, onsets=onsets)
    print(f'reference: {len(reference_bags)} bags, {len(reference["before"])} frames before '
          f'the onset, {len(reference["contact"])} at the contact; recordings: {len(bags)} '
          f'bags, {len(mine["before"])} and {len(mine["contact"])} frames')
    print(range_table(reference=reference, recordings=mine, names=names))
    return 0


if __name__ == '__main__':
    sys.exit(main())
