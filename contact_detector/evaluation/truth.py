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

import math
from pathlib import Path
from typing import Any, Dict, Optional, Sequence

from contact_detector.errors import BagError
from contact_detector.evaluation.metrics import Truth
from contact_detector.io.bags import manifest_entry, manifest_index, MANIFEST_NAME
from contact_detector.io.sensor_stream import truth_onsets


def conditions_of(bags: Sequence[Path]) -> dict:
    """
    Map bag path -> its manifest entry, from manifests beside the bags, where there are any.

    Keyed by path, not name: two simulated folders both have a ``trial_0000``. An entry is a
    bag's if its ``bag`` or its ``name`` is the bag's name (or, for a ROS 1 ``.bag`` file, its
    stem), the first such entry as :func:`contact_detector.io.bags.manifest_entry` finds it;
    each folder's manifest is read once.

    Raises
    ------
    BagError
        A manifest cannot be read or is not one.

    """
    out = {}
    indexes: Dict[Path, dict] = {}
    for bag in bags:
        if bag.parent not in indexes:
            manifest = bag.parent / MANIFEST_NAME
            indexes[bag.parent] = manifest_index(manifest) if manifest.is_file() else {}
        entry = manifest_entry(bag, index=indexes[bag.parent])
        if entry is not None:
            out[bag] = entry
    return out


def truth_for(bag: Path, events, manifest: dict, *, name: Optional[str] = None) -> Truth:
    """
    Ground truth of one bag: the manifest's entry, else the truth topic.

    ``name`` is the bag's name in reports (default its file name).

    Raises
    ------
    BagError
        The bag's manifest entry lacks ``onset_t`` or has a time that is not a finite number
        (the message names the manifest and the trial), or the bag has neither an entry nor a
        True on the truth topic.

    """
    name = name or bag.name
    info = manifest.get(bag)
    if info is not None:
        where = f'{bag.parent / MANIFEST_NAME}: trial {info.get("name") or info.get("bag")}'
        # checked here, where it is used, not in conditions_of: a bag a CSV labels needs none
        try:
            return _entry_truth(info=info, name=name)
        except KeyError as err:
            raise BagError(f'{where}: an impact has no {err} field') from err
        except (TypeError, ValueError) as err:
            raise BagError(f'{where}: {err}') from err
    onsets = truth_onsets(events)
    if not onsets:
        raise BagError(f'{bag}: no manifest entry and no True on /contact_truth')
    return Truth(name=name, condition='', onset_t=onsets[0][0])


def _entry_truth(*, info: dict, name: str) -> Truth:
    """
    Build the :class:`Truth` of a manifest entry, its times checked.

    Parameters
    ----------
    info : dict
        The trial's manifest entry.
    name : str
        The bag's name in reports.

    Returns
    -------
    Truth

    Raises
    ------
    ValueError
        A time is missing (``onset_t``) or not a finite number of seconds.
    KeyError
        An impact lacks ``t``, ``kind`` or ``in_air``.
    TypeError
        An impact or a phase is not shaped as the simulator writes it.

    """
    if 'onset_t' not in info:
        raise ValueError('no onset_t')
    end = info.get('contact_end_t')
    return Truth(name=name, condition=info.get('condition', ''),
                 onset_t=_seconds(info['onset_t'], field='onset_t'),
                 contact_end_t=None if end is None else _seconds(end, field='contact_end_t'),
                 impacts=tuple((_seconds(i['t'], field='impact t'), i['kind'],
                                bool(i['in_air'])) for i in info.get('impacts', [])),
                 phases=tuple((str(phase), _seconds(start, field=f'phase {phase} start'))
                              for phase, start, *_ in info.get('phases', [])))


def _seconds(value: Any, *, field: str) -> float:
    """Return ``value`` as a finite time, s; else raise ValueError naming ``field``."""
    try:
        seconds = float(value)
    except (TypeError, ValueError):
        seconds = math.nan
    if not math.isfinite(seconds):
        raise ValueError(f'{field} is {value!r}, not a time (a finite number of seconds)')
    return seconds


def knocked_in_air(truth: Truth) -> bool:
    """Return True if the trial has a knock on the hand while the object is in the air."""
    return any(kind == 'hand' and in_air for _, kind, in_air in truth.impacts)
