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
Which modality holds the forest back at your contacts: audio or F/T features, swapped in.

    .venv/bin/python benchmarks/modality_swap.py RECORDINGS... --reference data/train \
        [--labels LABELS.csv] [--model M] [--reference-trials 120] [--seed 0]

When a model is slower or less sure at the contacts of your robot than at the simulated ones,
this says whether the audio features or the F/T features make the difference. The frames of
the first 120 ms after each onset are cut into 10 ms bins (:func:`feature_ranges.window_frames`,
the model's feature core). Each recording frame is scored by the model's forest:

- as recorded;
- with its audio features (``audio_*``) replaced by those of a reference contact frame of the
  same bin, drawn at random (``--seed``);
- with its F/T features (every other one) replaced in the same way.

For each window (0-30, 30-60 and 60-120 ms after the onset) it prints the mean P(contact) and
the share of frames at or above the fast path's threshold (the model's rule), for the
reference as recorded and for the recordings in the three ways. If swapping in the
reference's F/T features brings the recordings near the reference and swapping in its audio
does not, the F/T features are the ones that differ. A model without audio features has
only the F/T swap; recordings without a microphone need one (``--model
models/contact_forest_ft.npz``), else the error names the bag.
"""

import sys
from typing import Dict, List, Optional, Sequence

from contact_detector.errors import ContactDetectorError
from contact_detector.io.bags import find_bags
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.training.protocol import labels_for
from feature_ranges import reference_parser, window_frames
import numpy as np

#: Bin width after the onset, s, and the number of bins (0-120 ms).
BIN_S, BINS = 0.01, 12
#: The windows reported, as ranges of bins: (name, first bin, end bin).
REPORTED = (('0-30 ms', 0, 3), ('30-60 ms', 3, 6), ('60-120 ms', 6, 12))


def swapped(*, frames: np.ndarray, reference: np.ndarray, columns: Sequence[int],
            rng: np.random.Generator) -> np.ndarray:
    """
    Return ``frames`` with ``columns`` taken from reference frames drawn at random.

    Parameters
    ----------
    frames : np.ndarray, shape (n, k)
        One bin's recording frames.
    reference : np.ndarray, shape (m, k)
        The same bin's reference frames, m >= 1.
    columns : sequence of int
        The columns to replace.
    rng : np.random.Generator
        Draws one reference frame per recording frame, with replacement.

    Returns
    -------
    np.ndarray, shape (n, k)
        A copy; ``out[i, c] = reference[j_i, c]`` for ``c`` in ``columns``.

    """
    out = frames.copy()
    drawn = reference[rng.integers(0, reference.shape[0], size=frames.shape[0])]
    out[:, list(columns)] = drawn[:, list(columns)]
    return out


def p_rows(*, reference: Dict[int, np.ndarray], recordings: Dict[int, np.ndarray],
           predict, groups: Dict[str, List[int]], seed: int) -> Dict[str, Dict[int, np.ndarray]]:
    """
    Return P(contact) per bin: the reference, the recordings, and each group swapped in.

    ``predict`` maps frames (n, k) to P (n,); ``groups`` names columns to swap. A bin without
    reference frames gets no swapped rows.
    """
    rng = np.random.default_rng(seed)
    rows: Dict[str, Dict[int, np.ndarray]] = {
        'reference': {b: predict(x) for b, x in reference.items() if len(x)},
        'recordings': {b: predict(x) for b, x in recordings.items() if len(x)}}
    for name, columns in groups.items():
        rows[f'recordings, reference {name}'] = {
            b: predict(swapped(frames=x, reference=reference[b], columns=columns, rng=rng))
            for b, x in recordings.items() if len(x) and len(reference.get(b, ()))}
    return rows


def table(rows: Dict[str, Dict[int, np.ndarray]], *, threshold: float) -> str:
    """Return the markdown table of :func:`p_rows`: mean P and share >= threshold per window."""
    head = ' | '.join(name for name, _, _ in REPORTED)
    lines = [f'| frames | {head} |', '|---' * (len(REPORTED) + 1) + '|']
    for label, by_bin in rows.items():
        cells = []
        for _, first, end in REPORTED:
            p = [by_bin[b] for b in range(first, end) if b in by_bin]
            p = np.concatenate(p) if p else np.zeros(0)
            cells.append(f'{p.mean():.2f}, {np.mean(p >= threshold):.0%} (n={p.size})'
                         if p.size else 'no frames')
        lines.append(f'| {label} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Print the table; return the exit status."""
    parser = reference_parser(__doc__.split('\n\n')[0], reference_trials=120)
    parser.add_argument('--seed', type=int, default=0, help='seed of the reference draws')
    args = parser.parse_args(argv)
    windows = {b: (b * BIN_S, (b + 1) * BIN_S) for b in range(BINS)}
    try:
        bundle = load_bundle(path=args.model or default_model_path())
        config = bundle.feature_config
        bags = find_bags(args.recordings)
        onsets = {}
        if args.labels is not None:
            labels = labels_for(csv_paths=args.labels, bags=bags)
            onsets = labels.onsets
            bags = [b for b in bags if b not in labels.left_out]
        reference, names = window_frames(
            bags=find_bags(args.reference)[:args.reference_trials], config=config, onsets={},
            windows=windows)
        mine, _ = window_frames(bags=bags, config=config, onsets=onsets, windows=windows)
    except ContactDetectorError as err:
        print(f'modality_swap.py: error: {err}', file=sys.stderr)
        return 1
    cols = [list(names).index(n) for n in bundle.feature_names]
    forest = bundle.compile()

    def predict(x: np.ndarray) -> np.ndarray:
        return forest.predict_proba(x[:, cols])

    audio = [i for i, n in enumerate(names) if n.startswith('audio')]
    groups = {'audio': audio} if audio else {}
    groups['F/T'] = [i for i in range(len(names)) if i not in audio]
    rows = p_rows(reference=reference, recordings=mine, predict=predict, groups=groups,
                  seed=args.seed)
    threshold = bundle.decision_rule.threshold
    print(f'{len(bags)} recordings; mean P(contact), and the share of frames at P >= '
          f'{threshold:g} (the fast path)')
    print(table(rows, threshold=threshold))
    return 0


if __name__ == '__main__':
    sys.exit(main())
