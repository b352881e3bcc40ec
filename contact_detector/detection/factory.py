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
Detectors for recordings, configured like the node: the offline tools' way to the detector.

:func:`build_detector_factory` reads the node's parameters (the ``contact_detector_node``
section of a YAML file) and returns a :class:`DetectorFactory` that gives each recording a
fresh, armed :class:`~contact_detector.detection.detector.ContactDetector` with the model it
needs (the shipped multimodal one, the shipped F/T-only one for recordings without audio, or
the model named), at that recording's rates; with ``model.ft_also_decides`` a multimodal model
with the shipped F/T-only model deciding beside it, as on the node.
"""

import dataclasses
from pathlib import Path
from typing import Optional, Union

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.fallback import AudioFallback
from contact_detector.detection.offline import Run, run_detector
from contact_detector.detection.parameters import read_param_file
from contact_detector.detection.release import rule_overrides
from contact_detector.features.noise import NOISE_JUMP_N
from contact_detector.io.discovery import Streams
from contact_detector.io.messages import normalise_msg_type
from contact_detector.io.sensor_stream import sensor_events, StreamSpec
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.rule import DecisionRule
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle


def settings_from_params(params: dict, *, audio_rate: Optional[float]) -> tuple:
    """Map node parameters onto (DetectorSettings, StreamSpec fields, model path, rule)."""
    rule = rule_overrides(params) or None
    settings = {
        'audio_rate': float(audio_rate or params.get('audio.sample_rate', 16000)),
        'wrench_rate': float(params.get('wrench.rate', 100.0)),
        'max_input_delay_s': float(params.get('max_input_delay_s', 0.5)),
        'max_ft_wait_s': float(params.get('max_ft_wait_s', 0.25)),
        'warmup_s': float(params.get('warmup_s', 0.5)),
        'corrupt_holdoff_s': float(params.get('corrupt_holdoff_s', 0.2)),
        'wrench_bias': tuple(params.get('wrench.bias', (0.0,) * 6)),
        'noise_jump_n': float(params.get('wrench.noise_jump', NOISE_JUMP_N)),
    }
    age = params.get('max_ft_age_s', 0.0)
    if age and age > 0:
        settings['max_ft_age_s'] = float(age)
    channel = int(params.get('audio.channel', -1))
    # The bag's audio must have the node's type (the node would not even subscribe otherwise).
    msg_type = params.get('audio.msg_type')
    stream = {'channels': int(params.get('audio.channels', 1)),
              'channel': None if channel < 0 else channel,
              'audio_msg_type': normalise_msg_type(msg_type) if msg_type else None}
    return settings, stream, params.get('model.path', ''), rule


class DetectorFactory:
    """
    Fresh detectors with the model a recording needs (each model file is loaded once).

    ``model`` given (``--model`` or ``model.path``): always that model. Otherwise the shipped
    multimodal model for recordings with an audio topic and the shipped F/T-only model for
    recordings without one, or for every recording when ``audio_enabled`` is False (the node's
    ``audio.enabled``). With ``ft_also_decides`` a multimodal model decides together with the
    shipped F/T-only model (:class:`AudioFallback` with ``both_decide``), as the node does.

    Parameters
    ----------
    model : Path or None
        Model file that overrides the choice.
    audio_enabled : bool
        False: use the F/T-only model even where there is audio.
    settings : dict
        :class:`DetectorSettings` fields (without the rule).
    rule : dict or None
        Decision rule fields that override each model's own rule.
    ft_also_decides : bool
        The node's ``model.ft_also_decides``: the shipped F/T-only model decides beside a
        multimodal model, the first release of either is the release.

    """

    def __init__(self, *, model: Optional[Path], audio_enabled: bool, settings: dict,
                 rule: Optional[dict], ft_also_decides: bool = False) -> None:
        self.model = model
        self.audio_enabled = audio_enabled
        self.settings = settings
        self.rule = rule
        self.ft_also_decides = ft_also_decides
        self._loaded: dict = {}

    def path_for(self, *, has_audio: bool = True) -> Path:
        """Return the model file for a recording with (or without) an audio topic."""
        if self.model is not None:
            return self.model
        if has_audio and self.audio_enabled:
            return default_model_path()
        return default_ft_model_path()

    def bundle_for(self, *, has_audio: bool = True) -> ModelBundle:
        """Return the loaded model for a recording with (or without) an audio topic."""
        return self._load(self.path_for(has_audio=has_audio))

    def pairs_with_ft(self, *, has_audio: bool = True) -> bool:
        """Whether the shipped F/T-only model decides too for such a recording."""
        return (self.ft_also_decides
                and not self.bundle_for(has_audio=has_audio).feature_config.ft_only)

    def _load(self, path: Path) -> ModelBundle:
        if path not in self._loaded:
            bundle = load_bundle(path=path)
            settings = dict(self.settings)
            if self.rule is not None:
                base = bundle.decision_rule.to_dict()
                base.update(self.rule)
                settings['rule'] = DecisionRule.from_dict(base)
            self._loaded[path] = (bundle, DetectorSettings(**settings))
        return self._loaded[path][0]

    def describe(self, *, has_audio: bool = True) -> str:
        """``PATH (model id, F/T-only or audio + F/T)`` for the messages the tools print."""
        bundle = self.bundle_for(has_audio=has_audio)
        kind = 'F/T-only' if bundle.feature_config.ft_only else 'audio + F/T'
        text = f'{self.path_for(has_audio=has_audio)} ({bundle.model_id}, {kind})'
        if self.pairs_with_ft(has_audio=has_audio):
            ft = self._load(default_ft_model_path())
            text += (f' and {default_ft_model_path()} ({ft.model_id}, F/T-only), the first '
                     'release of either (model.ft_also_decides)')
        return text

    @property
    def decides_without_audio(self) -> bool:
        """Whether recordings without an audio topic get an F/T-only model."""
        return self.bundle_for(has_audio=False).feature_config.ft_only

    def __call__(self, streams: Optional[Streams] = None, *,
                 has_audio: bool = True) -> Union[ContactDetector, AudioFallback]:
        """
        Return a fresh, armed detector for a recording with (or without) audio.

        Given a bag's :class:`Streams`, the recording has audio if it has an audio topic, and
        the detector runs at that bag's audio and F/T rates. With :meth:`pairs_with_ft`, two
        models that both decide (:func:`~contact_detector.detection.offline.run_both`).
        """
        if streams is not None:
            has_audio = streams.has_audio
        detector = self._fresh(self.path_for(has_audio=has_audio), streams)
        if not self.pairs_with_ft(has_audio=has_audio):
            return detector
        return AudioFallback(primary=detector,
                             fallback=self._fresh(default_ft_model_path(), streams),
                             timeout_s=0.0, both_decide=True)

    def _fresh(self, path: Path, streams: Optional[Streams]) -> ContactDetector:
        bundle = self._load(path)
        settings = self._loaded[path][1]
        if streams is not None:
            rates = {'wrench_rate': streams.wrench_rate}
            if streams.audio_rate is not None:
                rates['audio_rate'] = streams.audio_rate
            settings = dataclasses.replace(settings, **rates)
        return ContactDetector(bundle=bundle, settings=settings)


def stream_spec(streams: Streams, stream: dict) -> StreamSpec:
    """Return the StreamSpec of a discovered bag (``stream``: the parameter file's fields)."""
    return StreamSpec(wrench_topic=streams.wrench_topic, audio_topic=streams.audio_topic,
                      audio_msg_type=streams.audio_msg_type, channels=streams.channels,
                      channel=stream.get('channel'), coding=streams.coding,
                      audio_rate=streams.audio_rate)


def build_detector_factory(*, model: Optional[Path], params_file: Optional[Path],
                           audio_rate: Optional[float]):
    """
    Return (make_detector, stream_fields) from a model path and node parameters.

    ``make_detector(streams=None)`` builds a fresh detector; given a bag's :class:`Streams`,
    with that bag's audio and F/T rates.
    """
    params = read_param_file(params_file) if params_file else {}
    settings, stream, model_param, rule = settings_from_params(params, audio_rate=audio_rate)
    path = model or (Path(model_param) if model_param else None)
    make = DetectorFactory(model=path, audio_enabled=bool(params.get('audio.enabled', True)),
                           settings=settings, rule=rule,
                           ft_also_decides=bool(params.get('model.ft_also_decides', False)))
    make.bundle_for(has_audio=True)         # a missing or bad model fails here, not per bag
    return make, stream


def detect_bag(*, bag: Path, make_detector, spec: StreamSpec,
               streams: Optional[Streams] = None) -> Run:
    """Run a fresh, armed detector over one bag (with its discovered rates, if given)."""
    detector = make_detector(streams) if streams is not None else make_detector()
    return run_detector(sensor_events(bag, spec=spec), detector=detector)
