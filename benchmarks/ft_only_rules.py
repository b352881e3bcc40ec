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
Release rules of an F/T-only model on a simulated folder, knocks on the hand apart.

Scored on all trials and on the trials with knocks on the hand while the object is in the air
(the issue #16 figure).

The model's P(contact) is computed once per bag through the detector (``run_detector``, the
node's code); each rule then runs through :class:`ReleaseLogic` with the detector's warm-up and
is scored with the same metrics as ``evaluate`` (premature = release more than 10 ms before the
onset; detected = within [onset - 10 ms, onset + 500 ms]). The trials come with the folder's
``manifest.json`` (``contact-detector simulate``). Prints a markdown table.

Usage::

    python benchmarks/ft_only_rules.py FOLDER [--model models/contact_forest_ft.npz]
"""

import argparse
from dataclasses import replace
import json
from pathlib import Path
import sys

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector
from contact_detector.detection.release import ReleaseLogic
from contact_detector.evaluation.metrics import score_trial, summarize, Truth
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import load_events
from contact_detector.model.shipped import default_ft_model_path
from contact_detector.model.storage import load_bundle


def rules_of(base) -> dict:
    """Return the rules compared: the model's, then faster, slower and confirmed variants."""
    rules = {'model': base}
    for th in (0.3, 0.5):
        rules[f'mean15>={th}'] = replace(base, sustain_threshold=th)
    rules['p>=0.9'] = replace(base, threshold=0.9)
    for cf in (2, 3):
        rules[f'confirm {cf}'] = replace(base, confirm_frames=cf)
    for h, d in ((1.0, 0.3), (1.5, 0.5)):
        rules[f'evidence {h}/{d}'] = replace(base, evidence_threshold=h, evidence_drift=d)
    return rules


def main() -> int:
    """Print the table; return 0."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('folder', type=Path)
    parser.add_argument('--model', type=Path, default=None)
    args = parser.parse_args()
    bundle = load_bundle(path=args.model or default_ft_model_path())
    settings = DetectorSettings()
    manifest = {t['name']: t for t in
                json.loads((args.folder / 'manifest.json').read_text())['trials']}
    runs = [(bag.name, run_detector(load_events(bag), detector=ContactDetector(
        bundle=bundle, settings=settings))) for bag in find_bags([args.folder])]
    print(f'Model {bundle.model_id} on {args.folder} ({len(runs)} trials); "hand" = trials '
          'with a knock on the hand while the object is in the air.\n')
    print('| rule | hand: detected | hand: premature | hand: median [ms] | hand: p95 [ms] | '
          'all: detected | all: premature | all: median [ms] |')
    print('|---|---|---|---|---|---|---|---|')
    for name, rule in rules_of(bundle.decision_rule).items():
        every, hand = [], []
        for bag, run in runs:
            info = manifest[bag]
            logic = ReleaseLogic(rule=rule, armed=True)
            warm = run.t[0] + settings.warmup_s if run.t.size else 0.0
            _, releases = logic.step(t=run.t, p=run.p, valid=run.valid, blocked=run.t < warm)
            impacts = tuple((i['t'], i['kind'], i['in_air']) for i in info.get('impacts', []))
            outcome = score_trial(truth=Truth(name=bag, condition=info['condition'],
                                              onset_t=info['onset_t'],
                                              contact_end_t=info.get('contact_end_t'),
                                              impacts=impacts),
                                  releases=releases, events=releases)
            every.append(outcome)
            if any(kind == 'hand' and in_air for _, kind, in_air in impacts):
                hand.append(outcome)
        a, h = summarize(every), summarize(hand)

        def ms(value):
            return '-' if value is None else f'{value:.0f}'
        print(f"| {name} ({rule.short()}) | {h['detected']}/{h['trials']} | {h['premature']} | "
              f"{ms(h['latency_ms_median'])} | {ms(h['latency_ms_p95'])} | "
              f"{a['detected']}/{a['trials']} | {a['premature']} | {ms(a['latency_ms_median'])} |")
    return 0


if __name__ == '__main__':
    sys.exit(main())
