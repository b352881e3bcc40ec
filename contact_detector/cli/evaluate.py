"""``contact-detector evaluate``: event metrics of the forest and the baselines against truth.

    contact-detector evaluate BAG_OR_DIR... [--detector forest|threshold|highpass|
                              lowpass-bandpass|audio-onset|all ...] [--model M] [--report DIR]

Per trial: detected (first release within [onset - 10 ms, onset + 500 ms]), missed, late,
premature (before the onset: the object is dropped), latency, and contact events blamed on
exogenous impacts (within [-50, +500] ms of an impact, outside the true contact). Ground truth
comes from the simulator's ``manifest.json`` beside the bags (onset, lift-off, impacts,
condition) or, without one, from ``/contact_truth`` (onset only). Every detector sees the same
decoded messages. With ``--report``: summary.md, metrics.json, per-trial rows and figures.
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Dict, List, Optional, Sequence

import numpy as np
from tqdm import tqdm

from contact_detector.cli.detect import (add_stream_arguments, build_detector_factory,
                                         discover_all, read_node_params, stream_spec)
from contact_detector.cli.train import conditions_of
from contact_detector.detection.offline import run_detector
from contact_detector.errors import BagError, ContactDetectorError
from contact_detector.evaluation.baselines import BASELINES, make_baseline
from contact_detector.evaluation.metrics import (frame_labels, frame_report, outcome_dicts,
                                                 score_trial, summarize_by_condition, Truth)
from contact_detector.io.bags import find_bags
from contact_detector.io.discovery import Streams
from contact_detector.io.sensor_stream import load_events, StreamSpec, truth_onsets

DETECTORS = ('forest',) + BASELINES


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
             stream: Optional[dict] = None) -> Dict[str, dict]:
    """
    Run every detector on every bag; return per-detector outcomes, summaries, frame reports.

    ``found`` (bag -> discovered :class:`Streams`) replaces ``spec`` and the two rates per bag;
    ``stream`` holds the parameter file's stream fields (the audio channel).

    Returns
    -------
    dict
        detector -> {'outcomes': [...], 'summary': {...}, 'frames': {...} (forest only)}

    """
    manifest = conditions_of(bags)
    outcomes: Dict[str, list] = {d: [] for d in detectors}
    y_true, y_pred = [], []
    for bag in tqdm(bags, desc='evaluate', unit='bag', disable=len(bags) < 3):
        streams = (found or {}).get(bag)
        if streams is not None:
            spec = stream_spec(streams, stream or {})
            audio_rate, wrench_rate = streams.audio_rate, streams.wrench_rate
        events = load_events(bag, spec=spec)
        truth = truth_for(bag, events, manifest)
        for name in detectors:
            detector = ((make_forest(streams) if streams is not None else make_forest())
                        if name == 'forest' else
                        make_baseline(name, wrench_rate=wrench_rate, audio_rate=audio_rate))
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
    parser.add_argument('--model', type=Path, default=None)
    parser.add_argument('--params', type=Path, default=None)
    add_stream_arguments(parser)
    parser.add_argument('--report', type=Path, default=None)
    args = parser.parse_args(argv)
    chosen: List[str] = args.detector or ['forest']
    detectors = list(DETECTORS) if 'all' in chosen else list(dict.fromkeys(chosen))
    try:
        make, stream = build_detector_factory(model=args.model, params_file=args.params,
                                              audio_rate=args.audio_rate)
        probe = make()
        params = read_node_params(args.params) if args.params else {}
        found = dict(discover_all(find_bags(args.bags), args=args, params=params,
                                  prog='contact-detector evaluate'))
        results = evaluate(bags=list(found), detectors=detectors, make_forest=make,
                           spec=StreamSpec(**stream), audio_rate=probe.settings.audio_rate,
                           wrench_rate=probe.settings.wrench_rate,
                           label_window=probe.bundle.label_window, found=found,
                           stream=stream)
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
