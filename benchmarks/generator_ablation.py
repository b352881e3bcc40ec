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
A shipped recipe's features with one group left out, judged on labelled recordings of other worlds.

    .venv/bin/python benchmarks/generator_ablation.py SET... --train DIR...
        [--recipe multimodal|ft-only] [--drop NAME]... [--union NAME+NAME]...
        [--seeds 0,1,2] [--jobs 2] [--families] [--json out.json] [--cache fit.pkl]

For the recipe's feature setting (the features of ``tools/build_model.sh`` or
``tools/build_ft_model.sh``, ``F``) and ``F`` without each group of :data:`GROUPS` (all of
them unless ``--drop`` names some; ``--union A+B`` leaves out both), forests are trained on
the simulated folders of ``--train`` (the recipe's wrench augmentation, labels and event
weight, 10 trees, one forest per ``--seeds`` seed, every trial: no trial split) and decide
every recording of the ``SET`` folders (a ``labels.csv`` and one sub-folder per family, as
``generator_rules.py`` reads them) with the recipe's shipped rule. ``F`` is retrained the same
way, so the rows compare like for like; they are not the shipped model's figures
(``generator_rules.py`` scores that).

A family is a generator's family over all its sets: the sets' names start with the
generator's letter (``A3301``, ``A3320`` -> ``A/rigid``). Prints one line per candidate:
caught within 500 ms and early over every decision (recordings x seeds), the worst family by
``(caught - early) / decisions`` and that score; ``--families`` adds each family.
docs/decisions/2026-12-07-feature-groups-on-the-generators.md is the screen it was written for.
"""

import argparse
from dataclasses import replace
import json
from pathlib import Path
import sys
from typing import Dict, List

from contact_detector.evaluation.metrics import summarize_by_condition
from contact_detector.features.config import AUDIO_FEATURES
from contact_detector.training.recipe import recipe_defaults
from contact_detector.training.sweep import fit_forest, score_rules
from generator_rules import set_frames, sets_parser
from lofo_frames import load_frames
from lofo_rules import add_run_arguments, candidate_columns, GROUPS, recipe_rules, RECIPES


def pooled(frames: list, *, generator: str) -> list:
    """Return ``frames`` with each family named by its generator, not its set."""
    return [replace(f, truth=replace(
        f.truth, condition=f'{generator}/{f.truth.condition.split("/", 1)[1]}'))
        for f in frames]


def family_scores(outcomes: list) -> Dict[str, dict]:
    """
    Return each family's and ``'all'``'s counts with ``score`` = (caught - early) / decisions.

    ``outcomes`` are the decisions of every seed's forest, so a recording counts once per seed.
    """
    by_family = summarize_by_condition(outcomes)
    for figures in by_family.values():
        figures['score'] = (figures['detected'] - figures['premature']) / figures['trials']
    return by_family


def main(argv=None) -> int:
    """Run the screen; return the exit status."""
    parser = sets_parser(__doc__)
    parser.add_argument('--train', nargs='+', type=Path, required=True,
                        help="the recipe's simulated training folders")
    parser.add_argument('--recipe', choices=sorted(RECIPES), default='multimodal')
    parser.add_argument('--drop', action='append', default=[], choices=sorted(GROUPS),
                        help="a group to leave out (default: each group of the recipe's "
                             'features in turn)')
    parser.add_argument('--union', action='append', default=[],
                        help='groups left out together, joined by +')
    add_run_arguments(parser)
    parser.add_argument('--cache', type=Path, default=None,
                        help='a pickle of the training frames, reused when it matches')
    args = parser.parse_args(argv)
    pool = argparse.Namespace(folders=args.train, jobs=args.jobs, recipe=args.recipe, rule=[])
    setting, rules = recipe_rules(pool, parser)
    rule = rules['S']
    if RECIPES[args.recipe][2]:
        # sweep --lofo scores the F/T-only setting on audio frames; the shipped model and these
        # recordings (some without audio) are clocked by the F/T stream, as train --no-audio
        setting = replace(setting, config=replace(
            setting.config, audio=False, extra_features=tuple(
                e for e in setting.config.extra_features if e not in AUDIO_FEATURES)))
    candidates: Dict[str, List[str]] = {'F': []}
    # by default each group the recipe's features have (an F/T-only recipe has no audio)
    for group in args.drop or [g for g in GROUPS if any(map(GROUPS[g], setting.columns))]:
        candidates[f'-{group}'] = [group]
    for text in args.union:
        candidates['-' + '-'.join(text.split('+'))] = text.split('+')
    try:
        columns = {name: candidate_columns(setting.columns, drops=drops)
                   for name, drops in candidates.items()}
    except ValueError as err:
        parser.error(str(err))
    multimodal = not RECIPES[args.recipe][2]
    frames = []
    for folder in args.sets:
        found = set_frames(folder=folder, config=setting.config, multimodal=multimodal,
                           jobs=args.jobs)
        print(f'{folder.name}: {len(found)} recordings', file=sys.stderr, flush=True)
        frames += pooled(found, generator=folder.name[:1])
    recipe = recipe_defaults(ft_only=not multimodal)
    fit = list(load_frames(folders=args.train, config=setting.config, cache=args.cache,
                           jobs=args.jobs, augmentation=recipe.augmentation).values())
    print(f'training: {len(fit)} trials', file=sys.stderr, flush=True)
    results = {}
    for name, kept in columns.items():
        candidate = replace(setting, columns=kept)
        outcomes = []
        for seed in (int(s) for s in args.seeds.split(',')):
            forest = fit_forest(frames=fit, setting=candidate, n_estimators=10, seed=seed,
                                jobs=args.jobs)
            outcomes += score_rules(forest=forest, frames=frames, setting=candidate,
                                    rules=[rule])[0].outcomes
        by_family = family_scores(outcomes)
        worst = min((f for f in by_family if f != 'all'),
                    key=lambda f: (by_family[f]['score'], by_family[f]['detected']))
        results[name] = {'columns': list(kept), 'worst': worst, 'by_family': by_family}
        total = by_family['all']
        print(f"{name} ({len(kept)} features): all {total['detected']}/{total['trials']}, "
              f"{total['premature']} early, median {total['latency_ms_median'] or 0:.0f} ms; "
              f"worst {worst} {by_family[worst]['detected']}/{by_family[worst]['trials']}, "
              f"{by_family[worst]['premature']} early, score {by_family[worst]['score']:.3f}",
              flush=True)
        if args.families:
            for family, f in sorted(by_family.items()):
                if family != 'all':
                    print(f"    {family}: {f['detected']}/{f['trials']}, {f['premature']} "
                          f"early, score {f['score']:.3f}, median "
                          f"{f['latency_ms_median'] or 0:.0f} ms", flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps({'rule': rule.to_dict(), 'candidates': results},
                                        indent=1, default=float))
    return 0


if __name__ == '__main__':
    sys.exit(main())
