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
Calibrated probabilities across families, each family left out, beside the shipped rule.

    .venv/bin/python benchmarks/lofo_calibration.py DIR... [--recipe ft-only|multimodal]
        [--rule NAME:FIELD=VALUE[,...]]... [--seeds 0,1,2] [--groups 3] [--jobs 2]
        [--families] [--json out.json]

For each family left out and each seed, the fold's forest is trained as ``lofo_rules.py``
trains it (a shipped recipe: feature setting, labels, wrench augmentation, event weight), and
a monotone map ``g`` from its P(contact) to the frequency of contact frames is fitted on
*other families'* frames: the fold's training families are split into ``--groups`` groups
(sorted names, every ``groups``-th), a forest trained without each group predicts that
group's frames (as simulated, the frames training uses), and scikit-learn's
``IsotonicRegression`` is fitted to those out-of-family probabilities and the frames' contact
labels (the recipe's label window). The left-out family is then decided on ``g(P)``.

So ``g`` says how often a frame given P by a forest that never saw its family is a contact;
a forest that is only 0.3-0.6 sure of another world's contacts is mapped up where such
frames mostly are contacts, and down where they mostly are not. The calibration uses nothing
of the family left out.

Every rule (the recipe's shipped rule ``S`` and each ``--rule``, as in ``lofo_rules.py``) is
scored on the raw P and, as ``NAME~cal``, on ``g(P)``, with the same forests. Prints one line
per rule as ``lofo_rules.py`` does. About ``groups + 1`` times the cost of ``lofo_rules.py``.
"""

import argparse
import sys
from typing import Dict, List, Sequence

from contact_detector.evaluation.metrics import frame_labels
from contact_detector.evaluation.truth import knocked_in_air
from contact_detector.training.sweep import (FeatureSetting, fit_forest, p_contact,
                                             score_rules, setting_columns, TrialFrames)
from lofo_rules import (add_arguments, print_rules, recipe_frames, recipe_rules, summarise,
                        write_json)
import numpy as np
from sklearn.isotonic import IsotonicRegression


class CalibratedForest:
    """
    A fitted forest whose P(contact) passes through a fitted ``IsotonicRegression``.

    ``forest`` is a scikit-learn forest or a ``CompiledForest`` (``training.sweep.p_contact``).
    """

    def __init__(self, *, forest: object, calibration: IsotonicRegression) -> None:
        self.forest = forest
        self.calibration = calibration

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        """Return ``[1 - g(P), g(P)]`` per row, shape ``(n, 2)``."""
        p = self.calibration.predict(p_contact(self.forest, x))
        return np.column_stack([1.0 - p, p])


def cross_family_calibration(*, frames: Sequence[TrialFrames], fit: Sequence[TrialFrames],
                             setting: FeatureSetting, groups: int, seed: int,
                             jobs: int) -> IsotonicRegression:
    """
    Fit ``g`` on out-of-family probabilities of the families in ``frames``.

    ``frames`` are the fold's training trials as simulated, ``fit`` the same trials as the
    forests are trained on (augmented). Each of ``groups`` groups of families is predicted by a
    10-tree forest trained on ``fit`` without it; only the frames training uses (the label
    window's ``trained`` mask) enter the fit.
    """
    names = sorted({f.truth.condition for f in frames})
    cols = setting_columns(setting)
    p, y = [], []
    for part in (set(names[i::groups]) for i in range(groups)):
        forest = fit_forest(frames=[f for f in fit if f.truth.condition not in part],
                            setting=setting, n_estimators=10, seed=seed, jobs=jobs)
        for f in (f for f in frames if f.truth.condition in part and f.x.shape[0]):
            keep = setting.label.trained(t=f.t, onsets=[f.truth.onset_t])
            p.append(forest.predict_proba(f.x[keep][:, cols])[:, 1])
            y.append(frame_labels(t=f.t[keep], onsets=[f.truth.onset_t],
                                  start_s=setting.label.start_s, end_s=setting.label.end_s))
    return IsotonicRegression(y_min=0.0, y_max=1.0, out_of_bounds='clip').fit(
        np.concatenate(p), np.concatenate(y).astype(float))


def curve(calibration: IsotonicRegression) -> List[float]:
    """Return ``g`` at P = 0, 0.1, ..., 1, to 3 decimals (what the scripts print of a map)."""
    return np.round(calibration.predict(np.linspace(0.0, 1.0, 11)), 3).tolist()


def score_raw_and_calibrated(*, forest: object, calibration: IsotonicRegression,
                             frames: Sequence[TrialFrames], setting: FeatureSetting,
                             rules: Dict[str, object]) -> List[object]:
    """
    Score every rule on P and on ``g(P)`` with the same forest (``score_rules``' rows).

    The rows are in the order of ``list(rules) + [name + '~cal' for name in rules]``.
    """
    raw = score_rules(forest=forest, frames=frames, setting=setting, rules=list(rules.values()))
    cal = score_rules(forest=CalibratedForest(forest=forest, calibration=calibration),
                      frames=frames, setting=setting, rules=list(rules.values()))
    return raw + cal


def main(argv=None) -> int:
    """Run the comparison; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    parser.add_argument('--groups', type=int, default=3,
                        help='groups of training families the calibration predicts in turn')
    args = parser.parse_args(argv)
    if args.groups < 2:
        parser.error('--groups must be at least 2')
    setting, rules = recipe_rules(args, parser)
    keyed, fit = recipe_frames(args, setting)
    frames = list(keyed.values())
    names = list(rules) + [f'{name}~cal' for name in rules]
    outcomes: Dict[str, List] = {name: [] for name in names}
    knocked: Dict[str, List] = {name: [] for name in names}
    curves = {}
    for seed in (int(s) for s in args.seeds.split(',')):
        for family in sorted({f.truth.condition for f in frames}):
            test = [f for f in frames if f.truth.condition == family]
            train = [f for f in frames if f.truth.condition != family]
            train_fit = [f for f in fit if f.truth.condition != family]
            forest = fit_forest(frames=train_fit, setting=setting, n_estimators=10, seed=seed,
                                jobs=args.jobs)
            calibration = cross_family_calibration(frames=train, fit=train_fit,
                                                   setting=setting, groups=args.groups,
                                                   seed=seed, jobs=args.jobs)
            curves[f'{seed}/{family}'] = curve(calibration)
            rows = score_raw_and_calibrated(forest=forest, calibration=calibration,
                                            frames=test, setting=setting, rules=rules)
            for name, row in zip(names, rows):
                outcomes[name] += row.outcomes
                knocked[name] += [o for o, f in zip(row.outcomes, test)
                                  if knocked_in_air(f.truth)]
            print(f'seed {seed}, {family}: g(0, 0.1, ..., 1) = {curves[f"{seed}/{family}"]}',
                  file=sys.stderr, flush=True)
    summary = {name: summarise(outcomes=outcomes[name], knocked=knocked[name])
               for name in names}
    print_rules(summary, families=args.families)
    write_json(args.json, rules=rules, summary=summary, curves=curves)
    return 0


if __name__ == '__main__':
    sys.exit(main())
