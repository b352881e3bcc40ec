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
A screen: the multimodal model's contact frames gated by the F/T-only model's recent P(contact).

    .venv/bin/python benchmarks/generator_gate.py SET... [--gate NAME:FLOOR:WINDOW_S]...
        [--fast-only] [--both] [--jobs 2] [--families] [--json out.json]

``SET`` is a folder of labelled recordings, as for ``benchmarks/generator_rules.py``. Both
shipped models decide every recording with a microphone, each on its own feature frames and
with its own rule (``training.sweep.decide_trial``). A gate ``NAME:FLOOR:WINDOW_S`` lets a
multimodal frame be contact only if the F/T-only model's P(contact) reached ``FLOOR`` in one
of its frames of the ``WINDOW_S`` seconds up to that frame's time, ``(t - WINDOW_S, t]``: the
two models must agree that something touches. With ``--fast-only`` the gate holds only the
fast path (``P >= threshold``): the slow path and the load paths fire as before, so a frame is
contact if the rule without its fast path says so, or if the whole rule does and the gate is
open. The gated model releases at its first gated
contact frame (the multimodal rule confirms over one frame); a contact event starts each run of
gated contact frames at least the rule's refractory period after the event before. Printed,
as ``generator_rules.py`` prints its rules (``lofo_rules.print_rules``):

- ``S``: the multimodal model alone, ungated (the default today);
- each gate, alone;
- with ``--both`` also ``S+ft`` and each gate ``+ft``: the F/T-only model decides beside the
  (gated) multimodal model, and the first release of either is the release
  (``model.ft_also_decides``; ``detection.fallback.first_release``).

A screen, not the node: the node has no such gate. It answers whether the lead of
docs/decisions/2026-12-07-stricter-slow-path-with-both-models.md is worth building
(docs/decisions/2026-12-08-ft-only-gate.md).
"""

import argparse
import dataclasses
from pathlib import Path
import sys
from typing import Dict, List, Sequence, Tuple

from contact_detector.detection.fallback import first_release, merge_events
from contact_detector.evaluation.metrics import Outcome, score_trial
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.training.protocol import LabelWindow
from contact_detector.training.sweep import (decide_trial, FeatureSetting, p_contact,
                                             setting_columns)
from generator_rules import print_sets, set_frames, sets_parser
from lofo_rules import write_json
import numpy as np


def parse_gate(text: str) -> Tuple[str, float, float]:
    """Return ``(name, floor, window_s)`` of ``NAME:FLOOR:WINDOW_S``."""
    try:
        name, floor, window = text.split(':')
        floor_v, window_v = float(floor), float(window)
    except ValueError as err:
        raise argparse.ArgumentTypeError(
            f'expected NAME:FLOOR:WINDOW_S, got {text!r}') from err
    if not name or not 0.0 <= floor_v <= 1.0 or not window_v > 0.0:
        raise argparse.ArgumentTypeError(
            f'{text!r}: the floor must lie in [0, 1] and the window be > 0 s')
    return name, floor_v, window_v


def recent_max(*, t: np.ndarray, t_src: np.ndarray, p_src: np.ndarray,
               window_s: float) -> np.ndarray:
    """
    Return the largest ``p_src`` of the frames in ``(t_i - window_s, t_i]`` for every ``t_i``.

    Parameters
    ----------
    t : np.ndarray, shape (n,)
        Query times (the gated model's frame times), s.
    t_src : np.ndarray, shape (m,)
        The other model's frame times, s, ascending.
    p_src : np.ndarray, shape (m,)
        Its P(contact) per frame.
    window_s : float
        How far back a frame counts, s.

    Returns
    -------
    np.ndarray, shape (n,)
        ``max p_src[j]`` over ``t_i - window_s < t_src[j] <= t_i``, 0 where no frame is there.

    """
    hi = np.searchsorted(t_src, t, side='right')
    lo = np.searchsorted(t_src, t - window_s, side='right')
    if not p_src.size:
        return np.zeros(t.shape)
    # a running maximum over a variable window: per query, fine for a screen
    return np.array([p_src[a:b].max() if b > a else 0.0 for a, b in zip(lo, hi)])


def gated_run(*, t: np.ndarray, contact: np.ndarray,
              refractory_s: float) -> Tuple[List[float], List[float]]:
    """
    Return the releases and events of a one-frame-confirmed rule's (gated) contact frames.

    Parameters
    ----------
    t : np.ndarray, shape (n,)
        Frame times, s.
    contact : np.ndarray, shape (n,), bool
        The gated rule's decision per frame.
    refractory_s : float
        Minimum time between two contact events, s.

    Returns
    -------
    releases, events : list of float
        An event starts each run of contact frames at least ``refractory_s`` after the event
        before; the first event is the release (armed from the start).

    """
    starts = t[contact & ~np.concatenate(([False], contact[:-1]))]
    events, _ = merge_events(first=starts.tolist(), second=[], after=-np.inf,
                             refractory_s=refractory_s)
    return events[:1], events


def score_sets(*, pairs: Sequence[tuple], gates: Sequence[Tuple[str, float, float]],
               both: bool, fast_only: bool, mm, ft) -> Dict[str, List[Outcome]]:
    """
    Score every gate (and ``S``) on ``(mm_frames, mm_p, ft_frames, ft_p)`` pairs.

    ``mm`` and ``ft`` are ``(bundle, names)``: each model's bundle and frame column names.
    """
    (mm_bundle, mm_names), (ft_bundle, ft_names) = mm, ft
    rule = mm_bundle.decision_rule
    if rule.confirm_frames != 1 or rule.average_frames != 1:
        sys.exit('generator_gate: the multimodal rule must confirm over one frame, its fast '
                 'path on one frame')
    out: Dict[str, List[Outcome]] = {}
    for f, pm, g, pf in pairs:
        contact, mm_releases, mm_events = decide_trial(frames=f, p=pm, rule=rule, names=mm_names)
        ungated = np.zeros(f.t.shape, bool)
        if fast_only:
            # the fast path's mean over more frames than the trial has never fires (it is -1
            # until that many have come): the rule's other paths alone
            ungated, _, _ = decide_trial(
                frames=f, p=pm, names=mm_names,
                rule=dataclasses.replace(rule, average_frames=f.t.size + len(f.breaks) + 1))
        _, ft_releases, ft_events = decide_trial(frames=g, p=pf, rule=ft_bundle.decision_rule,
                                                 names=ft_names)
        runs = {'S': (mm_releases, mm_events)}
        for name, floor, window in gates:
            gate = recent_max(t=f.t, t_src=g.t, p_src=pf, window_s=window) >= floor
            runs[name] = gated_run(t=f.t, contact=ungated | (contact & gate),
                                   refractory_s=rule.refractory_s)
        if both:
            for name, (releases, events) in list(runs.items()):
                merged, _ = merge_events(first=events, second=ft_events, after=-np.inf,
                                         refractory_s=rule.refractory_s)
                runs[f'{name}+ft'] = (first_release(releases, ft_releases), merged)
        for name, (releases, events) in runs.items():
            out.setdefault(name, []).append(
                score_trial(truth=f.truth, releases=releases, events=events))
    return out


class ShippedModel:
    """A shipped model compiled once: its forest, its frames' column names and its columns."""

    def __init__(self, bundle) -> None:
        self.bundle = bundle
        self.config = bundle.feature_config.with_rule_columns()
        self.names = self.config.feature_names
        self.cols = setting_columns(FeatureSetting(
            'shipped', self.config, LabelWindow(**bundle.label_window),
            columns=bundle.feature_names))
        self.forest = bundle.compile()

    def p(self, frames: Sequence[object]) -> List[np.ndarray]:
        """Return P(contact) per frame of every recording."""
        return [p_contact(self.forest, f.x[:, self.cols]) if f.x.shape[0] else np.zeros(0)
                for f in frames]


def main(argv=None) -> int:
    """Run the screen; return the exit status."""
    parser = sets_parser(__doc__)
    parser.add_argument('--gate', action='append', default=[], type=parse_gate,
                        help='NAME:FLOOR:WINDOW_S, a gate by the F/T-only P(contact)')
    parser.add_argument('--fast-only', action='store_true',
                        help='the gates hold only the fast path (P >= threshold)')
    parser.add_argument('--both', action='store_true',
                        help='also with the F/T-only model deciding beside each')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--families', action='store_true', help='one line per family too')
    parser.add_argument('--json', type=Path, default=None,
                        help='the counts, as JSON')
    args = parser.parse_args(argv)
    mm = ShippedModel(load_bundle(path=default_model_path()))
    ft = ShippedModel(load_bundle(path=default_ft_model_path()))
    outcomes: Dict[str, Dict[str, List[Outcome]]] = {}
    for folder in args.sets:
        mm_frames = set_frames(folder=folder, config=mm.config, multimodal=True, jobs=args.jobs)
        ft_by_name = {g.truth.name: g for g in set_frames(
            folder=folder, config=ft.config, multimodal=False, jobs=args.jobs)}
        ft_frames = [ft_by_name[f.truth.name] for f in mm_frames]
        print(f'{folder.name}: {len(mm_frames)} recordings with a microphone', file=sys.stderr,
              flush=True)
        scored = score_sets(pairs=list(zip(mm_frames, mm.p(mm_frames), ft_frames,
                                           ft.p(ft_frames))),
                            gates=args.gate, both=args.both, fast_only=args.fast_only,
                            mm=(mm.bundle, mm.names), ft=(ft.bundle, ft.names))
        for key in (folder.name, 'all'):
            for name, o in scored.items():
                outcomes.setdefault(key, {}).setdefault(name, []).extend(o)
    summary = print_sets(outcomes, families=args.families)
    write_json(args.json, rules={'S': mm.bundle.decision_rule}, summary=summary,
               gates={name: {'floor': floor, 'window_s': window}
                      for name, floor, window in args.gate})
    return 0


if __name__ == '__main__':
    sys.exit(main())
