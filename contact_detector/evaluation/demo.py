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
The demo's trials and their report (no ROS): which trials, their scores, table and figure.

``contact-detector demo`` (``cli/demo.py``) runs the node live on these trials through
:func:`contact_detector.ros.demo_run.run_demo`; this module picks the trials, scores the
releases received against each trial's truth (:mod:`.metrics`), and writes the table rows,
the summary line, the verdict and the figure.
"""

from pathlib import Path
from typing import List, Optional, Sequence

from contact_detector.evaluation.metrics import Outcome, score_trial, summarize, Truth
from contact_detector.sim.trial import simulate_trial, Trial
import numpy as np


def pick_trials(*, n: int, seed: int) -> List[Trial]:
    """Paper-like trials, alternating hand and table hits, preferring hits in the air."""
    wanted = ['hand', 'table']
    chosen: List[Trial] = []
    index = 0
    while len(chosen) < n and index < 40 * n:
        trial = simulate_trial(seed=seed, index=index, condition='paper')
        index += 1
        kind = wanted[len(chosen) % 2]
        kinds = {i.kind for i in trial.impacts}
        in_air = any(i.in_air for i in trial.impacts)
        if kind in kinds and in_air:
            chosen.append(trial)
    return chosen


def score_live_trial(*, trial: Trial, releases: Sequence[float], wall0: float) -> Outcome:
    """
    Score releases received live against the trial's truth.

    Parameters
    ----------
    trial : Trial
        The trial that was replayed.
    releases : sequence of float
        Receive times of the ``release`` messages on this machine's clock, s.
    wall0 : float
        This machine's time of the trial's ``start_time``, s; a release at wall time ``r`` is
        at trial time ``r - wall0 + trial.start_time``.

    """
    in_trial = [r - wall0 + trial.start_time for r in releases]
    truth = Truth(name=trial.name, condition=trial.condition, onset_t=trial.onset_t,
                  contact_end_t=trial.contact_end_t,
                  impacts=tuple((i.t, i.kind, i.in_air) for i in trial.impacts))
    return score_trial(truth=truth, releases=in_trial, events=in_trial)


def table_header() -> str:
    """Return the header of the per-trial table."""
    return (f'{"trial":<11} {"onset [s]":>9} {"release [s]":>11} {"latency [ms]":>12}  '
            f'{"exogenous hits (s, in air?)":<34} verdict')


def table_row(*, trial: Trial, outcome: Outcome) -> str:
    """Return one row: onset, release (s in the trial), latency (ms), the hits, the verdict."""
    hits = ', '.join(f'{i.kind} {i.t - trial.start_time:.1f}'
                     f'{" air" if i.in_air else ""}' for i in trial.impacts)
    release = '-' if outcome.release_t is None else (
        f'{outcome.release_t - trial.start_time:.3f}')
    latency = '-' if outcome.latency_s is None else f'{1000 * outcome.latency_s:.0f}'
    return (f'{trial.name:<11} {trial.onset_t - trial.start_time:9.3f} {release:>11} '
            f'{latency:>12}  {hits:<34} {outcome.verdict}')


def summary_line(outcomes: Sequence[Outcome]) -> Optional[str]:
    """Return the summary of the trials that ran (None if none ran)."""
    if not outcomes:
        return None
    summary = summarize(outcomes)
    median = summary['latency_ms_median']
    latency = '-' if median is None else f'{median:.0f} ms'
    missed = summary['missed'] + summary['late']
    hits = sum(o.impacts for o in outcomes)
    in_air = sum(o.impacts_in_air for o in outcomes)
    return (f'{summary["detected"]}/{summary["trials"]} contacts detected, '
            f'{summary["premature"]} premature, {missed} missed, median latency {latency}; '
            f'{hits} exogenous hits, {in_air} while the glass was in the air')


def verdict_failures(*, outcomes: Sequence[Outcome], trials: int) -> List[str]:
    """Return why the demo failed: premature releases, missed contacts, trials that did not run."""
    summary = summarize(outcomes)
    failures = []
    if summary.get('premature'):
        failures.append(f"{summary['premature']} premature release(s)")
    if summary.get('missed') or summary.get('late'):
        failures.append(f"{summary['missed'] + summary['late']} missed contact(s)")
    if len(outcomes) < trials:
        failures.append(f'only {len(outcomes)} of {trials} trials ran')
    return failures


def plot_trial(*, trial: Trial, wall0: float, collected: dict, path: Path) -> None:
    """|F|, audio and P(contact) of one trial with onset, hits and the release marked."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    def rel(t_bag):
        return np.asarray(t_bag) - trial.start_time

    fig, axes = plt.subplots(3, 1, figsize=(9, 6), sharex=True)
    axes[0].plot(rel(trial.wrench_t), np.linalg.norm(trial.force, axis=1), lw=0.8)
    axes[0].set_ylabel('|F| [N]')
    ta = np.arange(trial.audio.size) / trial.audio_rate
    axes[1].plot(ta, trial.audio / 32768.0, lw=0.3)
    axes[1].set_ylabel('audio')
    if collected['probability']:
        tp, p = zip(*collected['probability'])
        axes[2].plot(np.asarray(tp) - wall0, p, lw=0.8, label='P(contact) (received)')
    if collected['contact']:
        tc, c = zip(*collected['contact'])
        axes[2].fill_between(np.asarray(tc) - wall0, 0, np.asarray(c, float), alpha=0.2,
                             step='post', label='contact')
    axes[2].set_ylabel('P(contact)')
    axes[2].set_ylim(-0.05, 1.05)
    axes[2].set_xlabel('time in trial [s]')
    for ax in axes:
        ax.axvline(trial.onset_t - trial.start_time, color='g', ls='--', lw=1)
        for impact in trial.impacts:
            ax.axvline(impact.t - trial.start_time, color='r', ls=':', lw=1)
        for release in collected['releases']:
            ax.axvline(release - wall0, color='k', lw=1.2)
    axes[0].set_title(f'{trial.name}: true onset (green dashed), exogenous hits (red dotted), '
                      'release (black)', fontsize=9)
    axes[2].legend(loc='upper left', fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
