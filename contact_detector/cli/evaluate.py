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

    contact-detector evaluate BAG_OR_DIR... [--detector forest|forest-both|forest-ft|threshold|
                              highpass|lowpass-bandpass|audio-onset|all ...] [--model M]
                              [--ft-model M]
                              [--labels labels.csv]... [--report DIR]

Per trial: detected (first release within [onset - 10 ms, onset + 500 ms]), missed, late,
premature (before the onset: the object is dropped), latency, and contact events blamed on
exogenous impacts (within [-50, +500] ms of an impact, outside the true contact). Ground truth
comes from ``--labels`` (the CSV ``train --labels`` takes: ``bag,onset_start,onset_end`` rows,
several rows for a recording with several contacts; a bag whose row ``label`` wrote without an
onset is left out, with a warning), else the simulator's ``manifest.json``
beside the bags (onset, lift-off, impacts, condition), else ``/contact_truth`` (onset only).
A recording with several labelled contacts is scored per contact, as if the detector were
re-armed for each (:func:`contact_detector.evaluation.metrics.score_onsets`). Every detector
sees the same decoded messages. The per-recording table (printed with ``--labels``) gives each
detector's verdicts on each recording. With ``--report``: summary.md, metrics.json,
per-trial rows, a latency histogram and ``recordings.png`` (each recording's labelled onsets
and every detector's contact events on one time line).
``forest`` is what the node runs: ``--model``, else the shipped model the recording needs (the
F/T-only one for a recording without an audio topic), with the shipped F/T-only model deciding
beside a multimodal one if ``model.ft_also_decides`` is true in ``--params`` (the first release
of either); ``forest-both`` that model with the F/T-only model beside it in any case;
``forest-ft`` the F/T-only model on every recording. The models used are printed.
"""

import argparse
from pathlib import Path
import sys
from typing import List, Optional, Sequence

from contact_detector.cli.common import add_stream_arguments, discover_all
from contact_detector.detection.factory import build_detector_factory
from contact_detector.detection.parameters import read_param_file
from contact_detector.errors import ContactDetectorError
from contact_detector.evaluation.baselines import BASELINES
from contact_detector.evaluation.compare import evaluate
from contact_detector.evaluation.report import comparison_table, recording_table, write_report
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.training.protocol import labels_for
from tqdm import tqdm

#: ``forest``: the model of ``--model``, else the shipped one the recording needs (multimodal
#: with an audio topic, F/T-only without), as the node runs it (``model.ft_also_decides``);
#: ``forest-both``: with the shipped F/T-only model deciding beside a multimodal one;
#: ``forest-ft``: the F/T-only model (``--ft-model``, else the shipped one) on every recording.
DETECTORS = ('forest', 'forest-both', 'forest-ft') + BASELINES


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
    parser.add_argument('--labels', type=Path, action='append', default=None,
                        help='CSV of bag,onset_start,onset_end rows (the truth; several rows '
                             'for a recording with several contacts); repeat it for recordings '
                             'whose rows are in several CSVs')
    parser.add_argument('--report', type=Path, default=None)
    args = parser.parse_args(argv)
    chosen: List[str] = args.detector or ['forest']
    detectors = list(DETECTORS) if 'all' in chosen else list(dict.fromkeys(chosen))
    # a model no chosen detector runs is a mistaken flag, not a choice: say so before any work
    if args.model is not None and 'forest-ft' in detectors and not {
            'forest', 'forest-both'} & set(detectors):
        parser.error('--model is the model of the forest detectors; --detector forest-ft '
                     'takes its model from --ft-model')
    if args.ft_model is not None and 'forest-ft' not in detectors:
        parser.error('--ft-model is the model of --detector forest-ft, which is not chosen')
    try:
        make, stream = build_detector_factory(model=args.model, params_file=args.params,
                                              audio_rate=args.audio_rate)
        probe = make()
        params = read_param_file(args.params) if args.params else {}
        make_ft = make_both = None
        if 'forest-both' in detectors:
            make_both, _ = build_detector_factory(model=args.model, params_file=args.params,
                                                  audio_rate=args.audio_rate)
            make_both.ft_also_decides = True
        if 'forest-ft' in detectors:
            make_ft, _ = build_detector_factory(model=args.ft_model, params_file=args.params,
                                                audio_rate=args.audio_rate)
            make_ft.model, make_ft.audio_enabled = args.ft_model, False
            make_ft.bundle_for(has_audio=False)
        # A bag without an audio topic is no error if the forest gets an F/T-only model for it.
        found = dict(discover_all(find_bags(args.bags), args=args, params=params,
                                  prog='contact-detector evaluate',
                                  allow_no_audio=make.decides_without_audio))
        labels = None
        if args.labels:
            labelled = labels_for(csv_paths=args.labels, bags=list(found))
            labels = labelled.onsets
            found = {b: s for b, s in found.items() if b not in labelled.left_out}
            if labelled.own_truth:
                csvs = ', '.join(map(str, args.labels))
                print(f'contact-detector evaluate: {len(labelled.own_truth)} bags without a row '
                      f'in {csvs} are scored against their own truth (manifest.json or '
                      '/contact_truth)', file=sys.stderr)
        results = evaluate(bags=list(found), detectors=detectors, make_forest=make,
                           spec=StreamSpec(**stream), audio_rate=probe.settings.audio_rate,
                           wrench_rate=probe.settings.wrench_rate,
                           label_window=make.bundle_for().label_window, found=found,
                           stream=stream, labels=labels, make_ft=make_ft,
                           make_both=make_both,
                           progress=lambda bags: tqdm(bags, desc='evaluate', unit='bag',
                                                      disable=len(bags) < 3),
                           log=lambda line: print(line, file=sys.stderr))
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
