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
and with the bag's log (receive) time otherwise, wrench samples with their header stamps. So
the features computed offline are those the node computes live: no train/serve skew.
"""

from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, List, Optional, Union

from contact_detector.errors import BagError, InputError
from contact_detector.io import cdr
from contact_detector.io.bags import iter_messages
from contact_detector.io.messages import audio_stamp, audio_to_samples, wrench_to_arrays
import numpy as np

DEFAULT_AUDIO_TYPE = 'std_msgs/msg/Int16MultiArray'


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

    """

    wrench_topic: str = '/wrist_wrench'
    audio_topic: str = '/audio'
    truth_topic: str = '/contact_truth'
    audio_msg_type: Optional[str] = None
    channels: int = 1
    channel: Optional[int] = None


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
        A rosbag2 directory (sqlite3 or mcap).
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
    topics = [spec.wrench_topic, spec.audio_topic, spec.truth_topic]
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
                yield AudioEvent(samples=samples, stamp=now if stamp is None else stamp,
                                 now=now)
            else:
                yield TruthEvent(value=bool(message.msg.data), now=now)
        except InputError as err:
            kind = 'wrench' if message.topic == spec.wrench_topic else 'audio'
            yield BadEvent(kind=kind, reason=str(err), now=now)


def load_events(path: Path, *, spec: StreamSpec = StreamSpec()) -> List[Event]:
    """Return :func:`sensor_events` as a list (decode a bag once, replay it many times)."""
    return list(sensor_events(path, spec=spec))


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
