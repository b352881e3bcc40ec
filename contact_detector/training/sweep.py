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
Choose defaults by measurement: feature settings x label windows x decision rules.

Each feature setting is computed with the streaming core on every bag (decoded once), a forest
is trained on the training trials, and its probabilities on the held-out trials are turned
into releases by :class:`~contact_detector.detection.release.ReleaseLogic` for every decision
rule, then scored by :mod:`contact_detector.evaluation.metrics`. The ``evaluate`` command
re-measures the chosen defaults through the full detector.
"""

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Dict, Iterable, List, Optional, Sequence, Tuple

from contact_detector.detection.factory import stream_spec
from contact_detector.detection.offline import run_features
from contact_detector.detection.release import ReleaseLogic, rule_inputs
from contact_detector.errors import ConfigError
from contact_detector.evaluation.metrics import frame_labels, score_trial, summarize, Truth
from contact_detector.evaluation.truth import conditions_of, truth_for
from contact_detector.features.config import FeatureConfig, RULE_FEATURES
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.discovery import Streams
from contact_detector.io.sensor_stream import load_events, StreamSpec
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.compiled_forest import CompiledForest
from contact_detector.model.rule import DecisionRule
from contact_detector.training.augmentation import augment_events, trial_seed, WrenchAugmentation
from contact_detector.training.protocol import LabelWindow, make_forest, stack_weights
from joblib import delayed, Parallel
import numpy as np
from sklearn.ensemble import RandomForestClassifier


@dataclass(frozen=True)
class FeatureSetting:
    """One point of the feature grid; ``columns`` selects a subset for ablations."""

    name: str
    config: FeatureConfig
    label: LabelWindow
    columns: Optional[tuple] = None


@dataclass
class TrialFrames:
    """
    Valid frames of one trial under one feature setting.

    ``breaks`` are the indices of the valid frames that follow invalid ones (an F/T window
    restarted mid-trial after a gap in the stamps): the detector decides those invalid frames,
    and each empties the rule's history, so :func:`score_rules` does the same there.
    """

    truth: Truth
    t: np.ndarray
    x: np.ndarray
    t0: float
    # a class attribute as well, so frames pickled before the field existed read as unbroken
    breaks: tuple = ()


@dataclass
class SweepRow:
    """Metrics of one (feature setting, rule) pair."""

    setting: str
    rule: str
    summary: dict
    precision: float
    recall: float
    extra: dict = field(default_factory=dict)
    outcomes: tuple = ()    # the per-trial Outcomes behind ``summary``


def decode_bags(*, bags: Sequence[Path], spec: StreamSpec, tag: str,
                progress: Callable[[Iterable], Iterable] = iter,
                found: Optional[Dict[Path, Streams]] = None) -> Dict[str, tuple]:
    """
    Decode every bag once, for the sweeps that reuse the messages.

    ``found`` (bag -> discovered :class:`~contact_detector.io.discovery.Streams`) gives each
    bag it names its own topics and audio format in place of ``spec``.

    Returns
    -------
    dict
        ``'<tag>/<bag name>'`` -> ``(events, Truth)``, the truth from the manifest beside the
        bags or the truth topic (:func:`~contact_detector.evaluation.truth.truth_for`).

    """
    manifest = conditions_of(bags)
    out = {}
    for bag in progress(bags):
        streams = (found or {}).get(bag)
        events = load_events(bag, spec=spec if streams is None else stream_spec(streams, {}))
        out[f'{tag}/{bag.name}'] = (events, truth_for(bag, events, manifest))
    return out


def rule_grid() -> List[DecisionRule]:
    """Thresholds x confirmation frames."""
    return [DecisionRule(threshold=th, confirm_frames=k, refractory_s=1.0)
            for th in (0.3, 0.5, 0.7, 0.9) for k in (1, 2, 3, 5)]


def model_rules(shipped: DecisionRule) -> List[DecisionRule]:
    """
    Rules scored with a trained model: its own, its variants, :func:`rule_grid`, single frames.

    The model's rule first; then the model's rule with the slow path at 0.3, 0.4 and 0.5,
    the fast path at 0.9, 2 or 3 confirmation frames, and the evidence paths
    ``sum(p - 0.3) >= 1`` and ``sum(p - 0.5) >= 1.5``; then the grid; thresholds 0.6, 0.8,
    0.85 with 1-3 confirmation frames; and the fast single-frame path (0.8, 0.85, 0.9) with a
    10-frame slow path at 0.4 or 0.5 for quiet contacts. Duplicates are dropped.
    """
    rules = [shipped]
    rules += [replace(shipped, sustain_threshold=th) for th in (0.3, 0.4, 0.5)]
    rules += [replace(shipped, threshold=0.9)]
    rules += [replace(shipped, confirm_frames=cf) for cf in (2, 3)]
    rules += [replace(shipped, evidence_threshold=h, evidence_drift=d)
              for h, d in ((1.0, 0.3), (1.5, 0.5))]
    rules += rule_grid()
    rules += [DecisionRule(threshold=t, confirm_frames=k) for t in (0.6, 0.8, 0.85)
              for k in (1, 2, 3)]
    rules += [DecisionRule(threshold=t, confirm_frames=1, sustain_frames=10,
                           sustain_threshold=s) for t in (0.8, 0.85, 0.9) for s in (0.4, 0.5)]
    return list(dict.fromkeys(rules))


def score_model(*, bundle: ModelBundle, events_by_trial: Dict[str, tuple], name: str,
                rules: Sequence[DecisionRule], audio_rate: float, wrench_rate: float,
                jobs: int) -> List[SweepRow]:
    """
    Score every rule with a trained model (no training): its features, labels and forest.

    ``events_by_trial`` comes from :func:`decode_bags`; ``name`` labels the rows. A model that
    measures the carried load also gets the load path's column, as the detector computes it.
    """
    config = bundle.feature_config.with_rule_columns()
    frames = compute_frames(events_by_trial=events_by_trial, config=config,
                            audio_rate=audio_rate, wrench_rate=wrench_rate, jobs=jobs)
    setting = FeatureSetting(name, config, LabelWindow(**bundle.label_window),
                             columns=bundle.feature_names)
    return score_rules(forest=bundle.compile(), frames=list(frames.values()), setting=setting,
                       rules=rules)


def trial_frames(*, events, truth: Truth, config: FeatureConfig, audio_rate: float,
                 wrench_rate: float, augmentation: Optional[WrenchAugmentation] = None,
                 augment_seed: Sequence[int] = (0,)) -> TrialFrames:
    """Compute one trial's valid feature frames with the streaming core (optionally augmented)."""
    if augmentation is not None:
        events = augment_events(events, augmentation=augmentation, seed=augment_seed)
    # noise_jump_n=0: the noise check only holds releases off, and training makes none; the
    # features are the same with it on (test_noise.py), at about 3 % more time
    extractor = StreamingFeatureExtractor(config=config, audio_rate=audio_rate,
                                          ft_input_rate=wrench_rate, noise_jump_n=0.0)
    frames = run_features(events, extractor=extractor)
    t0 = float(frames.t[0]) if len(frames) else 0.0
    kept = np.flatnonzero(frames.valid)
    breaks = tuple(int(i) for i in np.flatnonzero(np.diff(kept) > 1) + 1)
    return TrialFrames(truth=truth, t=frames.t[kept], x=frames.x[kept], t0=t0, breaks=breaks)


def compute_frames(*, events_by_trial: Dict[str, tuple], config: FeatureConfig,
                   audio_rate: float, wrench_rate: float, jobs: int,
                   augmentation: Optional[WrenchAugmentation] = None,
                   seed: int = 0) -> Dict[str, TrialFrames]:
    """
    Feature frames of every trial; ``events_by_trial`` maps name -> (events, truth).

    With ``augmentation``, each trial's wrench is varied first, drawn from
    ``trial_seed(seed=seed, name=name)`` (:mod:`contact_detector.training.augmentation`).
    """
    names = sorted(events_by_trial)
    frames = Parallel(n_jobs=jobs)(
        delayed(trial_frames)(events=events_by_trial[n][0], truth=events_by_trial[n][1],
                              config=config, audio_rate=audio_rate, wrench_rate=wrench_rate,
                              augmentation=augmentation,
                              augment_seed=trial_seed(seed=seed, name=n))
        for n in names)
    return dict(zip(names, frames))


def setting_columns(setting: FeatureSetting) -> np.ndarray:
    """Return the indices of ``setting``'s columns among its configuration's features."""
    names = setting.config.feature_names
    if setting.columns is None:
        return np.arange(len(names))
    return np.array([names.index(c) for c in setting.columns])


def fit_forest(*, frames: Sequence[TrialFrames], setting: FeatureSetting, n_estimators: int,
               seed: int, jobs: int, min_samples_leaf: int = 1,
               splitter: str = 'best') -> RandomForestClassifier:
    """
    Train the protocol's forest on the given trials (:func:`~.protocol.make_forest`).

    ``min_samples_leaf`` 1 = the paper's fully grown trees; ConfigError below 1.
    ``splitter`` ``'best'`` (a random forest) or ``'random'`` (extremely randomized trees,
    a scikit-learn ``ExtraTreesClassifier``); ConfigError for anything else. The frames
    near a trial's exogenous events weigh ``setting.label.event_weight``
    (:meth:`~.protocol.LabelWindow.weights`).
    """
    cols = setting_columns(setting)
    trained = [setting.label.trained(t=f.t, onsets=[f.truth.onset_t]) for f in frames]
    x = np.concatenate([f.x[keep][:, cols] for f, keep in zip(frames, trained)])
    y = np.concatenate([frame_labels(t=f.t[keep], onsets=[f.truth.onset_t],
                                     start_s=setting.label.start_s, end_s=setting.label.end_s)
                        for f, keep in zip(frames, trained)])
    weights = stack_weights([setting.label.weights(t=f.t[keep], onsets=[f.truth.onset_t],
                                                   exogenous=[e[0] for e in f.truth.impacts])
                             for f, keep in zip(frames, trained)],
                            sizes=[int(keep.sum()) for keep in trained])
    forest = make_forest(n_estimators=n_estimators, seed=seed, jobs=jobs,
                         min_samples_leaf=min_samples_leaf, splitter=splitter)
    return forest.fit(x, y, sample_weight=weights)


def p_contact(forest: object, x: np.ndarray) -> np.ndarray:
    """Return P(contact) per row, shape (n,), of a scikit-learn forest or a CompiledForest."""
    if isinstance(forest, CompiledForest):
        return forest.predict_proba(x)
    return forest.predict_proba(x)[:, 1]


def decide_trial(*, frames: TrialFrames, p: np.ndarray, rule: DecisionRule,
                 names: Sequence[str], warmup_s: float = 0.5) -> Tuple[np.ndarray, list, list]:
    """
    Decide one trial's frames with ``rule`` as the detector does.

    Parameters
    ----------
    frames : TrialFrames
        The trial's valid frames (``t``, s, shape (n,); ``x``, shape (n, len(names))).
    p : np.ndarray, shape (n,)
        P(contact) per frame.
    rule : DecisionRule
        The release rule; its load paths read ``names``' load columns (``rule_inputs``).
    names : sequence of str
        The names of ``frames.x``'s columns.
    warmup_s : float
        Frames before ``frames.t0 + warmup_s`` may not release (the detector's warm-up), s.

    Returns
    -------
    contact : np.ndarray, shape (n,), bool
        The rule's decision per frame.
    releases, events : list of float
        Release and contact-event times, s.

    Notes
    -----
    Before each of ``frames.breaks`` one invalid frame (P 0) is decided: the detector's
    invalid frames there (an F/T restart) empty the rule's history, and one does what they do.

    """
    at = np.asarray(frames.breaks, dtype=int)
    valid = np.insert(np.ones(frames.t.size, bool), at, False)
    inputs = {k: None if v is None else np.insert(v, at, 0.0)
              for k, v in rule_inputs(names=names, x=frames.x).items()}
    logic = ReleaseLogic(rule=rule, armed=True)
    contact, releases = logic.step(t=np.insert(frames.t, at, frames.t[at]),
                                   p=np.insert(p, at, 0.0), valid=valid,
                                   blocked=np.insert(frames.t < frames.t0 + warmup_s, at, False),
                                   **inputs)
    return contact[valid], releases, list(logic.last_events)


def score_rules(*, forest: object, frames: Sequence[TrialFrames],
                setting: FeatureSetting, rules: Sequence[DecisionRule],
                warmup_s: float = 0.5) -> List[SweepRow]:
    """
    Score every rule on held-out trials with one trained forest.

    ``forest`` is a fitted ``RandomForestClassifier`` or a :class:`CompiledForest` (e.g.
    ``bundle.compile()`` of an npz model); both give the same probabilities. A rule with the
    load path reads the setting's ``force_carried_shift`` and ``force_carried_shift_cos``
    columns (ConfigError without them).
    """
    cols = setting_columns(setting)
    names = setting.config.feature_names
    if any(rule.uses_load for rule in rules) and not set(RULE_FEATURES) <= set(names):
        raise ConfigError(f'a rule with the load path needs the {" and ".join(RULE_FEATURES)} '
                          f'columns, which setting {setting.name} does not compute')
    probs = [p_contact(forest, f.x[:, cols]) if f.x.shape[0] else np.zeros(0)
             for f in frames]
    labels = [frame_labels(t=f.t, onsets=[f.truth.onset_t], start_s=setting.label.start_s,
                           end_s=setting.label.end_s) for f in frames]
    y = np.concatenate(labels)
    rows = []
    for rule in rules:
        outcomes = []
        pred = []
        for f, p in zip(frames, probs):
            contact, releases, events = decide_trial(frames=f, p=p, rule=rule, names=names,
                                                     warmup_s=warmup_s)
            outcomes.append(score_trial(truth=f.truth, releases=releases, events=events))
            pred.append(contact)
        yp = np.concatenate(pred)
        tp = int(np.sum(yp & (y == 1)))
        precision = tp / max(1, int(yp.sum()))
        recall = tp / max(1, int(y.sum()))
        rows.append(SweepRow(setting=setting.name,
                             rule=rule.short(),
                             summary=summarize(outcomes), precision=precision,
                             recall=recall, outcomes=tuple(outcomes)))
    return rows


def rows_markdown(rows: Sequence[SweepRow]) -> str:
    """Return the sweep table as markdown."""
    lines = ['| setting | rule | detected | missed+late | premature | latency median [ms] | '
             'p95 [ms] | impact events | frame precision | frame recall |',
             '|---|---|---|---|---|---|---|---|---|---|']
    for r in rows:
        s = r.summary

        def ms(v):
            return '-' if v is None else f'{v:.0f}'
        lines.append(f"| {r.setting} | {r.rule} | {s['detected']}/{s['trials']} | "
                     f"{s['missed'] + s['late']} | {s['premature']} | "
                     f"{ms(s['latency_ms_median'])} | {ms(s['latency_ms_p95'])} | "
                     f"{s['impact_events']} | {r.precision:.2f} | {r.recall:.2f} |")
    return '\n'.join(lines)


def score_over_seeds(*, train: Sequence[TrialFrames], heldout: Sequence[TrialFrames],
                     setting: FeatureSetting, rules: Sequence[DecisionRule],
                     seeds: Sequence[int], n_estimators: int, jobs: int) -> List[dict]:
    """
    Train one forest per seed and sum each rule's scores over the seeds.

    A 10-tree forest is a noisy estimator: another seed moves the count of premature releases
    on a few hundred held-out trials by several, so one forest cannot tell two close settings
    apart; the sum over seeds can.

    Returns
    -------
    list of dict
        Per rule, in order: ``setting``, ``rule``, ``detected``, ``trials``, ``miss`` (missed
        + late), ``premature``, ``impact`` (events blamed on exogenous impacts), all summed
        over the seeds, and ``medians`` (each seed's median latency, ms).

    """
    totals = [{'setting': setting.name, 'rule': rule.short(), 'detected': 0, 'trials': 0,
               'miss': 0, 'premature': 0, 'impact': 0, 'medians': []} for rule in rules]
    for seed in seeds:
        forest = fit_forest(frames=train, setting=setting, n_estimators=n_estimators,
                            seed=seed, jobs=jobs)
        for total, row in zip(totals, score_rules(forest=forest, frames=heldout,
                                                  setting=setting, rules=rules)):
            s = row.summary
            total['detected'] += s['detected']
            total['trials'] += s['trials']
            total['miss'] += s['missed'] + s['late']
            total['premature'] += s['premature']
            total['impact'] += s['impact_events']
            if s['latency_ms_median'] is not None:
                total['medians'].append(s['latency_ms_median'])
    return totals


def seed_rows_markdown(totals: Sequence[dict], *, seeds: Sequence[int]) -> str:
    """Return :func:`score_over_seeds` rows as markdown (latency: median of the medians)."""
    lines = [f'Forest seeds {list(seeds)}; counts summed over the seeds, latency = median of '
             'the per-seed medians (range).', '',
             '| setting | rule | detected | missed+late | premature | impact events | '
             'latency median [ms] |', '|---|---|---|---|---|---|---|']
    for t in totals:
        m = np.array(t['medians'])
        latency = f'{np.median(m):.0f} ({m.min():.0f}-{m.max():.0f})' if m.size else '-'
        lines.append(f"| {t['setting']} | {t['rule']} | {t['detected']}/{t['trials']} | "
                     f"{t['miss']} | {t['premature']} | {t['impact']} | {latency} |")
    return '\n'.join(lines)


def best_row(rows: Sequence[SweepRow]) -> Optional[SweepRow]:
    """Zero premature first, then most detected, then lowest median latency."""
    def key(r: SweepRow):
        s = r.summary
        latency = s['latency_ms_median'] if s['latency_ms_median'] is not None else 1e9
        return (s['premature'], -s['detected'], s['impact_events'], latency)
    return min(rows, key=key) if rows else None


@dataclass
class FamilyRow:
    """One left-out family: the forest trained on every other family, scored on this one."""

    family: str
    rows: List[SweepRow]


def leave_one_family_out(*, frames: Sequence[TrialFrames], setting: FeatureSetting,
                         rules: Sequence[DecisionRule], n_estimators: int, seed: int,
                         jobs: int, families: Optional[Sequence[str]] = None,
                         fit_frames: Optional[Sequence[TrialFrames]] = None,
                         min_samples_leaf: int = 1,
                         splitter: str = 'best') -> List[FamilyRow]:
    """
    Train on all families but one, score every rule on the one left out; once per family.

    A family is a trial's ``truth.condition`` (the simulator's condition set, or the name a
    user gives a folder of recordings). The figure to quote is the worst family, not the
    pooled mean: a family left out stands for a robot, a room or a controller the model has
    never seen.

    Parameters
    ----------
    frames : sequence of TrialFrames
        Every trial, every family.
    setting : FeatureSetting
        Feature columns and label window.
    rules : sequence of DecisionRule
        Rules scored with each fold's forest.
    n_estimators, seed, jobs : int
        The forest (as :func:`fit_forest`).
    families : sequence of str, optional
        The families to leave out in turn (default: every family present).
    fit_frames : sequence of TrialFrames, optional
        The frames the forests are trained on (e.g. the same trials augmented), grouped by
        the same families; default ``frames``. The left-out family is always scored on
        ``frames``.
    min_samples_leaf, splitter
        Of every fold's forest (as :func:`fit_forest`).

    Returns
    -------
    list of FamilyRow
        One per family left out, in the order given (or sorted), each with one row per rule.

    """
    present = sorted({f.truth.condition for f in frames})
    out = []
    for family in (families or present):
        test = [f for f in frames if f.truth.condition == family]
        fit = [f for f in (frames if fit_frames is None else fit_frames)
               if f.truth.condition != family]
        if not test or not fit:
            continue
        forest = fit_forest(frames=fit, setting=setting, n_estimators=n_estimators, seed=seed,
                            jobs=jobs, min_samples_leaf=min_samples_leaf, splitter=splitter)
        out.append(FamilyRow(family=family,
                             rows=score_rules(forest=forest, frames=test, setting=setting,
                                              rules=rules)))
    return out


def worst_family(summaries: Sequence[dict]) -> Optional[dict]:
    """
    Return the worst of per-family summaries: most premature, fewest caught, slowest.

    Parameters
    ----------
    summaries : sequence of dict
        :func:`contact_detector.evaluation.metrics.summarize` outputs, one per family.

    Returns
    -------
    dict or None
        The worst summary (None for no families).

    """
    def key(s: dict):
        latency = s['latency_ms_median'] if s['latency_ms_median'] is not None else 1e9
        caught = s['detected'] / max(1, s['trials'])
        return (-s['premature'], caught, -latency)
    return min(summaries, key=key) if summaries else None
