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
Score every decision rule with a trained model bundle (the shipped one by default).

The sweep (``contact-detector sweep``) trains a forest per setting on all training trials; the
shipped model is trained by the paper's protocol on 75% of them. This script checks the rule
choice on the model that actually ships: on its own trial-split test trials and on a held-out
simulated set. It is how the default rule in docs/sweep.md was validated.

    python benchmarks/rule_check.py data/train data/heldout [--model models/contact_forest.npz]
"""

import argparse
from pathlib import Path

from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.rule import DecisionRule
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.training.protocol import LabelWindow
from contact_detector.training.sweep import (compute_frames, FeatureSetting, rows_markdown,
                                             score_rules)
from contact_detector.training.sweep import decode_bags, rule_grid


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('train', help='the training folder (its test trials are scored)')
    parser.add_argument('heldout', help='a held-out folder of simulated trials')
    parser.add_argument('--model', type=Path, default=None)
    parser.add_argument('--jobs', type=int, default=2)
    args = parser.parse_args()
    bundle = load_bundle(path=args.model or default_model_path())
    test_names = set(bundle.training.get('test_trials', []))
    spec = StreamSpec()
    own = decode_bags(bags=[p for p in find_bags([args.train]) if p.name in test_names],
                      spec=spec, tag='train')
    heldout = decode_bags(bags=find_bags([args.heldout]), spec=spec, tag='heldout')
    setting = FeatureSetting('shipped', bundle.feature_config,
                             LabelWindow(**bundle.label_window))
    rules = rule_grid() + [DecisionRule(threshold=t, confirm_frames=k)
                           for t in (0.6, 0.8, 0.85) for k in (1, 2, 3)]
    # the fast single-frame path with a slow path for quiet contacts (docs/model.md)
    rules += [DecisionRule(threshold=t, confirm_frames=1, sustain_frames=10,
                           sustain_threshold=s) for t in (0.8, 0.85, 0.9) for s in (0.4, 0.5)]
    rate = bundle.training.get('audio_rate', 16000.0)
    wrench = bundle.training.get('wrench_rate', 100.0)
    for tag, events in ((f'own {len(own)} test trials', own),
                        (f'{len(heldout)} held-out', heldout)):
        if not events:
            continue
        frames = compute_frames(events_by_trial=events, config=bundle.feature_config,
                                audio_rate=rate, wrench_rate=wrench, jobs=args.jobs)
        rows = score_rules(forest=bundle.compile(), frames=list(frames.values()),
                           setting=setting, rules=rules)
        for row in rows:
            row.setting = tag
        print(rows_markdown(rows), flush=True)
        print()


if __name__ == '__main__':
    main()
