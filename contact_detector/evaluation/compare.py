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
Every detector (the forest, the F/T-only forest, the baselines) on the same recordings, scored.

What ``contact-detector evaluate`` prints and writes; see its help for the truth and scores.
"""

from pathlib import Path
from typing import Callable, Dict, Iterable, List, Optional, Sequence

from contact_detector.detection.factory import stream_spec
from contact_detector.detection.offline import run_detector
from contact_detector.evaluation.baselines import make_baseline
from contact_detector.evaluation.metrics import (frame_labels, frame_report, outcome_dicts,
                                                 score_onsets, score_trial,
                                                 summarize_by_condition)
from contact_detector.evaluation.truth import conditions_of, truth_for
from contact_detector.io.bags import recording_names
from contact_detector.io.discovery import Streams
from contact_detector.io.sensor_stream import load_events, StreamSpec
import numpy as np


def evaluate(*, bags: Sequence[Path], detectors: Sequence[str], make_forest, spec: StreamSpec,
             audio_rate: float, wrench_rate: float,
             label_window: Optional[dict] = None,
             found: Optional[Dict[Path, Streams]] = None,
             stream: Optional[dict] = None,
             labels: Optional[Dict[Path, List[float]]] = None,
             make_ft=None, make_both=None,
             progress: Callable[[Iterable], Iterable] = iter,
             log: Callable[[str], None] = lambda _line: None) -> Dict[str, dict]:
    """
    Run every detector on every bag; return per-detector outcomes, summaries, frame reports.

    ``found`` (bag -> discovered :class:`Streams`) replaces ``spec`` and the two rates per bag;
    ``stream`` holds the parameter file's stream fields (the audio channel); ``labels`` (bag
    -> onsets, s, from :func:`~contact_detector.training.protocol.match_labels`) is the truth
    where given, every onset scored (:func:`score_onsets`). Recordings are named by
    :func:`~contact_detector.io.bags.recording_names` (the file name, or as much of the path
    as tells apart bags that share it).

    ``make_forest(streams, has_audio=...)`` gives the ``forest`` detector of a recording with or
    without an audio topic (:class:`contact_detector.detection.factory.DetectorFactory`);
    ``make_ft(streams)`` the ``forest-ft`` one, ``make_both(streams)`` the ``forest-both`` one
    (the ``forest`` model with the F/T-only model deciding beside it). The models used
    are passed to ``log`` once each; ``progress`` wraps the list of bags (e.g. a progress bar).

    Returns
    -------
    dict
        detector -> {'outcomes': [...], 'summary': {...}, 'recordings': {name: {'onsets',
        'events', 't0', 't1'}}, 'frames': {...} (forest only)}

    """
    manifest = conditions_of(bags)
    names = recording_names(bags)
    # labelled recordings from several folders are tabled per folder (a day, a robot, a family)
    several = len({Path(b).parent for b in bags}) > 1
    outcomes: Dict[str, list] = {d: [] for d in detectors}
    recordings: Dict[str, dict] = {d: {} for d in detectors}
    y_true, y_pred = [], []
    announced = set()
    default_audio_rate = audio_rate
    for bag in progress(bags):
        streams = (found or {}).get(bag)
        if streams is not None:
            spec = stream_spec(streams, stream or {})
            audio_rate, wrench_rate = streams.audio_rate, streams.wrench_rate
        events = load_events(bag, spec=spec)
        onsets = (labels or {}).get(bag)
        truth = None if onsets else truth_for(bag, events, manifest, name=names[bag])
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
            elif name == 'forest-both':
                detector = (make_both(streams) if streams is not None
                            else make_both(has_audio=has_audio))
                key = (name, has_audio)
            else:
                detector = make_baseline(name, wrench_rate=wrench_rate,
                                         audio_rate=audio_rate or default_audio_rate)
                key = None
            if key is not None and key not in announced and hasattr(make_forest, 'describe'):
                announced.add(key)
                factory = {'forest': make_forest, 'forest-ft': make_ft}.get(name, make_both)
                where = 'with' if has_audio else 'without'
                scope = ('every recording' if name == 'forest-ft'
                         else f'recordings {where} an audio topic')
                log(f'{name} on {scope}: {factory.describe(has_audio=has_audio)}')
            run = run_detector(events, detector=detector)
            problem = run.input_problem() if key is not None else None
            if problem:
                log(f'{names[bag]}: {name}: {problem}')
            if truth is None:
                outcomes[name].extend(score_onsets(name=names[bag],
                                                   condition=bag.parent.name if several
                                                   else 'labels',
                                                   onsets=onsets, events=run.events))
            else:
                outcomes[name].append(score_trial(truth=truth, releases=run.releases,
                                                  events=run.events))
            recordings[name][names[bag]] = {
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
