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
The shipped training recipe: the defaults ``contact-detector train`` uses and its data steps.

The feature configuration (:meth:`~contact_detector.features.config.FeatureConfig.shipped`),
label window and decision rule of the shipped model, the simulated trials ``--with-sim`` adds,
the card's record of the training data, and the event metrics of the full detector on the
test recordings.
"""

import json
from pathlib import Path
from typing import Callable, Iterable, Optional, Sequence

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.factory import stream_spec
from contact_detector.detection.offline import run_detector
from contact_detector.errors import BagError
from contact_detector.evaluation.metrics import score_onsets, score_trial, summarize, Truth
from contact_detector.features.config import FeatureConfig, SHIFT_FEATURES
from contact_detector.io.sensor_stream import load_events, StreamSpec
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.rule import DecisionRule
from contact_detector.sim.bag_writer import write_trials
from contact_detector.sim.trial import simulate_trials
from contact_detector.training.protocol import LabelWindow

#: Condition sets of the simulated trials ``--with-sim`` adds.
SIM_CONDITIONS = ('wide',)
#: Recordings (and simulated trials) the split by recording needs: one per set at least.
MIN_RECORDINGS = 3

#: The feature configuration, labels and rule of the shipped model, chosen by
#: leave-one-family-out (docs/generalisation.md): see :meth:`FeatureConfig.shipped`. Labels
#: cover the first 0.3 s of the contact; release at the first frame where every tree says
#: contact (p >= 0.95 with 10 trees; 0.9 was as safe on every left-out simulator family but
#: released early 3 times in 48 on the real_sounds family kept out of the choice), or when the
#: mean P(contact) of the last 15 frames reaches 0.3.
DEFAULT_FEATURES = FeatureConfig.shipped()
#: The extra features of an F/T-only model (``--no-audio``): the vector shift features, which
#: do not depend on the sensor's orientation, tare or sign convention (docs/offline.md,
#: "Robots without a microphone").
DEFAULT_FT_ONLY_EXTRA = SHIFT_FEATURES
#: Audio rate assumed for recordings without an audio topic (an F/T-only model reads none), Hz.
NO_AUDIO_RATE = 16000
DEFAULT_LABELS = LabelWindow(start_s=0.0, end_s=0.3)
DEFAULT_RULE = DecisionRule(threshold=0.95, confirm_frames=1, refractory_s=1.0,
                            sustain_frames=15, sustain_threshold=0.3)


def simulated_trials(*, sim_dir: Path, n: int, seed: int, ft_rate: float, audio_rate: int,
                     progress: Callable[[Iterable], Iterable] = iter) -> tuple[list, dict]:
    """
    Write (or reuse) ``n`` simulated trials of :data:`SIM_CONDITIONS` in ``sim_dir``.

    ``progress`` wraps the iterator of trials being simulated (e.g. a progress bar).

    Returns
    -------
    (list of Path, dict)
        The trial bags and the manifest's settings.

    Raises
    ------
    BagError
        ``sim_dir`` holds other simulator output (other trials, seed or audio rate, or an F/T
        rate more than 1 % away: one recording more or less moves the median a little).

    """
    settings = {'seed': seed, 'trials': n, 'start_index': 0,
                'conditions': list(SIM_CONDITIONS), 'storage': 'sqlite3',
                'audio_rate': audio_rate, 'ft_rate': ft_rate, 'chunk_size': None,
                'label_window_s': 0.1}
    manifest = sim_dir / 'manifest.json'
    if manifest.exists():
        held = json.loads(manifest.read_text())
        have = dict(held.get('settings', {}))
        same_rate = abs(float(have.pop('ft_rate', 0.0)) / ft_rate - 1.0) <= 0.01
        if not same_rate or have != {k: v for k, v in settings.items() if k != 'ft_rate'}:
            raise BagError(f'{sim_dir} holds other simulated trials ({held.get("settings")}); '
                           'give an empty or new --sim-dir')
        return [sim_dir / t['bag'] for t in held['trials']], held['settings']
    trials = simulate_trials(n=n, seed=seed, conditions=SIM_CONDITIONS, audio_rate=audio_rate,
                             ft_rate=ft_rate)
    records, _ = write_trials(trials=progress(trials),
                              out_dir=sim_dir, settings=settings)
    return [sim_dir / r['bag'] for r in records], settings


def training_sources(*, user: Sequence[Path], csv_onsets: Optional[dict],
                     labels_path: Optional[Path], sim: Sequence[Path], sim_settings: dict,
                     sim_dir: Optional[Path], kept: bool, manifest: dict) -> dict:
    """Return what the model was trained on, for the model card (``training.sources``)."""
    sources = {}
    if user:
        contacts = sum(len(csv_onsets[b.name]) for b in user) if csv_onsets else len(user)
        sources['recordings'] = {
            'count': len(user), 'contacts': contacts, 'bags': sorted(b.name for b in user),
            'labels': f'{labels_path.name} (--labels)' if labels_path else
            'the /contact_truth topic or the simulator manifest of each bag'}
    if sim:
        sources['simulated'] = {
            'trials': len(sim),
            'families': sorted({manifest.get(b, {}).get('condition', '') for b in sim}),
            'seed': sim_settings['seed'], 'ft_rate': sim_settings['ft_rate'],
            'audio_rate': sim_settings['audio_rate'],
            'labels': 'simulator truth (/contact_truth)',
            'kept_in': str(sim_dir) if kept else 'a temporary directory (deleted)'}
    return sources


def event_metrics(*, bundle: ModelBundle, bags: Sequence[Path], spec: StreamSpec,
                  audio_rate: float, wrench_rate: float, manifest: dict,
                  found: Optional[dict] = None, labels: Optional[dict] = None) -> dict:
    """
    Run the full detector on held-out bags; return the event summary.

    ``found`` (bag -> discovered Streams) replaces ``spec`` and the rates per bag; ``labels``
    (bag name -> onsets) is the truth of the bags it names, every onset scored
    (:func:`score_onsets`); other bags are scored against their manifest entry.
    """
    outcomes = []
    for bag in bags:
        streams = (found or {}).get(bag)
        if streams is not None:
            spec = stream_spec(streams, {})
            audio_rate = streams.audio_rate or NO_AUDIO_RATE
            wrench_rate = streams.wrench_rate
        events = load_events(bag, spec=spec)
        detector = ContactDetector(bundle=bundle, settings=DetectorSettings(
            audio_rate=audio_rate, wrench_rate=wrench_rate))
        run = run_detector(events, detector=detector)
        if bag.name in (labels or {}):
            outcomes.extend(score_onsets(name=bag.name, condition='recordings',
                                         onsets=labels[bag.name], events=run.events))
            continue
        info = manifest.get(bag)
        if info is None:
            continue
        truth = Truth(name=bag.name, condition=info.get('condition', ''),
                      onset_t=info['onset_t'], contact_end_t=info.get('contact_end_t'),
                      impacts=tuple((i['t'], i['kind'], i['in_air'])
                                    for i in info.get('impacts', [])))
        outcomes.append(score_trial(truth=truth, releases=run.releases, events=run.events))
    return summarize(outcomes)
