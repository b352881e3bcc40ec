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
The frames of the leave-one-family-out scripts (``lofo_early.py``, ``lofo_by_param.py``), cached.

Not a benchmark: imported by those two scripts, which run from this folder. Also their rule:
the shipped one, with ``--sustain-threshold`` to score the slow path a figure was measured with
(0.3 before the lever-arm augmentation, docs/decisions/2026-11-24-lever-arm-augmentation.md),
and their training protocol: a ``sweep --lofo`` setting, augmented (``NAME+aug``) and with
the frames near simulated events weighted as ``sweep --lofo`` does with the same options.
"""

import argparse
from dataclasses import replace
from pathlib import Path
import pickle
from typing import Any, Dict, Optional, Sequence, Tuple

from contact_detector.features.config import FeatureConfig
from contact_detector.io.bags import find_bags
from contact_detector.io.sensor_stream import StreamSpec
from contact_detector.model.rule import DecisionRule
from contact_detector.training.augmentation import (AUGMENTED, scale_range,
                                                    WrenchAugmentation)
from contact_detector.training.protocol import LabelWindow
from contact_detector.training.recipe import DEFAULT_RULE
from contact_detector.training.studies import FeatureSetting, lofo_setting, LOFO_SETTINGS
from contact_detector.training.sweep import compute_frames, decide_trial, decode_bags
import numpy as np


def add_rule_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--sustain-threshold``: the slow path of the scored rule (default: shipped)."""
    parser.add_argument('--sustain-threshold', type=float,
                        default=DEFAULT_RULE.sustain_threshold,
                        help='slow-path threshold of the scored rule (default: the shipped '
                             f'{DEFAULT_RULE.sustain_threshold:g}; 0.3 before the lever-arm '
                             'augmentation)')


def add_protocol_arguments(parser: argparse.ArgumentParser) -> None:
    """
    Add the training protocol's options, as ``sweep --lofo`` names them.

    ``--setting`` (a ``sweep --lofo`` setting, ``NAME+aug`` for augmented training wrenches),
    ``--augment-tare``, ``--augment-torque``, ``--augment-gain``, ``--augment-offset``,
    ``--augment-contact-offset``, ``--augment-lag`` and ``--augment-cache`` (the augmented
    frames' cache), ``--event-weight``; the options of train and sweep (cli/model_options.py,
    which a benchmark does not import), with WrenchAugmentation's defaults (sweep's) and its
    validation. The shipped multimodal protocol needs all five of train's: ``--augment-tare 0.5
    --augment-torque 0.1,2 --augment-gain 0.2,1.5 --augment-offset 0.5
    --augment-contact-offset 0.05``.
    """
    parser.add_argument('--setting', default='shipped',
                        choices=sorted([*LOFO_SETTINGS, *(s + AUGMENTED for s in LOFO_SETTINGS)]))
    parser.add_argument('--augment-tare', type=float,
                        default=WrenchAugmentation.tare_probability)
    # LOW,HIGH parsed as train and sweep parse it; argparse leaves a tuple default as it is
    parser.add_argument('--augment-torque', type=scale_range,
                        default=WrenchAugmentation.torque_scale)
    parser.add_argument('--augment-gain', type=scale_range, default=WrenchAugmentation.gain)
    parser.add_argument('--augment-offset', type=float,
                        default=WrenchAugmentation.offset_probability)
    parser.add_argument('--augment-contact-offset', type=float,
                        default=WrenchAugmentation.contact_offset_m)
    parser.add_argument('--augment-lag', type=scale_range, default=WrenchAugmentation.lag_s)
    parser.add_argument('--augment-cache', type=Path, default=None)
    parser.add_argument('--event-weight', type=float, default=1.0,
                        help='weight of the training frames near a simulated event (sweep '
                             '--lofo-event-weight; the shipped protocol: 3)')


def protocol_frames(args: argparse.Namespace) -> Tuple[FeatureSetting, Dict[str, object],
                                                       Dict[str, object], str]:
    """
    Return the setting, every trial's frames, the training frames and a description.

    The training frames are the augmented ones for a ``NAME+aug`` setting (the left-out family
    is scored on the plain ones, as ``sweep --lofo`` does), else the plain ones. The setting's
    label window is 0-0.3 s after the onset with ``--event-weight``.
    """
    setting, augmented = lofo_setting(args.setting, label=LabelWindow(
        0.0, 0.3, event_weight=args.event_weight))
    frames = load_frames(folders=args.folders, config=setting.config, cache=args.cache,
                         jobs=args.jobs)
    text = ''
    fit_frames = frames
    if augmented:
        augmentation = WrenchAugmentation(
            tare_probability=args.augment_tare, torque_scale=args.augment_torque,
            gain=args.augment_gain, offset_probability=args.augment_offset,
            contact_offset_m=args.augment_contact_offset, lag_s=args.augment_lag)
        fit_frames = load_frames(folders=args.folders, config=setting.config,
                                 cache=args.augment_cache, jobs=args.jobs,
                                 augmentation=augmentation)
        text += f', augmented ({augmentation.to_dict()})'
    if args.event_weight != 1:
        text += f', event weight {args.event_weight:g}'
    return setting, frames, fit_frames, text


#: Seconds after a recording's first frame in which no release may fire (the node's warm-up).
WARMUP_S = 0.5


def left_out_decisions(*, forest: Any, frames: Any, setting: FeatureSetting,
                       rule: DecisionRule) -> Tuple[np.ndarray, np.ndarray, list]:
    """
    Decide one left-out trial's frames as the detector would, warm-up included.

    Parameters
    ----------
    forest : fitted classifier
        From ``fit_forest`` on the setting's columns.
    frames : TrialFrames
        The left-out trial's frames (``t`` s, shape (n,); ``x``, shape (n, n_features), the
        full feature configuration's columns; ``t0`` its first frame).
    setting : FeatureSetting
        Which columns the forest reads.
    rule : DecisionRule
        The scored rule.

    Returns
    -------
    p, contact : np.ndarray, shape (n,)
        P(contact) and the rule's contact decision per frame.
    releases : list of float
        Release times, s.

    """
    names = setting.config.feature_names
    p = forest.predict_proba(frames.x[:, [names.index(c) for c in setting.columns]])[:, 1]
    contact, releases, _ = decide_trial(frames=frames, p=p, rule=rule, names=names,
                                        warmup_s=WARMUP_S)
    return p, contact, releases


def rule_from(args: argparse.Namespace) -> DecisionRule:
    """Return the shipped rule with the slow path of ``--sustain-threshold``."""
    return replace(DEFAULT_RULE, sustain_threshold=args.sustain_threshold)


def load_frames(*, folders: Sequence[Path], config: FeatureConfig, cache: Optional[Path],
                jobs: int, augmentation: Optional[WrenchAugmentation] = None,
                tag_prefix: str = '') -> Dict[str, object]:
    """
    Return every trial's frames of ``folders`` under ``config``, keyed as ``compute_frames``.

    The keys are ``'<tag_prefix><i>/<bag>'`` for the ``i``-th folder, as ``sweep --lofo``
    names its trials (``'train-only-'`` for those of ``--lofo-train-only``); the augmentation
    of a trial is drawn from its key.

    The simulator's bags: F/T at 100 Hz, audio at 16 kHz. With ``augmentation`` every trial's
    wrench is varied first, as ``sweep --lofo`` varies its training trials (``seed`` 0).
    ``cache`` (a pickle of the configuration, the augmentation and the frames) is read when it
    was written with the same ones, else the frames are computed and written there.
    """
    key = (config.to_dict(), None if augmentation is None else augmentation.to_dict())
    if cache is not None and cache.exists():
        written, frames = pickle.loads(cache.read_bytes())
        # a cache written with another configuration or augmentation, or by an older
        # script, is stale
        if written == key and isinstance(frames, dict):
            return frames
    trials = {}
    for i, folder in enumerate(folders):
        trials.update(decode_bags(bags=find_bags([folder]), spec=StreamSpec(),
                                  tag=f'{tag_prefix}{i}'))
    frames = compute_frames(events_by_trial=trials, config=config, audio_rate=16000.0,
                            wrench_rate=100.0, jobs=jobs, augmentation=augmentation)
    if cache is not None:
        cache.write_bytes(pickle.dumps((key, frames)))
    return frames
