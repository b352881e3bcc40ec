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
Variants of a shipped model's decision rule, each family left out, with the knocked trials.

    .venv/bin/python benchmarks/lofo_rules.py DIR... [--recipe ft-only|multimodal]
        [--rule NAME:FIELD=VALUE[,FIELD=VALUE...]]... [--seeds 0,1,2] [--jobs 2]
        [--families] [--json out.json] [--splitter best|random] [--drop GROUP]...
        [--train-only DIR]... [--outcomes OUT.json]

Trains the forests of ``contact-detector sweep --lofo`` with a shipped recipe (its feature
setting, labels, wrench augmentation and event weight: ``ft-only`` is
``tools/build_ft_model.sh``'s, ``multimodal`` is ``tools/build_model.sh``'s), one per family
left out and per seed, and scores on each left-out family the recipe's shipped rule (``S``)
and every ``--rule``: the shipped rule with the named fields changed (``th90:threshold=0.9``,
``th80c2st50:threshold=0.8,confirm_frames=2,sustain_threshold=0.5``; any field of
``DecisionRule``). ``sweep --lofo`` scores a fixed list of rules without the load paths; this
keeps the recipe's load paths in every variant, as the shipped model decides.

Prints one line per rule: caught within 500 ms and early over all families, the worst family
(most early releases, then fewest caught), and the trials knocked on the hand while the object
is in the air (issue #16's safety figure: caught, early, median latency); ``--families`` adds
one line per family. Every rule is scored with the same forests, so their differences are the
rule's alone. About 4 minutes per seed on the F/T-only pool of docs/offline.md (360 trials) on
two cores. ``--drop GROUP`` trains and scores the forests without a feature group of
:data:`GROUPS` (``benchmarks/generator_ablation.py``). ``--train-only DIR`` adds trials that
every fold trains on (augmented, except those of the family left out) and none is scored on,
keyed as ``sweep --lofo-train-only`` keys them, so ``S`` reproduces that sweep's row.
``--outcomes`` writes every rule's verdict on every trial and forest seed (the trial keyed by
its folder), which ``benchmarks/lofo_either.py`` combines with another recipe's.
"""

import argparse
from dataclasses import asdict, fields, replace
import json
from pathlib import Path
import sys
from typing import Dict, List, Optional, Sequence, Tuple

from contact_detector.evaluation.metrics import (Outcome, premature_text, summarize,
                                                 summarize_by_condition)
from contact_detector.evaluation.truth import knocked_in_air
from contact_detector.model.rule import DecisionRule
from contact_detector.training.protocol import SPLITTERS
from contact_detector.training.recipe import (DEFAULT_FT_ONLY_RULE, DEFAULT_RULE,
                                              recipe_defaults)
from contact_detector.training.studies import lofo_setting
from contact_detector.training.sweep import leave_one_family_out
from lofo_frames import load_frames

#: Each recipe's ``sweep --lofo`` setting and shipped rule.
RECIPES = {
    'ft-only': ('ft-only+signed+carried+aug', DEFAULT_FT_ONLY_RULE, True),
    'multimodal': ('shipped+aug', DEFAULT_RULE, False),
}


#: Feature groups by name: a feature belongs to a group if the test holds for its name.
GROUPS = {
    'audio_abs': lambda n: n == 'audio_power',
    'ft_spectral': lambda n: n.split('_', 1)[1] in ('centroid', 'spread', 'flux'),
    'audio_db': lambda n: n.startswith('audio_') and n.endswith('_db'),
    'change': lambda n: n.split('_', 1)[1] in ('change', 'change_max'),
    'shift': lambda n: n.split('_', 1)[1] in ('shift', 'shift_min', 'shift_max'),
    'carried': lambda n: n.split('_', 1)[1] in ('shift_rel', 'carried_cos'),
    'torque': lambda n: n.startswith('torque_'),
}


def candidate_columns(columns: Sequence[str], *, drops: Sequence[str]) -> tuple:
    """
    Return ``columns`` without the features of every group in ``drops``.

    A ``ValueError`` if a group is unknown or takes nothing out of ``columns``.
    """
    kept = tuple(columns)
    for group in drops:
        if group not in GROUPS:
            raise ValueError(f'unknown group {group!r}; known: {", ".join(GROUPS)}')
        fewer = tuple(n for n in kept if not GROUPS[group](n))
        if len(fewer) == len(kept):
            raise ValueError(f'group {group!r} takes no feature out of {", ".join(kept)}')
        kept = fewer
    return kept


def parse_rule(text: str, *, base: DecisionRule) -> Tuple[str, DecisionRule]:
    """
    Return ``(name, rule)`` for ``NAME:FIELD=VALUE,...``: ``base`` with those fields changed.

    Each value takes the type of the field's value in ``base``; an unknown field or a value of
    the wrong type is an ``argparse.ArgumentTypeError``.
    """
    name, _, changes = text.partition(':')
    known = {f.name: type(getattr(base, f.name)) for f in fields(base)}
    values = {}
    for item in filter(None, changes.split(',')):
        key, _, value = item.partition('=')
        if key not in known:
            raise argparse.ArgumentTypeError(f'{key!r} is not a DecisionRule field')
        try:
            values[key] = known[key](value)
        except ValueError as err:
            raise argparse.ArgumentTypeError(f'{key}={value!r}: {err}') from err
    if not name or not values:
        raise argparse.ArgumentTypeError(f'{text!r}: expected NAME:FIELD=VALUE[,...]')
    return name, replace(base, **values)


def summarise(*, outcomes: List[Outcome], knocked: List[Outcome]) -> Dict[str, object]:
    """
    Return one rule's figures: ``'by_family'``, ``'worst'`` and ``'knocked'``.

    ``'by_family'`` is :func:`summarize_by_condition` (``'all'`` and one entry per family),
    ``'worst'`` the family with the most early releases, then the fewest caught, and
    ``'knocked'`` the :func:`summarize` of the trials knocked on the hand in the air.
    """
    by_family = summarize_by_condition(outcomes)
    families = [f for f in by_family if f != 'all']
    worst = min(families, key=lambda f: (-by_family[f]['premature'], by_family[f]['detected']))
    return {'by_family': by_family, 'worst': worst, 'knocked': summarize(knocked)}


def counts(summary: Dict[str, object]) -> str:
    """Return ``'caught/trials, early early'`` of a :func:`summarize` dict."""
    return f"{summary['detected']}/{summary['trials']}, {summary['premature']} early"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the folders and the options every left-out rule comparison takes."""
    parser.add_argument('folders', nargs='+', type=Path)
    parser.add_argument('--recipe', choices=sorted(RECIPES), default='ft-only')
    parser.add_argument('--rule', action='append', default=[],
                        help='NAME:FIELD=VALUE[,...], the shipped rule with those fields')
    add_run_arguments(parser)


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the forests' seeds, the jobs and the output options the screens share."""
    parser.add_argument('--seeds', default='0,1,2')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--families', action='store_true', help='one line per family too')
    parser.add_argument('--json', type=Path, default=None, help='the counts, as JSON')


def recipe_rules(args: argparse.Namespace,
                 parser: argparse.ArgumentParser) -> Tuple[object, Dict[str, DecisionRule]]:
    """
    Return the recipe's ``sweep --lofo`` setting and the rules to score, ``S`` first.

    ``S`` is the recipe's shipped rule, then every ``--rule`` (a bad one is a parser error).
    """
    setting_name, shipped, ft_only = RECIPES[args.recipe]
    rules = {'S': shipped}
    for text in args.rule:
        try:
            name, rule = parse_rule(text, base=shipped)
        except argparse.ArgumentTypeError as err:
            parser.error(f'--rule: {err}')
        rules[name] = rule
    setting, _ = lofo_setting(setting_name, label=recipe_defaults(ft_only=ft_only).labels)
    return setting, rules


def recipe_frames(args: argparse.Namespace, setting, *,
                  train_only: Sequence[Path] = ()) -> Tuple[Dict[str, object], List]:
    """
    Return every trial's frames as simulated (keyed) and as the forests train on them.

    The second are the same trials with the recipe's wrench augmentation, and those of the
    folders ``train_only``, augmented too.
    """
    recipe = recipe_defaults(ft_only=RECIPES[args.recipe][2])
    frames = load_frames(folders=args.folders, config=setting.config, cache=None,
                         jobs=args.jobs)
    fit = list(load_frames(folders=args.folders, config=setting.config, cache=None,
                           jobs=args.jobs, augmentation=recipe.augmentation).values())
    if train_only:
        # keyed and augmented as sweep --lofo-train-only, so S's row is the sweep's
        fit += list(load_frames(folders=train_only, config=setting.config, cache=None,
                                jobs=args.jobs, augmentation=recipe.augmentation,
                                tag_prefix='train-only-').values())
    return frames, fit


def print_rules(summary: Dict[str, Dict[str, object]], *, families: bool) -> None:
    """Print one line per rule of :func:`summarise` outputs; ``families``: one per family too."""
    for name, figures in summary.items():
        by_family, worst, hit = figures['by_family'], figures['worst'], figures['knocked']
        median = ('n/a' if hit['latency_ms_median'] is None
                  else f"{hit['latency_ms_median']:.0f} ms")
        print(f"{name}: all {counts(by_family['all'])}, median "
              f"{by_family['all']['latency_ms_median'] or 0:.0f} ms; worst {worst} "
              f'{counts(by_family[worst])}; knocked on the hand {counts(hit)}, {median}')
        if families:
            for family, f in by_family.items():
                if family != 'all':
                    print(f'    {family}: {counts(f)} ({premature_text(f)}), median '
                          f"{f['latency_ms_median'] or 0:.0f} / p95 "
                          f"{f['latency_ms_p95'] or 0:.0f} ms")


def write_json(path: Optional[Path], *, rules: Dict[str, DecisionRule], summary: dict,
               **extra: object) -> None:
    """Write ``--json``: the rules, ``summary`` and any ``extra`` entries; nothing without it."""
    if path is not None:
        path.write_text(json.dumps({'rules': {n: r.to_dict() for n, r in rules.items()},
                                    **extra, 'summary': summary}, indent=1))


def main(argv=None) -> int:
    """Run the comparison; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    parser.add_argument('--splitter', choices=SPLITTERS, default='best',
                        help="the forests' trees: 'best' (the shipped random forests) or "
                             "'random' (extremely randomized trees)")
    parser.add_argument('--drop', action='append', default=[], choices=sorted(GROUPS),
                        help='a feature group the forests leave out (generator_ablation.py)')
    parser.add_argument('--outcomes', type=Path, default=None, metavar='OUT.json',
                        help="every rule's outcome on every trial and forest seed, as JSON "
                             '(benchmarks/lofo_either.py combines two such files)')
    parser.add_argument('--train-only', action='append', default=[], type=Path,
                        metavar='DIR',
                        help='trials every fold also trains on (except those of the family '
                             'left out) and none is scored on, as sweep --lofo-train-only')
    args = parser.parse_args(argv)
    both = {f.resolve() for f in args.folders} & {f.resolve() for f in args.train_only}
    if both:
        parser.error(f'a folder is both scored and only trained on: {sorted(map(str, both))}')
    setting, rules = recipe_rules(args, parser)
    try:
        setting = replace(setting, columns=candidate_columns(setting.columns, drops=args.drop))
    except ValueError as err:
        parser.error(str(err))
    frames, fit = recipe_frames(args, setting, train_only=args.train_only)
    keys = list(frames)
    outcomes = {name: [] for name in rules}
    knocked = {name: [] for name in rules}
    records = {name: [] for name in rules}
    for seed in (int(s) for s in args.seeds.split(',')):
        for fold in leave_one_family_out(frames=list(frames.values()), setting=setting,
                                         rules=list(rules.values()), n_estimators=10,
                                         seed=seed, jobs=args.jobs, fit_frames=fit,
                                         splitter=args.splitter):
            test = [k for k in keys if frames[k].truth.condition == fold.family]
            hit = [knocked_in_air(frames[k].truth) for k in test]
            for name, row in zip(rules, fold.rows):
                outcomes[name] += row.outcomes
                knocked[name] += [o for o, h in zip(row.outcomes, hit) if h]
                records[name] += [{'seed': seed, 'trial': k, 'knocked': h, **asdict(o)}
                                  for o, k, h in zip(row.outcomes, test, hit)]
        print(f'seed {seed}: every family left out', file=sys.stderr, flush=True)
    summary = {name: summarise(outcomes=outcomes[name], knocked=knocked[name])
               for name in rules}
    print_rules(summary, families=args.families)
    write_json(args.json, rules=rules, summary=summary)
    if args.outcomes is not None:
        args.outcomes.write_text(json.dumps({'recipe': args.recipe, 'outcomes': records}))
    return 0


if __name__ == '__main__':
    sys.exit(main())
