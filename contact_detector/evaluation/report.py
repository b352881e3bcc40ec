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

"""Tables, figures and the report directory of an evaluation (:mod:`.compare`'s results)."""

import json
from pathlib import Path
from typing import Dict

from contact_detector.evaluation.metrics import LATE_S, ONSET_TOLERANCE_S, premature_text
import numpy as np

#: recordings drawn in recordings.png at most
MAX_FIGURE_RECORDINGS = 40


def comparison_table(results: Dict[str, dict]) -> str:
    """One markdown table, every detector on the same trials."""
    lines = ['| detector | trials | detected | missed | late | premature | latency median '
             '[ms] | p95 [ms] | max [ms] | impact events |',
             '|---|---|---|---|---|---|---|---|---|---|']

    def ms(value):
        return '-' if value is None else f'{value:.0f}'
    for name, result in results.items():
        s = result['summary']['all']
        lines.append(f"| {name} | {s['trials']} | {s['detected']} | {s['missed']} | "
                     f"{s['late']} | {s['premature']} | {ms(s['latency_ms_median'])} | "
                     f"{ms(s['latency_ms_p95'])} | {ms(s['latency_ms_max'])} | "
                     f"{s['impact_events']} |")
    return '\n'.join(lines)


def recording_table(results: Dict[str, dict]) -> str:
    """
    One markdown row per recording: each detector's verdicts on its labelled contacts.

    A cell reads ``caught/contacts`` (detected within [-10, +500] ms of the label), then the
    early (premature) and late counts with their median release - label time, and the missed
    count, where not zero, and the median latency of the caught ones.
    """
    names = list(results)
    per: Dict[str, Dict[str, list]] = {}
    for name, result in results.items():
        for o in result['outcomes']:
            recording = o.get('extra', {}).get('recording', o['name'])
            per.setdefault(recording, {n: [] for n in names})[name].append(o)
    lines = ['| recording | contacts | ' + ' | '.join(names) + ' |',
             '|---|---|' + '---|' * len(names)]
    for recording, by_detector in per.items():
        cells = []
        for name in names:
            rows = by_detector[name]
            count = {v: sum(o['verdict'] == v for o in rows)
                     for v in ('detected', 'premature', 'late', 'missed')}
            text = f"{count['detected']}/{len(rows)}"
            extra = []
            for verdict, word in (('premature', 'early'), ('late', 'late'), ('missed', 'missed')):
                if count[verdict]:
                    off = [1000 * o['latency_s'] for o in rows
                           if o['verdict'] == verdict and o['latency_s'] is not None]
                    extra.append(f'{count[verdict]} {word}'
                                 + (f' {np.median(off):+.0f} ms' if off else ''))
            caught = [1000 * o['latency_s'] for o in rows if o['verdict'] == 'detected']
            if extra:
                text += ' (' + ', '.join(extra) + ')'
            if caught:
                text += f', {np.median(caught):.0f} ms'
            cells.append(text)
        n = len(by_detector[names[0]]) if names else 0
        lines.append(f'| {recording} | {n} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def plot_recordings(*, path: Path, results: Dict[str, dict]) -> int:
    """
    Draw each recording's labelled onsets and every detector's contact events; return the count.

    One row per recording (at most :data:`MAX_FIGURE_RECORDINGS`), time from the recording's
    first decision; black lines are the labels, markers the contact events (a release when
    the detector is armed), shaded the [-10, +500] ms window that counts as caught.
    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    names = list(results)
    bags = list(next(iter(results.values()))['recordings'])[:MAX_FIGURE_RECORDINGS] \
        if names else []
    if not bags:
        return 0
    # a row needs room for its title and tick labels even with one detector, else
    # tight_layout gives up with a warning and the rows overlap
    row_inches = max(0.8, 0.45 * len(names))
    fig, axes = plt.subplots(len(bags), 1, figsize=(8, 0.9 + row_inches * len(bags)),
                             squeeze=False)
    markers = 'ovs^Dx'
    for ax, bag in zip(axes[:, 0], bags):
        info = results[names[0]]['recordings'][bag]
        t0 = info['t0']
        for onset in info['onsets']:
            ax.axvspan(onset - ONSET_TOLERANCE_S - t0, onset + LATE_S - t0, color='0.9')
            ax.axvline(onset - t0, color='k', lw=1)
        for i, name in enumerate(names):
            events = np.asarray(results[name]['recordings'][bag]['events']) - t0
            ax.plot(events, np.full(events.size, i), markers[i % len(markers)], ms=5,
                    label=name)
        ax.set_yticks(range(len(names)), names, fontsize=7)
        ax.set_ylim(-0.7, len(names) - 0.3)
        ax.set_xlim(0, info['t1'] - t0)
        ax.set_title(bag, fontsize=8, loc='left')
    axes[-1, 0].set_xlabel('time from the first decision [s]; black: label, grey: caught '
                           'window')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return len(bags)


def condition_table(result: dict) -> str:
    """
    Per-condition breakdown of one detector.

    Premature releases with what they followed and, for simulated trials, the motion phase
    they fell in.
    """
    lines = ['| condition | trials | detected | missed | late | premature (after) | '
             'premature (phase) | latency median [ms] | impact events |',
             '|---|---|---|---|---|---|---|---|---|']
    for condition, s in result['summary'].items():
        median = '-' if s['latency_ms_median'] is None else f"{s['latency_ms_median']:.0f}"
        lines.append(f"| {condition} | {s['trials']} | {s['detected']} | {s['missed']} | "
                     f"{s['late']} | {premature_text(s)} | "
                     f"{premature_text(s, by='premature_phase')} | {median} | "
                     f"{s['impact_events']} |")
    return '\n'.join(lines)


def write_report(*, report: Path, results: Dict[str, dict]) -> None:
    """summary.md, metrics.json, trials.json and a latency figure."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    report.mkdir(parents=True, exist_ok=True)
    (report / 'metrics.json').write_text(json.dumps(
        {name: {'summary': r['summary'], 'frames': r.get('frames', {}).get('dict')}
         for name, r in results.items()}, indent=2))
    (report / 'trials.json').write_text(json.dumps(
        {name: r['outcomes'] for name, r in results.items()}, indent=2))
    lines = ['# Evaluation', '', comparison_table(results), '', '## Per recording', '',
             recording_table(results), '']
    drawn = plot_recordings(path=report / 'recordings.png', results=results)
    if drawn:
        total = len(next(iter(results.values()))['recordings'])
        lines += ['![recordings](recordings.png)' + (
            f' (the first {drawn} of {total} recordings)' if drawn < total else ''), '']
    for name, result in results.items():
        lines += [f'## {name} by condition', '', condition_table(result), '']
    if 'frames' in results.get('forest', {}):
        lines += ["## Forest, frame level (the paper's Table 2)", '', '```',
                  results['forest']['frames']['text'].rstrip(), '```', '']
    lines += ['![latency](latency.png)', '']
    (report / 'summary.md').write_text('\n'.join(lines))

    fig, ax = plt.subplots(figsize=(6, 3.5))
    for name, result in results.items():
        latency = [1000 * o['latency_s'] for o in result['outcomes']
                   if o['latency_s'] is not None]
        if latency:
            ax.hist(latency, bins=30, alpha=0.5, label=name)
    ax.axvline(0, color='k', lw=0.8)
    ax.set_xlabel('release time - true onset [ms] (negative = premature)')
    ax.set_ylabel('trials')
    if ax.get_legend_handles_labels()[1]:
        ax.legend()
    else:   # no detector released (e.g. recordings whose F/T stops at the contact)
        ax.text(0.5, 0.5, 'no release', transform=ax.transAxes, ha='center')
    fig.tight_layout()
    fig.savefig(report / 'latency.png', dpi=120)
    plt.close(fig)
