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
Find a bag's sensor topics, audio format and F/T rate, so offline commands need no flags.

* Wrench topic: the one topic of type ``geometry_msgs/msg/WrenchStamped`` (a topic named by
  the command's flag must be of that type too, :func:`find_wrench_topic`).
* Audio topic: the one topic of a supported audio type (:data:`AUDIO_MSG_TYPES`).
* Audio format, first found of: the command's flag; the bag's own description, an
  ``audio_common_msgs/msg/AudioInfo`` topic (ros-drivers: rate, channels, coding ``wave`` or
  ``mp3``) or the format every mgonzs13 ``AudioStamped`` carries; for ``AudioData`` without
  ``AudioInfo``, the mp3 frame headers when its bytes are mp3 (:func:`sniff_mp3`); the
  node's parameter file; else an estimate: samples per second of recording (bag log) time,
  snapped to the nearest standard rate (:data:`STANDARD_AUDIO_RATES`), with a warning.
* No audio topic: an error, unless the caller can decide without audio (``allow_no_audio``,
  an F/T-only model): the bag's :class:`Streams` then has ``audio_topic`` None, and its
  ``audio_note`` names a topic that looks like audio but has an unsupported type.
* F/T rate: the command's flag, else the mean period of the regular steps of the header stamps
  (:func:`measure_wrench_rate`).

Both measurements come from one pass over the first messages (:func:`probe`).

With several candidate topics the error lists them; a flag then chooses. Only the first
:data:`PROBE_MESSAGES` messages of a topic (and at most :data:`PROBE_SECONDS` of audio) are
read, so discovery costs little next to decoding the bag.
"""

from dataclasses import dataclass
import math
from pathlib import Path
from typing import Optional, Sequence

from contact_detector.errors import BagError, ConfigError, InputError
from contact_detector.io.bags import iter_messages, topic_types
from contact_detector.io.cdr import FAST_DECODERS
from contact_detector.io.messages import (AUDIO_MSG_TYPES, audio_to_samples, check_audio_info,
                                          embedded_audio_format, MAX_SAMPLE_RATE,
                                          MIN_SAMPLE_RATE, normalise_msg_type, wrench_sample)
from contact_detector.io.mp3 import mp3_format
import numpy as np

WRENCH_TYPE = 'geometry_msgs/msg/WrenchStamped'
AUDIO_INFO_TYPE = 'audio_common_msgs/msg/AudioInfo'
#: Sample rates an estimate is snapped to, Hz.
STANDARD_AUDIO_RATES = (8000.0, 11025.0, 16000.0, 22050.0, 32000.0, 44100.0, 48000.0, 96000.0)
#: Wrench messages read to measure the F/T rate.
PROBE_MESSAGES = 500
#: Seconds of audio (log time) used to estimate an audio rate.
PROBE_SECONDS = 5.0
#: AudioData messages read to tell mp3 from PCM when no AudioInfo says.
SNIFF_MESSAGES = 8
#: The audio type whose bytes may be mp3.
MP3_CAPABLE_TYPE = 'audio_common_msgs/msg/AudioData'


@dataclass(frozen=True)
class Streams:
    """
    What one bag holds and how to read it.

    Attributes
    ----------
    wrench_topic : str
        Topic name.
    audio_topic : str or None
        Topic name; None: the bag has no audio topic (only an F/T-only model decides it).
    audio_msg_type : str
        ``pkg/msg/Type`` of the audio topic ('' without one).
    audio_rate : float or None
        Audio sample rate, Hz (None without an audio topic).
    audio_rate_source : str
        Where it comes from: ``flag``, ``AudioInfo``, ``AudioStamped``, ``mp3 header``,
        ``parameters`` or ``estimated`` ('' without an audio topic).
    channels : int
        Interleaved audio channels.
    coding : str
        ``pcm`` (raw samples) or ``mp3`` (AudioData bytes are an mp3 stream).
    wrench_rate : float
        F/T sample rate, Hz.
    wrench_rate_source : str
        ``flag`` or ``stamps`` (measured).
    warnings : tuple of str
        What the user should know (an estimated rate).
    audio_note : str
        Without an audio topic: why a topic that looks like audio was not read (its type is
        not supported); '' if there is none.

    """

    wrench_topic: str
    audio_topic: Optional[str]
    audio_msg_type: str
    audio_rate: Optional[float]
    audio_rate_source: str
    channels: int
    coding: str
    wrench_rate: float
    wrench_rate_source: str
    warnings: tuple = ()
    audio_note: str = ''

    @property
    def has_audio(self) -> bool:
        """Whether the bag has an audio topic."""
        return self.audio_topic is not None

    def describe(self) -> str:
        """One line: topics, audio format and F/T rate, with their sources."""
        if not self.has_audio:
            note = f' ({self.audio_note})' if self.audio_note else ''
            return (f'wrench {self.wrench_topic} at {self.wrench_rate:.4g} Hz '
                    f'({self.wrench_rate_source}); no audio topic{note}')
        coding = ', mp3' if self.coding == 'mp3' else ''
        return (f'wrench {self.wrench_topic} at {self.wrench_rate:.4g} Hz '
                f'({self.wrench_rate_source}); audio {self.audio_topic} '
                f'[{self.audio_msg_type.replace("/msg/", "/")}] {self.audio_rate:g} Hz, '
                f'{self.channels} ch{coding} ({self.audio_rate_source})')


def snap_audio_rate(rate: float) -> float:
    """Return the standard rate nearest to ``rate`` on a log scale (Hz)."""
    return min(STANDARD_AUDIO_RATES, key=lambda r: abs(math.log(r / rate)))


def _pick(path: Path, types: dict, wanted, what: str, flag: str, given: Optional[str]) -> str:
    if given:
        if given not in types:
            raise BagError(f'{path}: no topic {given} ({flag}); topics: '
                           f'{", ".join(sorted(types)) or "none"}')
        return given
    found = sorted(topic for topic, msgtype in types.items() if wanted(msgtype))
    if len(found) == 1:
        return found[0]
    if not found:
        raise BagError(f'{path}: no {what} topic; topics: '
                       + ', '.join(f'{t} [{m}]' for t, m in sorted(types.items())))
    raise BagError(f'{path}: several {what} topics: '
                   + ', '.join(f'{t} [{types[t]}]' for t in found) + f'; choose one with {flag}')


def find_wrench_topic(path: Path, *, types: dict, given: Optional[str] = None) -> str:
    """
    Return the wrench topic of a bag: ``given`` (``--wrench-topic``), else found by its type.

    Parameters
    ----------
    path : Path
        The bag, for the messages.
    types : dict
        Topic name -> message type of the bag (:func:`~contact_detector.io.bags.topic_types`).
    given : str or None
        The topic the user named; None = the one topic of type :data:`WRENCH_TYPE`.

    Returns
    -------
    str

    Raises
    ------
    BagError
        ``given`` is missing from the bag or is of another type than :data:`WRENCH_TYPE`
        (the message names the type found), or no or several topics have that type.

    """
    topic = _pick(path, types, lambda m: m == WRENCH_TYPE, 'geometry_msgs/WrenchStamped',
                  '--wrench-topic', given)
    if types[topic] != WRENCH_TYPE:
        # Every reader downstream takes the messages for wrenches: refuse here, by name.
        raise BagError(f'{path}: {topic} (--wrench-topic) holds {types[topic]}, not '
                       f'{WRENCH_TYPE}')
    return topic


def unsupported_audio_note(types: dict) -> str:
    """
    Say which topics look like audio but have a type that cannot be read ('' if none).

    A topic looks like audio when ``audio`` is part of its name or type (``AudioInfo``, the
    format topic, aside), e.g. ``/audio`` recorded as ``std_msgs/msg/String``.
    """
    odd = sorted((t, m) for t, m in types.items()
                 if m not in AUDIO_MSG_TYPES and m != AUDIO_INFO_TYPE
                 and 'audio' in f'{t} {m}'.lower())
    if not odd:
        return ''
    listed = ', '.join(f'{t} holds {m}' for t, m in odd)
    return f'{listed}: not a supported audio type'


def _flag_rates(audio_rate: Optional[float],
                wrench_rate: Optional[float]) -> tuple[Optional[float], Optional[float]]:
    """Check the rates given by flags; 0 is refused like any value out of range."""
    if audio_rate is not None:
        value = float(audio_rate)
        if not MIN_SAMPLE_RATE <= value <= MAX_SAMPLE_RATE:     # also False for NaN
            raise ConfigError(f'--audio-rate: audio sample rate must be in '
                              f'[{MIN_SAMPLE_RATE:.0f}, {MAX_SAMPLE_RATE:.0f}] Hz, got '
                              f'{value:g}')
        audio_rate = value
    if wrench_rate is not None:
        value = float(wrench_rate)
        # the accepted range is the resampler's (features layer): only what no rate can be here
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f'--wrench-rate: F/T rate must be a positive number of Hz, '
                              f'got {value:g}')
        wrench_rate = value
    return audio_rate, wrench_rate


def _info_topic(types: dict, audio_topic: str) -> Optional[str]:
    infos = sorted(t for t, m in types.items() if m == AUDIO_INFO_TYPE)
    if len(infos) <= 1:
        return infos[0] if infos else None
    near = [t for t in infos if t.rsplit('/', 1)[0] == audio_topic.rsplit('/', 1)[0]]
    return near[0] if len(near) == 1 else None


def probe(path: Path, *, wrench_topic: Optional[str], audio_topic: Optional[str] = None,
          audio_msg_type: str = '', channels: int = 1) -> tuple[list, list, list]:
    """
    Read the first messages of the wrench and audio topics once, for the rate measurements.

    Returns
    -------
    stamps : list of float
        Header stamps of the first :data:`PROBE_MESSAGES` wrench messages, s.
    sizes, times : list
        Sample frames and log times (s) of the audio chunks of the first
        :data:`PROBE_SECONDS` (empty without ``audio_topic``).

    """
    stamps, sizes, times = [], [], []
    topics = [t for t in (wrench_topic, audio_topic) if t]
    wrench_done = wrench_topic is None
    audio_done = audio_topic is None
    for message in iter_messages(path, topics=topics, decoders=FAST_DECODERS):
        if message.topic == wrench_topic and not wrench_done:
            try:
                stamps.append(wrench_sample(message.msg)[0])
            except InputError:
                pass
            wrench_done = len(stamps) >= PROBE_MESSAGES
        elif message.topic == audio_topic and not audio_done:
            try:
                samples = audio_to_samples(message.msg, msg_type=audio_msg_type,
                                           channels=channels)
            except InputError:
                continue
            sizes.append(samples.size)
            times.append(message.log_time_ns * 1e-9)
            audio_done = times[-1] - times[0] >= PROBE_SECONDS
        if wrench_done and audio_done:
            break
    return stamps, sizes, times


def measure_wrench_rate(*, stamps: Sequence[float], path: Path, topic: str) -> float:
    """
    F/T rate from the header stamps of the first messages, Hz.

    The regular steps are those shorter than 1.5 median steps (gaps and dropped messages
    left out); the rate is their count over their total duration: the mean period, which
    float stamps (~0.2 us resolution today) resolve far better than a single step at 10 kHz.

    Raises
    ------
    BagError
        Fewer than two increasing stamps.

    """
    steps = np.diff(np.asarray(stamps, dtype=float))
    steps = steps[steps > 0]
    if steps.size == 0:
        raise BagError(f'{path}: cannot measure the F/T rate of {topic} (fewer than two '
                       'increasing header stamps); give --wrench-rate')
    regular = steps[steps < 1.5 * np.median(steps)]
    return float(regular.size / regular.sum())


def estimate_audio_rate(*, sizes: Sequence[int], times: Sequence[float], path: Path,
                        topic: str) -> float:
    """
    Audio samples per second of bag log time: ``sum(n_k, k > 0) / (t_last - t_first)``, Hz.

    The first chunk's samples were recorded before its log time, so they are left out.

    Raises
    ------
    BagError
        Fewer than three readable chunks, or no log time elapsed.

    """
    if len(sizes) < 3 or times[-1] <= times[0]:
        raise BagError(f'{path}: too little audio on {topic} to estimate its sample rate; '
                       'give --audio-rate')
    return float(sum(sizes[1:]) / (times[-1] - times[0]))


def sniff_mp3(path: Path, *, topic: str) -> Optional[tuple[float, int]]:
    """
    ``(rate, channels)`` if the first :data:`SNIFF_MESSAGES` messages of ``topic`` are mp3.

    For ``AudioData`` without ``AudioInfo`` (audio_common records mp3 by default, and
    ``rosbag record`` of the audio topic alone leaves the info out): the mp3 frame headers
    carry the sample rate and channel mode (:func:`contact_detector.io.mp3.mp3_format`).
    """
    chunks = []
    for message in iter_messages(path, topics=[topic]):
        chunks.append(bytes(getattr(message.msg, 'data', b'')))
        if len(chunks) >= SNIFF_MESSAGES:
            break
    return mp3_format(b''.join(chunks))


def discover_streams(path: Path, *, wrench_topic: Optional[str] = None,
                     audio_topic: Optional[str] = None, audio_msg_type: Optional[str] = None,
                     audio_rate: Optional[float] = None, wrench_rate: Optional[float] = None,
                     param_audio_rate: Optional[float] = None,
                     param_source: str = 'parameters', channels: Optional[int] = None,
                     coding: Optional[str] = None, allow_no_audio: bool = False) -> Streams:
    """
    Find the topics and formats of one bag; arguments that are given override what is found.

    Parameters
    ----------
    path : Path
        A bag (rosbag2 directory or ROS 1 ``.bag``).
    wrench_topic, audio_topic : str or None
        Topic names (flags); None = find by type.
    audio_msg_type : str or None
        Only audio topics of this type (``audio.msg_type`` of a parameter file).
    audio_rate, wrench_rate : float or None
        Rates from flags, Hz.
    param_audio_rate : float or None
        ``audio.sample_rate`` of a parameter file (or the simulator manifest's rate): used
        when the bag does not describe its audio, before an estimate.
    param_source : str
        Where ``param_audio_rate`` comes from, as printed.
    channels : int or None
        Interleaved audio channels (parameter file), used when the bag does not say.
    coding : str or None
        ``pcm`` or ``mp3`` (flag); None = from AudioInfo, else from the bytes of AudioData
        (mp3 frame headers), else ``pcm``.
    allow_no_audio : bool
        True (the caller can use an F/T-only model): a bag without any audio topic, and no
        ``audio_topic`` given, yields ``Streams`` with ``audio_topic`` None instead of an error.

    Raises
    ------
    BagError
        A topic is missing (the audio topic: unless ``allow_no_audio``), ambiguous or of the
        wrong type, or a rate can be neither read nor measured.
    ConfigError
        ``audio_rate`` outside [MIN_SAMPLE_RATE, MAX_SAMPLE_RATE] Hz, or ``wrench_rate`` not a
        positive number (0 included: it is a value, not "no flag").

    """
    path = Path(path)
    audio_rate, wrench_rate = _flag_rates(audio_rate, wrench_rate)
    types = topic_types(path)
    wanted_audio = normalise_msg_type(audio_msg_type) if audio_msg_type else None
    w_topic = find_wrench_topic(path, types=types, given=wrench_topic)
    if allow_no_audio and not audio_topic and not any(m in AUDIO_MSG_TYPES
                                                      for m in types.values()):
        stamps = [] if wrench_rate is not None else probe(path, wrench_topic=w_topic)[0]
        w_rate = (wrench_rate if wrench_rate is not None else
                  measure_wrench_rate(stamps=stamps, path=path, topic=w_topic))
        return Streams(wrench_topic=w_topic, audio_topic=None, audio_msg_type='',
                       audio_rate=None, audio_rate_source='', channels=channels or 1,
                       coding='pcm', wrench_rate=w_rate,
                       wrench_rate_source='flag' if wrench_rate is not None else 'stamps',
                       audio_note=unsupported_audio_note(types))
    a_topic = _pick(path, types,
                    lambda m: m == wanted_audio if wanted_audio else m in AUDIO_MSG_TYPES,
                    f'audio {wanted_audio} (audio.msg_type)' if wanted_audio else
                    'audio (' + ', '.join(t.replace('/msg/', '/') for t in AUDIO_MSG_TYPES)
                    + ')',
                    '--audio-topic', audio_topic)
    a_type = types[a_topic]
    if a_type not in AUDIO_MSG_TYPES:
        raise BagError(f'{path}: {a_topic} holds {a_type}, not a supported audio type '
                       f'({", ".join(AUDIO_MSG_TYPES)})')
    spec = AUDIO_MSG_TYPES[a_type]
    warnings = []
    rate, source, n_ch, found_coding = None, None, None, None
    info_topic = _info_topic(types, a_topic) if spec.info_topic else None
    if info_topic is not None:
        for message in iter_messages(path, topics=[info_topic]):
            info = message.msg
            if str(getattr(info, 'coding_format', '')).strip().lower() == 'mp3':
                rate, n_ch, found_coding = float(info.sample_rate), int(info.channels), 'mp3'
            else:
                try:
                    fmt = check_audio_info(info)
                except ConfigError as err:
                    raise BagError(f'{path}: {info_topic}: {err}') from err
                rate, n_ch, found_coding = fmt.sample_rate, fmt.channels, 'pcm'
            source = 'AudioInfo'
            break
    elif spec.embedded_info:
        for message in iter_messages(path, topics=[a_topic]):
            try:
                fmt = embedded_audio_format(message.msg, a_type)
            except InputError as err:
                raise BagError(f'{path}: {a_topic}: {err}') from err
            rate, n_ch, source = fmt.sample_rate, fmt.channels, 'AudioStamped'
            break
    if found_coding is None and coding is None and a_type == MP3_CAPABLE_TYPE:
        sniffed = sniff_mp3(path, topic=a_topic)
        if sniffed is not None:
            rate, n_ch, found_coding, source = sniffed + ('mp3', 'mp3 header')
    n_ch = n_ch or channels or 1
    found_coding = coding or found_coding or 'pcm'
    if audio_rate is not None:
        rate, source = audio_rate, 'flag'
    elif rate is None and param_audio_rate:
        rate, source = float(param_audio_rate), param_source
    estimate = rate is None
    if estimate and found_coding == 'mp3':
        raise BagError(f'{path}: mp3 audio on {a_topic} without AudioInfo; give --audio-rate')
    stamps, sizes, times = probe(path, wrench_topic=None if wrench_rate is not None else w_topic,
                                 audio_topic=a_topic if estimate else None,
                                 audio_msg_type=a_type, channels=n_ch)
    if estimate:
        raw = estimate_audio_rate(sizes=sizes, times=times, path=path, topic=a_topic)
        rate, source = snap_audio_rate(raw), 'estimated'
        warnings.append(f'audio rate of {a_topic} estimated from the recording time: '
                        f'{raw:.0f} samples/s -> {rate:g} Hz')
    if wrench_rate is not None:
        w_rate, w_source = wrench_rate, 'flag'
    else:
        w_rate = measure_wrench_rate(stamps=stamps, path=path, topic=w_topic)
        w_source = 'stamps'
    return Streams(wrench_topic=w_topic, audio_topic=a_topic, audio_msg_type=a_type,
                   audio_rate=float(rate), audio_rate_source=source, channels=n_ch,
                   coding=found_coding, wrench_rate=w_rate, wrench_rate_source=w_source,
                   warnings=tuple(warnings))


def summary_lines(found: Sequence[tuple]) -> list:
    """
    Return lines that say what was found: one for all bags if they agree, else one per bag.

    Parameters
    ----------
    found : sequence of (Path, Streams)
        Each bag with the streams discovery found in it.

    Returns
    -------
    list of str

    """
    texts = [(bag, streams.describe()) for bag, streams in found]
    warned = [(bag, w) for bag, streams in found for w in streams.warnings]
    if len({text for _, text in texts}) == 1 and len(texts) > 1:
        lines = [f'{len(texts)} bags: {texts[0][1]}']
        if warned:
            lines.append(f'warning: {len(warned)} bags: {warned[0][1]} (first bag; give '
                         '--audio-rate if wrong)')
        return lines
    lines = [f'{bag.name}: {text}' for bag, text in texts]
    return lines + [f'warning: {bag.name}: {w} (give --audio-rate if wrong)'
                    for bag, w in warned]


#: Rates of the bags of one run agree when within this fraction of their median.
RATE_AGREEMENT = 0.01


def common_rates(found: Sequence[tuple], *,
                 allow_no_audio: bool = False) -> tuple[Optional[float], float]:
    """
    Return the one audio rate and one F/T rate of a run whose bags share them (Hz).

    Each rate is the median over the bags (measured F/T rates differ from bag to bag in the
    last digits); the bags agree when every one is within :data:`RATE_AGREEMENT` of it.

    Parameters
    ----------
    found : sequence of (Path, Streams)
        Each bag with its discovered streams (:func:`discover_streams`).
    allow_no_audio : bool
        Bags without audio are read (an F/T-only model decides): if none has audio the audio
        rate is None; the bags with audio must still share one rate.

    Returns
    -------
    audio_rate : float or None
    wrench_rate : float

    Raises
    ------
    BagError
        No bag, a bag without audio (unless ``allow_no_audio``), or rates that disagree: the
        error lists the rates found, with the count of bags and a first bag at each.

    """
    if not found:
        raise BagError('no bag to read')
    silent = [bag.name for bag, streams in found if not streams.has_audio]
    if silent and not allow_no_audio:
        raise BagError(f'{len(silent)} bags have no audio topic (first: {silent[0]})')
    rates: list = []
    for what, flag, key in (('audio', '--audio-rate', 'audio_rate'),
                            ('F/T', '--wrench-rate', 'wrench_rate')):
        measured = [(bag, getattr(streams, key)) for bag, streams in found
                    if key != 'audio_rate' or streams.has_audio]
        if not measured:
            rates.append(None)
            continue
        values = np.array([value for _, value in measured], dtype=float)
        middle = float(np.median(values))
        if np.any(np.abs(values - middle) > RATE_AGREEMENT * middle):
            groups: dict = {}
            for bag, value in measured:
                groups.setdefault(f'{value:.4g}', []).append(bag)
            listed = '; '.join(f'{rate} Hz: {len(bags)} bags (first {bags[0]})'
                               for rate, bags in sorted(groups.items(),
                                                        key=lambda kv: float(kv[0])))
            raise BagError(f'the bags of one run must share one {what} rate, found {listed}; '
                           f'run the folders separately, or give {flag} if the bags are '
                           'wrongly stamped')
        rates.append(middle)
    return rates[0], rates[1]
