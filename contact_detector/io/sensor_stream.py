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
Bag -> sensor events, in the order and with the times the live node would see them.

Every offline tool (``train``, ``detect``, ``evaluate``, the sweep, the demo's checks) reads
recordings through :func:`sensor_events`, which applies the node's own message adapters
(:mod:`contact_detector.io.messages`): audio is stamped with its header where the type has one
and with the bag's log (receive) time otherwise, wrench samples with their header stamps. An
audio header stamp that repeats or precedes the one before is dropped and counted, as the node
drops it. So the features computed offline are those the node computes live: no train/serve
skew.
"""

import dataclasses
from dataclasses import dataclass
import math
from pathlib import Path
from typing import Iterator, List, Optional, Union

from contact_detector.errors import BagError, InputError
from contact_detector.io import cdr
from contact_detector.io.bags import AudioSeries, iter_messages
from contact_detector.io.messages import (audio_stamp, audio_to_samples, check_stamp,
                                          wrench_to_arrays)
import numpy as np


@dataclass(frozen=True)
class StreamSpec:
    """
    Which topics carry what, and how to read the audio.

    Attributes
    ----------
    wrench_topic, audio_topic, truth_topic : str
        Topic names in the bag.
    audio_msg_type : str or None
        Audio message type, ``pkg/msg/Type``; None = take it from the bag. When set, a bag
        whose audio topic holds another type is refused (BagError).
    channels : int
        Interleaved channels in each audio message.
    channel : int or None
        Channel to keep; None mixes all channels.
    coding : str
        ``pcm`` (samples in the messages) or ``mp3`` (``AudioData`` bytes form an mp3
        stream, decoded by :mod:`contact_detector.io.mp3`).
    audio_rate : float or None
        Sample rate, Hz (needed for mp3: the decoded samples are timed with it).

    """

    wrench_topic: str = '/wrist_wrench'
    audio_topic: str = '/audio'
    truth_topic: str = '/contact_truth'
    audio_msg_type: Optional[str] = None
    channels: int = 1
    channel: Optional[int] = None
    coding: str = 'pcm'
    audio_rate: Optional[float] = None


@dataclass(frozen=True)
class AudioEvent:
    """An audio chunk: mono samples, the time of its last sample, the receive time (s)."""

    samples: np.ndarray
    stamp: float
    now: float


@dataclass(frozen=True)
class WrenchEvent:
    """Wrench samples: stamps (n,), force and torque (n, 3), the receive time (s)."""

    t: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    now: float


@dataclass(frozen=True)
class TruthEvent:
    """A ``/contact_truth`` message: True at the true onset, False at the label window's end."""

    value: bool
    now: float


@dataclass(frozen=True)
class BadEvent:
    """A message the adapters refused: which stream, why, and the receive time."""

    kind: str
    reason: str
    now: float


Event = Union[AudioEvent, WrenchEvent, TruthEvent, BadEvent]


#: CDR readers for the common sensor types (:data:`contact_detector.io.cdr.FAST_DECODERS`).
FAST_DECODERS = cdr.FAST_DECODERS


def sensor_events(path: Path, *, spec: StreamSpec = StreamSpec()) -> Iterator[Event]:
    """
    Yield the bag's sensor messages as events, in log-time order.

    Parameters
    ----------
    path : Path
        A rosbag2 directory (sqlite3 or mcap) or a ROS 1 ``.bag`` file.
    spec : StreamSpec
        Topics and audio format.

    Yields
    ------
    AudioEvent, WrenchEvent, TruthEvent or BadEvent

    Raises
    ------
    BagError
        The bag cannot be read, or ``spec.audio_msg_type`` is set (full ``pkg/msg/Type``
        form) and the audio topic holds another type.

    """
    if spec.coding == 'mp3':
        yield from _mp3_events(Path(path), spec=spec)
        return
    topics = [t for t in (spec.wrench_topic, spec.audio_topic, spec.truth_topic) if t]
    previous: Optional[float] = None       # the last accepted audio header stamp
    for message in iter_messages(Path(path), topics=topics, decoders=FAST_DECODERS):
        now = message.log_time_ns * 1e-9
        if message.topic == spec.audio_topic and spec.audio_msg_type \
                and message.msgtype != spec.audio_msg_type:
            raise BagError(f'{path}: {spec.audio_topic} holds {message.msgtype}, but the audio '
                           f'type is set to {spec.audio_msg_type} (audio.msg_type)')
        try:
            if message.topic == spec.wrench_topic:
                t, force, torque = wrench_to_arrays(message.msg)
                yield WrenchEvent(t=t, force=force, torque=torque, now=now)
            elif message.topic == spec.audio_topic:
                msg_type = spec.audio_msg_type or message.msgtype
                samples = audio_to_samples(message.msg, msg_type=msg_type,
                                           channels=spec.channels, channel=spec.channel)
                stamp = audio_stamp(message.msg, msg_type)
                if stamp is not None:
                    # the node's checks of header stamps (audio.stamp_source header): a
                    # repeated or reordered stamp is dropped and counted, not decided at a
                    # time that goes backwards; a driver that never fills the stamp (all 0)
                    # shows up here. The recorder's clock is not the sensor's, so no
                    # max_future_s.
                    check_stamp(stamp=stamp, now=now, max_future_s=math.inf,
                                previous=previous, what='audio header stamp')
                    previous = stamp
                yield AudioEvent(samples=samples, stamp=now if stamp is None else stamp,
                                 now=now)
            else:
                yield TruthEvent(value=bool(message.msg.data), now=now)
        except InputError as err:
            kind = 'wrench' if message.topic == spec.wrench_topic else 'audio'
            yield BadEvent(kind=kind, reason=str(err), now=now)


def _mp3_events(path: Path, *, spec: StreamSpec) -> Iterator[Event]:
    """:func:`sensor_events` for an mp3 AudioData stream: decoded at once, then interleaved."""
    from contact_detector.io.mp3 import decode_mp3

    chunks, log_t = [], []
    for message in iter_messages(path, topics=[spec.audio_topic]):
        audio = getattr(message.msg, 'audio', message.msg)       # AudioDataStamped: .audio
        chunks.append(bytes(np.asarray(audio.data, dtype=np.uint8)))
        log_t.append(message.log_time_ns * 1e-9)
    if not chunks:
        raise BagError(f'{path}: no messages on {spec.audio_topic}')
    try:
        mp3 = decode_mp3(chunks=chunks, log_t=log_t, channel=spec.channel)
    except InputError as err:
        raise BagError(f'{path}: {spec.audio_topic}: {err}') from err
    if spec.audio_rate and abs(mp3.rate - spec.audio_rate) > 0.5:
        raise BagError(f'{path}: the mp3 stream on {spec.audio_topic} is at {mp3.rate:g} Hz, '
                       f'not {spec.audio_rate:g} Hz as AudioInfo / --audio-rate say')
    audio_events, lo = [], 0
    for k, end in enumerate(mp3.ends.tolist()):
        if end > lo:
            audio_events.append(AudioEvent(samples=mp3.samples[lo:end],
                                           stamp=mp3.t0 + (end - 1) / mp3.rate, now=log_t[k]))
            lo = end
    others = sensor_events(path, spec=dataclasses.replace(spec, coding='pcm',
                                                          audio_topic='\0 no audio'))
    # both in log-time order: merge them (audio first on ties, as it was logged first)
    pending = iter(audio_events)
    nxt = next(pending, None)
    for event in others:
        while nxt is not None and nxt.now <= event.now:
            yield nxt
            nxt = next(pending, None)
        yield event
    while nxt is not None:
        yield nxt
        nxt = next(pending, None)


def load_events(path: Path, *, spec: StreamSpec = StreamSpec()) -> List[Event]:
    """Return :func:`sensor_events` as a list (decode a bag once, replay it many times)."""
    return list(sensor_events(path, spec=spec))


def read_audio_series(path: Path, *, spec: StreamSpec) -> AudioSeries:
    """
    Read a bag's audio into one array, through the node's adapters (any supported type).

    Returns
    -------
    AudioSeries
        ``samples`` in full-scale units (float64 in [-1, 1]), chunk ends, and per chunk the
        time of its last sample (its header stamp, else its log time).

    Raises
    ------
    BagError
        No readable audio.

    """
    chunks, stamps = [], []
    for event in sensor_events(path, spec=spec):
        if isinstance(event, AudioEvent):
            samples = event.samples
            scale = 32768.0 if samples.dtype == np.int16 else 1.0
            chunks.append(samples.astype(np.float64) / scale)
            stamps.append(event.stamp)
    if not chunks:
        raise BagError(f'{path}: no readable audio on {spec.audio_topic}')
    ends = np.cumsum([c.size for c in chunks]).astype(np.int64)
    return AudioSeries(np.concatenate(chunks), ends, np.asarray(stamps))


def truth_onsets(events: List[Event]) -> List[tuple]:
    """Return ``(onset_t, window_end_t)`` pairs from the truth events (end may be None)."""
    pairs, start = [], None
    for event in events:
        if isinstance(event, TruthEvent):
            if event.value and start is None:
                start = event.now
            elif not event.value and start is not None:
                pairs.append((start, event.now))
                start = None
    if start is not None:
        pairs.append((start, None))
    return pairs
