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
The feature, label and rule options of train and sweep (not a command).

Their defaults are the shipped recipe's (:mod:`contact_detector.training.recipe`).
"""

import argparse
from typing import Callable, Optional, Tuple, TypeVar

from contact_detector.features.config import EXTRA_FEATURES, FeatureConfig, TORQUE_FEATURES
from contact_detector.model.rule import DecisionRule, LOAD2_FIELDS, LOAD_FIELDS, STEADY_FRAMES
from contact_detector.training.augmentation import scale_range, WrenchAugmentation
from contact_detector.training.protocol import LabelWindow
from contact_detector.training.recipe import (DEFAULT_FEATURES, DEFAULT_FT_ONLY_RULE,
                                              DEFAULT_RULE, recipe_defaults, RecipeDefaults)

_T = TypeVar('_T')


def add_feature_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the feature/label/rule options shared by train and sweep."""
    d = DEFAULT_FEATURES
    parser.add_argument('--ft-window', type=int, default=d.ft_window,
                        help=f'F/T DFT window, samples (default {d.ft_window})')
    parser.add_argument('--ft-hop', type=int, default=d.ft_hop,
                        help=f'F/T feature hop, samples (default {d.ft_hop})')
    parser.add_argument('--ft-detrend', choices=('none', 'mean'), default=d.ft_detrend,
                        help=f"remove each F/T window's mean (default {d.ft_detrend})")
    parser.add_argument('--ft-window-fn', choices=('rect', 'hann'), default=d.ft_window_fn)
    for field, text in (('delta_window', 'F/T change features: newest samples averaged'),
                        ('delta_lag', 'F/T change features: samples back to the reference'),
                        ('baseline_window',
                         'samples in the median baseline of the *_change features'),
                        ('rise_frames', 'audio frames back to the reference of audio_rise_db'),
                        ('change_max_frames',
                         'F/T feature frames over which the *_change_max and *_shift_max '
                         'features take the maximum'),
                        ('shift_min_frames',
                         'F/T feature frames over which the *_shift_min features take the '
                         'minimum'),
                        ('shift_lag', 'F/T samples from the newest to the end of the '
                                      '*_shift baseline'),
                        ('shift_window', 'F/T samples in the median baseline of *_shift'),
                        ('hold_frames', 'F/T feature frames over which the *_hold features '
                                        'see whether a change held'),
                        ('carried_window', 'F/T samples after a start or an arming whose '
                                           'median is the carried load of *_shift_rel and '
                                           '*_carried_cos'),
                        ('audio_hold_frames', 'audio frames over which audio_hold_db takes '
                                              'the minimum')):
        default = getattr(d, field)
        parser.add_argument('--' + field.replace('_', '-'), type=int, default=default,
                            help=f'{text} (default {default})')
    for field, unit in (('carried_floor_force', 'N'), ('carried_floor_torque', 'N m')):
        default = getattr(d, field)
        parser.add_argument('--' + field.replace('_', '-'), type=float, default=default,
                            help=f'smallest carried load in {unit} that *_shift_rel divides '
                                 f'by and *_carried_cos takes a direction from (default '
                                 f'{default})')
    # the defaults of a multimodal model, and of an F/T-only one (--no-audio)
    m, f = recipe_defaults(ft_only=False), recipe_defaults(ft_only=True)
    parser.add_argument('--extra-features', default=None,
                        help='comma-separated extra features, from '
                             f"{', '.join(EXTRA_FEATURES)} (default "
                             f"{','.join(m.extra_features)}; with --no-audio "
                             f"{','.join(f.extra_features)})")
    parser.add_argument('--no-audio', action='store_true',
                        help='an F/T-only model (robots without a microphone): no audio '
                             'column, one frame per F/T feature frame')
    parser.add_argument('--torque', action=argparse.BooleanOptionalAction, default=None,
                        help="the torque columns; --no-torque: a force-only model (the paper's "
                             'three torque columns and the torque extra features leave the '
                             'defaults; one named in --extra-features is refused; default '
                             f"{'--torque' if m.torque else '--no-torque'}; with --no-audio "
                             f"{'--torque' if f.torque else '--no-torque'})")
    parser.add_argument('--label-start', type=float, default=None,
                        help='label window start after the onset, s (default '
                             f'{m.labels.start_s:g}; with --no-audio {f.labels.start_s:g})')
    parser.add_argument('--label-end', type=float, default=None,
                        help=f'label window end after the onset, s (default {m.labels.end_s:g}; '
                             f'with --no-audio {f.labels.end_s:g})')
    parser.add_argument('--label-ignore', type=float, default=m.labels.ignore_s,
                        metavar='S', help='leave the frames up to S s after the label window '
                        'out of training (default %(default)s: labelled no contact)')
    parser.add_argument('--label-ignore-lead', action='store_true',
                        help='leave the frames from the onset to --label-start out of training '
                             '(default: labelled no contact)')
    parser.add_argument('--event-weight', type=float, default=None, metavar='W',
                        help='training weight of the no-contact frames from 20 ms before to '
                             '0.8 s after a simulated knock, touch, brush or set-down starts '
                             f'(default {m.labels.event_weight:g}; with --no-audio '
                             f'{f.labels.event_weight:g}: as every other frame)')
    parser.add_argument('--threshold', type=float, default=DEFAULT_RULE.threshold)
    parser.add_argument('--confirm-frames', type=int, default=DEFAULT_RULE.confirm_frames)
    parser.add_argument('--refractory', type=float, default=DEFAULT_RULE.refractory_s)
    parser.add_argument('--average-frames', type=int, default=DEFAULT_RULE.average_frames,
                        help='compare the mean P(contact) of this many frames with --threshold')
    parser.add_argument('--sustain-frames', type=int, default=DEFAULT_RULE.sustain_frames,
                        help='slow path: also contact when the mean P(contact) of this many '
                             'frames >= --sustain-threshold (0 = off)')
    parser.add_argument('--sustain-threshold', type=float, default=None,
                        help=f'(default {DEFAULT_RULE.sustain_threshold:g}; with --no-audio '
                             f'{DEFAULT_FT_ONLY_RULE.sustain_threshold:g})')
    parser.add_argument('--evidence-threshold', type=float,
                        default=DEFAULT_RULE.evidence_threshold,
                        help='evidence path: also contact when the sum of P(contact) - '
                             '--evidence-drift over consecutive frames reaches this (0 = off)')
    parser.add_argument('--evidence-drift', type=float, default=DEFAULT_RULE.evidence_drift)
    add_load_path_arguments(
        parser, field='load',
        help_text='load path: also contact when the force has stayed this many N from the load '
                  'carried at the start or arming for --load-frames frames and the mean '
                  'P(contact) of --load-support-frames frames >= --load-support')
    add_load_path_arguments(
        parser, field='load2',
        help_text="second load path: the load path's test with its own --load2-* distance, "
                  'frames, backing and direction gate')
    parser.add_argument('--load2-steady', type=float, default=None, metavar='S',
                        help='the second load path also needs the distances of the newest '
                             f'{STEADY_FRAMES} frames within max - min <= S x their median, a '
                             'steady load rather than noise (0 = off; default '
                             f'{DEFAULT_RULE.load2_steady:g}; with --no-audio '
                             f'{DEFAULT_FT_ONLY_RULE.load2_steady:g})')


def add_load_path_arguments(parser: argparse.ArgumentParser, *, field: str, help_text: str,
                            defaults: Optional[DecisionRule] = None) -> None:
    """
    Add one load path's five options, ``--{field}-threshold`` and the rest.

    Without ``defaults`` (``train``) their defaults are None and :func:`rule_from_args` fills
    in the model kind's; with ``defaults`` (``sweep``) each takes that rule's field.
    """
    option = '--' + field.replace('_', '-')

    def default(name: str) -> object:
        return getattr(defaults or DEFAULT_FT_ONLY_RULE, f'{field}_{name}')

    def given(name: str) -> object:
        return None if defaults is None else default(name)

    if defaults is None:
        threshold_help = (f'{help_text} (0 = off; default '
                          f'{getattr(DEFAULT_RULE, field + "_threshold"):g}; with --no-audio '
                          f'{default("threshold"):g})')
    else:
        threshold_help = f'{help_text} (default {default("threshold"):g}: off)'
    parser.add_argument(f'{option}-threshold', type=float, default=given('threshold'),
                        metavar='N', help=threshold_help)
    parser.add_argument(f'{option}-frames', type=int, default=given('frames'),
                        help=f'default {default("frames")}')
    parser.add_argument(f'{option}-support', type=float, default=given('support'),
                        help=f'default {default("support"):g}')
    parser.add_argument(f'{option}-support-frames', type=int, default=given('support_frames'),
                        help=f'default {default("support_frames")}')
    parser.add_argument(f'{option}-direction', type=float, default=given('direction'),
                        metavar='COS',
                        help='direction gate: the path also needs the cosine between the '
                             "force's distance from the carried load and the carried load "
                             '<= COS, or exactly 0 (a tared sensor) (1 = off; '
                             f'default {default("direction"):g})')


def tree_counts(text: str) -> list:
    """Parse ``1-10,20,50`` into sorted distinct tree counts (argparse type)."""
    counts = set()
    try:
        for part in text.split(','):
            low, _, high = part.strip().partition('-')
            counts.update(range(int(low), int(high or low) + 1))
    except ValueError as err:
        raise argparse.ArgumentTypeError(f'not a list of tree counts: {text!r}') from err
    if not counts or min(counts) < 1:
        raise argparse.ArgumentTypeError(f'tree counts must be >= 1: {text!r}')
    return sorted(counts)


def rule_from_args(args: argparse.Namespace) -> DecisionRule:
    """
    Build the DecisionRule from parsed options.

    The slow path's threshold and the load paths' options not given take the defaults of the
    model kind: the F/T-only recipe's with ``--no-audio``, else the multimodal one's.
    """
    kind = DEFAULT_FT_ONLY_RULE if getattr(args, 'no_audio', False) else DEFAULT_RULE
    by_kind = {name: (getattr(kind, name) if getattr(args, name, None) is None
                      else getattr(args, name))
               for name in LOAD_FIELDS + LOAD2_FIELDS + ('load2_steady', 'sustain_threshold')}
    return DecisionRule(threshold=args.threshold, confirm_frames=args.confirm_frames,
                        refractory_s=args.refractory, average_frames=args.average_frames,
                        sustain_frames=args.sustain_frames,
                        evidence_threshold=args.evidence_threshold,
                        evidence_drift=args.evidence_drift, **by_kind)


def config_from_args(args: argparse.Namespace) -> FeatureConfig:
    """Build the FeatureConfig from parsed options."""
    no_audio = bool(getattr(args, 'no_audio', False))
    torque = _given(getattr(args, 'torque', None), default=_defaults(args).torque)
    if args.extra_features is None:
        extra = tuple(e for e in _defaults(args).extra_features
                      if torque or e not in TORQUE_FEATURES)
    else:
        extra = tuple(e for e in args.extra_features.split(',') if e)
    return FeatureConfig(audio=not no_audio, torque=torque, ft_window=args.ft_window,
                         ft_hop=args.ft_hop,
                         ft_detrend=args.ft_detrend, ft_window_fn=args.ft_window_fn,
                         delta_window=args.delta_window, delta_lag=args.delta_lag,
                         baseline_window=args.baseline_window, rise_frames=args.rise_frames,
                         change_max_frames=args.change_max_frames,
                         shift_min_frames=args.shift_min_frames, shift_lag=args.shift_lag,
                         shift_window=args.shift_window, hold_frames=args.hold_frames,
                         carried_window=args.carried_window,
                         audio_hold_frames=args.audio_hold_frames,
                         carried_floor_force=args.carried_floor_force,
                         carried_floor_torque=args.carried_floor_torque,
                         extra_features=extra)


def labels_from_args(args: argparse.Namespace) -> LabelWindow:
    """
    Return the label window the options name (raises ConfigError on a bad window).

    An option not given takes the shipped recipe's value: the F/T-only model's with
    ``--no-audio``, else the multimodal model's (:func:`recipe_defaults`).
    """
    d = _defaults(args).labels
    return LabelWindow(start_s=_given(args.label_start, default=d.start_s),
                       end_s=_given(args.label_end, default=d.end_s),
                       ignore_s=args.label_ignore,
                       event_weight=_given(args.event_weight, default=d.event_weight),
                       ignore_lead=args.label_ignore_lead)


def add_augmentation_arguments(parser: argparse.ArgumentParser, *,
                               defaults: Optional[WrenchAugmentation] = None) -> None:
    """
    Add the wrench-augmentation ranges shared by train and sweep.

    ``defaults``: the ranges an option not given takes (sweep's); None, the shipped recipes'
    (train's: the multimodal model's, or with ``--no-audio`` the F/T-only model's).
    """
    # with given defaults (sweep's) one value per option; else train's two recipes'
    m = defaults if defaults is not None else recipe_defaults(ft_only=False).augmentation
    f = None if defaults is not None else recipe_defaults(ft_only=True).augmentation

    def default(show: Callable[[WrenchAugmentation], str]) -> str:
        return show(m) if f is None else f'{show(m)}; train --no-audio {show(f)}'
    parser.add_argument('--augment-tare', type=float, default=None,
                        help='augmentation: probability of a tared sensor (default '
                             f'{default(lambda a: f"{a.tare_probability:g}")})')
    parser.add_argument('--augment-torque', type=scale_range, default=None,
                        help='augmentation: torque scale range LOW,HIGH, log-uniform (default '
                             f'{default(lambda a: _pair(a.torque_scale))})')
    parser.add_argument('--augment-offset', type=float, default=None,
                        help='augmentation: probability that an untared trial reads with a '
                             f'sensor offset of up to +-{m.offset_force_n:g} N and '
                             f'+-{m.offset_torque_nm:g} N m per axis (default '
                             f'{default(lambda a: f"{a.offset_probability:g}")})')
    parser.add_argument('--augment-offset-size', type=scale_range, default=None, metavar='N,NM',
                        help='augmentation: the largest sensor offset per axis, force (N) and '
                             'torque (N m), of --augment-offset (default '
                             f'{default(lambda a: _pair(_offset_size(a)))})')
    parser.add_argument('--augment-gain', type=scale_range, default=None, metavar='LOW,HIGH',
                        help='augmentation: the whole wrench times a gain drawn log-uniformly '
                             f'from LOW,HIGH (default {default(lambda a: _pair(a.gain))})')
    parser.add_argument('--augment-contact-offset', type=float, default=None, metavar='M',
                        help='augmentation: every load change acts up to M m away from where '
                             'it was simulated (default '
                             f'{default(lambda a: f"{a.contact_offset_m:g}")})')
    parser.add_argument('--augment-lag', type=scale_range, default=None, metavar='LOW,HIGH',
                        help='augmentation: the whole wrench through a first-order lag whose '
                             'time constant (s) is drawn log-uniformly from LOW,HIGH: a softer '
                             'wrist or surface (default '
                             f'{default(lambda a: _pair(a.lag_s) if any(a.lag_s) else "none")})')


def _offset_size(augmentation: WrenchAugmentation) -> Tuple[float, float]:
    return augmentation.offset_force_n, augmentation.offset_torque_nm


def _pair(value: Tuple[float, float]) -> str:
    return f'{value[0]:g},{value[1]:g}'


def augmentation_from_args(args: argparse.Namespace, *,
                           defaults: Optional[WrenchAugmentation] = None) -> WrenchAugmentation:
    """
    Return the augmentation the options name (raises ConfigError on a bad range).

    A range not given takes ``defaults``'s, or if that is None the shipped recipe's: the F/T-only
    model's with ``--no-audio``, else the multimodal model's (:func:`recipe_defaults`).
    """
    d = defaults if defaults is not None else _defaults(args).augmentation
    offset_force_n, offset_torque_nm = _given(args.augment_offset_size, default=_offset_size(d))
    return WrenchAugmentation(
        tare_probability=_given(args.augment_tare, default=d.tare_probability),
        torque_scale=tuple(_given(args.augment_torque, default=d.torque_scale)),
        offset_probability=_given(args.augment_offset, default=d.offset_probability),
        offset_force_n=offset_force_n,
        offset_torque_nm=offset_torque_nm,
        contact_offset_m=_given(args.augment_contact_offset, default=d.contact_offset_m),
        gain=tuple(_given(args.augment_gain, default=d.gain)),
        lag_s=tuple(_given(args.augment_lag, default=d.lag_s)))


def _defaults(args: argparse.Namespace) -> RecipeDefaults:
    # sweep has no --no-audio: its defaults are the multimodal model's
    return recipe_defaults(ft_only=bool(getattr(args, 'no_audio', False)))


def _given(value: Optional[_T], *, default: _T) -> _T:
    # argparse leaves an option that was not given at None
    return default if value is None else value
