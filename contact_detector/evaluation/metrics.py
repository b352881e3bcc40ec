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
        Exogenous impacts: time (start), kind ('hand', 'table', 'touch', 'brush', 'setdown'),
        whether the object was in the air. Every kind is blamed the same way.
    phases : tuple of (str, float)
        The motion's phases in time order, each its name ('rest', 'lift', 'hold',
        'accelerate', 'descend', ...) and start time, seconds, when known (a simulated
        trial's manifest); empty otherwise.

    """

    name: str
    condition: str
    onset_t: float
    contact_end_t: Optional[float] = None
    impacts: tuple = ()
    phases: tuple = ()


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
    # What a premature release followed: the kind of the newest exogenous event that started
    # at most IMPACT_WINDOW_S[1] before it ('hand', 'touch', 'brush', ...), or 'none'.
    premature_after: Optional[str] = None
    # The motion phase a premature release fell in ('lift', 'descend', ...), when the truth
    # has phases: a release during the lift is one a robot that arms after the lift avoids.
    premature_phase: Optional[str] = None


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
    cause = phase = None
    if verdict == 'premature':
        cause = premature_cause(truth=truth, release_t=release)
        phase = phase_at(truth=truth, t=release)
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
                   impacts_in_air=sum(1 for _, _, air in truth.impacts if air),
                   premature_after=cause, premature_phase=phase)


def phase_at(*, truth: Truth, t: float) -> Optional[str]:
    """
    Name the motion phase that time ``t`` falls in.

    Parameters
    ----------
    truth : Truth
        Ground truth with its phases (name, start time).
    t : float
        Time, seconds (bag time).

    Returns
    -------
    str or None
        The name of the last phase that started at or before ``t`` (the first phase's name
        before it starts), or None when the truth has no phases.

    """
    if not truth.phases:
        return None
    started = [name for name, start in truth.phases if start <= t]
    return started[-1] if started else truth.phases[0][0]


def premature_cause(*, truth: Truth, release_t: float) -> str:
    """
    Name the exogenous event a premature release followed.

    Parameters
    ----------
    truth : Truth
        Ground truth with its exogenous impacts.
    release_t : float
        The premature release, seconds.

    Returns
    -------
    str
        The kind of the newest impact that started in ``[release_t - 0.5 s, release_t +
        0.05 s]`` (:data:`IMPACT_WINDOW_S`, the window that blames contact events on impacts),
        or ``'none'`` when the release followed no event: the detector fired on the approach
        itself.

    """
    kinds = [(t, kind) for t, kind, _ in truth.impacts
             if t + IMPACT_WINDOW_S[0] <= release_t <= t + IMPACT_WINDOW_S[1]]
    return max(kinds)[1] if kinds else 'none'


def score_onsets(*, name: str, condition: str, onsets: Sequence[float],
                 events: Sequence[float], tolerance_s: float = ONSET_TOLERANCE_S,
                 late_s: float = LATE_S) -> List[Outcome]:
    """
    Score a recording with one or several labelled contacts, one Outcome per onset.

    A recording of a user's robot may hold many placements (a labels CSV with several rows
    for one bag). Each onset is scored as if the detector had been re-armed for it: onset
    ``k`` owns the contact events in ``[o_{k-1} + late_s, o_{k+1} - tolerance_s)`` (open at
    the recording's ends) after the release of onset ``k - 1`` (an event releases once), and
    the first of them is its release, judged as in
    :func:`score_trial`: before ``o_k - tolerance_s`` premature, up to ``o_k + late_s``
    detected, later late, none missed. With one onset this is :func:`score_trial` with the
    first event as the release (a fresh detector is armed, so its first event releases).

    Parameters
    ----------
    name, condition : str
        The recording's name and condition; outcome ``k`` is named ``name#k`` (from 1) when
        there are several onsets.
    onsets : sequence of float
        Labelled onsets, seconds (bag time), any order.
    events : sequence of float
        Every confirmed contact event of the run, seconds.
    tolerance_s, late_s : float
        As in :func:`score_trial`.

    Returns
    -------
    list of Outcome
        In onset order; ``extra`` holds ``{'recording': name, 'contact': k}``.

    """
    order = sorted(float(o) for o in onsets)
    times = np.sort(np.asarray(events, dtype=float))
    outcomes = []
    used = -np.inf
    for k, onset in enumerate(order):
        lo = order[k - 1] + late_s if k > 0 else -np.inf
        hi = order[k + 1] - tolerance_s if k + 1 < len(order) else np.inf
        mine = times[(times >= lo) & (times < hi) & (times > used)]
        if mine.size:
            used = mine[0]
        label = f'{name}#{k + 1}' if len(order) > 1 else name
        outcome = score_trial(truth=Truth(name=label, condition=condition, onset_t=onset),
                              releases=mine[:1].tolist(), events=(),
                              tolerance_s=tolerance_s, late_s=late_s)
        outcome.extra = {'recording': name, 'contact': k + 1}
        outcomes.append(outcome)
    return outcomes


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
        'premature_after': premature_counts(outcomes),
        'premature_phase': premature_counts(outcomes, by='premature_phase'),
    }
    return summary


def premature_counts(outcomes: Sequence[Outcome], *,
                     by: str = 'premature_after') -> Dict[str, int]:
    """
    Count premature releases by an Outcome field.

    ``by='premature_after'``: the event they followed (:func:`premature_cause`, 'none' when
    none); ``by='premature_phase'``: the motion phase they fell in (:func:`phase_at`; trials
    without phases have None and are left out).
    """
    counts: Dict[str, int] = {}
    for o in outcomes:
        key = getattr(o, by)
        if o.verdict == 'premature' and key is not None:
            counts[key] = counts.get(key, 0) + 1
    return dict(sorted(counts.items()))


def premature_text(summary: Dict[str, object], *, by: str = 'premature_after') -> str:
    """
    Return ``summary``'s premature count with its causes, e.g. ``'3 (brush 2, touch 1)'``.

    ``by='premature_phase'`` gives the motion phases instead, e.g. ``'3 (lift 2, descend 1)'``;
    without phases (recordings, not simulated trials), the count alone.
    """
    causes = summary.get(by) or {}
    if not causes:
        return str(summary['premature'])
    return f"{summary['premature']} ({', '.join(f'{k} {v}' for k, v in causes.items())})"


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


def frame_report(*, y_true: np.ndarray, y_pred: np.ndarray,
                 names: Sequence[str] = ('not contact', 'contact'),
                 digits: int = 2) -> tuple:
    """
    Per-class precision, recall, F1 and support of binary frame labels, without scikit-learn.

    The same numbers and layout as ``sklearn.metrics.classification_report(y_true, y_pred,
    labels=[0, 1], target_names=names, zero_division=0)``: precision = TP / (TP + FP), recall
    = TP / (TP + FN), F1 = 2 TP / (2 TP + FP + FN) (= 2 P R / (P + R)), each 0 when its
    denominator is 0; ``macro avg`` the plain mean over the two classes, ``weighted avg`` the
    mean weighted by support.

    Parameters
    ----------
    y_true, y_pred : np.ndarray of int, shape (n,)
        Labels in {0, 1}.
    names : sequence of str
        Names of class 0 and class 1.
    digits : int
        Decimals in the text.

    Returns
    -------
    (str, dict)
        The text table and the dict form (``output_dict=True``).

    """
    y_true = np.asarray(y_true).astype(int)
    y_pred = np.asarray(y_pred).astype(int)
    rows = []
    for label in (0, 1):
        tp = float(np.sum((y_pred == label) & (y_true == label)))
        predicted = float(np.sum(y_pred == label))
        support = float(np.sum(y_true == label))
        precision = tp / predicted if predicted else 0.0
        recall = tp / support if support else 0.0
        f1_den = predicted + support  # = 2 TP + FP + FN
        f1 = 2 * tp / f1_den if f1_den else 0.0
        rows.append((precision, recall, f1, support))
    total = rows[0][3] + rows[1][3]
    scores = np.array([row[:3] for row in rows])
    support = np.array([row[3] for row in rows])
    macro = tuple(float(v) for v in scores.mean(axis=0)) + (total,)
    weighted = (tuple(float(v) for v in np.average(scores, axis=0, weights=support))
                if total else (0.0, 0.0, 0.0)) + (total,)
    accuracy = float(np.mean(y_true == y_pred)) if y_true.size else 0.0
    keys = ('precision', 'recall', 'f1-score', 'support')
    report = {name: dict(zip(keys, row)) for name, row in zip(names, rows)}
    report['accuracy'] = accuracy
    report['macro avg'] = dict(zip(keys, macro))
    report['weighted avg'] = dict(zip(keys, weighted))
    width = max(max(len(name) for name in names), len('weighted avg'), digits)
    row_fmt = '{:>{width}s} ' + ' {:>9.{digits}f}' * 3 + ' {:>9}\n'
    text = ('{:>{width}s} ' + ' {:>9}' * 4).format('', *keys, width=width) + '\n\n'
    for name, row in zip(names, rows):
        text += row_fmt.format(name, *row[:3], int(row[3]), width=width, digits=digits)
    text += '\n'
    text += ('{:>{width}s} ' + ' {:>9.{digits}}' * 2 + ' {:>9.{digits}f}' + ' {:>9}\n').format(
        'accuracy', '', '', accuracy, int(total), width=width, digits=digits)
    for name, row in (('macro avg', macro), ('weighted avg', weighted)):
        text += row_fmt.format(name, *row[:3], int(row[3]), width=width, digits=digits)
    return text, report
