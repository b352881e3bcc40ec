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
``contact-detector evaluate``: event metrics of the forest and the baselines against truth.

    contact-detector evaluate BAG_OR_DIR... [--detector forest|forest-ft|threshold|highpass|
                              lowpass-bandpass|audio-onset|all ...] [--model M] [--ft-model M]
                              [--labels labels.csv] [--report DIR]

Per trial: detected (first release within [onset - 10 ms, onset + 500 ms]), missed, late,
premature (before the onset: the object is dropped), latency, and contact events blamed on
exogenous impacts (within [-50, +500] ms of an impact, outside the true contact). Ground truth
comes from ``--labels`` (the CSV ``train --labels`` takes: ``bag,onset_start,onset_end`` rows,
several rows for a recording with several contacts), else the simulator's ``manifest.json``
beside the bags (onset, lift-off, impacts, condition), else ``/contact_truth`` (onset only).
A recording with several labelled contacts is scored per contact, as if the detector were
re-armed for each (:func:`contact_detector.evaluation.metrics.score_onsets`). Every detector
sees the same decoded messages. The per-recording table (printed with ``--labels``) gives each
detector's verdicts on each recording. With ``--report``: summary.md, metrics.json,
per-trial rows, a latency histogram and ``recordings.png`` (each recording's labelled onsets
and every detector's contact events on one time line).
``forest`` is ``--model``, else the shipped model the recording needs (the F/T-only one for a
recording without an audio topic); ``forest-ft`` the F/T-only model on every recording. The
models used are printed.
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Dict, List, Optional, Sequence

from contact_detector.cli.detect import (add_stream_arguments, build_detector_factory,
                                         discover_all, read_node_params, stream_spec)
from contact_detector.cli.train import conditions_of
from contact_detector.detection.offline import run_detector
from contact_detector.errors import BagError, ContactDetectorError
from contact_detector.evaluation.baselines import BASELINES, make_baseline
from contact_detector.evaluation.metrics import (frame_labels, frame_report, outcome_dicts,
                                                 score_onsets, score_trial,
                                                 summarize_by_condition, Truth)
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import Streams
from contact_detector.io.sensor_stream import load_events, StreamSpec, truth_onsets
from contact_detector.model.training import read_labels_csv
import numpy as np
from tqdm import tqdm

#: ``forest``: the model of ``--model``, else the shipped one the recording needs (multimodal
#: with an audio topic, F/T-only without); ``forest-ft``: the F/T-only model (``--ft-model``,
#: else the shipped one) on every recording, for a comparison.
DETECTORS = ('forest', 'forest-ft') + BASELINES
#: recordings drawn in recordings.png at most
MAX_FIGURE_RECORDINGS = 40


def truth_for(bag: Path, events, manifest: dict) -> Truth:
    """Ground truth of one bag: the manifest's entry, else the truth topic."""
    info = manifest.get(bag)
    if info is not None:
        return Truth(name=bag.name, condition=info.get('condition', ''),
                     onset_t=float(info['onset_t']), contact_end_t=info.get('contact_end_t'),
                     impacts=tuple((float(i['t']), i['kind'], bool(i['in_air']))
                                   for i in info.get('impacts', [])))
    onsets = truth_onsets(events)
    if not onsets:
        raise BagError(f'{bag}: no manifest entry and no True on /contact_truth')
    return Truth(name=bag.name, condition='', onset_t=onsets[0][0])


def evaluate(*, bags: Sequence[Path], detectors: Sequence[str], make_forest, spec: StreamSpec,
             audio_rate: float, wrench_rate: float,
             label_window: Optional[dict] = None,
             found: Optional[Dict[Path, Streams]] = None,
             stream: Optional[dict] = None,
             labels: Optional[Dict[str, List[float]]] = None,
             make_ft=None) -> Dict[str, dict]:
    """
    Run every detector on every bag; return per-detector outcomes, summaries, frame reports.

    ``found`` (bag -> discovered :class:`Streams`) replaces ``spec`` and the two rates per bag;
    ``stream`` holds the parameter file's stream fields (the audio channel); ``labels`` (bag
    name -> onsets, s, from :func:`read_labels_csv`) is the truth where given, every onset
    scored (:func:`score_onsets`).

    ``make_forest(streams, has_audio=...)`` gives the ``forest`` detector of a recording with or
    without an audio topic (:class:`contact_detector.cli.detect.DetectorFactory`);
    ``make_ft(streams)`` the ``forest-ft`` one. The models used are printed once each.

    Returns
    -------
    dict
        detector -> {'outcomes': [...], 'summary': {...}, 'recordings': {name: {'onsets',
        'events', 't0', 't1'}}, 'frames': {...} (forest only)}

    """
    manifest = conditions_of(bags)
    outcomes: Dict[str, list] = {d: [] for d in detectors}
    recordings: Dict[str, dict] = {d: {} for d in detectors}
    y_true, y_pred = [], []
    announced = set()
    default_audio_rate = audio_rate
    for bag in tqdm(bags, desc='evaluate', unit='bag', disable=len(bags) < 3):
        streams = (found or {}).get(bag)
        if streams is not None:
            spec = stream_spec(streams, stream or {})
            audio_rate, wrench_rate = streams.audio_rate, streams.wrench_rate
        events = load_events(bag, spec=spec)
        onsets = (labels or {}).get(bag.name)
        truth = None if onsets else truth_for(bag, events, manifest)
        onsets = onsets or [truth.onset_t]
        has_audio = streams.has_audio if streams is not None else True
        for name in detectors:
            if name == 'forest':
                detector = (make_forest(streams) if streams is not None
                            else make_forest(has_audio=has_audio))
                key = (name, has_audio)
            elif name == 'forest-ft':
                detector = make_ft(streams) if streams is not None else make_ft()
                key = (name, True)
            else:
                detector = make_baseline(name, wrench_rate=wrench_rate,
                                         audio_rate=audio_rate or default_audio_rate)
                key = None
            if key is not None and key not in announced and hasattr(make_forest, 'describe'):
                announced.add(key)
                factory = make_forest if name == 'forest' else make_ft
                where = 'with' if has_audio else 'without'
                scope = (f'recordings {where} an audio topic' if name == 'forest'
                         else 'every recording')
                print(f'{name} on {scope}: {factory.describe(has_audio=has_audio)}',
                      file=sys.stderr)
            run = run_detector(events, detector=detector)
            if truth is None:
                outcomes[name].extend(score_onsets(name=bag.name, condition='labels',
                                                   onsets=onsets, events=run.events))
            else:
                outcomes[name].append(score_trial(truth=truth, releases=run.releases,
                                                  events=run.events))
            recordings[name][bag.name] = {
                'onsets': sorted(onsets), 'events': [float(t) for t in run.events],
                't0': float(run.t[0]) if run.t.size else min(onsets),
                't1': float(run.t[-1]) if run.t.size else max(onsets)}
            if name == 'forest' and label_window:
                keep = run.valid
                y_true.append(frame_labels(t=run.t[keep], onsets=onsets,
                                           start_s=label_window['start_s'],
                                           end_s=label_window['end_s']))
                y_pred.append(run.contact[keep].astype(int))
    results = {}
    for name in detectors:
        results[name] = {'outcomes': outcome_dicts(outcomes[name]),
                         'summary': summarize_by_condition(outcomes[name]),
                         'recordings': recordings[name]}
    if y_true:
        yt, yp = np.concatenate(y_true), np.concatenate(y_pred)
        text, report = frame_report(y_true=yt, y_pred=yp)
        results['forest']['frames'] = {'text': text, 'dict': report}
    return results


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
    from contact_detector.evaluation.metrics import LATE_S, ONSET_TOLERANCE_S

    names = list(results)
    bags = list(next(iter(results.values()))['recordings'])[:MAX_FIGURE_RECORDINGS] \
        if names else []
    if not bags:
        return 0
    fig, axes = plt.subplots(len(bags), 1, figsize=(8, 0.9 + 0.45 * len(names) * len(bags)),
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
    """Per-condition breakdown of one detector."""
    lines = ['| condition | trials | detected | missed | late | premature | latency median '
             '[ms] | impact events |', '|---|---|---|---|---|---|---|---|']
    for condition, s in result['summary'].items():
        median = '-' if s['latency_ms_median'] is None else f"{s['latency_ms_median']:.0f}"
        lines.append(f"| {condition} | {s['trials']} | {s['detected']} | {s['missed']} | "
                     f"{s['late']} | {s['premature']} | {median} | {s['impact_events']} |")
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
    ax.legend()
    fig.tight_layout()
    fig.savefig(report / 'latency.png', dpi=120)
    plt.close(fig)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector evaluate', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+')
    parser.add_argument('--detector', action='append', choices=DETECTORS + ('all',),
                        help='detector(s) to evaluate (repeatable; default forest)')
    parser.add_argument('--model', type=Path, default=None,
                        help='model of the forest detector (default: the shipped model, or the '
                             'shipped F/T-only model for recordings without the audio topic)')
    parser.add_argument('--ft-model', type=Path, default=None,
                        help='model of the forest-ft detector (default: the shipped F/T-only '
                             'model)')
    parser.add_argument('--params', type=Path, default=None)
    add_stream_arguments(parser)
    parser.add_argument('--labels', type=Path, default=None,
                        help='CSV of bag,onset_start,onset_end rows (the truth; several rows '
                             'for a recording with several contacts)')
    parser.add_argument('--report', type=Path, default=None)
    args = parser.parse_args(argv)
    chosen: List[str] = args.detector or ['forest']
    detectors = list(DETECTORS) if 'all' in chosen else list(dict.fromkeys(chosen))
    try:
        make, stream = build_detector_factory(model=args.model, params_file=args.params,
                                              audio_rate=args.audio_rate)
        probe = make()
        params = read_node_params(args.params) if args.params else {}
        make_ft = None
        if 'forest-ft' in detectors:
            make_ft, _ = build_detector_factory(model=args.ft_model, params_file=args.params,
                                                audio_rate=args.audio_rate)
            make_ft.model, make_ft.audio_enabled = args.ft_model, False
            make_ft.bundle_for(has_audio=False)
        # A bag without an audio topic is no error if the forest gets an F/T-only model for it.
        found = dict(discover_all(find_bags(args.bags), args=args, params=params,
                                  prog='contact-detector evaluate',
                                  allow_no_audio=make.decides_without_audio))
        labels = read_labels_csv(args.labels) if args.labels else None
        if labels is not None:
            missing = [b.name for b in found if b.name not in labels]
            if missing:
                raise BagError(f'{args.labels} has no onset for {", ".join(missing[:5])}'
                               + (' ...' if len(missing) > 5 else ''))
        results = evaluate(bags=list(found), detectors=detectors, make_forest=make,
                           spec=StreamSpec(**stream), audio_rate=probe.settings.audio_rate,
                           wrench_rate=probe.settings.wrench_rate,
                           label_window=probe.bundle.label_window, found=found,
                           stream=stream, labels=labels, make_ft=make_ft)
    except ContactDetectorError as err:
        print(f'contact-detector evaluate: {err}', file=sys.stderr)
        return 1
    print(comparison_table(results))
    if args.labels:
        print()
        print(recording_table(results))
    if args.report:
        write_report(report=args.report, results=results)
        print(f'report written to {args.report}/summary.md')
    return 0


if __name__ == '__main__':
    sys.exit(main())
