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
``contact-detector plot BAG -o fig.png``: a figure like the paper's figure 4.

Panels: the trial's phases (from the manifest beside the bag, if any); |F| and its
spectrogram; the force spectral features (centroid, spread, flux); |T| and its spectrogram; the
torque spectral features; the audio with its power feature. The true contact onset (from
``/contact_truth``, else the manifest) is a dashed line on every panel; exogenous impacts from
the manifest are marked (hand: magenta, table: cyan; solid if the object was in the air).
"""

import argparse
import json
from pathlib import Path
import sys
from typing import Sequence

from contact_detector.errors import ContactDetectorError
from contact_detector.features.config import FeatureConfig
from contact_detector.io.bags import find_bags, manifest_entry, read_truth, read_wrench
from contact_detector.io.discovery import discover_streams
from contact_detector.io.sensor_stream import read_audio_series, StreamSpec
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
import numpy as np

PROG = 'contact-detector plot'
PHASE_COLOURS = {'rest': '#eeeeee', 'lift': '#d9e8f5', 'hold': '#f3f3e0',
                 'accelerate': '#fde2c8', 'descend': '#fbd0a0', 'push': '#c9ecc9',
                 'settle': '#e3d7f0', 'retreat': '#d9e8f5'}


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Plot a bag like the paper's figure 4: |F|, |T|, their spectrograms and "
                    'spectral features, audio and its power.')
    parser.add_argument('bag', metavar='BAG',
                        help='rosbag2 directory or ROS 1 .bag file (or a directory with '
                             'exactly one bag)')
    parser.add_argument('-o', '--output', required=True, type=Path, metavar='PNG',
                        help='output image (png, pdf or svg by suffix)')
    parser.add_argument('--feature-config', type=Path, default=None, metavar='FILE',
                        help='JSON (or YAML) FeatureConfig; top level or under "features" '
                             "(default: the shipped model's card)")
    parser.add_argument('--audio-rate', type=float, default=None, metavar='HZ',
                        help='audio sample rate (default: from the bag, else the manifest, '
                             'else estimated)')
    parser.add_argument('--wrench-topic', default=None,
                        help='wrench topic (default: the one WrenchStamped topic)')
    parser.add_argument('--audio-topic', default=None,
                        help='audio topic (default: the one topic of a supported audio type)')
    parser.add_argument('--title', default=None)
    parser.add_argument('--dpi', type=int, default=110)
    return parser


def load_feature_config(path: Path | None) -> FeatureConfig:
    """
    Load a FeatureConfig from a JSON/YAML file (keys at top level or under 'features').

    Without a file, the configuration of the shipped model's card.
    """
    if path is None:
        return load_bundle(path=default_model_path()).feature_config
    try:
        text = path.read_text(encoding='utf-8')
    except OSError as err:
        raise ContactDetectorError(f'cannot read {path}: {err}') from err
    if path.suffix in ('.yaml', '.yml'):
        try:
            import yaml
        except ImportError as err:
            raise ContactDetectorError('YAML feature configs need PyYAML; use JSON') from err
        data = yaml.safe_load(text)
    else:
        try:
            data = json.loads(text)
        except ValueError as err:
            raise ContactDetectorError(f'{path} is not JSON: {err}') from err
    if isinstance(data, dict):
        for key in ('features', 'feature_config'):
            if isinstance(data.get(key), dict):
                data = data[key]
                break
    if not isinstance(data, dict):
        raise ContactDetectorError(f'{path}: expected a mapping of FeatureConfig fields')
    return FeatureConfig.from_dict(data)


def _spectrogram(ax, *, t: np.ndarray, y: np.ndarray, rate: float, t_ref: float) -> None:
    from scipy.signal import spectrogram
    nper = int(min(len(y), max(16, round(0.32 * rate))))
    f, ts, sxx = spectrogram(y, fs=rate, nperseg=nper, noverlap=nper - max(1, nper // 8),
                             detrend='constant', scaling='density')
    db = 10 * np.log10(sxx + 1e-12)
    vmax = float(np.percentile(db, 99.5))
    ax.pcolormesh(t[0] - t_ref + ts, f, db, shading='auto', cmap='magma',
                  vmin=vmax - 60, vmax=vmax, rasterized=True)
    ax.set_ylim(0, min(rate / 2, 100.0))
    ax.set_ylabel('Hz')


def _features_panel(ax, frames, prefix: str, t_ref: float) -> None:
    names = list(frames.names)
    t = frames.t - t_ref
    ok = frames.valid
    for suffix, colour in (('centroid', 'tab:blue'), ('spread', 'tab:orange')):
        col = names.index(f'{prefix}_{suffix}')
        ax.plot(t[ok], frames.x[ok, col], color=colour, lw=0.9, label=suffix)
    ax.set_ylabel('C, S\n(x Fs/2)')
    ax2 = ax.twinx()
    col = names.index(f'{prefix}_flux')
    ax2.plot(t[ok], frames.x[ok, col], color='tab:green', lw=0.9, label='flux')
    ax2.set_ylabel('flux')
    lines = ax.get_lines() + ax2.get_lines()
    ax.legend(lines, [ln.get_label() for ln in lines], loc='upper left', fontsize=7, ncol=3)


def plot_bag(*, bag: Path, output: Path, config: FeatureConfig, audio_rate: float | None = None,
             wrench_topic: str | None = None, audio_topic: str | None = None,
             title: str | None = None, dpi: int = 110) -> Path:
    """
    Draw the figure for one bag and save it to ``output``.

    Raises
    ------
    ContactDetectorError
        The bag lacks the wrench or audio topic, or the feature code is unavailable.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    try:
        from contact_detector.features.batch import batch_features
    except ImportError as err:
        raise ContactDetectorError(f'feature code unavailable: {err}') from err

    entry = manifest_entry(bag)
    streams = discover_streams(bag, wrench_topic=wrench_topic, audio_topic=audio_topic,
                               audio_rate=audio_rate,
                               param_audio_rate=(entry or {}).get('audio_rate'))
    for line in streams.warnings:
        print(f'{PROG}: warning: {line}', file=sys.stderr)
    print(f'{PROG}: {bag.name}: {streams.describe()}')
    wrench = read_wrench(bag, topic=streams.wrench_topic)
    if wrench.dropped:
        # the figure shows what is left: say what is not in it
        print(f'{PROG}: warning: {bag.name}: {wrench.describe_drops()}', file=sys.stderr)
    rate = streams.audio_rate
    audio = read_audio_series(bag, spec=StreamSpec(
        wrench_topic=streams.wrench_topic, audio_topic=streams.audio_topic,
        audio_msg_type=streams.audio_msg_type, channels=streams.channels,
        coding=streams.coding, audio_rate=rate))
    ft_rate = streams.wrench_rate
    audio_t0 = float(entry['start_time']) if entry else audio.t0(rate)
    truth = [t for t, value in read_truth(bag) if value]
    if not truth and entry:
        truth = [entry['onset_t']]
    t_ref = float(entry['start_time']) if entry else float(min(wrench.t[0], audio_t0))

    frames = batch_features(config=config, audio=audio.samples, audio_rate=rate, audio_t0=audio_t0,
                            ft_t=wrench.t, force=wrench.force, torque=wrench.torque,
                            ft_input_rate=ft_rate)

    fmag = np.linalg.norm(wrench.force, axis=1)
    tmag = np.linalg.norm(wrench.torque, axis=1)
    tw = wrench.t - t_ref
    ta = audio_t0 - t_ref + np.arange(len(audio.samples)) / rate

    ratios = [0.35, 1, 1, 1, 1, 1, 1, 1.3]
    fig, axes = plt.subplots(len(ratios), 1, figsize=(11, 13), sharex=True,
                             gridspec_kw={'height_ratios': ratios})
    ax_ph, ax_f, ax_fs, ax_ff, ax_t, ax_ts, ax_tf, ax_a = axes
    # (a) phases
    if entry:
        for name, a, b in entry['phases']:
            ax_ph.axvspan(a - t_ref, b - t_ref, color=PHASE_COLOURS.get(name, '#eeeeee'))
            ax_ph.text((a + b) / 2 - t_ref, 0.5, name, ha='center', va='center', fontsize=7,
                       rotation=0 if b - a > 0.6 else 90)
        ax_ph.set_title(f'(a) phases   condition={entry["condition"]}', loc='left', fontsize=9)
    else:
        ax_ph.set_title('(a) phases: no manifest beside the bag', loc='left', fontsize=9)
    ax_ph.set_yticks([])
    # (b) |F| + spectrogram
    ax_f.plot(tw, fmag, color='k', lw=0.8)
    ax_f.set_ylabel('|F| (N)')
    ax_f.set_title('(b) force magnitude and its spectrogram', loc='left', fontsize=9)
    _spectrogram(ax_fs, t=tw, y=fmag, rate=ft_rate, t_ref=0.0)
    # (c) force features
    _features_panel(ax_ff, frames, 'force', t_ref)
    ax_ff.set_title('(c) force spectral features', loc='left', fontsize=9)
    # (d) |T| + spectrogram
    ax_t.plot(tw, tmag, color='k', lw=0.8)
    ax_t.set_ylabel('|T| (N m)')
    ax_t.set_title('(d) torque magnitude and its spectrogram', loc='left', fontsize=9)
    _spectrogram(ax_ts, t=tw, y=tmag, rate=ft_rate, t_ref=0.0)
    # (e) torque features
    _features_panel(ax_tf, frames, 'torque', t_ref)
    ax_tf.set_title('(e) torque spectral features', loc='left', fontsize=9)
    # (f) audio + power
    ax_a.plot(ta, audio.samples, color='0.5', lw=0.3)
    ax_a.set_ylabel('audio (FS)')
    peak = float(np.max(np.abs(audio.samples))) if len(audio.samples) else 1.0
    ax_a.set_ylim(-1.1 * max(peak, 0.01), 1.1 * max(peak, 0.01))
    ax_p = ax_a.twinx()
    power = frames.x[:, list(frames.names).index('audio_power')]
    ax_p.semilogy(frames.t - t_ref, np.maximum(power, 1e-10), color='tab:red', lw=0.9)
    ax_p.set_ylabel('power P(i)', color='tab:red')
    ax_a.set_title('(f) audio and its power feature', loc='left', fontsize=9)
    ax_a.set_xlabel(f'time (s) from {t_ref:.3f}')

    for ax in axes:
        for t in truth:
            ax.axvline(t - t_ref, color='k', ls='--', alpha=0.5, lw=1.2)
        for hit in (entry or {}).get('impacts', []):
            ax.axvline(hit['t'] - t_ref, color='m' if hit['kind'] == 'hand' else 'c',
                       ls='-' if hit['in_air'] else ':', alpha=0.8, lw=1.0)
    handles = [plt.Line2D([], [], color='k', ls='--', alpha=0.5, label='true contact onset'),
               plt.Line2D([], [], color='m', label='hand hit'),
               plt.Line2D([], [], color='c', label='table hit')]
    ax_ph.legend(handles=handles, loc='upper right', fontsize=7, ncol=3,
                 bbox_to_anchor=(1.0, 1.9))
    fig.suptitle(title or bag.name, fontsize=11)
    fig.tight_layout()
    output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(output, dpi=dpi)
    plt.close(fig)
    return output


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; return the exit status (0 ok, 1 error, 2 usage)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        bags = find_bags([args.bag])
        if len(bags) != 1:
            raise ContactDetectorError(f'{args.bag} holds {len(bags)} bags; give one of them '
                                       f'(e.g. {bags[0]})')
        config = load_feature_config(args.feature_config)
        out = plot_bag(bag=bags[0], output=args.output, config=config,
                       audio_rate=args.audio_rate, wrench_topic=args.wrench_topic,
                       audio_topic=args.audio_topic, title=args.title, dpi=args.dpi)
    except ContactDetectorError as err:
        print(f'{PROG}: error: {err}', file=sys.stderr)
        return 1
    print(f'wrote {out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
