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
The studies of ``contact-detector sweep``, each as markdown tables.

The feature grids, the ablation, leave one family out, and the rules on a trained model.

The building blocks (decoding, frames, forests, scoring a rule) are in
:mod:`contact_detector.training.sweep`; this module holds which settings and rules each study
compares and how its table reads.
"""

from dataclasses import replace
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence

from contact_detector.errors import ConfigError
from contact_detector.evaluation.metrics import premature_text, summarize
from contact_detector.evaluation.truth import knocked_in_air
from contact_detector.features.config import (CARRIED_FEATURES, CARRIED_SHIFT_FEATURES,
                                              EXTRA_FEATURES, FeatureConfig, ROUGH_FEATURES)
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.rule import DecisionRule
from contact_detector.training.augmentation import AUGMENTED, WrenchAugmentation
from contact_detector.training.protocol import (check_min_samples_leaf, check_splitter,
                                                LabelWindow)
from contact_detector.training.recipe import (DEFAULT_FEATURES, DEFAULT_FT_ONLY_RULE,
                                              DEFAULT_RULE, PREVIOUS_RULE)
from contact_detector.training.sweep import (best_row, compute_frames, FeatureSetting,
                                             fit_forest, leave_one_family_out, model_rules,
                                             rows_markdown, rule_grid, score_model,
                                             score_over_seeds, score_rules, worst_family)
import numpy as np

#: The extra features of the first grids.
EXTRAS = ('audio_power_rel_db', 'audio_peak_rel_db', 'force_delta', 'torque_delta')
#: The audio features measured against the tracked noise floor, and the two onset features.
ONSET_AUDIO = ('audio_rise_db', 'audio_peak_gap_db')
RELATIVE_AUDIO = ('audio_power_rel_db', 'audio_peak_rel_db') + ONSET_AUDIO
#: The recent maxima of the signed F/T changes.
CHANGE_MAX = ('force_change_max', 'torque_change_max')
ONSET = LabelWindow(0.0, 0.1)
STATE = LabelWindow(0.0, 0.3)
#: ``sweep``'s augmentation for a range not given: a tare on a quarter of the trials, lever arms
#: x0.5-2, none of the other three. Not the shipped recipe's (``training/recipe.py``), so that a
#: sweep command written down keeps the meaning it had; the shipped protocols give every range.
STUDY_AUGMENTATION = WrenchAugmentation()


_SPECTRAL = ('force_centroid', 'force_spread', 'force_flux', 'torque_centroid', 'torque_spread',
             'torque_flux')
_SHIFT = ('force_shift', 'torque_shift', 'force_shift_min', 'torque_shift_min',
          'force_shift_max', 'torque_shift_max')
_SIGNED = ('force_change', 'torque_change', 'force_change_max', 'torque_change_max')
_HOLD = ('force_change_hold', 'torque_change_hold', 'force_shift_hold', 'torque_shift_hold')
#: The feature settings --lofo compares: name -> columns (None: the shipped model's).
LOFO_SETTINGS = {
    'shipped': None,
    # the model shipped before the carried-load features (2026-11-24), in its column order
    'previous': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + _SIGNED + _SHIFT,
    'angles': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + (
        'force_delta', 'torque_delta', 'ft_delta_angle', 'force_change', 'torque_change',
        'ft_change_angle', 'force_change_max', 'torque_change_max'),
    'invariant': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + _SHIFT,
    'invariant-no-raw-power': _SPECTRAL + RELATIVE_AUDIO + _SHIFT,
    'invariant+signed': ('audio_power',) + _SPECTRAL + RELATIVE_AUDIO + _SHIFT + _SIGNED,
    'ft-only': _SPECTRAL + _SHIFT,
    'ft-only+signed': _SPECTRAL + _SHIFT + _SIGNED,
    'ft-only+signed+hold': _SPECTRAL + _SHIFT + _SIGNED + _HOLD,
    # the carried-load features of the multimodal model: a knock on the hand does not take
    # the carried load off, a table does
    'ft-only+signed+carried': _SPECTRAL + _SHIFT + _SIGNED + CARRIED_FEATURES,
    'ft-only+signed+carried+hold': _SPECTRAL + _SHIFT + _SIGNED + CARRIED_FEATURES + _HOLD,
    'ft-only+signed+max20': _SPECTRAL + _SHIFT + _SIGNED,
    'ft-only+signed+max30': _SPECTRAL + _SHIFT + _SIGNED,
    'ft-only+signed+w32': _SPECTRAL + _SHIFT + _SIGNED,
    # the shipped columns and the share of the carried torque against that of the carried
    # force that changed: a table takes the weight off under the centre of mass, a brush or a
    # knock pushes elsewhere (docs/decisions/2026-11-24-brush-lever-not-shipped.md)
    'lever': tuple(DEFAULT_FEATURES.feature_names) + ('ft_carried_lever',),
    # the shipped columns and the quietest of the last 4 (8) audio frames above the floor: a
    # brush scrapes for 0.15-0.6 s, a touch clicks for tens of ms (issue #14)
    'scrape4': tuple(DEFAULT_FEATURES.feature_names) + ('audio_hold_db',),
    'scrape8': tuple(DEFAULT_FEATURES.feature_names) + ('audio_hold_db',),
    # the shipped columns with the recent audio peak held over 0.3 or 0.2 s instead of 0.1 s:
    # a slow transfer's click is then still in view while its load moves (issue #14)
    'peak30': tuple(DEFAULT_FEATURES.feature_names),
    'peak20': tuple(DEFAULT_FEATURES.feature_names),
    # the shipped columns (the F/T-only model's) and the distance from the carried load with
    # its recent minimum: the whole transfer since the arming, however slowly it came (a
    # guard's |F - F_rest|; issue #14)
    'cshift': tuple(DEFAULT_FEATURES.feature_names) + CARRIED_SHIFT_FEATURES,
    # the shipped columns and how rough the force is, alone and against how rough it was
    # shift_lag samples earlier: the arm brushing something changes the load by a force that
    # fluctuates as it slips, a table takes it off smoothly
    # (docs/decisions/2026-11-28-force-roughness.md)
    'rough': tuple(DEFAULT_FEATURES.feature_names) + ROUGH_FEATURES,
    'ft-only+signed+carried+cshift': (_SPECTRAL + _SHIFT + _SIGNED + CARRIED_FEATURES
                                      + CARRIED_SHIFT_FEATURES),
}
#: The settings of :data:`LOFO_SETTINGS` whose features are computed with other
#: :class:`~contact_detector.features.config.FeatureConfig` fields: name -> the fields changed
#: (``+max20``, ``+max30``: the ``*_change_max`` / ``*_shift_max`` window shortened from 50 F/T
#: feature frames, so that a knock on the hand 0.2-0.5 s before a touch has left it; ``+w32``:
#: the F/T spectra over 32 samples instead of 64, so that they forget a knock's ringing sooner;
#: ``scrape4``, ``scrape8``: ``audio_hold_db`` over 4 or 8 audio frames, 40 or 80 ms;
#: ``peak20``, ``peak30``: ``audio_peak_rel_db`` and ``audio_peak_gap_db`` over 20 or 30 audio
#: frames, not 10).
LOFO_CONFIG_CHANGES = {
    'ft-only+signed+max20': {'change_max_frames': 20},
    'ft-only+signed+max30': {'change_max_frames': 30},
    'ft-only+signed+w32': {'ft_window': 32},
    'scrape4': {'audio_hold_frames': 4},
    'scrape8': {'audio_hold_frames': 8},
    'peak20': {'peak_frames': 20},
    'peak30': {'peak_frames': 30},
}


def feature_grid(name: str) -> List[FeatureSetting]:
    """Return the feature settings to try: 'compare', 'focus' or 'full' (both)."""
    paper = FeatureConfig.paper()
    base = FeatureConfig(ft_window=32, ft_hop=1)
    ours = FeatureConfig(ft_detrend='mean', extra_features=EXTRAS)
    compare = [
        FeatureSetting('paper W160 H128, onset labels', paper, ONSET),
        FeatureSetting('W32 H1, onset labels', base, ONSET),
        FeatureSetting('W32 H1, state labels', base, STATE),
        FeatureSetting('W32 H1 detrend, state labels', FeatureConfig(ft_detrend='mean'), STATE),
        FeatureSetting('W32 H1 detrend+extras, onset labels', ours, ONSET),
        FeatureSetting('W32 H1 detrend+extras, state labels', ours, STATE),
    ]
    focus = [
        FeatureSetting('detrend+extras, state labels, delta lag 5',
                       replace(ours, delta_lag=5), STATE),
        FeatureSetting('detrend+extras, state labels, delta lag 3',
                       replace(ours, delta_lag=3, delta_window=2), STATE),
        FeatureSetting('detrend+extras, labels 0-0.2 s', ours, LabelWindow(0.0, 0.2)),
        FeatureSetting('detrend+extras, labels 0-0.5 s', ours, LabelWindow(0.0, 0.5)),
        FeatureSetting('W16 H1 detrend+extras, state labels', replace(ours, ft_window=16),
                       STATE),
        FeatureSetting('W64 H1 detrend+extras, state labels', replace(ours, ft_window=64),
                       STATE),
        FeatureSetting('W32 H4 detrend+extras, state labels', replace(ours, ft_hop=4), STATE),
        FeatureSetting('audio 16 ms / 5 ms, detrend+extras, state labels',
                       replace(ours, audio_frame_s=0.016, audio_hop_s=0.005), STATE),
    ]
    return {'compare': compare, 'focus': focus, 'full': compare + focus, 'none': []}[name]


def ablation_settings() -> List[FeatureSetting]:
    """Return the settings compared on held-out condition sets (the shipped window, W64)."""
    full = DEFAULT_FEATURES
    paper7 = replace(full, ft_detrend='none', extra_features=())
    return [
        FeatureSetting('paper 7 features, no detrend', paper7, STATE),
        FeatureSetting('paper 7, detrend', replace(paper7, ft_detrend='mean'), STATE),
        FeatureSetting('detrend + extras (shipped)', full, STATE),
        FeatureSetting('shipped, without the vector shifts', full, STATE,
                       columns=tuple(n for n in full.feature_names if n not in _SHIFT)),
        FeatureSetting('shipped, without raw audio power', full, STATE,
                       columns=tuple(n for n in full.feature_names if n != 'audio_power')),
        FeatureSetting('shipped, without the *_change_max features', full, STATE,
                       columns=tuple(n for n in full.feature_names if n not in CHANGE_MAX)),
        FeatureSetting('shipped, without the audio onset features', full, STATE,
                       columns=tuple(n for n in full.feature_names if n not in ONSET_AUDIO)),
        FeatureSetting('shipped, without the dB-above-floor features', full, STATE,
                       columns=tuple(n for n in full.feature_names
                                     if n not in RELATIVE_AUDIO)),
        FeatureSetting('audio only (power, dB above floor, its peak, rise and gap)', full, STATE,
                       columns=('audio_power',) + RELATIVE_AUDIO),
        FeatureSetting('F/T only', full, STATE,
                       columns=tuple(n for n in full.feature_names
                                     if not n.startswith('audio'))),
        FeatureSetting('reduced: dB above floor, recent peak, torque centroid/spread, shifts',
                       full, STATE,
                       columns=('audio_power_rel_db', 'audio_peak_rel_db', 'torque_centroid',
                                'torque_spread', 'force_shift', 'torque_shift',
                                'force_shift_min')),
    ]


def lofo_rules() -> List[DecisionRule]:
    """
    Return the rules --lofo scores: the shipped rule, faster, slower and evidence paths.

    The shipped rule first; each variant with the slow path at 0.4 (shipped) and at 0.3 (the
    rule shipped before, :data:`~contact_detector.training.recipe.PREVIOUS_RULE`), so tables
    measured before and after the change score the same rules. Last, the shipped rule with a
    stricter slow path (0.45, 0.5): two forests are compared at equal early releases by
    moving that threshold (docs/decisions/2026-11-29-ignore-the-rest-on-the-generators.md).
    """
    rules = [DEFAULT_RULE, PREVIOUS_RULE]
    rules += [replace(PREVIOUS_RULE, threshold=th) for th in (0.8, 0.9)]
    # Slower and safer (the F/T-only model against knocks on the hand): confirmation frames
    # and a stricter slow path.
    rules += [replace(PREVIOUS_RULE, confirm_frames=cf) for cf in (2, 3)]
    rules += [replace(DEFAULT_RULE, confirm_frames=3)]
    rules += [replace(DEFAULT_RULE, threshold=th) for th in (0.8, 0.9)]
    rules += [replace(DEFAULT_RULE, evidence_threshold=h, evidence_drift=0.3)
              for h in (1.0, 1.5)]
    rules += [replace(PREVIOUS_RULE, evidence_threshold=h, evidence_drift=d)
              for d in (0.3, 0.4, 0.5) for h in (0.5, 1.0, 1.5, 2.5)]
    rules += [replace(DEFAULT_RULE, sustain_threshold=st) for st in (0.45, 0.5)]
    return rules


def grid_study(*, train: Dict[str, tuple], heldout: Dict[str, tuple],
               settings: Sequence[FeatureSetting], seeds: Optional[Sequence[int]], seed: int,
               audio_rate: float, wrench_rate: float, jobs: int,
               progress: Callable[[Iterable], Iterable] = iter) -> tuple:
    """
    Train a forest per feature setting on ``train``, score :func:`rule_grid` on ``heldout``.

    With ``seeds``, one forest per seed and the counts summed
    (:func:`~contact_detector.training.sweep.score_over_seeds`); else one forest of ``seed``.

    Returns
    -------
    (rows, best_rows, totals)
        Every :class:`SweepRow`, the best per setting (:func:`best_row`), and the seed sums.

    """
    rules = rule_grid()
    rows, best_rows, totals = [], [], []
    cache = {}
    for setting in progress(settings):
        key = setting.config
        if key not in cache:
            cache = {key: (compute_frames(events_by_trial=train, config=key,
                                          audio_rate=audio_rate,
                                          wrench_rate=wrench_rate, jobs=jobs),
                           compute_frames(events_by_trial=heldout, config=key,
                                          audio_rate=audio_rate,
                                          wrench_rate=wrench_rate, jobs=jobs))}
        train_frames, heldout_frames = cache[key]
        if seeds:
            totals += score_over_seeds(train=list(train_frames.values()),
                                       heldout=list(heldout_frames.values()), setting=setting,
                                       rules=rules, seeds=seeds, n_estimators=10,
                                       jobs=jobs)
            continue
        forest = fit_forest(frames=list(train_frames.values()), setting=setting,
                            n_estimators=10, seed=seed, jobs=jobs)
        scored = score_rules(forest=forest, frames=list(heldout_frames.values()),
                             setting=setting, rules=rules)
        rows += scored
        best_rows.append(best_row(scored))
    return rows, best_rows, totals


def lofo_setting(name: str, *, label: LabelWindow) -> tuple[FeatureSetting, bool]:
    """
    Return the feature setting a ``--lofo`` setting name stands for, and whether it is augmented.

    ``name`` is a key of :data:`LOFO_SETTINGS`, optionally ending in
    :data:`~contact_detector.training.augmentation.AUGMENTED`. Its configuration is the shipped
    one with every extra feature and the fields of :data:`LOFO_CONFIG_CHANGES` changed; its
    columns are the setting's (all of the shipped model's when the entry is None). The
    leave-one-family-out diagnostics in ``benchmarks/`` resolve names the same way.
    """
    base = name.removesuffix(AUGMENTED)
    config = replace(DEFAULT_FEATURES, extra_features=EXTRA_FEATURES,
                     **LOFO_CONFIG_CHANGES.get(base, {}))
    columns = LOFO_SETTINGS[base] or DEFAULT_FEATURES.feature_names
    return FeatureSetting(name, config, label, columns=tuple(columns)), name.endswith(AUGMENTED)


def lofo_study(*, trials: Dict[str, tuple], settings: Sequence[str], label: LabelWindow,
               trees: int, seed: int, audio_rate: float, wrench_rate: float, jobs: int,
               augmentation: WrenchAugmentation = STUDY_AUGMENTATION,
               seeds: Sequence[int] = (), min_samples_leaf: int = 1,
               splitter: str = 'best', families: Optional[Sequence[str]] = None,
               load: Optional[Dict[str, Any]] = None,
               train_only: Optional[Dict[str, tuple]] = None,
               progress: Callable[[Iterable], Iterable] = iter) -> str:
    """
    Leave-one-family-out over the pooled trials; per setting and rule the worst family.

    ``trials`` comes from :func:`~contact_detector.training.sweep.decode_bags`; ``settings``
    are names of :data:`LOFO_SETTINGS`, column subsets of one feature configuration (the
    shipped one with every extra feature, with the fields of :data:`LOFO_CONFIG_CHANGES`
    changed for the settings there) computed once per trial and configuration. The trials with
    a knock on the hand in the air (:func:`~contact_detector.evaluation.truth.knocked_in_air`)
    are also scored together, each while its family is left out. A name ending in
    :data:`~contact_detector.training.augmentation.AUGMENTED` (``shipped+aug``) trains the
    forests on the same trials with their wrenches varied by ``augmentation`` (drawn from
    ``seed`` and each trial's name); the left-out family is never augmented. With ``seeds``,
    every fold trains one forest per seed and each family's row pools the outcomes of all of
    them (``n`` trials x ``len(seeds)``), so that two settings are not told apart by one
    forest's randomness; else one forest of ``seed``. Every forest has ``trees`` trees,
    ``min_samples_leaf`` (1: fully grown, the paper's) and ``splitter`` (``'best'``, random
    forests; ``'random'``, extremely randomized trees) and learns ``label``: the contact
    frames, the frames left out after them and the weight of the frames near an exogenous
    event (:class:`~.protocol.LabelWindow`).
    ``families`` leaves only those families out in turn (every forest still trains on all the
    others; default: every family, the figure to choose by); a name no trial has raises
    ConfigError. ``load`` (the load paths' :class:`DecisionRule` fields) adds the shipped rule
    with those load paths, second after the shipped rule (see :func:`load_rules`), then the
    same with the F/T-only model's slow path (``DEFAULT_FT_ONLY_RULE.sustain_threshold``).
    ``train_only`` (the form of ``trials``, other keys: a shared one raises ConfigError) are
    trials every fold also trains on, augmented as the others, except those of the family
    left out, and none is scored: a learning curve on the same scored trials. Returns
    markdown.
    """
    check_min_samples_leaf(min_samples_leaf)
    check_splitter(splitter)
    present = {events_truth[1].condition for events_truth in trials.values()}
    unknown = sorted(set(families or ()) - present)
    if unknown:
        raise ConfigError(f'no trials of the families {unknown} (the folders hold '
                          f'{sorted(present)})')
    shared = sorted(set(trials) & set(train_only or {}))
    if shared:
        raise ConfigError(f'trials both scored and only trained on: {shared[:3]}')
    cache: Dict[tuple, list] = {}

    def frames_of(config: FeatureConfig, augmented: bool, scored: bool = True) -> list:
        if (config, augmented, scored) not in cache:
            cache[config, augmented, scored] = list(compute_frames(
                events_by_trial=trials if scored else train_only, config=config,
                audio_rate=audio_rate, wrench_rate=wrench_rate, jobs=jobs,
                augmentation=augmentation if augmented else None, seed=seed).values())
        return cache[config, augmented, scored]

    def training_frames(config: FeatureConfig, augmented: bool) -> Optional[list]:
        if not augmented and not train_only:
            return None
        return (frames_of(config, augmented)
                + (frames_of(config, augmented, scored=False) if train_only else []))

    rules = lofo_rules()
    # the load paths on the multimodal model's slow path (0.4, the F/T-only rule before
    # 2026-12-07) and on the F/T-only model's (0.45), so that tables of either are rerun
    ft_base = replace(DEFAULT_RULE, sustain_threshold=DEFAULT_FT_ONLY_RULE.sustain_threshold)
    rules[1:1] = (load_rules(base=DEFAULT_RULE, load=load)
                  + load_rules(base=ft_base, load=load))
    worst_lines = ['| setting | rule | worst family | detected | premature (after) | '
                   'median [ms] | p95 [ms] | all families: detected / premature | '
                   'knocked on the hand, all families: detected / premature / median [ms] |',
                   '|---|---|---|---|---|---|---|---|---|']
    family_lines = ['| setting | rule | family | detected | premature (after) | '
                    'impact events | median [ms] | p95 [ms] |',
                    '|---|---|---|---|---|---|---|---|']
    for name in progress(settings):
        setting, augmented = lofo_setting(name, label=label)
        config = setting.config
        frames = frames_of(config, False)
        knocked = {}
        for f in frames:
            knocked.setdefault(f.truth.condition, []).append(knocked_in_air(f.truth))
        pooled: Dict[tuple, list] = {}
        pooled_knocked: Dict[int, list] = {}
        for forest_seed in (seeds or (seed,)):
            for fold in leave_one_family_out(frames=frames, setting=setting, rules=rules,
                                             n_estimators=trees, seed=forest_seed, jobs=jobs,
                                             fit_frames=training_frames(config, augmented),
                                             families=families,
                                             min_samples_leaf=min_samples_leaf,
                                             splitter=splitter):
                for k, row in enumerate(fold.rows):
                    pooled.setdefault((k, fold.family), []).extend(row.outcomes)
                    # the fold's test trials are its family's frames, in order
                    pooled_knocked.setdefault(k, []).extend(
                        o for o, hit in zip(row.outcomes, knocked[fold.family]) if hit)
        scored = sorted({family for _, family in pooled})
        for k, rule in enumerate(rules):
            summaries = []
            for family in scored:
                s = dict(summarize(pooled[(k, family)]), family=family)
                summaries.append(s)
                family_lines.append(f'| {name} | {rule.short()} | {family} | '
                                    f"{s['detected']}/{s['trials']} | {premature_text(s)} | "
                                    f"{s['impact_events']} | {_ms(s['latency_ms_median'])} | "
                                    f"{_ms(s['latency_ms_p95'])} |")
            w = worst_family(summaries)
            if w is None:
                continue
            total = sum(s['detected'] for s in summaries)
            trials_n = sum(s['trials'] for s in summaries)
            early = sum(s['premature'] for s in summaries)
            kn = summarize(pooled_knocked.get(k, []))
            worst_lines.append(f"| {name} | {rule.short()} | {w['family']} | "
                               f"{w['detected']}/{w['trials']} | {premature_text(w)} | "
                               f"{_ms(w['latency_ms_median'])} | {_ms(w['latency_ms_p95'])} | "
                               f'{total}/{trials_n} / {early} | '
                               f"{kn['detected']}/{kn['trials']} / {kn['premature']} / "
                               f"{_ms(kn['latency_ms_median'])} |")
    kind = '' if splitter == 'best' else 'extremely randomized trees, '
    forests = (f'Forests: {trees} trees, {kind}min_samples_leaf {min_samples_leaf}, '
               f"seeds {', '.join(str(k) for k in (seeds or (seed,)))} (each family's row pools "
               'them).')
    if label.event_weight != 1.0:
        forests += (f' The frames near a simulated exogenous event weigh {label.event_weight:g} '
                    'in training.')
    if families:
        forests += (f" Left out: only {', '.join(families)} (a screen; the worst family is "
                    'over these).')
    if train_only:
        forests += (f' Every fold also trains on {len(train_only)} trials that are never '
                    'scored (those of the family left out excepted).')
    return '\n'.join(['## Leave one family out: the worst family per setting and rule', '',
                      forests, '',
                      *worst_lines, '', '## Every family', '', *family_lines, ''])


def _ms(value) -> str:
    return '-' if value is None else f'{value:.0f}'


def ablation_study(*, trials: Dict[str, tuple], sustain: Sequence[float], seeds: Sequence[int],
                   audio_rate: float, wrench_rate: float, jobs: int,
                   progress: Callable[[Iterable], Iterable] = iter) -> str:
    """
    Leave-one-condition-out table for :func:`ablation_settings` (the shipped rule).

    For heavy, soft, noisy and gain: train on every trial of the other condition sets, score
    on that one, with the slow-path thresholds ``sustain``, summed over ``seeds``. Returns
    markdown.
    """
    everything = trials
    rules = [replace(DEFAULT_RULE, sustain_threshold=th) for th in sustain]
    lines = [f'Rule: {DEFAULT_RULE.short()} (slow-path thresholds '
             f"{', '.join(str(th) for th in sustain)}); forest of 10 trees "
             'trained on every trial of the other condition sets'
             + (f', counts summed over seeds {seeds}, latency the median of the per-seed '
                'medians.' if len(seeds) > 1 else '.'), '',
             '| setting | held-out condition | slow path | detected | premature | '
             'impact events | latency median [ms] |', '|---|---|---|---|---|---|---|']
    cache = {}
    for setting in progress(ablation_settings()):
        if setting.config not in cache:
            cache = {setting.config: compute_frames(
                events_by_trial=everything, config=setting.config,
                audio_rate=audio_rate, wrench_rate=wrench_rate, jobs=jobs)}
        frames = cache[setting.config]
        for condition in ('heavy', 'soft', 'noisy', 'gain'):
            fit = [f for f in frames.values() if f.truth.condition != condition]
            test = [f for f in frames.values() if f.truth.condition == condition]
            if not test:
                continue
            totals = score_over_seeds(train=fit, heldout=test, setting=setting, rules=rules,
                                      seeds=seeds, n_estimators=10, jobs=jobs)
            for rule, t in zip(rules, totals):
                median = '-' if not t['medians'] else f"{np.median(t['medians']):.0f}"
                slow = f'mean{rule.sustain_frames}>={rule.sustain_threshold}'
                lines.append(f'| {setting.name} | {condition} | {slow} | '
                             f"{t['detected']}/{t['trials']} | {t['premature']} | "
                             f"{t['impact']} | {median} |")
    return '\n'.join(lines)


def load_rules(*, base: DecisionRule, load: Optional[Dict[str, Any]]) -> List[DecisionRule]:
    """
    Return the rules a study adds for the load paths' fields ``load`` (None: none).

    ``base`` with the load path; when ``load`` turns the second load path on as well, first
    ``base`` with the load path alone and then with both, so that one run scores what the
    second path adds on the same forests.
    """
    if not load:
        return []
    rules = [replace(base, **load)]
    if load.get('load2_threshold', 0.0) > 0:
        rules.insert(0, replace(rules[0], load2_threshold=0.0))
    return rules


def model_study(*, bundle: ModelBundle, groups: Sequence[tuple], title: str,
                audio_rate: float, wrench_rate: float, jobs: int,
                load: Optional[Dict[str, Any]] = None) -> str:
    """
    Score :func:`model_rules` with a trained model on groups of trials; return markdown.

    ``groups``: ``(name, trials)`` pairs, ``trials`` from :func:`decode_bags`. ``load`` (the
    load paths' :class:`DecisionRule` fields) adds the model's rule with those load paths,
    second (see :func:`load_rules`).
    """
    rules = model_rules(bundle.decision_rule)
    rules[1:1] = load_rules(base=bundle.decision_rule, load=load)
    rules = list(dict.fromkeys(rules))
    text = [title, '']
    for name, trials in groups:
        if trials:
            text += [rows_markdown(score_model(bundle=bundle, events_by_trial=trials, name=name,
                                               rules=rules, audio_rate=audio_rate,
                                               wrench_rate=wrench_rate, jobs=jobs)),
                     '']
    return '\n'.join(text)
