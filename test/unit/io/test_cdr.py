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

"""The CDR readers behind offline decoding give rosbags' values, and step aside when unsure."""

from contact_detector.io import cdr
from contact_detector.io.bags import jazzy_typestore
from contact_detector.io.messages import audio_to_samples, stamp_to_seconds, wrench_to_arrays
import numpy as np
import pytest


@pytest.fixture(scope='module')
def store():
    return jazzy_typestore()


def _wrench(store, *, sec, nanosec, frame_id, values):
    t = store.types
    v = [t['geometry_msgs/msg/Vector3'](x=a, y=b, z=c) for a, b, c in (values[:3], values[3:])]
    return t['geometry_msgs/msg/WrenchStamped'](
        header=t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
            sec=sec, nanosec=nanosec), frame_id=frame_id),
        wrench=t['geometry_msgs/msg/Wrench'](force=v[0], torque=v[1]))


def _multiarray(store, name, *, labels, data_offset, data):
    t = store.types
    dims = [t['std_msgs/msg/MultiArrayDimension'](label=label, size=len(data), stride=1)
            for label in labels]
    return t[f'std_msgs/msg/{name}'](
        layout=t['std_msgs/msg/MultiArrayLayout'](dim=dims, data_offset=data_offset),
        data=data)


def test_wrench_every_frame_id_alignment(store):
    rng = np.random.default_rng(0)
    for frame_id in ['', 'a', 'ab', 'abc', 'wrist_ft_sensor_frame', 'x' * 13, 'é' * 3]:
        values = rng.normal(size=6) * 10
        msg = _wrench(store, sec=1_700_000_123, nanosec=987_654_321, frame_id=frame_id,
                      values=values)
        raw = bytes(store.serialize_cdr(msg, 'geometry_msgs/msg/WrenchStamped'))
        stamp, got = cdr.read_wrench_stamped(raw)
        t, force, torque = wrench_to_arrays(store.deserialize_cdr(
            raw, 'geometry_msgs/msg/WrenchStamped'))
        assert stamp_to_seconds(stamp) == t[0]
        assert np.array_equal(np.array([got[:3]]), force) and np.array_equal(
            np.array([got[3:]]), torque)


@pytest.mark.parametrize('name, dtype', [('Int16MultiArray', np.int16),
                                         ('Float32MultiArray', np.float32)])
def test_multiarrays_with_any_layout(store, name, dtype):
    rng = np.random.default_rng(1)
    for labels in [[], ['samples'], ['channels', 'samples'], ['abc', 'de', 'f']]:
        for n in (0, 1, 7, 160):
            for offset in (0, 3):
                data = (rng.integers(-32768, 32768, n) if dtype == np.int16
                        else rng.uniform(-1, 1, n)).astype(dtype)
                msg = _multiarray(store, name, labels=labels, data_offset=offset, data=data)
                raw = bytes(store.serialize_cdr(msg, f'std_msgs/msg/{name}'))
                fast = cdr.read_multiarray(raw, dtype=dtype)
                ref = store.deserialize_cdr(raw, f'std_msgs/msg/{name}')
                assert fast.layout.data_offset == ref.layout.data_offset
                assert len(fast.layout.dim) == len(ref.layout.dim)
                assert fast.data.dtype == ref.data.dtype
                assert np.array_equal(fast.data, ref.data)
                if n > offset:
                    # The node's adapter sees the same thing either way.
                    kind = f'std_msgs/msg/{name}'
                    assert np.array_equal(audio_to_samples(fast, msg_type=kind),
                                          audio_to_samples(ref, msg_type=kind))


def test_bool(store):
    for value in (True, False):
        raw = bytes(store.serialize_cdr(store.types['std_msgs/msg/Bool'](data=value),
                                        'std_msgs/msg/Bool'))
        assert cdr.read_bool(raw).data is value


def test_written_outputs_are_rosbags_bytes(store):
    t = store.types
    for value in (True, False):
        raw = bytes(store.serialize_cdr(t['std_msgs/msg/Bool'](data=value), 'std_msgs/msg/Bool'))
        assert (cdr.BOOL_TRUE if value else cdr.BOOL_FALSE)[:5] == raw[:5]
        assert cdr.read_bool(cdr.BOOL_TRUE if value else cdr.BOOL_FALSE).data is value
    rng = np.random.default_rng(1)
    for value in [0.0, 1.0, 1 / 3, 0.1, 1e-45, 0.9999999999] + list(rng.random(200)):
        # rclpy rounds the Python float to float32 on assignment, as numpy does.
        expect = np.float32(value)
        raw = bytes(store.serialize_cdr(t['std_msgs/msg/Float32'](data=expect),
                                        'std_msgs/msg/Float32'))
        assert cdr.write_float32(float(value)) == raw


def test_unsure_input_goes_back_to_rosbags(store):
    msg = _wrench(store, sec=1, nanosec=2, frame_id='f', values=np.arange(6.0))
    raw = bytes(store.serialize_cdr(msg, 'geometry_msgs/msg/WrenchStamped'))
    big_endian = b'\x00\x00' + raw[2:]
    assert cdr.read_wrench_stamped(big_endian) is None
    assert cdr.read_wrench_stamped(raw[:40]) is None            # truncated
    array = _multiarray(store, 'Int16MultiArray', labels=['s'], data_offset=0,
                        data=np.arange(10, dtype=np.int16))
    raw = bytes(store.serialize_cdr(array, 'std_msgs/msg/Int16MultiArray'))
    assert cdr.read_multiarray(raw[:-4], dtype=np.int16) is None
    assert cdr.read_multiarray(b'\x00\x01\x00\x00\xff\xff', dtype=np.int16) is None
    assert cdr.read_bool(b'\x00\x00\x00\x00\x01') is None
