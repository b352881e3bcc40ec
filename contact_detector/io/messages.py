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
Message -> array adapters shared by the live node and the offline tools.

Pure and duck-typed: no ROS import. The same functions read rclpy messages (arrays are
``array.array`` or ``bytes``), rosbags-deserialised messages (arrays are numpy) and test doubles
(``types.SimpleNamespace`` with lists), so the node and ``detect`` turn the same message into
the same samples.

Supported audio message types (:data:`AUDIO_MSG_TYPES`):

* ``std_msgs/msg/Int16MultiArray``: ``data`` holds interleaved int16 PCM.
* ``std_msgs/msg/Float32MultiArray``: ``data`` holds interleaved float PCM in [-1, 1].
* ``audio_common_msgs/msg/AudioData`` (ros-drivers/audio_common): ``uint8[] data``, raw bytes
  in the format announced on ``audio_info`` (``AudioInfo {uint8 channels, uint32 sample_rate,
  string sample_format, uint32 bitrate, string coding_format}``); only ``coding_format`` 'wave'
  with ``sample_format`` 'S16LE' (little-endian int16 PCM) is accepted, see
  :func:`check_audio_info`. Its capture node defaults to mp3, which is refused.
* ``audio_common_msgs/msg/AudioDataStamped`` (ros-drivers/audio_common):
  ``{std_msgs/Header header, AudioData audio}``.
* ``audio_common_msgs/msg/AudioStamped`` (mgonzs13/audio_common): ``{std_msgs/Header header,
  Audio audio}`` with ``Audio {AudioData audio_data, AudioInfo info}``, ``AudioInfo {int32
  format, int32 channels, int32 rate, int32 chunk}`` and ``AudioData {float32[] float32_data,
  int32[] int32_data, int32[] int24_data, int16[] int16_data, int8[] int8_data, uint8[]
  uint8_data}``; ``format`` is a PortAudio sample format (:data:`PORTAUDIO_FORMATS`).

Length: over 500 lines because every supported message type's adapter (wrench, the audio
types, AudioInfo, stamps) lives here, so the node and the offline tools share one table of
types; each adapter is a few short functions.
"""

from dataclasses import dataclass
import math
from typing import Any, Optional

from contact_detector.errors import ConfigError, InputError
from contact_detector.io.cdr import Stamp
import numpy as np

#: Sample rates the feature core accepts, Hz (see ``AudioFramer``).
MIN_SAMPLE_RATE = 1000.0
MAX_SAMPLE_RATE = 384000.0


@dataclass(frozen=True)
class AudioMsgType:
    """
    How one audio message type is read.

    Attributes
    ----------
    name : str
        Full type name, ``package/msg/Type``.
    package : str
        Python package of the message module (``<package>.msg``).
    type_name : str
        Class name in that module.
    stamped : bool
        Whether the message has a ``header`` whose stamp can time the chunk.
    info_topic : bool
        Whether the format comes from a separate ``audio_info`` topic (ros-drivers
        AudioInfo) instead of the parameters.
    embedded_info : bool
        Whether every message carries its own format (mgonzs13 AudioStamped).
    source : str
        Where the type comes from, for error messages.

    """

    name: str
    package: str
    type_name: str
    stamped: bool
    info_topic: bool
    embedded_info: bool
    source: str


#: The audio message types the node and the offline tools read, by full type name.
AUDIO_MSG_TYPES = {
    t.name: t for t in (
        AudioMsgType(name='std_msgs/msg/Int16MultiArray', package='std_msgs',
                     type_name='Int16MultiArray', stamped=False, info_topic=False,
                     embedded_info=False, source='std_msgs (common_interfaces)'),
        AudioMsgType(name='std_msgs/msg/Float32MultiArray', package='std_msgs',
                     type_name='Float32MultiArray', stamped=False, info_topic=False,
                     embedded_info=False, source='std_msgs (common_interfaces)'),
        AudioMsgType(name='audio_common_msgs/msg/AudioData', package='audio_common_msgs',
                     type_name='AudioData', stamped=False, info_topic=True,
                     embedded_info=False, source='ros-drivers/audio_common (ROS 2 branch)'),
        AudioMsgType(name='audio_common_msgs/msg/AudioDataStamped',
                     package='audio_common_msgs', type_name='AudioDataStamped', stamped=True,
                     info_topic=True, embedded_info=False,
                     source='ros-drivers/audio_common (ROS 2 branch)'),
        AudioMsgType(name='audio_common_msgs/msg/AudioStamped', package='audio_common_msgs',
                     type_name='AudioStamped', stamped=True, info_topic=False,
                     embedded_info=True, source='mgonzs13/audio_common'),
    )
}

#: PortAudio sample formats used by mgonzs13/audio_common's ``AudioInfo.format``:
#: code -> (AudioData field, full-scale divisor, offset subtracted first).
PORTAUDIO_FORMATS = {
    1: ('float32_data', 1.0, 0.0),           # paFloat32
    2: ('int32_data', 2.0 ** 31, 0.0),       # paInt32
    4: ('int24_data', 2.0 ** 23, 0.0),       # paInt24 (sign-extended in int32)
    8: ('int16_data', 32768.0, 0.0),         # paInt16
    16: ('int8_data', 128.0, 0.0),           # paInt8
    32: ('uint8_data', 128.0, 128.0),        # paUInt8 (offset binary)
}

_TYPED_FIELDS = {field: code for code, (field, _, _) in PORTAUDIO_FORMATS.items()}


@dataclass(frozen=True)
class AudioFormat:
    """Sample rate (Hz) and interleaved channel count of an audio stream."""

    sample_rate: float
    channels: int


def normalise_msg_type(msg_type: str) -> str:
    """
    Return the full ``package/msg/Type`` form of an audio message type name.

    ``package/Type`` is accepted too. Raises ConfigError for an unsupported type, listing the
    supported ones.
    """
    name = str(msg_type).strip()
    parts = name.split('/')
    if len(parts) == 2:
        name = f'{parts[0]}/msg/{parts[1]}'
    if name not in AUDIO_MSG_TYPES:
        raise ConfigError(f'unsupported audio message type {msg_type!r}; supported: '
                          f'{", ".join(AUDIO_MSG_TYPES)}')
    return name


def stamp_to_seconds(stamp: Any) -> float:
    """
    Convert a ``builtin_interfaces/Time`` to seconds: ``sec + nanosec * 1e-9``.

    Raises
    ------
    InputError
        Missing fields, or ``nanosec`` outside [0, 1e9).

    """
    try:
        sec = int(stamp.sec)
        nanosec = int(stamp.nanosec)
    except (AttributeError, TypeError, ValueError, OverflowError) as err:
        raise InputError(f'invalid time stamp {stamp!r}: {err}') from err
    if not 0 <= nanosec < 1_000_000_000:
        raise InputError(f'invalid time stamp: nanosec={nanosec} is outside [0, 1e9)')
    return sec + nanosec * 1e-9


def wrench_to_arrays(msg: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Read a ``geometry_msgs/WrenchStamped`` (or what ``cdr.read_wrench_stamped`` gives).

    The CDR reader's ``(stamp, six values)`` tuple is read directly.

    Returns
    -------
    t : np.ndarray, shape (1,)
        Header stamp, seconds.
    force : np.ndarray, shape (1, 3)
        Force, N.
    torque : np.ndarray, shape (1, 3)
        Torque, N m.

    Raises
    ------
    InputError
        Missing or non-numeric fields. (NaN/Inf and stamp order are checked by the core.)

    """
    t, values = wrench_sample(msg)
    return np.array([t]), np.array([values[:3]]), np.array([values[3:]])


def wrench_sample(msg: Any) -> tuple[float, tuple]:
    """
    Read a ``geometry_msgs/WrenchStamped`` (or what ``cdr.read_wrench_stamped`` gives) as floats.

    Returns
    -------
    t : float
        Header stamp, seconds.
    values : tuple of 6 float
        Force x, y, z (N), then torque x, y, z (N m).

    Raises
    ------
    InputError
        Missing or non-numeric fields, or a message of another type (e.g. what the CDR
        readers give for ``std_msgs/Bool``). (NaN/Inf and stamp order are checked by the core.)

    """
    if isinstance(msg, tuple):
        # The fast readers give NamedTuples for other types too (cdr.Bool, cdr.MultiArray):
        # only a (Stamp, six values) pair is what cdr.read_wrench_stamped returns.
        if len(msg) == 2 and isinstance(msg[0], Stamp) and isinstance(msg[1], tuple) \
                and len(msg[1]) == 6:
            return stamp_to_seconds(msg[0]), msg[1]
        raise InputError(f'{type(msg).__name__} is not a geometry_msgs/msg/WrenchStamped '
                         '(wrong message type?)')
    t = stamp_to_seconds(_field(_field(msg, 'header'), 'stamp'))
    wrench = _field(msg, 'wrench')
    try:
        f, m = wrench.force, wrench.torque
        values = (float(f.x), float(f.y), float(f.z), float(m.x), float(m.y), float(m.z))
    except (AttributeError, TypeError, ValueError, OverflowError) as err:
        raise InputError(f'malformed wrench message: {err}') from err
    return t, values


def audio_stamp(msg: Any, msg_type: str) -> Optional[float]:
    """
    Return the header stamp (s) of a stamped audio message, None for unstamped types.

    The caller then uses the receive time (the node's clock, or a bag's log time).
    """
    spec = AUDIO_MSG_TYPES[normalise_msg_type(msg_type)]
    if not spec.stamped:
        return None
    return stamp_to_seconds(_field(_field(msg, 'header'), 'stamp'))


def check_stamp(*, stamp: float, now: float, max_future_s: float,
                previous: Optional[float] = None, backjump_s: float = 0.5,
                what: str = 'stamp', unset_hint: str = '') -> None:
    """
    Refuse a stamp that is unset, from the future, or repeats or slightly precedes the last.

    A stamp of exactly 0 is a ``header.stamp`` the publisher never set. Taken as a time, it
    would be a jump back to the epoch, which resets the detector, or, for a driver that never
    sets it, a repeat of the previous stamp on every message.

    Parameters
    ----------
    stamp : float
        The message's stamp, s.
    now : float
        Receive time on the same clock, s.
    max_future_s : float
        Largest accepted ``stamp - now``, s.
    previous : float or None
        The previous accepted stamp of the stream (None: no order check).
    backjump_s : float
        A stamp more than this before ``previous`` is a time jump (the detector resets),
        not a duplicate, and passes.
    what : str
        Name used in the message.
    unset_hint : str
        Appended to the message for a stamp of 0: what to do about it.

    Raises
    ------
    InputError
        Non-finite or unset (0) stamp, a stamp more than ``max_future_s`` ahead of ``now``, or a
        repeated / reordered one.

    """
    if not math.isfinite(stamp):
        raise InputError(f'{what} {stamp!r} is not finite')
    if stamp == 0.0:
        raise InputError(f'{what} is 0: the publisher does not set header.stamp{unset_hint}')
    if stamp - now > max_future_s:
        raise InputError(f'{what} {stamp:.6f} is {stamp - now:.3f} s ahead of the receive time '
                         f'{now:.6f} (clocks not synchronised, or use_sim_time without /clock?)')
    if previous is not None and previous - backjump_s <= stamp <= previous:
        raise InputError(f'{what} {stamp:.6f} repeats or precedes the previous one '
                         f'({previous:.6f}): duplicated or reordered message')


def embedded_audio_format(msg: Any, msg_type: str) -> Optional[AudioFormat]:
    """
    Return the format a message carries itself (mgonzs13 ``AudioStamped``), else None.

    Raises
    ------
    InputError
        The embedded rate or channel count is out of range.

    """
    spec = AUDIO_MSG_TYPES[normalise_msg_type(msg_type)]
    if not spec.embedded_info:
        return None
    info = _field(_field(msg, 'audio'), 'info')
    return _audio_format(rate=_int_field(info, 'rate'), channels=_int_field(info, 'channels'),
                         error=InputError, rate_text='AudioStamped info.rate={} Hz',
                         channels_text='AudioStamped info.channels={}')


def check_audio_info(info: Any) -> AudioFormat:
    """
    Validate a ros-drivers ``audio_common_msgs/AudioInfo`` and return the stream format.

    Only raw little-endian int16 PCM is accepted: ``coding_format`` 'wave' (or 'wav'/'raw'/'pcm')
    with ``sample_format`` 'S16LE'. An mgonzs13-style ``AudioInfo`` (``format``, ``rate``) is
    accepted with any PortAudio format of :data:`PORTAUDIO_FORMATS`.

    Raises
    ------
    ConfigError
        mp3 or another compressed coding, a sample format other than S16LE, a rate or channel
        count out of range; the message says what to change.

    """
    if hasattr(info, 'coding_format'):
        coding = str(info.coding_format).strip().lower()
        if coding == 'mp3':
            raise ConfigError(
                "audio_info says coding_format='mp3': the detector needs raw PCM. Start "
                "audio_common's audio_capture node with format:=wave (and "
                'sample_format:=S16LE); its default is mp3')
        if coding not in ('wave', 'wav', 'raw', 'pcm'):
            raise ConfigError(f'audio_info coding_format={info.coding_format!r} is not '
                              "supported: only 'wave' (raw PCM) can be read")
        sample_format = str(info.sample_format).strip().upper()
        if sample_format != 'S16LE':
            raise ConfigError(f'audio_info sample_format={info.sample_format!r} is not '
                              "supported: only 'S16LE' (little-endian int16) can be read")
        rate = _int_field(info, 'sample_rate')
    elif hasattr(info, 'rate') and hasattr(info, 'format'):
        code = _int_field(info, 'format')
        if code not in PORTAUDIO_FORMATS:
            raise ConfigError(f'audio info format={code} is not a supported PortAudio format '
                              f'(supported: {sorted(PORTAUDIO_FORMATS)})')
        rate = _int_field(info, 'rate')
    else:
        raise ConfigError(f'unrecognised audio info message {type(info).__name__}: it has '
                          'neither coding_format (ros-drivers) nor rate/format (mgonzs13)')
    return _audio_format(rate=rate, channels=_int_field(info, 'channels'), error=ConfigError,
                         rate_text='audio_info sample rate {} Hz',
                         channels_text='audio_info channels={}')


def audio_to_samples(msg: Any, *, msg_type: str, channels: int = 1,
                     channel: Optional[int] = None,
                     max_samples: Optional[int] = None) -> np.ndarray:
    """
    Turn an audio message into mono samples.

    Parameters
    ----------
    msg : message
        Of type ``msg_type`` (rclpy, rosbags or duck-typed).
    msg_type : str
        One of :data:`AUDIO_MSG_TYPES` (``package/Type`` accepted).
    channels : int
        Interleaved channels per sample frame. Ignored for types that carry their own format
        (AudioStamped: ``audio.info.channels`` is used).
    channel : int or None
        Channel to keep (0-based); None averages all channels.
    max_samples : int or None
        Largest accepted chunk, in sample frames (per channel).

    Returns
    -------
    np.ndarray, shape (n,)
        int16 when the source is int16 and no mixing happens; otherwise float32 in [-1, 1]
        (int formats divided by their full scale, e.g. mixed int16 as ``mean / 32768``).

    Raises
    ------
    InputError
        Empty chunk, odd byte count, wrong element type, values out of range, NaN/Inf, a length
        that is not a multiple of ``channels``, a channel index out of range, a too-large chunk.

    """
    spec = AUDIO_MSG_TYPES[normalise_msg_type(msg_type)]
    scale, offset = 32768.0, 0.0
    if spec.name == 'std_msgs/msg/Int16MultiArray':
        data = _int_array(_multiarray_data(msg), np.int16, 'Int16MultiArray.data')
    elif spec.name == 'std_msgs/msg/Float32MultiArray':
        data, scale = _float_array(_multiarray_data(msg), 'Float32MultiArray.data'), 1.0
    elif spec.name == 'audio_common_msgs/msg/AudioData':
        data, scale, offset = _audio_data(msg, None, 'AudioData')
    elif spec.name == 'audio_common_msgs/msg/AudioDataStamped':
        data, scale, offset = _audio_data(_field(msg, 'audio'), None, 'AudioDataStamped.audio')
    else:
        audio = _field(msg, 'audio')
        fmt = embedded_audio_format(msg, spec.name)
        channels = fmt.channels
        code = _int_field(_field(audio, 'info'), 'format')
        if code not in PORTAUDIO_FORMATS:
            raise InputError(f'AudioStamped info.format={code} is not a supported PortAudio '
                             f'format (supported: {sorted(PORTAUDIO_FORMATS)})')
        # 'audio_data' in current mgonzs13/audio_common; 'audio' in its first ROS 2 releases.
        payload = getattr(audio, 'audio_data', None)
        if payload is None:
            payload = _field(audio, 'audio')
        data, scale, offset = _audio_data(payload, code, 'AudioStamped.audio.audio_data')
    return _to_mono(data, channels=channels, channel=channel, scale=scale, offset=offset,
                    max_samples=max_samples)


# --- helpers -----------------------------------------------------------------------------------

def _field(msg: Any, name: str) -> Any:
    try:
        return getattr(msg, name)
    except AttributeError as err:
        raise InputError(f'{type(msg).__name__} has no field {name!r} (wrong message type?)'
                         ) from err


def _int_field(msg: Any, name: str) -> int:
    return _as_int(_field(msg, name), name)


def _as_int(value: Any, name: str) -> int:
    if isinstance(value, float) and not value.is_integer():
        raise InputError(f'{name}={value!r} is not an integer')
    try:
        return int(value)
    except (TypeError, ValueError, OverflowError) as err:
        raise InputError(f'{name}={value!r} is not an integer') from err


def _length(value: Any) -> int:
    """Return the number of elements of an array field (0 for None, scalars and junk)."""
    if value is None:
        return 0
    try:
        return int(np.size(value)) if not isinstance(value, (bytes, bytearray)) else len(value)
    except (TypeError, ValueError):
        return 0


def _multiarray_data(msg: Any) -> Any:
    data = _field(msg, 'data')
    offset = getattr(getattr(msg, 'layout', None), 'data_offset', 0)
    offset = 0 if offset is None else _as_int(offset, 'layout.data_offset')
    if offset < 0:
        raise InputError(f'layout.data_offset={offset} is negative')
    if offset:
        data = _raw_array(data, 'data')[offset:]
    return data


def _raw_array(data: Any, what: str) -> np.ndarray:
    try:
        if isinstance(data, (bytes, bytearray, memoryview)):
            return np.frombuffer(data, dtype=np.uint8)
        arr = np.asarray(data)
    except (TypeError, ValueError) as err:
        raise InputError(f'{what} is not an array: {err}') from err
    if arr.ndim != 1:
        raise InputError(f'{what} must be a flat array, got shape {arr.shape}')
    return arr


def _int_array(data: Any, dtype: type, what: str) -> np.ndarray:
    arr = _raw_array(data, what)
    if arr.dtype == dtype:
        return arr
    if arr.size == 0:
        return arr.astype(dtype)
    if arr.dtype.kind not in 'iu':
        raise InputError(f'{what} must hold integers ({np.dtype(dtype).name}), got '
                         f'{arr.dtype.name} values')
    info = np.iinfo(dtype)
    if arr.min() < info.min or arr.max() > info.max:
        raise InputError(f'{what} values are outside the {np.dtype(dtype).name} range '
                         f'[{info.min}, {info.max}]')
    return arr.astype(dtype)


def _float_array(data: Any, what: str) -> np.ndarray:
    arr = _raw_array(data, what)
    if not arr.size:
        # an empty array of any type is no samples (numpy warns when it casts complex ones)
        return np.zeros(arr.shape, dtype=np.float32)
    if arr.dtype.kind not in 'fiu':
        raise InputError(f'{what} must hold numbers, got {arr.dtype.name} values')
    with np.errstate(over='ignore'):       # too large for float32 -> Inf, refused below
        out = arr.astype(np.float32, copy=False)
    if not np.all(np.isfinite(out)):
        raise InputError(f'{what} contains NaN or Inf')
    return out


def _audio_data(audio: Any, code: Optional[int], what: str) -> tuple[np.ndarray, float, float]:
    """Read either AudioData flavour; return (samples, full scale, offset)."""
    if hasattr(audio, 'data') and code is None:
        # ros-drivers: raw S16LE bytes.
        raw = _int_array(audio.data, np.uint8, f'{what}.data')
        if raw.size % 2:
            raise InputError(f'{what}.data has an odd byte count ({raw.size}); S16LE audio '
                             'needs 2 bytes per sample')
        return raw.view('<i2').astype(np.int16, copy=False), 32768.0, 0.0
    if code is None:
        # mgonzs13 AudioData without info: take the one non-empty typed array.
        filled = [f for f in _TYPED_FIELDS if _length(getattr(audio, f, None)) > 0]
        if len(filled) != 1:
            raise InputError(f'{what}: expected exactly one non-empty typed array, got '
                             f'{filled or "none"}')
        code = _TYPED_FIELDS[filled[0]]
    field, scale, offset = PORTAUDIO_FORMATS[code]
    values = _field(audio, field)
    if field == 'float32_data':
        return _float_array(values, f'{what}.{field}'), 1.0, 0.0
    dtype = {'int32_data': np.int32, 'int24_data': np.int32, 'int16_data': np.int16,
             'int8_data': np.int8, 'uint8_data': np.uint8}[field]
    arr = _int_array(values, dtype, f'{what}.{field}')
    if field == 'int24_data' and arr.size and (arr.min() < -2 ** 23 or arr.max() >= 2 ** 23):
        raise InputError(f'{what}.int24_data values are outside the 24-bit range')
    return arr, scale, offset


def _to_mono(data: np.ndarray, *, channels: int, channel: Optional[int], scale: float,
             offset: float, max_samples: Optional[int]) -> np.ndarray:
    if isinstance(channels, bool) or not isinstance(channels, (int, np.integer)) or channels < 1:
        raise InputError(f'channels must be an int >= 1, got {channels!r}')
    if data.size == 0:
        raise InputError('audio chunk is empty')
    if data.size % channels:
        raise InputError(f'audio chunk of {data.size} samples is not a multiple of the '
                         f'{channels} configured channels (wrong audio.channels?)')
    frames = data.size // channels
    if max_samples is not None and frames > max_samples:
        raise InputError(f'audio chunk of {frames} samples exceeds the limit of {max_samples}')
    if channel is not None and not 0 <= channel < channels:
        raise InputError(f'audio channel {channel} does not exist in a {channels}-channel '
                         'stream')
    if channels > 1:
        block = data.reshape(frames, channels)
        data = block[:, channel] if channel is not None else block.mean(
            axis=1, dtype=np.float64)
    if data.dtype == np.int16 and scale == 32768.0 and offset == 0.0:
        return np.ascontiguousarray(data)
    if data.dtype.kind == 'f' and scale == 1.0 and offset == 0.0:
        return np.ascontiguousarray(data, dtype=np.float32)
    return ((data.astype(np.float64) - offset) / scale).astype(np.float32)


def _audio_format(*, rate: float, channels: int, error: type, rate_text: str,
                  channels_text: str) -> AudioFormat:
    """Return the AudioFormat, or raise ``error`` if the rate or channel count is unusable."""
    if not MIN_SAMPLE_RATE <= rate <= MAX_SAMPLE_RATE:
        raise error(f'{rate_text.format(rate)} is outside '
                    f'[{MIN_SAMPLE_RATE:.0f}, {MAX_SAMPLE_RATE:.0f}]')
    if channels < 1:
        raise error(f'{channels_text.format(channels)} must be >= 1')
    return AudioFormat(sample_rate=float(rate), channels=channels)
