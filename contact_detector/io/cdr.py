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
Direct readers for the CDR bytes of the two sensor types every recording has, and writers.

rosbags deserialises a message through generated Python (~15-30 us per message); offline
``detect`` reads ~200 sensor messages per second of recording, so decoding alone would cap it
near 200x real time. These readers take the same bytes apart with ``struct`` and numpy views
(a few us) and hand the values to the node's own adapters (:mod:`contact_detector.io.messages`),
so every check and every refusal is the adapters', and the values are bit-identical to
rosbags' (test_cdr.py compares them on every simulated layout).

Only little-endian plain CDR (encapsulation ``00 01``, what Fast DDS and rosbag2 write) is
read here; anything else returns None and the caller falls back to rosbags.

CDR alignment is relative to the first byte after the 4-byte encapsulation header.

The writers give the bytes of the node's per-frame outputs (``std_msgs/Bool``, ``Float32``),
which rclpy publishes as they are (``Publisher.publish(bytes)``): no message object to convert
per frame.
"""

import struct
from typing import NamedTuple, Optional

import numpy as np

#: Little-endian plain CDR, the encapsulation rosbag2 and Fast DDS write.
CDR_LE = b'\x00\x01'
_U32 = struct.Struct('<I')
_STAMP = struct.Struct('<iI')
_SIX_DOUBLES = struct.Struct('<6d')
_FLOAT32 = struct.Struct('<4sf')
#: ``std_msgs/msg/Bool`` with ``data`` True / False (padded to 4 bytes as Fast DDS writes it).
BOOL_TRUE = CDR_LE + b'\x00\x00\x01\x00\x00\x00'
BOOL_FALSE = CDR_LE + b'\x00\x00\x00\x00\x00\x00'


class Stamp(NamedTuple):
    """``builtin_interfaces/Time`` fields."""

    sec: int
    nanosec: int


class Layout(NamedTuple):
    """The part of ``std_msgs/MultiArrayLayout`` the adapters read."""

    dim: tuple
    data_offset: int


class MultiArray(NamedTuple):
    """A ``std_msgs/*MultiArray`` with its data as a numpy array (as rosbags gives it)."""

    layout: Layout
    data: np.ndarray


_LE = {np.dtype(np.int16): np.dtype('<i2'), np.dtype(np.float32): np.dtype('<f4')}


class Bool(NamedTuple):
    """``std_msgs/msg/Bool``."""

    data: bool


def read_bool(raw: bytes) -> Optional[Bool]:
    """Take a ``std_msgs/msg/Bool`` apart (None if not little-endian CDR)."""
    if raw[:2] != CDR_LE or len(raw) < 5:
        return None
    return Bool(raw[4] != 0)


def write_float32(value: float) -> bytes:
    """
    Return the CDR bytes of a ``std_msgs/msg/Float32`` holding ``value``.

    ``value`` is rounded to the nearest float32 as rclpy does (C ``(float)`` cast); values
    beyond the float32 range raise OverflowError.
    """
    return _FLOAT32.pack(CDR_LE + b'\x00\x00', value)


def _align(pos: int, size: int) -> int:
    rel = pos - 4
    return pos + (-rel % size)


def read_wrench_stamped(raw: bytes) -> Optional[tuple]:
    """
    Take a ``geometry_msgs/msg/WrenchStamped`` apart.

    Parameters
    ----------
    raw : bytes
        The serialised message (CDR with its encapsulation header).

    Returns
    -------
    (Stamp, tuple of 6 float) or None
        Header stamp, and force x, y, z (N) then torque x, y, z (N m); None if the bytes are
        not little-endian CDR or are too short (the caller then uses rosbags, which reports
        the problem).

    """
    if raw[:2] != CDR_LE or len(raw) < 16:
        return None
    sec, nanosec = _STAMP.unpack_from(raw, 4)
    (length,) = _U32.unpack_from(raw, 12)
    pos = _align(16 + length, 8)
    if pos + 48 > len(raw):
        return None
    return Stamp(sec, nanosec), _SIX_DOUBLES.unpack_from(raw, pos)


def read_multiarray(raw: bytes, *, dtype: np.dtype) -> Optional[MultiArray]:
    """
    Take a ``std_msgs/msg/Int16MultiArray`` or ``Float32MultiArray`` apart.

    Parameters
    ----------
    raw : bytes
        The serialised message.
    dtype : np.dtype
        ``np.int16`` or ``np.float32``: the element type of ``data``.

    Returns
    -------
    MultiArray or None
        ``layout.dim`` holds one placeholder per dimension (the adapters only count them);
        ``data`` is a read-only view of ``raw``. None if the bytes are not little-endian CDR
        or are inconsistent.

    """
    if raw[:2] != CDR_LE or len(raw) < 16:
        return None
    dtype = _LE[np.dtype(dtype)]
    try:
        (n_dims,) = _U32.unpack_from(raw, 4)
        pos = 8
        for _ in range(n_dims):
            (length,) = _U32.unpack_from(raw, pos)
            pos = _align(pos + 4 + length, 4) + 8      # label, then size and stride
        (data_offset,) = _U32.unpack_from(raw, pos)
        (count,) = _U32.unpack_from(raw, pos + 4)
    except struct.error:
        return None
    start = _align(pos + 8, dtype.itemsize)
    if start + count * dtype.itemsize > len(raw):
        return None
    data = np.frombuffer(raw, dtype=dtype, count=count, offset=start)
    return MultiArray(layout=Layout(dim=(None,) * n_dims, data_offset=data_offset), data=data)


def _int16_multiarray(raw: bytes) -> Optional[MultiArray]:
    return read_multiarray(raw, dtype=np.int16)


def _float32_multiarray(raw: bytes) -> Optional[MultiArray]:
    return read_multiarray(raw, dtype=np.float32)


#: The readers by message type (values identical to rosbags', test_cdr.py): bag decoding and
#: the node's raw subscriptions use them, with the generic deserialiser as fallback.
FAST_DECODERS = {
    'geometry_msgs/msg/WrenchStamped': read_wrench_stamped,
    'std_msgs/msg/Int16MultiArray': _int16_multiarray,
    'std_msgs/msg/Float32MultiArray': _float32_multiarray,
    'std_msgs/msg/Bool': read_bool,
}
