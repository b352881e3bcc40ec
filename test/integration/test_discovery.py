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

"""ROS 1 bags and stream discovery: the offline commands read a user's bags without flags."""

import json
from pathlib import Path

from contact_detector.cli import detect as detect_cli
from contact_detector.detection import factory
from contact_detector.errors import BagError, ConfigError
from contact_detector.io.bags import find_bags, iter_cdr, iter_messages
from contact_detector.io.discovery import (common_rates, discover_streams, snap_audio_rate,
                                           Streams)
from contact_detector.io.sensor_stream import AudioEvent, load_events, StreamSpec, WrenchEvent
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

pytestmark = pytest.mark.slow   # writes and reads bags

WS = 'geometry_msgs/msg/WrenchStamped'
I16 = 'std_msgs/msg/Int16MultiArray'
AD = 'audio_common_msgs/msg/AudioData'
AI = 'audio_common_msgs/msg/AudioInfo'
AS = 'audio_common_msgs/msg/AudioStamped'
ROS_DRIVERS_MSGS = {
    AD: 'uint8[] data\n',
    AI: 'uint8 channels\nuint32 sample_rate\nstring sample_format\nuint32 bitrate\n'
        'string coding_format\n',
}
MGONZS13_MSGS = {
    AD: 'float32[] float32_data\nint32[] int32_data\nint32[] int24_data\nint16[] int16_data\n'
        'int8[] int8_data\nuint8[] uint8_data\n',
    AI: 'int32 format\nint32 channels\nint32 rate\nint32 chunk\n',
    'audio_common_msgs/msg/Audio':
        'audio_common_msgs/AudioInfo info\naudio_common_msgs/AudioData audio_data\n',
    AS: 'std_msgs/Header header\naudio_common_msgs/Audio audio\n',
}


def store_with(kind: str, msgs: dict):
    """Return a rosbags typestore (ROS 1 Noetic or ROS 2 Jazzy) with extra definitions."""
    store = get_typestore(Stores.ROS1_NOETIC if kind == 'ros1' else Stores.ROS2_JAZZY)
    for name, text in msgs.items():
        store.register(get_types_from_msg(text, name))
    return store


def wrench_msg(store, t_ns: int, fz: float):
    """Return a WrenchStamped in ``store``'s layout (ROS 1 headers have ``seq``)."""
    types = store.types
    time = types['builtin_interfaces/msg/Time']
    header = {'stamp': time(sec=t_ns // 10**9, nanosec=t_ns % 10**9), 'frame_id': 'ft'}
    if 'seq' in types['std_msgs/msg/Header'].__dataclass_fields__:
        header['seq'] = 0
    vec = types['geometry_msgs/msg/Vector3']
    return types[WS](header=types['std_msgs/msg/Header'](**header),
                     wrench=types['geometry_msgs/msg/Wrench'](force=vec(x=0.0, y=0.0, z=fz),
                                                              torque=vec(x=0.0, y=0.0, z=0.0)))


def write_bag(path: Path, kind: str, store, messages: list) -> Path:
    """
    Write ``messages`` = [(topic, type, log_ns, msg)] as a ROS 1 bag or rosbag2 (sqlite3, mcap).

    Messages are written in log-time order.
    """
    messages = sorted(messages, key=lambda m: m[2])
    if kind == 'ros1':
        writer, serialize = Ros1Writer(path), store.serialize_ros1
    else:
        plugin = StoragePlugin.MCAP if kind == 'mcap' else StoragePlugin.SQLITE3
        writer, serialize = Writer(path, version=9, storage_plugin=plugin), store.serialize_cdr
    with writer:
        conns = {}
        for topic, msgtype, _, _ in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
        for topic, msgtype, log_ns, msg in messages:
            writer.write(conns[topic], log_ns, serialize(msg, msgtype))
    return path


def wrench_series(store, *, rate: float, seconds: float, topic: str = '/ft',
                  start_ns: int = 10**18) -> list:
    n = int(seconds * rate)
    return [(topic, WS, start_ns + int(k * 1e9 / rate) + 2_000_000,
             wrench_msg(store, start_ns + int(k * 1e9 / rate), float(k))) for k in range(n)]


def audio_data_series(store, *, rate: float, chunk: int, seconds: float, channels: int = 1,
                      topic: str = '/audio/audio', start_ns: int = 10**18, seed: int = 0) -> list:
    rng = np.random.default_rng(seed)
    out = []
    for k in range(int(seconds * rate / chunk)):
        pcm = rng.integers(-3000, 3000, size=chunk * channels).astype('<i2')
        log = start_ns + int((k + 1) * chunk / rate * 1e9) + int(rng.uniform(0, 3e6))
        out.append((topic, AD, log, store.types[AD](data=np.frombuffer(pcm.tobytes(),
                                                                       np.uint8))))
    return out


def audio_info(store, *, rate: int, channels: int, coding: str = 'wave',
               topic: str = '/audio/audio_info', start_ns: int = 10**18) -> tuple:
    return (topic, AI, start_ns, store.types[AI](channels=channels, sample_rate=rate,
                                                 sample_format='S16LE', bitrate=0,
                                                 coding_format=coding))


# --- ROS 1 bags in every command --------------------------------------------------------------

def _rows(path: Path) -> list:
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    for row in rows:
        row['bag'] = row['bag'].removesuffix('.bag')
    return rows


def test_ros1_bag_gives_the_decisions_of_the_rosbag2_recording(tmp_path, capsys):
    trial = simulate_trial(seed=11, index=0)
    ros2 = write_trial_bag(trial=trial, path=tmp_path / 'ros2' / trial.name)
    ros1 = write_trial_bag(trial=trial, path=tmp_path / 'ros1' / trial.name, storage='ros1')
    assert ros1.suffix == '.bag' and ros1.is_file()
    # a folder of ROS 1 bags, the file itself, and a mixed list are all bags
    assert find_bags([tmp_path / 'ros1']) == [ros1] == find_bags([ros1])
    assert find_bags([ros1, ros2]) == [ros1, ros2]
    for name, bag in (('a', ros2), ('b', ros1)):
        assert detect_cli.main([str(bag), '--audio-rate', '16000',
                                '--out', str(tmp_path / f'{name}.jsonl')]) == 0
    one, two = _rows(tmp_path / 'a.jsonl'), _rows(tmp_path / 'b.jsonl')
    assert len(one) > 100 and one == two
    assert any(row.get('event') == 'release' for row in two)
    # The ROS 1 messages read as the ROS 2 ones do, value for value.
    a = [e for e in load_events(ros2) if isinstance(e, WrenchEvent)]
    b = [e for e in load_events(ros1) if isinstance(e, WrenchEvent)]
    assert len(a) == len(b) and all(np.array_equal(x.force, y.force) and x.t == y.t
                                    for x, y in zip(a, b))
    out = capsys.readouterr().out
    assert 'wrench /wrist_wrench at 100 Hz (stamps)' in out and '16000 Hz, 1 ch (flag)' in out


def test_ros1_messages_convert_to_ros2_cdr(tmp_path):
    store = store_with('ros1', ROS_DRIVERS_MSGS)
    messages = (wrench_series(store, rate=125.0, seconds=0.1)
                + audio_data_series(store, rate=16000, chunk=160, seconds=0.05)
                + [audio_info(store, rate=16000, channels=1)])
    bag = write_bag(tmp_path / 'old.bag', 'ros1', store, messages)
    jazzy = store_with('ros2', ROS_DRIVERS_MSGS)
    got = list(iter_cdr(bag))
    assert len(got) == len(messages)
    for topic, msgtype, log_ns, raw in got:
        msg = jazzy.deserialize_cdr(raw, msgtype)       # ROS 2 layout: no Header.seq
        original = next(m for t, _, n, m in messages if t == topic and n == log_ns)
        if msgtype == WS:
            assert not hasattr(msg.header, 'seq')
            assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.wrench.force.z) == (
                original.header.stamp.sec, original.header.stamp.nanosec,
                original.wrench.force.z)
        elif msgtype == AD:
            assert np.array_equal(msg.data, original.data)
        else:
            assert msg.sample_rate == 16000 and msg.coding_format == 'wave'


# --- discovery ---------------------------------------------------------------------------------

@pytest.mark.parametrize('kind', ['ros1', 'sqlite3', 'mcap'])
def test_audio_info_and_stamps_give_the_format_without_flags(tmp_path, kind):
    store = store_with(kind, ROS_DRIVERS_MSGS)
    messages = (wrench_series(store, rate=200.0, seconds=1.0)
                + audio_data_series(store, rate=22050, chunk=441, seconds=1.0, channels=2)
                + [audio_info(store, rate=22050, channels=2)])
    bag = write_bag(tmp_path / ('b.bag' if kind == 'ros1' else 'b'), kind, store, messages)
    found = discover_streams(bag)
    assert (found.wrench_topic, found.audio_topic, found.audio_msg_type) == (
        '/ft', '/audio/audio', AD)
    assert (found.audio_rate, found.audio_rate_source, found.channels) == (
        22050.0, 'AudioInfo', 2)
    assert found.wrench_rate == pytest.approx(200.0, rel=1e-4)
    assert found.wrench_rate_source == 'stamps' and not found.warnings
    events = load_events(bag, spec=factory.stream_spec(found, {}))
    audio = [e for e in events if isinstance(e, AudioEvent)]
    assert len(audio) == 50 and all(e.samples.size == 441 for e in audio)   # mixed to mono
    # flags win over what the bag says
    forced = discover_streams(bag, audio_rate=44100.0, wrench_rate=100.0)
    assert (forced.audio_rate, forced.audio_rate_source) == (44100.0, 'flag')
    assert (forced.wrench_rate, forced.wrench_rate_source) == (100.0, 'flag')


@pytest.mark.parametrize('rate', [8000, 11025, 16000, 44100, 48000])
def test_audio_rate_without_info_is_estimated_snapped_and_warned(tmp_path, rate, capsys):
    store = store_with('ros1', ROS_DRIVERS_MSGS)
    messages = (wrench_series(store, rate=100.0, seconds=3.0)
                + audio_data_series(store, rate=rate, chunk=1024, seconds=3.0))
    bag = write_bag(tmp_path / 'x.bag', 'ros1', store, messages)
    found = discover_streams(bag)
    assert (found.audio_rate, found.audio_rate_source) == (float(rate), 'estimated')
    assert found.warnings and 'estimated' in found.warnings[0]
    # what detect prints: the estimate and the warning
    assert detect_cli.main([str(bag), '--out', str(tmp_path / 'o.jsonl')]) == 0
    out = capsys.readouterr().out
    assert f'{rate:g} Hz, 1 ch (estimated)' in out and 'warning:' in out


def test_snap_audio_rate():
    assert snap_audio_rate(16150.0) == 16000.0
    assert snap_audio_rate(43000.0) == 44100.0
    assert snap_audio_rate(23000.0) == 22050.0


def test_audio_stamped_carries_its_rate(tmp_path):
    store = store_with('mcap', MGONZS13_MSGS)
    t = store.types
    messages = wrench_series(store, rate=500.0, seconds=0.5)
    for k in range(20):
        stamp_ns = 10**18 + int((k + 1) * 480 / 48000 * 1e9)
        info = t[AI](format=8, channels=1, rate=48000, chunk=480)
        data = t[AD](float32_data=np.zeros(0, np.float32), int32_data=np.zeros(0, np.int32),
                     int24_data=np.zeros(0, np.int32),
                     int16_data=np.full(480, 100, np.int16), int8_data=np.zeros(0, np.int8),
                     uint8_data=np.zeros(0, np.uint8))
        header = t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
            sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9), frame_id='mic')
        messages.append(('/mic', AS, stamp_ns, t[AS](header=header, audio=t[
            'audio_common_msgs/msg/Audio'](info=info, audio_data=data))))
    bag = write_bag(tmp_path / 'm', 'mcap', store, messages)
    found = discover_streams(bag)
    assert (found.audio_topic, found.audio_rate, found.audio_rate_source) == (
        '/mic', 48000.0, 'AudioStamped')
    assert found.wrench_rate == pytest.approx(500.0, rel=1e-4)


def test_several_candidate_topics_are_listed_and_a_flag_chooses(tmp_path, capsys):
    store = store_with('sqlite3', {})
    messages = (wrench_series(store, rate=100.0, seconds=1.0, topic='/left/ft')
                + wrench_series(store, rate=100.0, seconds=1.0, topic='/right/ft'))
    arr = store.types[I16]
    layout = store.types['std_msgs/msg/MultiArrayLayout'](dim=[], data_offset=0)
    messages += [('/audio', I16, 10**18 + k * 10**7,
                  arr(layout=layout, data=np.zeros(160, np.int16))) for k in range(1, 100)]
    bag = write_bag(tmp_path / 'two', 'sqlite3', store, messages)
    with pytest.raises(BagError, match='several geometry_msgs/WrenchStamped topics') as err:
        discover_streams(bag)
    assert '/left/ft' in str(err.value) and '/right/ft' in str(err.value)
    assert detect_cli.main([str(bag), '--out', str(tmp_path / 'o.jsonl')]) == 1
    assert '--wrench-topic' in capsys.readouterr().err
    assert discover_streams(bag, wrench_topic='/right/ft').wrench_topic == '/right/ft'
    with pytest.raises(BagError, match='no topic /nope'):
        discover_streams(bag, wrench_topic='/nope')
    # a bag without audio says which topics it has
    only = write_bag(tmp_path / 'noaudio', 'sqlite3', store, messages[:100])
    with pytest.raises(BagError, match=r'no audio .* topic; topics: /left/ft'):
        discover_streams(only)


def test_a_wrench_topic_of_another_type_is_refused_naming_its_type(tmp_path, capsys):
    store = store_with('sqlite3', {})
    types = store.types
    header = types['std_msgs/msg/Header'](
        stamp=types['builtin_interfaces/msg/Time'](sec=1, nanosec=0), frame_id='ft')
    vec = types['geometry_msgs/msg/Vector3'](x=1.0, y=2.0, z=3.0)
    arr = store.types[I16]
    layout = store.types['std_msgs/msg/MultiArrayLayout'](dim=[], data_offset=0)
    messages = wrench_series(store, rate=100.0, seconds=1.0, topic='/ft')
    messages += [('/audio', I16, 10**18 + k * 10**7,
                  arr(layout=layout, data=np.zeros(160, np.int16))) for k in range(1, 100)]
    messages += [('/flag', 'std_msgs/msg/Bool', 10**18 + k, types['std_msgs/msg/Bool'](data=True))
                 for k in range(5)]
    messages += [('/vec', 'geometry_msgs/msg/Vector3Stamped', 10**18 + k,
                  types['geometry_msgs/msg/Vector3Stamped'](header=header, vector=vec))
                 for k in range(5)]
    bag = write_bag(tmp_path / 'typed', 'sqlite3', store, messages)
    for topic, found in (('/flag', 'std_msgs/msg/Bool'), ('/audio', I16),
                         ('/vec', 'geometry_msgs/msg/Vector3Stamped')):
        for rate in (None, 100.0):      # with --wrench-rate nothing is probed: still refused
            with pytest.raises(BagError, match=f'{topic} \\(--wrench-topic\\) holds {found}, '
                                               f'not {WS}'):
                discover_streams(bag, wrench_topic=topic, wrench_rate=rate)
    # detect says so, instead of a traceback from the message adapter
    assert detect_cli.main([str(bag), '--wrench-topic', '/flag', '--wrench-rate', '100',
                            '--out', str(tmp_path / 'o.jsonl')]) == 1
    assert 'holds std_msgs/msg/Bool' in capsys.readouterr().err
    assert discover_streams(bag, wrench_topic='/ft').wrench_topic == '/ft'


def test_a_rate_flag_of_zero_is_refused_not_ignored(tmp_path):
    store = store_with('sqlite3', ROS_DRIVERS_MSGS)
    messages = (wrench_series(store, rate=200.0, seconds=1.0)
                + audio_data_series(store, rate=22050, chunk=441, seconds=1.0)
                + [audio_info(store, rate=22050, channels=1)])
    bag = write_bag(tmp_path / 'b', 'sqlite3', store, messages)
    for bad in (0, 0.0, -16000.0, float('nan')):
        with pytest.raises(ConfigError, match='--audio-rate: audio sample rate must be in'):
            discover_streams(bag, audio_rate=bad)
    for bad in (0, -100.0, float('inf')):
        with pytest.raises(ConfigError, match='--wrench-rate: F/T rate must be a positive'):
            discover_streams(bag, wrench_rate=bad)
        with pytest.raises(ConfigError, match='--wrench-rate'):
            discover_streams(bag, wrench_rate=bad, allow_no_audio=True)
    found = discover_streams(bag, audio_rate=16000, wrench_rate=250)
    assert (found.audio_rate, found.audio_rate_source) == (16000.0, 'flag')
    assert (found.wrench_rate, found.wrench_rate_source) == (250.0, 'flag')


def test_an_audio_topic_of_an_unsupported_type_is_named(tmp_path):
    store = store_with('sqlite3', {})
    messages = wrench_series(store, rate=100.0, seconds=1.0)
    messages += [('/audio', 'std_msgs/msg/String', 10**18 + k * 10**7,
                  store.types['std_msgs/msg/String'](data='pcm?')) for k in range(1, 10)]
    bag = write_bag(tmp_path / 'b', 'sqlite3', store, messages)
    streams = discover_streams(bag, allow_no_audio=True)     # the F/T-only fallback stays
    assert not streams.has_audio
    assert streams.audio_note == '/audio holds std_msgs/msg/String: not a supported audio type'
    assert streams.describe().endswith(
        'no audio topic (/audio holds std_msgs/msg/String: not a supported audio type)')
    # a bag with no such topic says only that it has no audio topic
    plain = write_bag(tmp_path / 'p', 'sqlite3', store, messages[:100])
    assert discover_streams(plain, allow_no_audio=True).describe().endswith('no audio topic')


def test_a_bag_without_audio_is_found_only_for_an_ft_only_model(tmp_path, capsys):
    # A robot without a microphone, recorded with ROS 1: no audio topic at all.
    trial = simulate_trial(seed=12, index=0)
    bag = write_trial_bag(trial=trial, path=tmp_path / trial.name, storage='ros1', audio=False)
    with pytest.raises(BagError, match='no audio .* topic'):
        discover_streams(bag)
    streams = discover_streams(bag, allow_no_audio=True)
    assert streams.audio_topic is None and not streams.has_audio
    assert streams.wrench_topic == '/wrist_wrench' and round(streams.wrench_rate) == 100
    assert 'no audio topic' in streams.describe()
    # An explicit audio topic that is missing stays an error.
    with pytest.raises(BagError, match='no topic /mic'):
        discover_streams(bag, audio_topic='/mic', allow_no_audio=True)
    # detect routes the bag to the shipped F/T-only model.
    assert detect_cli.main([str(bag), '--out', str(tmp_path / 'o.jsonl')]) == 0
    out = capsys.readouterr().out
    assert 'no audio topic' in out and 'contact_forest_ft.npz' in out
    assert len([r for r in _rows(tmp_path / 'o.jsonl') if 'p' in r]) > 300


def test_iter_messages_reads_ros1_with_and_without_fast_decoders(tmp_path):
    trial = simulate_trial(seed=3, index=1)
    bag = write_trial_bag(trial=trial, path=tmp_path / 't', storage='ros1')
    fast = list(iter_messages(bag, decoders={'x': None}))
    slow = list(iter_messages(bag))
    assert len(fast) == len(slow) > 100
    spec = StreamSpec()
    events = load_events(bag, spec=spec)
    audio = np.concatenate([e.samples for e in events if isinstance(e, AudioEvent)])
    assert np.array_equal(audio, trial.audio[:audio.size]) and audio.size == trial.audio.size


def detect_found_and_by_hand(folder: Path, tmp_path: Path, capsys) -> tuple:
    """
    Run ``detect`` on three 200 Hz ROS 1 bags without flags, then with the settings by hand.

    Checks that the run without flags found the rate from the stamps and estimated the audio
    rate; returns the two JSONL outputs (found, by hand).
    """
    found, by_hand = tmp_path / 'found.jsonl', tmp_path / 'by_hand.jsonl'
    assert detect_cli.main([str(folder), '--out', str(found)]) == 0
    printed = capsys.readouterr().out
    assert '3 bags: wrench /wrist_wrench at 200 Hz (stamps)' in printed
    assert '16000 Hz, 1 ch (estimated)' in printed
    assert detect_cli.main([str(folder), '--wrench-topic', '/wrist_wrench', '--audio-topic',
                            '/audio', '--audio-rate', '16000', '--wrench-rate', '200',
                            '--out', str(by_hand)]) == 0
    return found, by_hand


def test_200_hz_ros1_bags_without_flags_decide_as_with_the_settings_by_hand(tmp_path, capsys):
    """Recordings as users have them: ROS 1, 200 Hz F/T, no rate anywhere in the bag."""
    folder = tmp_path / 'robot'
    for index in range(3):
        trial = simulate_trial(seed=31, index=index, ft_rate=200.0)
        write_trial_bag(trial=trial, path=folder / f'place_{index}', storage='ros1')
    found, by_hand = detect_found_and_by_hand(folder, tmp_path, capsys)
    rows = _rows(found)
    assert rows == _rows(by_hand)
    assert sum(row.get('event') == 'release' for row in rows) == 3


def _streams(*, wrench_rate: float, audio_rate: float = 16000.0) -> Streams:
    return Streams(wrench_topic='/ft', audio_topic='/audio', audio_msg_type=I16,
                   audio_rate=audio_rate, audio_rate_source='manifest', channels=1,
                   coding='pcm', wrench_rate=wrench_rate, wrench_rate_source='stamps')


def test_common_rates_take_the_median_of_agreeing_bags_and_list_disagreeing_ones():
    found = [(Path(f'b{i}'), _streams(wrench_rate=r))
             for i, r in enumerate((199.9, 200.0, 200.3))]
    assert common_rates(found) == (16000.0, 200.0)
    found.append((Path('slow'), _streams(wrench_rate=100.0)))
    with pytest.raises(BagError, match=r'one F/T rate, found 100 Hz: 1 bags \(first slow\); '
                                       r'199.9 Hz: 1 bags \(first b0\)'):
        common_rates(found)
    with pytest.raises(BagError, match='one audio rate'):
        common_rates([(Path('a'), _streams(wrench_rate=100.0)),
                      (Path('b'), _streams(wrench_rate=100.0, audio_rate=44100.0))])


def test_common_rates_read_bags_without_audio_only_for_an_ft_only_model():
    deaf = Streams(wrench_topic='/ft', audio_topic=None, audio_msg_type=None, audio_rate=None,
                   audio_rate_source='', channels=1, coding='pcm', wrench_rate=200.0,
                   wrench_rate_source='stamps')
    with pytest.raises(BagError, match='1 bags have no audio topic'):
        common_rates([(Path('deaf'), deaf)])
    assert common_rates([(Path('deaf'), deaf)], allow_no_audio=True) == (None, 200.0)
    # the bags that have audio still set (and must share) the audio rate
    assert common_rates([(Path('deaf'), deaf), (Path('b'), _streams(wrench_rate=200.0))],
                        allow_no_audio=True) == (16000.0, 200.0)
