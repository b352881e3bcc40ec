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

"""Ground truth of recordings: the simulator's manifest beside the bags, else the truth topic."""

import json
from pathlib import Path
from typing import Optional, Sequence

from contact_detector.errors import BagError
from contact_detector.evaluation.metrics import Truth
from contact_detector.io.sensor_stream import truth_onsets


def conditions_of(bags: Sequence[Path]) -> dict:
    """
    Map bag path -> its manifest entry, from manifests beside the bags, where there are any.

    Keyed by path, not name: two simulated folders both have a ``trial_0000``.
    """
    out = {}
    for parent in {b.parent for b in bags}:
        manifest = parent / 'manifest.json'
        if manifest.exists():
            for trial in json.loads(manifest.read_text()).get('trials', []):
                out[parent / trial['name']] = trial
    return out


def truth_for(bag: Path, events, manifest: dict, *, name: Optional[str] = None) -> Truth:
    """
    Ground truth of one bag: the manifest's entry, else the truth topic.

    ``name`` is the bag's name in reports (default its file name).
    """
    name = name or bag.name
    info = manifest.get(bag)
    if info is not None:
        return Truth(name=name, condition=info.get('condition', ''),
                     onset_t=float(info['onset_t']), contact_end_t=info.get('contact_end_t'),
                     impacts=tuple((float(i['t']), i['kind'], bool(i['in_air']))
                                   for i in info.get('impacts', [])),
                     phases=tuple((str(name), float(start))
                                  for name, start, *_ in info.get('phases', [])))
    onsets = truth_onsets(events)
    if not onsets:
        raise BagError(f'{bag}: no manifest entry and no True on /contact_truth')
    return Truth(name=name, condition='', onset_t=onsets[0][0])


def knocked_in_air(truth: Truth) -> bool:
    """Return True if the trial has a knock on the hand while the object is in the air."""
    return any(kind == 'hand' and in_air for _, kind, in_air in truth.impacts)
