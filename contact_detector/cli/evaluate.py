"""``contact-detector evaluate``: event metrics of the forest and the baselines against truth.

    contact-detector evaluate BAG_OR_DIR... [--detector forest|forest-ft|threshold|highpass|
                              lowpass-bandpass|audio-onset|all ...] [--model M] [--ft-model M]
                              [--report DIR]

Per trial: detected (first release within [onset - 10 ms, onset + 500 ms]), missed, late,
premature (before the onset: the object is dropped), latency, and contact events blamed on
exogenous impacts (within [-50, +500] ms of an impact, outside the true contact). Ground truth
comes from the simulator's ``manifest.json`` beside the bags (onset, lift-off, impacts,
condition) or, without one, from ``/contact_truth`` (onset only). Every detector sees the same
decoded messages. With ``--report``: summary.md, metrics.json, per-trial rows and figures.
``forest`` is ``--model``, else the shipped model the recording needs (the F/T-only one for a
recording without the audio topic); ``forest-ft`` the F/T-only model on every recording. The
models used are printed.
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Dict, List, Optional, Sequence

import numpy as np
from tqdm import tqdm

from contact_detector.cli.detect import build_detector_factory, has_audio_topic
from contact_detector.cli.train import conditions_of
from contact_detector.detection.offline import run_detector
from contact_detector.errors import BagError, ContactDetectorError
from contact_detector.evaluation.baselines import BASELINES, make_baseline
from contact_detector.evaluation.metrics import (frame_labels, frame_report, outcome_dicts,
                                                 score_trial, summarize_by_condition, Truth)
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import load_events, StreamSpec, truth_onsets

#: ``forest``: the model of ``--model``, else the shipped one the recording needs (multimodal
#: with an audio topic, F/T-only without); ``forest-ft``: the F/T-only model (``--ft-model``,
#: else the shipped one) on every recording, for a comparison.
DETECTORS = ('forest', 'forest-ft') + BASELINES


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
             label_window: Optional[dict] = None, make_ft=None) -> Dict[str, dict]:
    """
    Run every detector on every bag; return per-detector outcomes, summaries, frame reports.

    ``make_forest(has_audio=...)`` gives the ``forest`` detector of a recording with or without
    the audio topic (:class:`contact_detector.cli.detect.DetectorFactory`); ``make_ft()`` the
    ``forest-ft`` one. The models used are printed once each.

    Returns
    -------
    dict
        detector -> {'outcomes': [...], 'summary': {...}, 'frames': {...} (forest only)}

    """
    manifest = conditions_of(bags)
    outcomes: Dict[str, list] = {d: [] for d in detectors}
    y_true, y_pred = [], []
    announced = set()
    for bag in tqdm(bags, desc='evaluate', unit='bag', disable=len(bags) < 3):
        events = load_events(bag, spec=spec)
        truth = truth_for(bag, events, manifest)
        has_audio = has_audio_topic(bag, spec=spec)
        for name in detectors:
            if name == 'forest':
                detector = make_forest(has_audio=has_audio)
                key = (name, has_audio)
            elif name == 'forest-ft':
                detector = make_ft()
                key = (name, True)
            else:
                detector = make_baseline(name, wrench_rate=wrench_rate, audio_rate=audio_rate)
                key = None
            if key is not None and key not in announced and hasattr(make_forest, 'describe'):
                announced.add(key)
                factory = make_forest if name == 'forest' else make_ft
                where = 'with' if has_audio else 'without'
                scope = (f'recordings {where} {spec.audio_topic}' if name == 'forest'
                         else 'every recording')
                print(f'{name} on {scope}: {factory.describe(has_audio=has_audio)}',
                      file=sys.stderr)
            run = run_detector(events, detector=detector)
            outcomes[name].append(score_trial(truth=truth, releases=run.releases,
                                              events=run.events))
            if name == 'forest' and label_window:
                keep = run.valid
                y_true.append(frame_labels(t=run.t[keep], onsets=[truth.onset_t],
                                           start_s=label_window['start_s'],
                                           end_s=label_window['end_s']))
                y_pred.append(run.contact[keep].astype(int))
    results = {}
    for name in detectors:
        results[name] = {'outcomes': outcome_dicts(outcomes[name]),
                         'summary': summarize_by_condition(outcomes[name])}
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
    lines = ['# Evaluation', '', comparison_table(results), '']
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
    parser.add_argument('--audio-rate', type=float, default=None)
    parser.add_argument('--wrench-topic', default='/wrist_wrench')
    parser.add_argument('--audio-topic', default='/audio')
    parser.add_argument('--report', type=Path, default=None)
    args = parser.parse_args(argv)
    chosen: List[str] = args.detector or ['forest']
    detectors = list(DETECTORS) if 'all' in chosen else list(dict.fromkeys(chosen))
    try:
        make, stream = build_detector_factory(model=args.model, params_file=args.params,
                                              audio_rate=args.audio_rate)
        probe = make()
        make_ft = None
        if 'forest-ft' in detectors:
            make_ft, _ = build_detector_factory(model=args.ft_model, params_file=args.params,
                                                audio_rate=args.audio_rate)
            make_ft.model, make_ft.audio_enabled = args.ft_model, False
            make_ft.bundle_for(has_audio=False)
        spec = StreamSpec(wrench_topic=args.wrench_topic, audio_topic=args.audio_topic,
                          **stream)
        results = evaluate(bags=find_bags(args.bags), detectors=detectors, make_forest=make,
                           spec=spec, audio_rate=probe.settings.audio_rate,
                           wrench_rate=probe.settings.wrench_rate,
                           label_window=probe.bundle.label_window, make_ft=make_ft)
    except ContactDetectorError as err:
        print(f'contact-detector evaluate: {err}', file=sys.stderr)
        return 1
    print(comparison_table(results))
    if args.report:
        write_report(report=args.report, results=results)
        print(f'report written to {args.report}/summary.md')
    return 0


if __name__ == '__main__':
    sys.exit(main())
