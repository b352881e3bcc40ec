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

"""Message -> array adapters on duck-typed, rclpy and rosbags-deserialised messages."""

from types import SimpleNamespace as NS

from contact_detector.errors import ConfigError, InputError
from contact_detector.io import cdr
from contact_detector.io.messages import (AUDIO_MSG_TYPES, audio_stamp, audio_to_samples,
                                          AudioFormat, check_audio_info, embedded_audio_format,
                                          normalise_msg_type, stamp_to_seconds, wrench_sample,
                                          wrench_to_arrays)
import numpy as np
import pytest
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

I16 = 'std_msgs/msg/Int16MultiArray'
F32 = 'std_msgs/msg/Float32MultiArray'
AD = 'audio_common_msgs/msg/AudioData'
ADS = 'audio_common_msgs/msg/AudioDataStamped'
AS = 'audio_common_msgs/msg/AudioStamped'

# Message definitions of both audio_common variants (ROS 2), for rosbags' type store.
ROS_DRIVERS_MSGS = {
    'audio_common_msgs/msg/AudioData': 'uint8[] data\n',
    'audio_common_msgs/msg/AudioDataStamped':
        'std_msgs/Header header\naudio_common_msgs/AudioData audio\n',
    'audio_common_msgs/msg/AudioInfo':
        'uint8 channels\nuint32 sample_rate\nstring sample_format\nuint32 bitrate\n'
        'string coding_format\n',
}
MGONZS13_MSGS = {
    'audio_common_msgs/msg/AudioData':
        'float32[] float32_data\nint32[] int32_data\nint32[] int24_data\nint16[] int16_data\n'
        'int8[] int8_data\nuint8[] uint8_data\n',
    'audio_common_msgs/msg/AudioInfo': 'int32 format\nint32 channels\nint32 rate\nint32 chunk\n',
    'audio_common_msgs/msg/Audio':
        'audio_common_msgs/AudioInfo info\naudio_common_msgs/AudioData audio_data\n',
    'audio_common_msgs/msg/AudioStamped':
        'std_msgs/Header header\naudio_common_msgs/Audio audio\n',
}


def header(sec=12, nanosec=500_000_000):
    return NS(stamp=NS(sec=sec, nanosec=nanosec), frame_id='mic')


def typed_audio(**fields):
    names = ('float32_data', 'int32_data', 'int24_data', 'int16_data', 'int8_data',
             'uint8_data')
    return NS(**{n: fields.get(n, []) for n in names})


def audio_stamped(*, fmt, channels=1, rate=16000, **fields):
    info = NS(format=fmt, channels=channels, rate=rate, chunk=160)
    return NS(header=header(), audio=NS(info=info, audio_data=typed_audio(**fields)))


# --- time and wrench ---------------------------------------------------------------------------

def test_stamp_to_seconds():
    assert stamp_to_seconds(NS(sec=3, nanosec=250_000_000)) == pytest.approx(3.25)
    assert stamp_to_seconds(NS(sec=0, nanosec=0)) == 0.0
    with pytest.raises(InputError, match='nanosec'):
        stamp_to_seconds(NS(sec=1, nanosec=1_000_000_000))
    with pytest.raises(InputError, match='invalid time stamp'):
        stamp_to_seconds(NS(sec=1))


def test_wrench_to_arrays():
    msg = NS(header=header(), wrench=NS(force=NS(x=1.0, y=2.0, z=3.0),
                                        torque=NS(x=-0.1, y=0.2, z=-0.3)))
    t, force, torque = wrench_to_arrays(msg)
    assert t.shape == (1,) and t[0] == pytest.approx(12.5)
    np.testing.assert_array_equal(force, [[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(torque, [[-0.1, 0.2, -0.3]])
    # NaN passes through: the core rejects it (one place decides what is corrupt).
    msg.wrench.force.x = float('nan')
    assert np.isnan(wrench_to_arrays(msg)[1][0, 0])
    with pytest.raises(InputError, match='malformed wrench'):
        bad = NS(force=NS(x=1.0, y='a', z=0.0), torque=NS(x=0, y=0, z=0))
        wrench_to_arrays(NS(header=header(), wrench=bad))
    with pytest.raises(InputError, match='no field'):
        wrench_to_arrays(NS(header=header()))


def test_wrench_sample_reads_the_cdr_pair_and_refuses_other_fast_decodings():
    raw = (cdr.CDR_LE + b'\x00\x00' + (3).to_bytes(4, 'little')
           + (250_000_000).to_bytes(4, 'little') + (1).to_bytes(4, 'little') + b'\x00'
           + bytes(3) + np.arange(1.0, 7.0).tobytes())
    t, values = wrench_sample(cdr.read_wrench_stamped(raw))
    assert t == pytest.approx(3.25) and values == (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
    # what the fast readers give for a Bool or a MultiArray topic named as the wrench topic
    layout = cdr.Layout(dim=(), data_offset=0)
    for other in (cdr.read_bool(cdr.BOOL_TRUE), cdr.MultiArray(layout, np.zeros(6)),
                  (cdr.Stamp(1, 0),), (cdr.Stamp(1, 0), (1.0, 2.0))):
        with pytest.raises(InputError, match='not a geometry_msgs/msg/WrenchStamped'):
            wrench_sample(other)
    with pytest.raises(InputError, match='nanosec'):
        wrench_sample((cdr.Stamp(1, 1_500_000_000), values))


def test_wrench_from_rclpy_message():
    from geometry_msgs.msg import WrenchStamped
    msg = WrenchStamped()
    msg.header.stamp.sec, msg.header.stamp.nanosec = 7, 10
    msg.wrench.force.z = -9.81
    t, force, _ = wrench_to_arrays(msg)
    assert t[0] == pytest.approx(7.00000001) and force[0, 2] == pytest.approx(-9.81)


# --- type table --------------------------------------------------------------------------------

def test_type_table_and_names():
    assert set(AUDIO_MSG_TYPES) == {I16, F32, AD, ADS, AS}
    assert normalise_msg_type('std_msgs/Int16MultiArray') == I16
    assert AUDIO_MSG_TYPES[AS].embedded_info and AUDIO_MSG_TYPES[ADS].info_topic
    with pytest.raises(ConfigError, match='supported'):
        normalise_msg_type('sensor_msgs/msg/Image')


def test_audio_stamp():
    msg = NS(header=header(5, 1000), audio=NS(data=b'\x00\x00'))
    assert audio_stamp(msg, ADS) == pytest.approx(5.000001)
    assert audio_stamp(NS(data=[1]), I16) is None
    assert audio_stamp(NS(data=b''), AD) is None


# --- std_msgs ----------------------------------------------------------------------------------

def test_int16_multiarray_mono_stays_int16():
    msg = NS(layout=NS(dim=[], data_offset=0), data=[0, 1000, -32768, 32767])
    out = audio_to_samples(msg, msg_type=I16, channels=1, channel=None)
    assert out.dtype == np.int16
    np.testing.assert_array_equal(out, [0, 1000, -32768, 32767])


def test_int16_multiarray_from_rclpy_message():
    from std_msgs.msg import Int16MultiArray
    msg = Int16MultiArray()
    msg.data = [5, -5, 7, -7]
    out = audio_to_samples(msg, msg_type=I16, channels=2, channel=1)
    assert out.dtype == np.int16
    np.testing.assert_array_equal(out, [-5, -7])


def test_stereo_mix_and_select():
    data = np.array([1000, 3000, -2000, 0], dtype=np.int16)    # L R L R
    msg = NS(data=data)
    mixed = audio_to_samples(msg, msg_type=I16, channels=2, channel=None)
    assert mixed.dtype == np.float32
    np.testing.assert_allclose(mixed, [2000 / 32768, -1000 / 32768], rtol=1e-6)
    right = audio_to_samples(msg, msg_type=I16, channels=2, channel=1)
    np.testing.assert_array_equal(right, [3000, 0])
    with pytest.raises(InputError, match='channel 2 does not exist'):
        audio_to_samples(msg, msg_type=I16, channels=2, channel=2)


def test_data_offset_is_honoured():
    msg = NS(layout=NS(dim=[], data_offset=2), data=[99, 99, 1, 2])
    np.testing.assert_array_equal(audio_to_samples(msg, msg_type=I16), [1, 2])


def test_float32_multiarray():
    msg = NS(data=[0.5, -0.25])
    out = audio_to_samples(msg, msg_type=F32, channels=1, channel=None)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, [0.5, -0.25])
    with pytest.raises(InputError, match='NaN or Inf'):
        audio_to_samples(NS(data=[0.1, float('inf')]), msg_type=F32)


@pytest.mark.parametrize('data, match', [
    ([], 'empty'),
    ([1, 2, 3], 'not a multiple of the 2'),
    ([0.5, 0.25], 'must hold integers'),
    ([40000, 0], 'outside the int16 range'),
    (['a', 'b'], 'must hold integers'),
])
def test_bad_int16_chunks(data, match):
    with pytest.raises(InputError, match=match):
        audio_to_samples(NS(data=data), msg_type=I16, channels=2 if match.startswith('not')
                         else 1, channel=None)


def test_huge_chunk_refused():
    msg = NS(data=np.zeros(20000, dtype=np.int16))
    with pytest.raises(InputError, match='exceeds the limit'):
        audio_to_samples(msg, msg_type=I16, max_samples=16000)
    assert audio_to_samples(msg, msg_type=I16, max_samples=20000).size == 20000


# --- ros-drivers audio_common ------------------------------------------------------------------

def test_audio_data_s16le():
    pcm = np.array([1, -2, 300, -32768], dtype='<i2')
    out = audio_to_samples(NS(data=pcm.tobytes()), msg_type=AD)
    assert out.dtype == np.int16
    np.testing.assert_array_equal(out, pcm)
    stamped = NS(header=header(), audio=NS(data=list(pcm.tobytes())))
    np.testing.assert_array_equal(audio_to_samples(stamped, msg_type=ADS), pcm)


def test_audio_data_bad_bytes():
    with pytest.raises(InputError, match='odd byte count'):
        audio_to_samples(NS(data=b'\x01\x02\x03'), msg_type=AD)
    with pytest.raises(InputError, match='empty'):
        audio_to_samples(NS(data=b''), msg_type=AD)
    with pytest.raises(InputError, match='uint8 range'):
        audio_to_samples(NS(data=[1, 300]), msg_type=AD)
    with pytest.raises(InputError, match='no field'):
        audio_to_samples(NS(header=header()), msg_type=ADS)


def test_check_audio_info_ros_drivers():
    good = NS(channels=2, sample_rate=44100, sample_format='S16LE', bitrate=0,
              coding_format='wave')
    assert check_audio_info(good) == AudioFormat(sample_rate=44100.0, channels=2)
    with pytest.raises(ConfigError, match='mp3.*format:=wave'):
        check_audio_info(NS(channels=1, sample_rate=16000, sample_format='S16LE', bitrate=128,
                            coding_format='mp3'))
    with pytest.raises(ConfigError, match="only 'S16LE'"):
        check_audio_info(NS(channels=1, sample_rate=16000, sample_format='F32LE', bitrate=0,
                            coding_format='wave'))
    with pytest.raises(ConfigError, match='sample rate 100 Hz'):
        check_audio_info(NS(channels=1, sample_rate=100, sample_format='S16LE', bitrate=0,
                            coding_format='wave'))
    with pytest.raises(ConfigError, match='channels=0'):
        check_audio_info(NS(channels=0, sample_rate=16000, sample_format='S16LE', bitrate=0,
                            coding_format='wave'))
    with pytest.raises(ConfigError, match='unrecognised'):
        check_audio_info(NS(foo=1))


# --- mgonzs13 audio_common ---------------------------------------------------------------------

@pytest.mark.parametrize('fmt, field, values, expected', [
    (8, 'int16_data', [16384, -32768], [0.5, -1.0]),
    (1, 'float32_data', [0.5, -0.25], [0.5, -0.25]),
    (2, 'int32_data', [2 ** 30, -2 ** 31], [0.5, -1.0]),
    (4, 'int24_data', [2 ** 22, -2 ** 23], [0.5, -1.0]),
    (16, 'int8_data', [64, -128], [0.5, -1.0]),
    (32, 'uint8_data', [192, 0], [0.5, -1.0]),
])
def test_audio_stamped_formats(fmt, field, values, expected):
    msg = audio_stamped(fmt=fmt, **{field: values})
    out = audio_to_samples(msg, msg_type=AS, channels=1, channel=None)
    np.testing.assert_allclose(np.asarray(out, dtype=np.float64)
                               / (32768.0 if out.dtype == np.int16 else 1.0), expected)
    assert audio_stamp(msg, AS) == pytest.approx(12.5)
    assert embedded_audio_format(msg, AS) == AudioFormat(sample_rate=16000.0, channels=1)


def test_audio_stamped_uses_its_own_channel_count():
    msg = audio_stamped(fmt=8, channels=2, int16_data=[100, 200, 300, 400])
    # The configured channels (1) are overridden by info.channels (2).
    np.testing.assert_array_equal(audio_to_samples(msg, msg_type=AS, channels=1, channel=0),
                                  [100, 300])


def test_audio_stamped_bad():
    with pytest.raises(InputError, match='PortAudio'):
        audio_to_samples(audio_stamped(fmt=3, int16_data=[1]), msg_type=AS)
    with pytest.raises(InputError, match='empty'):
        audio_to_samples(audio_stamped(fmt=8, float32_data=[0.1]), msg_type=AS)
    with pytest.raises(InputError, match='info.rate=0'):
        audio_to_samples(audio_stamped(fmt=8, rate=0, int16_data=[1]), msg_type=AS)
    with pytest.raises(InputError, match='must hold integers'):
        audio_to_samples(audio_stamped(fmt=8, int16_data=[0.5]), msg_type=AS)


def test_typed_audio_data_without_info():
    # mgonzs13's early AudioDataStamped: typed arrays, no format; the filled array is used.
    msg = NS(header=header(), audio=typed_audio(int16_data=[7, 8]))
    np.testing.assert_array_equal(audio_to_samples(msg, msg_type=ADS), [7, 8])
    with pytest.raises(InputError, match='exactly one non-empty'):
        audio_to_samples(NS(header=header(), audio=typed_audio(int16_data=[1],
                                                               float32_data=[0.1])),
                         msg_type=ADS)


# --- rosbags-deserialised messages -------------------------------------------------------------

def _store(defs):
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for name, text in defs.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def _roundtrip(store, msg, typename):
    return store.deserialize_cdr(store.serialize_cdr(msg, typename), typename)


def test_rosbags_ros_drivers_messages():
    store = _store(ROS_DRIVERS_MSGS)
    t = store.types
    pcm = np.array([3, -4, 5, -6], dtype='<i2')
    msg = t[ADS](header=t['std_msgs/msg/Header'](
        stamp=t['builtin_interfaces/msg/Time'](sec=2, nanosec=5), frame_id=''),
        audio=t[AD](data=np.frombuffer(pcm.tobytes(), dtype=np.uint8)))
    back = _roundtrip(store, msg, ADS)
    assert isinstance(back.audio.data, np.ndarray)
    np.testing.assert_array_equal(audio_to_samples(back, msg_type=ADS, channels=2, channel=0),
                                  [3, 5])
    assert audio_stamp(back, ADS) == pytest.approx(2.000000005)
    info = t['audio_common_msgs/msg/AudioInfo'](channels=1, sample_rate=48000,
                                                sample_format='S16LE', bitrate=0,
                                                coding_format='wave')
    assert check_audio_info(_roundtrip(store, info, 'audio_common_msgs/msg/AudioInfo')
                            ).sample_rate == 48000.0


def test_rosbags_mgonzs13_and_std_msgs():
    store = _store(MGONZS13_MSGS)
    t = store.types
    empty = {n: np.zeros(0, dtype=d) for n, d in (
        ('float32_data', np.float32), ('int32_data', np.int32), ('int24_data', np.int32),
        ('int16_data', np.int16), ('int8_data', np.int8), ('uint8_data', np.uint8))}
    empty['float32_data'] = np.array([0.25, -0.5, 0.75, 0.0], dtype=np.float32)
    info = t['audio_common_msgs/msg/AudioInfo'](format=1, channels=2, rate=44100, chunk=2)
    head = t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](sec=1, nanosec=0),
                                    frame_id='')
    msg = t[AS](header=head, audio=t['audio_common_msgs/msg/Audio'](
        info=info, audio_data=t[AD](**empty)))
    back = _roundtrip(store, msg, AS)
    out = audio_to_samples(back, msg_type=AS, channels=1, channel=None)
    np.testing.assert_allclose(out, [-0.125, 0.375])
    assert embedded_audio_format(back, AS).sample_rate == 44100.0

    arr = t[I16](layout=t['std_msgs/msg/MultiArrayLayout'](dim=[], data_offset=0),
                 data=np.array([1, 2, 3], dtype=np.int16))
    back = _roundtrip(store, arr, I16)
    np.testing.assert_array_equal(audio_to_samples(back, msg_type=I16), [1, 2, 3])
