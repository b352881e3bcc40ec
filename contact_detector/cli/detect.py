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
``contact-detector detect``: run the node's processing on bags, in bag time.

    contact-detector detect BAG_OR_DIR... [--model M] [--params P] [--wrench-topic T]
                            [--audio-topic T] [--audio-rate HZ] [--wrench-rate HZ]
                            [--audio-coding pcm|mp3] --out FILE.jsonl

Bags are rosbag2 directories (sqlite3, mcap) or ROS 1 ``.bag`` files. The wrench and audio
topics, the audio format and the F/T rate are found in each bag
(:mod:`contact_detector.io.discovery`) and printed; the options override what is found.

Writes one JSON object per line: for every audio frame
``{"bag": NAME, "t": T, "p": P, "contact": B}`` and for every release
``{"bag": NAME, "t": T, "event": "release"}``; NAME is the bag directory's name, T the absolute
bag time in seconds of the last audio sample the decision used (of the last F/T sample with an
F/T-only model). Each bag starts a fresh detector, armed. A recording without the audio topic
is decided by the shipped F/T-only model unless ``--model`` (or ``model.path``) names one; the
command prints which model it used. ``--params`` reads the node's YAML parameter file (the
``contact_detector_node: ros__parameters:`` section), so offline runs use the robot's settings;
its ``audio.sample_rate`` serves bags that do not describe their audio, and ``--audio-rate``
overrides both.
"""

import argparse
import dataclasses
import json
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import Run, run_detector
from contact_detector.detection.release import rule_overrides
from contact_detector.errors import ConfigError, ContactDetectorError
from contact_detector.io.bags import find_bags, manifest_entry
from contact_detector.io.discovery import discover_streams, Streams, summary_lines
from contact_detector.io.messages import normalise_msg_type
from contact_detector.io.sensor_stream import sensor_events, StreamSpec
from contact_detector.model.bundle import (DecisionRule, default_ft_model_path,
                                           default_model_path, load_bundle, ModelBundle)
from tqdm import tqdm


def read_node_params(path: Path) -> dict:
    """
    Return the node's parameters from a ROS 2 YAML parameter file, flattened ('a.b': v).

    Raises
    ------
    ConfigError
        If the file cannot be read or has no ``ros__parameters`` section.

    """
    import yaml
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as err:
        raise ConfigError(f'cannot read parameter file {path}: {err}') from err
    section = None
    for value in (data or {}).values():
        if isinstance(value, dict) and 'ros__parameters' in value:
            section = value['ros__parameters']
            break
    if section is None:
        raise ConfigError(f'{path} has no "<node>: ros__parameters:" section')
    flat = {}

    def walk(prefix, node):
        for key, value in node.items():
            name = f'{prefix}.{key}' if prefix else key
            if isinstance(value, dict):
                walk(name, value)
            else:
                flat[name] = value
    walk('', section)
    return flat


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


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector detect', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', help='bag directories or folders of bags')
    parser.add_argument('--model', type=Path, default=None,
                        help='model bundle (default: model.path from --params, else the '
                             'shipped model; for a recording without the audio topic, or '
                             'with audio.enabled false in --params, the shipped F/T-only '
                             'model)')
    parser.add_argument('--params', type=Path, default=None, help='node parameter YAML')
    add_stream_arguments(parser)
    parser.add_argument('--out', type=Path, required=True, help='JSONL output file')
    args = parser.parse_args(argv)
    try:
        return _detect(args)
    except ContactDetectorError as err:
        print(f'contact-detector detect: {err}', file=sys.stderr)
        return 1


class DetectorFactory:
    """
    Fresh detectors with the model a recording needs (each model file is loaded once).

    ``model`` given (``--model`` or ``model.path``): always that model. Otherwise the shipped
    multimodal model for recordings with an audio topic and the shipped F/T-only model for
    recordings without one, or for every recording when ``audio_enabled`` is False (the node's
    ``audio.enabled``).

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

    """

    def __init__(self, *, model: Optional[Path], audio_enabled: bool, settings: dict,
                 rule: Optional[dict]) -> None:
        self.model = model
        self.audio_enabled = audio_enabled
        self.settings = settings
        self.rule = rule
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
        path = self.path_for(has_audio=has_audio)
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
        return f'{self.path_for(has_audio=has_audio)} ({bundle.model_id}, {kind})'

    @property
    def decides_without_audio(self) -> bool:
        """Whether recordings without an audio topic get an F/T-only model."""
        return self.bundle_for(has_audio=False).feature_config.ft_only

    def __call__(self, streams: Optional[Streams] = None, *,
                 has_audio: bool = True) -> ContactDetector:
        """
        Return a fresh, armed detector for a recording with (or without) audio.

        Given a bag's :class:`Streams`, the recording has audio if it has an audio topic, and
        the detector runs at that bag's audio and F/T rates.
        """
        if streams is not None:
            has_audio = streams.has_audio
        bundle = self.bundle_for(has_audio=has_audio)
        settings = self._loaded[self.path_for(has_audio=has_audio)][1]
        if streams is not None:
            rates = {'wrench_rate': streams.wrench_rate}
            if streams.audio_rate is not None:
                rates['audio_rate'] = streams.audio_rate
            settings = dataclasses.replace(settings, **rates)
        return ContactDetector(bundle=bundle, settings=settings)


def add_stream_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options that override what discovery finds in a bag."""
    parser.add_argument('--wrench-topic', default=None,
                        help='wrench topic (default: the one WrenchStamped topic)')
    parser.add_argument('--audio-topic', default=None,
                        help='audio topic (default: the one topic of a supported audio type)')
    parser.add_argument('--audio-rate', type=float, default=None, metavar='HZ',
                        help='audio sample rate (default: from AudioInfo / AudioStamped, '
                             'else audio.sample_rate of --params, else estimated)')
    parser.add_argument('--wrench-rate', type=float, default=None, metavar='HZ',
                        help='F/T rate (default: measured from the header stamps)')
    parser.add_argument('--audio-coding', choices=('pcm', 'mp3'), default=None,
                        help='AudioData payload (default: from AudioInfo, else pcm)')


def discover_all(bags: Sequence[Path], *, args: argparse.Namespace, params: dict,
                 prog: str, allow_no_audio: bool = False) -> list:
    """
    Discover every bag's streams (flags override); print what was found; return the list.

    ``allow_no_audio``: the caller decides recordings without an audio topic with an F/T-only
    model, so such a bag is no error (its :class:`Streams` has ``audio_topic`` None).

    Returns
    -------
    list of (Path, Streams)

    """
    msg_type = params.get('audio.msg_type')
    found = []
    for bag in bags:
        # A simulator manifest beside the bag knows its rate; a parameter file is the robot's.
        entry = manifest_entry(bag)
        hint = (entry['audio_rate'], 'manifest') if entry and 'audio_rate' in entry else (
            params.get('audio.sample_rate'), 'parameters')
        found.append((bag, discover_streams(
            bag, wrench_topic=args.wrench_topic, audio_topic=args.audio_topic,
            audio_msg_type=msg_type or None, audio_rate=args.audio_rate,
            wrench_rate=getattr(args, 'wrench_rate', None),
            param_audio_rate=hint[0], param_source=hint[1],
            channels=int(params['audio.channels']) if 'audio.channels' in params else None,
            coding=getattr(args, 'audio_coding', None), allow_no_audio=allow_no_audio)))
    for line in summary_lines(found):
        print(f'{prog}: {line}')
    return found


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
    params = read_node_params(params_file) if params_file else {}
    settings, stream, model_param, rule = settings_from_params(params, audio_rate=audio_rate)
    path = model or (Path(model_param) if model_param else None)
    make = DetectorFactory(model=path, audio_enabled=bool(params.get('audio.enabled', True)),
                           settings=settings, rule=rule)
    make.bundle_for(has_audio=True)         # a missing or bad model fails here, not per bag
    return make, stream


def detect_bag(*, bag: Path, make_detector, spec: StreamSpec,
               streams: Optional[Streams] = None) -> Run:
    """Run a fresh, armed detector over one bag (with its discovered rates, if given)."""
    detector = make_detector(streams) if streams is not None else make_detector()
    return run_detector(sensor_events(bag, spec=spec), detector=detector)


def _detect(args: argparse.Namespace) -> int:
    make, stream = build_detector_factory(model=args.model, params_file=args.params,
                                          audio_rate=args.audio_rate)
    params = read_node_params(args.params) if args.params else {}
    found = discover_all(find_bags(args.bags), args=args, params=params,
                         prog='contact-detector detect',
                         allow_no_audio=make.decides_without_audio)
    bags = [bag for bag, _ in found]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    frames = releases = 0
    used = set()
    with args.out.open('w') as out:
        for bag, streams in tqdm(found, desc='detect', unit='bag', disable=len(bags) < 2):
            if streams.has_audio not in used:
                used.add(streams.has_audio)
                where = 'with' if streams.has_audio else 'without'
                print(f'model for recordings {where} an audio topic: '
                      f'{make.describe(has_audio=streams.has_audio)}')
            run = detect_bag(bag=bag, make_detector=make, spec=stream_spec(streams, stream),
                             streams=streams)
            name = bag.name
            rows = [(float(t), 0, {'bag': name, 't': float(t), 'p': float(p),
                                   'contact': bool(c)})
                    for t, p, c in zip(run.t, run.p, run.contact)]
            rows += [(float(t), 1, {'bag': name, 't': float(t), 'event': 'release'})
                     for t in run.releases]
            # A release line follows the frame that fired it.
            lines = [json.dumps(row) for _, _, row in sorted(rows, key=lambda r: r[:2])]
            out.write('\n'.join(lines) + ('\n' if lines else ''))
            frames += len(run.t)
            releases += len(run.releases)
            if run.counts.get('audio_dropped') or run.counts.get('wrench_dropped'):
                print(f'{name}: dropped {run.counts["audio_dropped"]} audio and '
                      f'{run.counts["wrench_dropped"]} wrench messages', file=sys.stderr)
    print(f'{len(bags)} bags, {frames} frames, {releases} releases -> {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
