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

"""Tests of the shared bag helpers in contact_detector.io.bags."""

import json
from pathlib import Path
import sqlite3

from contact_detector.errors import BagError
from contact_detector.io.bags import (find_bags, iter_messages, jazzy_typestore, manifest_entry,
                                      open_reader, read_audio, read_manifest, read_truth,
                                      read_wrench, topic_types)
from contact_detector.sim.bag_writer import (int16_multiarray_cdr, wrench_cdr, write_manifest,
                                             write_trial_bag)
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

pytestmark = pytest.mark.slow   # writes bags

AUDIO_DATA = 'audio_common_msgs/msg/AudioData'


@pytest.fixture(scope='module')
def run_dir(tmp_path_factory) -> Path:
    """Two simulated trials (sqlite3) with a manifest."""
    out = tmp_path_factory.mktemp('bags')
    trials = [simulate_trial(seed=4, index=i, condition=c)
              for i, c in enumerate(('paper', 'odd_chunking'))]
    for tr in trials:
        write_trial_bag(trial=tr, path=out / tr.name)
    write_manifest(trials=trials, out_dir=out, settings={'seed': 4})
    return out


def _custom_store():
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg('uint8[] data', AUDIO_DATA))
    return store


def _write_custom_bag(path: Path, storage: StoragePlugin) -> None:
    store = _custom_store()
    AudioData = store.types[AUDIO_DATA]
    Bool = store.types['std_msgs/msg/Bool']
    with Writer(path, version=9, storage_plugin=storage) as writer:
        audio = writer.add_connection('/mic', AUDIO_DATA, typestore=store)
        flag = writer.add_connection('/flag', 'std_msgs/msg/Bool', typestore=store)
        writer.write(flag, 2_000, store.serialize_cdr(Bool(data=True), 'std_msgs/msg/Bool'))
        for k in range(3):
            data = np.arange(4 * k, 4 * k + 4, dtype=np.uint8)
            raw = store.serialize_cdr(AudioData(data=data), AUDIO_DATA)
            writer.write(audio, 1_000 + 1_000 * k, raw)


def test_find_bags(run_dir, tmp_path):
    bags = find_bags([run_dir])
    assert [b.name for b in bags] == ['trial_0000', 'trial_0001']
    assert find_bags([run_dir / 'trial_0001', str(run_dir / 'trial_0000')]) == bags[::-1]
    assert find_bags([run_dir / 'trial_0000' / 'trial_0000.db3']) == [bags[0]]
    assert find_bags([run_dir, run_dir / 'trial_0000']) == bags  # no duplicates
    with pytest.raises(BagError):
        find_bags([tmp_path / 'missing'])
    (tmp_path / 'empty').mkdir()
    with pytest.raises(BagError):
        find_bags([tmp_path / 'empty'])
    with pytest.raises(BagError):
        find_bags([])


def test_iter_messages_in_log_time_order(run_dir):
    bag = run_dir / 'trial_0001'
    msgs = list(iter_messages(bag))
    times = [m.log_time_ns for m in msgs]
    assert times == sorted(times)
    assert {m.topic for m in msgs} == {'/wrist_wrench', '/audio', '/contact_truth'}
    wrench = list(iter_messages(bag, topics=['/wrist_wrench', '/nothing']))
    assert wrench and all(m.msgtype == 'geometry_msgs/msg/WrenchStamped' for m in wrench)
    first = wrench[0].msg
    assert first.header.frame_id == 'wrist_ft_sensor_frame'
    assert isinstance(first.wrench.force.x, float)
    audio = next(iter_messages(bag, topics=['/audio'])).msg
    assert isinstance(audio.data, np.ndarray) and audio.data.dtype == np.int16
    assert list(iter_messages(bag, topics=['/nothing'])) == []
    assert topic_types(bag)['/audio'] == 'std_msgs/msg/Int16MultiArray'


def test_truth_wrench_audio_and_manifest(run_dir):
    manifest = read_manifest(run_dir)
    assert manifest == read_manifest(run_dir / 'manifest.json')
    assert manifest['settings'] == {'seed': 4}
    entry = manifest_entry(run_dir / 'trial_0000')
    assert entry['name'] == 'trial_0000'
    truth = read_truth(run_dir / 'trial_0000')
    assert truth[0] == (pytest.approx(entry['onset_t'], abs=1e-6), True)
    assert truth[1] == (pytest.approx(entry['onset_end_t'], abs=1e-6), False)
    w = read_wrench(run_dir / 'trial_0000')
    assert w.force.shape == (len(w.t), 3) and np.all(np.diff(w.t) > 0)
    a = read_audio(run_dir / 'trial_0000')
    assert a.samples.dtype == np.int16 and a.chunk_ends[-1] == len(a.samples)
    assert a.t0(16000) == pytest.approx(entry['start_time'], abs=0.003)


def test_manifest_errors(tmp_path):
    with pytest.raises(BagError):
        read_manifest(tmp_path)
    (tmp_path / 'manifest.json').write_text('{not json')
    with pytest.raises(BagError):
        read_manifest(tmp_path)
    (tmp_path / 'manifest.json').write_text(json.dumps({'trials': 3}))
    with pytest.raises(BagError):
        read_manifest(tmp_path)
    assert manifest_entry(tmp_path / 'no_manifest_here' / 'bag') is None


@pytest.mark.parametrize('storage', [StoragePlugin.SQLITE3, StoragePlugin.MCAP])
def test_embedded_definitions_decode_custom_types(tmp_path, storage):
    bag = tmp_path / 'custom'
    _write_custom_bag(bag, storage)
    assert AUDIO_DATA not in jazzy_typestore().fielddefs
    msgs = list(iter_messages(bag))
    assert [m.topic for m in msgs] == ['/mic', '/flag', '/mic', '/mic']
    mic = [m.msg.data.tolist() for m in msgs if m.topic == '/mic']
    assert mic == [[0, 1, 2, 3], [4, 5, 6, 7], [8, 9, 10, 11]]
    assert msgs[1].msg.data is True
    assert AUDIO_DATA not in jazzy_typestore().fielddefs  # the shared store is not modified


def test_missing_definition_falls_back_to_jazzy(tmp_path):
    # a bag that embeds the custom type but not a standard one (as older recorders leave it)
    bag = tmp_path / 'mixed'
    _write_custom_bag(bag, StoragePlugin.SQLITE3)
    with sqlite3.connect(bag / 'mixed.db3') as db:
        db.execute("DELETE FROM message_definitions WHERE topic_type = 'std_msgs/msg/Bool'")
    flags = [m.msg.data for m in iter_messages(bag, topics=['/flag'])]
    assert flags == [True]
    with open_reader(bag) as reader:
        assert AUDIO_DATA in reader.typestore.fielddefs


def test_broken_bags_raise_bag_error(tmp_path):
    with pytest.raises(BagError):
        list(iter_messages(tmp_path))
    bag = tmp_path / 'broken'
    bag.mkdir()
    (bag / 'metadata.yaml').write_text('rosbag2_bagfile_information: [garbage')
    with pytest.raises(BagError):
        list(iter_messages(bag))
    with pytest.raises(BagError):
        read_wrench(tmp_path / 'broken')


def _wrench_bag(path: Path, stamps: list, *, nan_at: tuple = ()) -> Path:
    """Write a bag whose /ft holds one WrenchStamped per ``(sec, nanosec)`` (fz = index)."""
    store = jazzy_typestore()
    types = store.types
    vec = types['geometry_msgs/msg/Vector3']
    with Writer(path, version=9) as writer:
        ft = writer.add_connection('/ft', 'geometry_msgs/msg/WrenchStamped', typestore=store)
        other = writer.add_connection('/vec', 'geometry_msgs/msg/Vector3Stamped',
                                      typestore=store)
        for k, (sec, nanosec) in enumerate(stamps):
            header = types['std_msgs/msg/Header'](
                stamp=types['builtin_interfaces/msg/Time'](sec=sec, nanosec=nanosec),
                frame_id='ft')
            fz = float('nan') if k in nan_at else float(k)
            msg = types['geometry_msgs/msg/WrenchStamped'](
                header=header, wrench=types['geometry_msgs/msg/Wrench'](
                    force=vec(x=0.0, y=0.0, z=fz), torque=vec(x=0.0, y=0.0, z=0.0)))
            writer.write(ft, 1_000 + k, store.serialize_cdr(
                msg, 'geometry_msgs/msg/WrenchStamped'))
            writer.write(other, 1_000 + k, store.serialize_cdr(
                types['geometry_msgs/msg/Vector3Stamped'](header=header, vector=vec(
                    x=0.0, y=0.0, z=0.0)), 'geometry_msgs/msg/Vector3Stamped'))
    return path


def test_read_wrench_drops_and_counts_what_the_detector_would_not_use(tmp_path):
    ms = 1_000_000
    stamps = [(5, 0), (5, 10 * ms), (5, 1_500_000_000), (5, 20 * ms), (5, 20 * ms),
              (5, 15 * ms), (5, 30 * ms), (5, 40 * ms), (5, 50 * ms)]
    bag = _wrench_bag(tmp_path / 'mixed', stamps, nan_at=(7,))
    w = read_wrench(bag, topic='/ft')
    # kept: strictly increasing stamps in bag order, finite values, valid stamps
    np.testing.assert_allclose(w.t, [5.0, 5.01, 5.02, 5.03, 5.05])
    np.testing.assert_array_equal(w.force[:, 2], [0.0, 1.0, 3.0, 6.0, 8.0])
    assert (w.bad_messages, w.non_finite, w.out_of_order, w.dropped) == (1, 1, 2, 4)
    assert 'nanosec=1500000000' in w.first_problem and w.frame_id == 'ft'
    assert w.describe_drops() == (
        f'dropped 4 of 9 F/T messages: 1 refused (first: {w.first_problem}), 1 with NaN/Inf '
        'values, 2 with a stamp that repeats or precedes the previous one')
    clean = read_wrench(_wrench_bag(tmp_path / 'clean', stamps[:2]), topic='/ft')
    assert clean.dropped == 0 and clean.describe_drops() == ''
    # one stamp an hour ahead: that one is left out, not every sample after it
    lone = [(5, 0), (5, 10 * ms), (3605, 20 * ms), (5, 30 * ms), (5, 40 * ms), (5, 50 * ms)]
    w = read_wrench(_wrench_bag(tmp_path / 'lone', lone), topic='/ft')
    np.testing.assert_allclose(w.t, [5.0, 5.01, 5.03, 5.04, 5.05])
    assert w.out_of_order == 1
    # another type under the name: refused by name, not an AttributeError
    with pytest.raises(BagError, match='/vec holds geometry_msgs/msg/Vector3Stamped, not '
                                       'geometry_msgs/msg/WrenchStamped'):
        read_wrench(bag, topic='/vec')
    # nothing usable: a BagError that says why
    invalid = _wrench_bag(tmp_path / 'invalid', [(5, 1_500_000_000)] * 3)
    with pytest.raises(BagError, match=r'no usable messages on /ft \(dropped 3 of 3 F/T '
                                       r'messages: 3 refused \(first: invalid time stamp'):
        read_wrench(invalid, topic='/ft')


def test_fast_cdr_matches_typestore():
    store = jazzy_typestore()
    types = store.types
    rng = np.random.default_rng(0)
    stamps = np.array([1_700_000_000_000_000_000, 1_700_000_000_123_456_789, 5])
    force, torque = rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
    raw = wrench_cdr(stamp_ns=stamps, force=force, torque=torque)
    for i, ns in enumerate(stamps.tolist()):
        msg = types['geometry_msgs/msg/WrenchStamped'](
            header=types['std_msgs/msg/Header'](
                stamp=types['builtin_interfaces/msg/Time'](sec=ns // 10**9,
                                                           nanosec=ns % 10**9),
                frame_id='wrist_ft_sensor_frame'),
            wrench=types['geometry_msgs/msg/Wrench'](
                force=types['geometry_msgs/msg/Vector3'](x=force[i, 0], y=force[i, 1],
                                                         z=force[i, 2]),
                torque=types['geometry_msgs/msg/Vector3'](x=torque[i, 0], y=torque[i, 1],
                                                          z=torque[i, 2])))
        assert raw[i].tobytes() == bytes(store.serialize_cdr(
            msg, 'geometry_msgs/msg/WrenchStamped'))
    for n in (0, 1, 3, 160):
        data = rng.integers(-32768, 32768, n).astype(np.int16)
        msg = types['std_msgs/msg/Int16MultiArray'](
            layout=types['std_msgs/msg/MultiArrayLayout'](
                dim=[types['std_msgs/msg/MultiArrayDimension'](label='samples', size=n,
                                                               stride=n)],
                data_offset=0),
            data=data)
        assert int16_multiarray_cdr(data) == bytes(store.serialize_cdr(
            msg, 'std_msgs/msg/Int16MultiArray'))
