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
Drive the detector pipeline from recorded sensor events (bag time, no ROS).

``detect``, ``evaluate``, ``train`` and the sweep call these, so offline results come from the
exact code the node runs: events go to :class:`ContactDetector` (or its feature extractor) in
log-time order, audio stamped as the node stamps it.
"""

from dataclasses import dataclass, field
from typing import Iterable, List, Optional, Union

from contact_detector.detection.detector import ContactDetector, Decisions
from contact_detector.detection.fallback import AudioFallback
from contact_detector.errors import ConfigError
from contact_detector.features.carried import CarriedLoad
from contact_detector.features.frames import FeatureFrames
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.sensor_stream import AudioEvent, BadEvent, Event, WrenchEvent
import numpy as np


@dataclass
class Run:
    """
    Decisions of one recording.

    Attributes
    ----------
    t, p, contact, valid : np.ndarray, shape (n,)
        Per audio frame: time (s), P(contact), decision, valid input.
    releases : list of float
        Release times, seconds.
    events : list of float
        Contact event times (armed or not), seconds.
    counts : dict
        The detector's counters at the end.
    carried : CarriedLoad or None
        The detector's last carried-load measurement (None if its model has no carried-load
        feature or the recording is shorter than the measurement).
    released_by : str or None
        With two models deciding (:func:`run_both`), which one made the release
        (:data:`~contact_detector.detection.fallback.MULTIMODAL` or ``FT_ONLY``); else None.

    """

    t: np.ndarray
    p: np.ndarray
    contact: np.ndarray
    valid: np.ndarray
    releases: List[float] = field(default_factory=list)
    events: List[float] = field(default_factory=list)
    counts: dict = field(default_factory=dict)
    carried: Optional[CarriedLoad] = None
    released_by: Optional[str] = None

    def input_problem(self) -> Optional[str]:
        """
        Say what kept frames from being decided, if anything did beyond the warm-up.

        A frame without valid input (no F/T near its time, stale, non-finite) is decided
        ``p = 0``, which looks like a confident "no contact" in the output; when most frames
        are such frames, a miss says nothing about the detector.

        Returns
        -------
        str or None
            One line for the tools to print; None when at least half of the frames were
            decided, no frame was stale, non-finite or after a time jump, no F/T sample
            was left out as a driver's placeholder (a force or torque of exactly 0 after a load)
            and none was noise (``wrench_noise``: releases held off after it).

        """
        c = self.counts
        frames, invalid = c.get('frames', 0), c.get('invalid_frames', 0)
        msgs = c.get('audio_msgs', 0) + c.get('wrench_msgs', 0)
        found = [f'{c[k]} {what}' for k, what in (
            ('stale_frames', 'stale'), ('nonfinite_frames', 'non-finite'),
            ('time_jumps', 'time jumps')) if c.get(k)]
        placeholders, noisy = c.get('wrench_placeholders', 0), c.get('wrench_noise', 0)
        notes = []
        if placeholders:
            notes.append(f'{placeholders} F/T samples with a force or torque of exactly (0, 0, 0) '
                         "after a load were left out (a driver's placeholder for a missing "
                         'reading)')
        if noisy:
            notes.append(f'{noisy} F/T samples were noise (the force jumped back and forth: '
                         'interference or a loose connector?); no frame whose F/T features saw '
                         'them could release')
        note = '; '.join(notes) or None
        if frames == 0:
            return f'no frame from {msgs} messages' if msgs else note
        if invalid * 2 <= frames and not found:
            return note
        text = f'{invalid} of {frames} frames could not be decided (p 0)'
        if found:
            text += ': ' + ', '.join(found)
        if invalid * 2 > frames:
            text += ('; most frames found no F/T sample near their time: are the wrench '
                     'stamps and the audio times on one clock? A miss here says nothing '
                     'about the detector')
        return text if note is None else f'{text}; {note}'


def run_detector(events: Iterable[Event], *, detector: Union[ContactDetector, AudioFallback],
                 in_blocks: bool = True) -> Run:
    """
    Feed events to ``detector`` as the node would; return every frame's decision.

    Parameters
    ----------
    events : iterable of Event
        From :func:`contact_detector.io.sensor_stream.sensor_events`.
    detector : ContactDetector or AudioFallback
        A fresh detector (armed as wanted), or two models that both decide
        (:func:`run_both`).
    in_blocks : bool
        Decide a clean recording in blocks (:mod:`contact_detector.detection.blocks`: the same
        bits, ~20x faster); False, or a recording with anything the node would drop, reset or
        restart on, goes message by message.

    Returns
    -------
    Run

    """
    if isinstance(detector, AudioFallback):
        return run_both(events, pair=detector, in_blocks=in_blocks)
    if in_blocks:
        events = list(events)
        run = _in_blocks(events, detector=detector)
        if run is not None:
            return run
    return _by_message(events, detector=detector)


def _in_blocks(events: List[Event], *, detector: ContactDetector) -> Optional[Run]:
    """Decide the recording in blocks; None if it needs the per-message path."""
    from contact_detector.detection.blocks import run_blocks

    decided = run_blocks(events, detector=detector)
    if decided is None:
        return None
    return Run(t=decided.t, p=decided.p, contact=decided.contact, valid=decided.valid,
               releases=decided.releases, events=decided.events,
               counts=dict(detector.counts), carried=detector.carried_load)


def _by_message(events: Iterable[Event], *,
                detector: Union[ContactDetector, AudioFallback]) -> Run:
    """Decide the recording message by message, as the node takes it."""
    blocks: List[Decisions] = []
    for event in events:
        if isinstance(event, AudioEvent):
            blocks.append(detector.on_audio(event.samples, stamp=event.stamp, now=event.now))
        elif isinstance(event, WrenchEvent):
            blocks.append(detector.on_wrench(t=event.t, force=event.force, torque=event.torque,
                                             now=event.now))
        elif isinstance(event, BadEvent):
            blocks.append(detector.drop(kind=event.kind, reason=event.reason, stamp=event.now))
    blocks.append(detector.flush())
    d = Decisions.concat(blocks)
    return Run(t=d.t, p=d.p, contact=d.contact, valid=d.valid, releases=d.releases,
               events=d.events, counts=dict(detector.counts), carried=detector.carried_load)


def run_both(events: Iterable[Event], *, pair: AudioFallback, in_blocks: bool = True) -> Run:
    """
    Both models of ``pair`` decide a recording: the node's default with a multimodal model.

    Each model runs over the whole recording as :func:`run_detector` runs one (in blocks where
    it can), and :meth:`~contact_detector.detection.fallback.AudioFallback.combine` takes the
    earlier of their first releases and merges the contact events: what the pair gives message
    by message while the audio keeps coming, except that message by message an F/T-only
    release less than one audio chunk after the audio model's comes first (its wrench sample
    arrives before the chunk that completes the audio frame), so the node's release can be
    that much later (docs/node.md, "Two models decide"). The frames are the multimodal
    model's.

    Parameters
    ----------
    events : iterable of Event
        From :func:`contact_detector.io.sensor_stream.sensor_events`.
    pair : AudioFallback
        Fresh, with ``both_decide`` and ``timeout_s`` 0: offline the audio is never waited
        for, so the F/T-only model never takes over alone.
    in_blocks : bool
        As for :func:`run_detector`.

    Returns
    -------
    Run
        With ``released_by``; its counts are the pair's (``ft_*`` for the F/T-only model).

    Raises
    ------
    ConfigError
        ``pair`` does not have both models deciding, or has an audio timeout.

    """
    if not pair.both_decide or pair.timeout_s > 0:
        raise ConfigError('offline, two models run only as both deciding with no audio '
                          f'timeout (both_decide=True, timeout_s=0; got {pair.both_decide}, '
                          f'{pair.timeout_s:g})')
    events = list(events)
    run = _in_blocks(events, detector=pair.primary) if in_blocks else None
    if run is None:
        # Something the node drops, restarts or resets on: the audio model's hold-off holds
        # the F/T-only model too, so the pair goes message by message, as on the node.
        run = _by_message(events, detector=pair)
        run.released_by = pair.last_release_by
        return run
    # A clean recording: no hold-off, so each model's run is that of the pair.
    ft = run_detector(events, detector=pair.fallback, in_blocks=in_blocks)
    both = pair.combine(_decisions(run), _decisions(ft))
    return Run(t=run.t, p=run.p, contact=run.contact, valid=run.valid, releases=both.releases,
               events=both.events, counts=pair.counts, carried=run.carried,
               released_by=pair.last_release_by if both.releases else None)


def _decisions(run: Run) -> Decisions:
    return Decisions(t=run.t, p=run.p, contact=run.contact, valid=run.valid,
                     releases=run.releases, events=run.events)


def run_features(events: Iterable[Event], *, extractor: StreamingFeatureExtractor,
                 in_blocks: bool = True) -> FeatureFrames:
    """
    Feed events to a feature extractor exactly as :class:`ContactDetector` does.

    Bad events are skipped (the detector would drop them too). With ``in_blocks`` a clean
    recording is computed in blocks (the same bits, :mod:`contact_detector.detection.blocks`).
    """
    if in_blocks:
        from contact_detector.detection.blocks import block_features

        events = list(events)
        got = block_features(events, extractor=extractor)
        if got is not None:
            return got.frames
    blocks = []
    for event in events:
        if isinstance(event, AudioEvent):
            blocks.append(extractor.push_audio(event.samples, stamp=event.stamp))
        elif isinstance(event, WrenchEvent):
            blocks.append(extractor.push_wrench(t=event.t, force=event.force,
                                                torque=event.torque))
    blocks.append(extractor.flush())
    return FeatureFrames.concat(blocks, extractor.names)
