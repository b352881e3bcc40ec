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
ROS 1 bags: direct readers of the sensor types, and ROS 1 -> ROS 2 message conversion.

ROS 1 serialisation is packed little-endian without alignment (a ``string`` or array is a
``uint32`` length and its elements). rosbags deserialises ROS 1 messages with the type
definitions stored in the bag; their field names are those of ROS 2 (``header.stamp.sec``,
``header.stamp.nanosec``), except that ROS 1's ``std_msgs/Header`` has a ``seq`` the adapters
never read. So the adapters of :mod:`contact_detector.io.messages` read ROS 1 messages as they
are, and :func:`to_ros2_cdr` re-serialises one as ROS 2 CDR for ``replay`` (fields that ROS 2
does not have, like ``seq``, are dropped).

The readers below give the same values as rosbags' ROS 1 deserialiser, in the shapes of the
CDR readers (:mod:`contact_detector.io.cdr`), so the offline tools use one adapter path.
"""

import struct
from typing import Any, Optional

from contact_detector.io.cdr import Bool, Layout, MultiArray, Stamp
import numpy as np

_U32 = struct.Struct('<I')
_STAMP = struct.Struct('<II')
_SIX_DOUBLES = struct.Struct('<6d')


def read_wrench_stamped(raw: bytes) -> Optional[tuple]:
    """
    Take a ROS 1 ``geometry_msgs/WrenchStamped`` apart.

    Layout: ``uint32 seq, uint32 sec, uint32 nsec, string frame_id, 6 float64``.

    Returns
    -------
    (Stamp, tuple of 6 float) or None
        Header stamp, then force x, y, z (N) and torque x, y, z (N m); None if the bytes are
        too short (the caller then uses rosbags, which reports the problem).

    """
    if len(raw) < 16:
        return None
    sec, nanosec = _STAMP.unpack_from(raw, 4)
    (length,) = _U32.unpack_from(raw, 12)
    pos = 16 + length
    if pos + 48 > len(raw):
        return None
    return Stamp(sec, nanosec), _SIX_DOUBLES.unpack_from(raw, pos)


def read_multiarray(raw: bytes, *, dtype: np.dtype) -> Optional[MultiArray]:
    """
    Take a ROS 1 ``std_msgs/Int16MultiArray`` or ``Float32MultiArray`` apart.

    Layout: ``uint32 n_dims, n_dims x (string label, uint32 size, uint32 stride),
    uint32 data_offset, uint32 count, count x element``.

    Returns
    -------
    MultiArray or None
        ``data`` is a read-only view of ``raw``; None if the bytes are inconsistent.

    """
    dtype = np.dtype(dtype).newbyteorder('<')
    try:
        (n_dims,) = _U32.unpack_from(raw, 0)
        pos = 4
        for _ in range(n_dims):
            (length,) = _U32.unpack_from(raw, pos)
            pos += 4 + length + 8
        data_offset, count = struct.unpack_from('<II', raw, pos)
    except struct.error:
        return None
    start = pos + 8
    if start + count * dtype.itemsize != len(raw):
        return None
    data = np.frombuffer(raw, dtype=dtype, count=count, offset=start)
    return MultiArray(layout=Layout(dim=(None,) * n_dims, data_offset=data_offset), data=data)


def _int16_multiarray(raw: bytes) -> Optional[MultiArray]:
    return read_multiarray(raw, dtype=np.int16)


def _float32_multiarray(raw: bytes) -> Optional[MultiArray]:
    return read_multiarray(raw, dtype=np.float32)


def read_bool(raw: bytes) -> Optional[Bool]:
    """Take a ROS 1 ``std_msgs/Bool`` apart (None if empty)."""
    return Bool(raw[0] != 0) if len(raw) >= 1 else None


#: The ROS 1 readers by message type (rosbags' type names), bag decoding only.
FAST_DECODERS = {
    'geometry_msgs/msg/WrenchStamped': read_wrench_stamped,
    'std_msgs/msg/Int16MultiArray': _int16_multiarray,
    'std_msgs/msg/Float32MultiArray': _float32_multiarray,
    'std_msgs/msg/Bool': read_bool,
}


def to_ros2(msg: Any, *, msgtype: str, typestore: Any) -> Any:
    """
    Copy a deserialised ROS 1 message into the ROS 2 class of the same type.

    Fields are taken by name from the ROS 2 definition in ``typestore``; fields only ROS 1
    has (``Header.seq``) are dropped.

    Parameters
    ----------
    msg : rosbags message
        Deserialised from a ROS 1 bag.
    msgtype : str
        ``pkg/msg/Type``.
    typestore : rosbags Typestore
        Holds the ROS 2 definition of ``msgtype`` and of every nested type.

    Raises
    ------
    KeyError
        ``typestore`` does not know a type; AttributeError: a ROS 2 field is missing in ROS 1.

    """
    cls = typestore.types[msgtype]
    values = {}
    for name in cls.__dataclass_fields__:
        if name == '__msgtype__':
            continue
        value = getattr(msg, name)
        if hasattr(value, '__msgtype__'):
            value = to_ros2(value, msgtype=value.__msgtype__, typestore=typestore)
        elif isinstance(value, list) and value and hasattr(value[0], '__msgtype__'):
            value = [to_ros2(v, msgtype=v.__msgtype__, typestore=typestore) for v in value]
        values[name] = value
    return cls(**values)
