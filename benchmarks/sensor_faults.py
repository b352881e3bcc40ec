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
What a broken F/T reading or audio stream 1 s before the contact does to the shipped models.

    .venv/bin/python benchmarks/sensor_faults.py [--trials 24] [--seed 8600] [--only KIND,...]
        [--ft-rule NAME:FIELD=VALUE,...]...
    .venv/bin/python benchmarks/sensor_faults.py --scan DIR_OR_BAG...

Simulated trials (``--conditions wide``: the twelve families in turn, the hand holding the
object) get, 1 s before the contact onset, one of these faults:

- ``zeros K``: K F/T samples of six exact zeros (a driver's placeholder for a missing reading);
- ``force-zeros K``, ``torque-zeros K``: the force (or the torque) of K samples zeroed;
- ``gone K``: K samples a hair above zero (1e-9: the load really gone, as far as the values
  say);
- ``spike K``: K samples with 3, -2 and 5 kN added to the force (a garbled message);
- ``frozen K``: K samples repeating the one before (a driver that republishes);
- ``noise5 K``, ``noise20 K``: K samples with white noise of 5 or 20 N per force axis and a
  twentieth of it in N m per torque axis added, the same draw (seed 1) in every trial
  (interference on the sensor's cable, a loose connector);
- ``audio-zeros MS``, ``audio-silent``: MS milliseconds of digital silence, or silence from
  then on (a muted microphone, an underrun filled with zeros);
- ``audio-clip MS``, ``audio-dc MS``, ``audio-noise MS``, ``audio-gain30 MS``: the samples
  at full scale with their sign, held at +20000, replaced by full-scale white noise, or x30
  (clipped).

Each trial is run through :class:`~contact_detector.detection.detector.ContactDetector` with
the shipped multimodal and F/T-only models, message by message as the node takes them (the
F/T-only model ignores audio: its audio rows are left out). The output lists, per fault, how
many trials each model released in before the onset (early), caught within 500 ms, and
missed. ``--only`` keeps the rows of the named kinds (``--only noise5,noise20``).
``--ft-rule NAME:FIELD=VALUE,...`` adds a column: the F/T-only model with those fields of its
rule changed (``no_hold:load2_threshold=0.0``: without the gated hold), to find the path that
releases. Run it from another checkout (``PYTHONPATH``) to compare code versions.

``--scan`` instead counts, in real or generated recordings, the F/T samples the node would
leave out as placeholders and the grid samples it would call noise (the first WrenchStamped
topic of each bag, at its own rate, through the detector's F/T stream): how often the checks
fire on sensors that are fine. It also prints the largest **force jitter** of any recording on
its raw samples (the median, over 0.1 s, at least 5 samples, of the length of the force's
change from one sample to the next, N), and the largest **reversing jump** on the 100 Hz
feature grid: the median jump of a 0.1 s window in which at least 60 % of the changes reverse
direction (:mod:`contact_detector.features.noise`; the noise check fires from 15 N). White
noise of 5 N per axis gives a jitter of about 11 N at any rate and a reversing jump of about
11 N; clean recordings show how far they stay below (docs/reliability.md,
docs/decisions/2026-12-07-noisy-reading-hold-off.md).
"""

import argparse
import dataclasses
import sys
from typing import Optional, Sequence

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.features.config import FeatureConfig
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.features.noise import jump_statistics, REVERSAL_SHARE
from contact_detector.features.resample import MAX_INPUT_RATE, MIN_INPUT_RATE, WrenchResampler
from contact_detector.io.bags import find_bags, read_wrench, topic_types, WRENCH_TYPE
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim.messages import message_events
from contact_detector.sim.trial import simulate_trials, Trial
from lofo_rules import parse_rule
import numpy as np

BREAKS = (('none', 0), ('zeros', 1), ('zeros', 3), ('zeros', 10), ('zeros', 50),
          ('force-zeros', 10), ('torque-zeros', 10), ('gone', 3), ('gone', 10), ('spike', 1),
          ('spike', 3), ('frozen', 20), ('noise5', 20), ('noise5', 80), ('noise20', 20),
          ('audio-zeros', 50), ('audio-zeros', 300),
          ('audio-silent', 0), ('audio-clip', 50), ('audio-dc', 500), ('audio-noise', 300),
          ('audio-gain30', 300))


def broken(trial: Trial, *, kind: str, k: int) -> Trial:
    """Return ``trial`` with ``k`` F/T samples (ms of audio) from 1 s before the onset broken."""
    if kind.startswith('audio-'):
        return broken_audio(trial, kind=kind[6:], ms=k)
    force, torque = trial.force.copy(), trial.torque.copy()
    j = int(np.searchsorted(trial.wrench_t, trial.onset_t - 1.0))
    span = slice(j, j + k)
    if kind == 'zeros':
        force[span], torque[span] = 0.0, 0.0
    elif kind == 'force-zeros':
        force[span] = 0.0
    elif kind == 'torque-zeros':
        torque[span] = 0.0
    elif kind == 'gone':
        force[span], torque[span] = 1e-9, 1e-9
    elif kind == 'spike':
        force[span] += np.array([3000.0, -2000.0, 5000.0])
    elif kind == 'frozen':
        force[span], torque[span] = force[j - 1], torque[j - 1]
    elif kind.startswith('noise'):
        sigma = float(kind[5:])
        rng = np.random.default_rng(1)
        force[span] += rng.normal(0.0, sigma, force[span].shape)
        torque[span] += rng.normal(0.0, sigma / 20, torque[span].shape)
    return dataclasses.replace(trial, force=force, torque=torque)


def broken_audio(trial: Trial, *, kind: str, ms: int) -> Trial:
    """Return ``trial`` with ``ms`` milliseconds of audio from 1 s before the onset broken."""
    audio = trial.audio.copy()
    i = int((trial.onset_t - 1.0 - trial.start_time) * trial.audio_rate)
    n = audio.size - i if kind == 'silent' else int(ms * trial.audio_rate / 1000)
    part = audio[i:i + n]
    if kind in ('zeros', 'silent'):
        part[:] = 0
    elif kind == 'clip':
        part[:] = np.where(part >= 0, 32767, -32768)
    elif kind == 'dc':
        part[:] = 20000
    elif kind == 'noise':
        part[:] = np.random.default_rng(0).integers(-32768, 32767, size=part.size)
    elif kind == 'gain30':
        part[:] = np.clip(part.astype(np.int64) * 30, -32768, 32767)
    return dataclasses.replace(trial, audio=audio)


def outcome(trial: Trial, *, bundle) -> str:
    """Return 'early', 'caught' (within 0.5 s of the onset) or 'missed' for one trial."""
    detector = ContactDetector(bundle=bundle, settings=DetectorSettings(
        audio_rate=trial.audio_rate, wrench_rate=trial.ft_rate))
    for e in message_events(trial=trial):
        if e.kind == 'audio':
            decided = detector.on_audio(trial.audio[e.lo:e.hi], stamp=e.t, now=e.t)
        else:
            decided = detector.on_wrench(t=trial.wrench_t[e.lo:e.hi],
                                         force=trial.force[e.lo:e.hi],
                                         torque=trial.torque[e.lo:e.hi], now=e.t)
        if decided.releases:
            t = decided.releases[0]
            return ('early' if t < trial.onset_t
                    else 'caught' if t <= trial.onset_t + 0.5 else 'missed')
    return 'missed'


def scan(paths: Sequence[str]) -> None:
    """Print how many F/T samples of the recordings the node would leave out or call noise."""
    bags = find_bags(paths)
    samples = left_out = noisy = 0
    worst = {'force jitter': (0.0, None), 'reversing jump on the grid': (0.0, None)}
    for bag in bags:
        topics = [name for name, kind in topic_types(bag).items() if kind == WRENCH_TYPE]
        if not topics:
            continue
        wrench = read_wrench(bag, topic=topics[0])
        if wrench.t.size < 2:
            continue
        rate = float(np.clip(1.0 / np.median(np.diff(wrench.t)), MIN_INPUT_RATE,
                             MAX_INPUT_RATE))
        # the whole recording in one call: the same samples left out, and the same noisy
        # ones, as one per call (test_wrench_placeholders.py, test_noise.py)
        stream = ForceTorqueStream(config=FeatureConfig(), input_rate=rate)
        stream.push(t=wrench.t, force=wrench.force, torque=wrench.torque)
        samples += wrench.t.size
        left_out += stream.placeholders
        noisy += stream.noisy
        if stream.placeholders or stream.noisy:
            print(f'{bag}: {stream.placeholders} placeholders, {stream.noisy} noisy grid samples '
                  f'({wrench.t.size} samples)')
        for name, value in (('force jitter', force_jitter(t=wrench.t, force=wrench.force)),
                            ('reversing jump on the grid', reversing_jump(
                                t=wrench.t, force=wrench.force, rate=rate))):
            if value > worst[name][0]:
                worst[name] = (value, bag)
    print(f'{len(bags)} recordings, {samples} F/T samples, {left_out} left out as placeholders, '
          f'{noisy} grid samples noisy')
    for name, (value, bag) in worst.items():
        if bag is not None:
            print(f'largest {name}: {value:.2f} N ({bag})')


def reversing_jump(*, t: np.ndarray, force: np.ndarray, rate: float) -> float:
    """
    Return the largest median jump of a window that reverses direction enough to be noise, N.

    The force (``t`` s, shape (n,); ``force`` N, shape (n, 3), at ``rate`` Hz) is resampled
    onto the 100 Hz feature grid as the detector does, and
    :func:`~contact_detector.features.noise.jump_statistics` gives each window's median jump
    and share of reversals; windows with a share of at least
    :data:`~contact_detector.features.noise.REVERSAL_SHARE` count. 0 when none does.
    """
    grid = WrenchResampler(input_rate=rate, output_rate=FeatureConfig().ft_rate_hz)
    _, values = grid.push(t=t, values=np.concatenate([force, np.zeros_like(force)], axis=1))
    jump, reversals = jump_statistics(force=values[:, :3])
    turning = jump[reversals >= REVERSAL_SHARE]
    return float(turning.max()) if turning.size else 0.0


def force_jitter(*, t: np.ndarray, force: np.ndarray) -> float:
    """
    Return the largest median of ``|F_{i+1} - F_i|`` over 0.1 s windows, N.

    ``t`` (s, shape (n,)) gives the rate; ``force`` is (n, 3) in N. 0 for fewer samples than a
    window (0.1 s, at least 5 sample-to-sample changes).
    """
    steps = np.linalg.norm(np.diff(force, axis=0), axis=1)
    window = max(5, int(round(0.1 / float(np.median(np.diff(t)))))) if t.size > 1 else 5
    if steps.size < window:
        return 0.0
    return float(np.median(np.lib.stride_tricks.sliding_window_view(steps, window),
                           axis=1).max())


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the table; print one row per broken reading and model."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--trials', type=int, default=24)
    parser.add_argument('--seed', type=int, default=8600)
    parser.add_argument('--scan', nargs='+', metavar='DIR_OR_BAG')
    parser.add_argument('--only', default='',
                        help='comma-separated kinds: only their rows (default: every row)')
    parser.add_argument('--ft-rule', action='append', default=[], metavar='NAME:FIELD=VALUE,...',
                        help="a column more: the F/T-only model with its rule's fields changed "
                             '(e.g. no_hold:load2_threshold=0.0); repeatable')
    args = parser.parse_args(argv)
    only = set(filter(None, args.only.split(',')))
    unknown = only - {kind for kind, _ in BREAKS}
    if unknown:
        parser.error(f'--only: unknown kinds {sorted(unknown)}')
    if args.scan:
        scan(args.scan)
        return 0
    trials = list(simulate_trials(n=args.trials, seed=args.seed, conditions=('wide',)))
    models = {'multimodal': load_bundle(path=default_model_path()),
              'F/T-only': load_bundle(path=default_ft_model_path())}
    for text in args.ft_rule:
        shipped = models['F/T-only']
        try:
            name, rule = parse_rule(text, base=shipped.decision_rule)
        except argparse.ArgumentTypeError as err:
            parser.error(f'--ft-rule: {err}')
        models[f'F/T-only {name}'] = dataclasses.replace(shipped, decision_rule=rule)
    print(f'{args.trials} trials, --seed {args.seed} --conditions wide; broken 1 s before the '
          'onset; early / caught within 500 ms / missed')
    print('| broken reading | ' + ' | '.join(models) + ' |')
    print('|---|' + '---|' * len(models))
    for kind, k in BREAKS:
        if only and kind not in only:
            continue
        cells = []
        for bundle in models.values():
            if kind.startswith('audio') and bundle.feature_config.ft_only:
                cells.append('(ignores audio)')
                continue
            got = [outcome(broken(trial, kind=kind, k=k), bundle=bundle) for trial in trials]
            cells.append(' / '.join(str(got.count(w)) for w in ('early', 'caught', 'missed')))
        name = 'none' if kind == 'none' else kind if kind == 'audio-silent' else f'{kind} {k}'
        print(f'| {name} | ' + ' | '.join(cells) + ' |', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
