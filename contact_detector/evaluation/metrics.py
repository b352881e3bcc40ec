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
Event metrics of a detector against the true contact onset.

What a user of the release cares about, per trial: did the gripper open after the glass
touched (detected, with what latency), never (missed), or before (premature: the glass is
dropped)? And did other impacts trigger contact events outside the true contact?
"""

from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional, Sequence

import numpy as np

#: A release this much before the labelled onset still counts as on time (one audio hop).
ONSET_TOLERANCE_S = 0.01
#: A release later than this after the onset counts as missed: the arm has pushed too long.
LATE_S = 0.5
#: An event this close to an exogenous impact (before, after) is blamed on the impact.
IMPACT_WINDOW_S = (-0.05, 0.5)


@dataclass(frozen=True)
class Truth:
    """
    Ground truth of one trial.

    Attributes
    ----------
    name, condition : str
        Trial name (the bag directory's name) and condition set.
    onset_t : float
        True contact onset, seconds (bag time).
    contact_end_t : float or None
        Lift-off, seconds, when known.
    impacts : tuple of (float, str, bool)
        Exogenous impacts: time, kind ('hand' or 'table'), whether the object was in the air.

    """

    name: str
    condition: str
    onset_t: float
    contact_end_t: Optional[float] = None
    impacts: tuple = ()


@dataclass
class Outcome:
    """The verdict on one trial."""

    name: str
    condition: str
    onset_t: float
    release_t: Optional[float]
    latency_s: Optional[float]
    verdict: str                    # 'detected', 'missed', 'late' or 'premature'
    impact_events: int = 0          # contact events blamed on exogenous impacts
    impacts: int = 0
    impacts_in_air: int = 0
    extra: dict = field(default_factory=dict)


def score_trial(*, truth: Truth, releases: Sequence[float], events: Sequence[float],
                tolerance_s: float = ONSET_TOLERANCE_S, late_s: float = LATE_S) -> Outcome:
    """
    Score one trial.

    Parameters
    ----------
    truth : Truth
        Ground truth.
    releases : sequence of float
        Release times (the first one counts), seconds.
    events : sequence of float
        Every confirmed contact event, armed or not, seconds.
    tolerance_s, late_s : float
        A first release in ``[onset - tolerance_s, onset + late_s]`` is a detection; before
        that it is premature, after it late.

    Returns
    -------
    Outcome

    """
    release = min(releases) if len(releases) else None
    if release is None:
        verdict, latency = 'missed', None
    elif release < truth.onset_t - tolerance_s:
        verdict, latency = 'premature', release - truth.onset_t
    elif release <= truth.onset_t + late_s:
        verdict, latency = 'detected', release - truth.onset_t
    else:
        verdict, latency = 'late', release - truth.onset_t
    contact_end = truth.contact_end_t if truth.contact_end_t is not None else (
        truth.onset_t + late_s)
    blamed = 0
    for t in events:
        if truth.onset_t - tolerance_s <= t <= contact_end:
            continue
        if any(it + IMPACT_WINDOW_S[0] <= t <= it + IMPACT_WINDOW_S[1]
               for it, _, _ in truth.impacts):
            blamed += 1
    return Outcome(name=truth.name, condition=truth.condition, onset_t=truth.onset_t,
                   release_t=release, latency_s=latency, verdict=verdict, impact_events=blamed,
                   impacts=len(truth.impacts),
                   impacts_in_air=sum(1 for _, _, air in truth.impacts if air))


def summarize(outcomes: Sequence[Outcome]) -> Dict[str, object]:
    """
    Aggregate outcomes: counts of each verdict, latency median/p95/max (ms), impact events.

    Returns
    -------
    dict
        JSON-serialisable summary.

    """
    n = len(outcomes)
    latencies = np.array([o.latency_s for o in outcomes if o.verdict == 'detected'])
    summary = {
        'trials': n,
        'detected': sum(o.verdict == 'detected' for o in outcomes),
        'missed': sum(o.verdict == 'missed' for o in outcomes),
        'late': sum(o.verdict == 'late' for o in outcomes),
        'premature': sum(o.verdict == 'premature' for o in outcomes),
        'impact_events': sum(o.impact_events for o in outcomes),
        'trials_with_impacts': sum(o.impacts > 0 for o in outcomes),
        'latency_ms_median': float(np.median(latencies) * 1000) if latencies.size else None,
        'latency_ms_p95': float(np.percentile(latencies, 95) * 1000) if latencies.size else None,
        'latency_ms_max': float(latencies.max() * 1000) if latencies.size else None,
    }
    return summary


def summarize_by_condition(outcomes: Sequence[Outcome]) -> Dict[str, Dict[str, object]]:
    """Return :func:`summarize` per condition set, plus 'all'."""
    out = {'all': summarize(outcomes)}
    for condition in sorted({o.condition for o in outcomes}):
        out[condition] = summarize([o for o in outcomes if o.condition == condition])
    return out


def outcome_dicts(outcomes: Sequence[Outcome]) -> List[dict]:
    """Return outcomes as plain dicts (for JSON)."""
    return [asdict(o) for o in outcomes]


def frame_labels(*, t: np.ndarray, onsets: Sequence[float], start_s: float,
                 end_s: float) -> np.ndarray:
    """
    Label frames 1 inside ``[onset + start_s, onset + end_s)`` of any onset, else 0.

    Parameters
    ----------
    t : np.ndarray, shape (n,)
        Frame times (last sample), seconds.
    onsets : sequence of float
        True onsets, seconds.
    start_s, end_s : float
        The label window relative to each onset, seconds.

    Returns
    -------
    np.ndarray, shape (n,), int

    """
    labels = np.zeros(t.shape[0], dtype=np.int64)
    for onset in onsets:
        labels[(t >= onset + start_s) & (t < onset + end_s)] = 1
    return labels
