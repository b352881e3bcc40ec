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
``contact-detector convert-model``: turn a joblib/skops model into the npz format.

    contact-detector convert-model OLD.joblib NEW.npz

Reads the old bundle through scikit-learn (which must be installed, at the major.minor version
that saved it), writes the same forest and metadata as ``NEW.npz`` with its card, and checks
that the npz forest gives scikit-learn's ``predict_proba`` bit for bit on frames placed on both
sides of every split threshold. The npz file then loads with numpy alone (docs/model.md).
"""

import argparse
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.errors import ContactDetectorError
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.forest_arrays import boundary_frames
from contact_detector.model.storage import FORMATS, load_bundle, save_bundle

#: Frames compared with scikit-learn beyond save_bundle's own check.
CHECK_ROWS = 50000


def convert(*, source: Path, target: Path, check_rows: int = CHECK_ROWS) -> ModelBundle:
    """
    Convert the bundle at ``source`` (any format) to an npz bundle at ``target``.

    Returns
    -------
    ModelBundle
        The bundle loaded back from ``target``.

    Raises
    ------
    ModelError
        ``source`` cannot be loaded, or the npz forest differs from it.
    ConfigError
        ``target`` does not end in ``.npz`` or sits beside another model of the same stem.

    """
    bundle = load_bundle(path=source)
    frames = boundary_frames(bundle.trees, n_rows=check_rows, seed=1)
    save_bundle(bundle=bundle, path=target, fmt='npz', check_frames=frames)
    converted = load_bundle(path=target)
    if converted.model_id != bundle.model_id or converted.metadata() != bundle.metadata():
        raise ContactDetectorError(f'{target} does not reproduce {source}')
    return converted


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector convert-model', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('source', type=Path, help='model file (.joblib or .skops, or .npz)')
    parser.add_argument('target', type=Path, help='new model file, ending in .npz')
    parser.add_argument('--check-rows', type=int, default=CHECK_ROWS,
                        help=f'threshold-boundary frames compared with scikit-learn (default '
                             f'{CHECK_ROWS})')
    args = parser.parse_args(argv)
    if FORMATS.get(args.target.suffix) != 'npz':
        parser.error(f'the target must end in .npz, got {args.target.name}')
    if args.check_rows < 1:
        parser.error('--check-rows must be >= 1')
    try:
        bundle = convert(source=args.source, target=args.target, check_rows=args.check_rows)
    except ContactDetectorError as err:
        print(f'contact-detector convert-model: {err}', file=sys.stderr)
        return 1
    print(f'{args.target} written ({args.target.stat().st_size} bytes), model {bundle.model_id}; '
          f"probabilities equal scikit-learn's bit for bit")
    return 0
