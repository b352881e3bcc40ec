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
Recordings and parameter files the offline tools must refuse or flag, not decide silently.

A parameter file gets the node's own checks; audio header stamps that repeat are dropped and
counted as the node drops them; a recording whose frames cannot be decided says so.
"""

import dataclasses
import json
from pathlib import Path

from contact_detector.cli import detect as detect_cli
from contact_detector.detection.parameters import PARAMS_BY_NAME, read_param_file
from contact_detector.errors import ConfigError
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest
from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

pytestmark = pytest.mark.slow   # writes and reads bags

AD = 'audio_common_msgs/msg/AudioData'
AI = 'audio_common_msgs/msg/AudioInfo'
ADS = 'audio_common_msgs/msg/AudioDataStamped'


# --- parameter files -----------------------------------------------------------------------------

def params_file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / 'params.yaml'
    path.write_text(text)
    return path


@pytest.mark.parametrize('text, match', [
    ('/**:\n  ros__parameters:\n    max_input_delay_s: abc\n', 'max_input_delay_s must be a'),
    ('/**:\n  ros__parameters:\n    wrench:\n      rate: fast\n', 'wrench.rate must be a float'),
    ('/**:\n  ros__parameters:\n    model:\n      path: 5\n', 'model.path must be a str'),
    ('/**:\n  ros__parameters:\n    audio:\n      enabled: "no"\n', 'enabled must be a bool'),
    ('/**:\n  ros__parameters:\n    release:\n      threshold: .nan\n', 'must be finite'),
    ('/**:\n  ros__parameters:\n    audio:\n      channels: 0\n', 'outside'),
    ('/**:\n  ros__parameters:\n    audio:\n      channel: 5\n', 'audio.channel=5 does not exist'),
    ('/**:\n  ros__parameters:\n    wrench:\n      rat: 200.0\n', 'wrench.rat: not a parameter'),
    ('- a\n- b\n', 'top level must map node names'),
    ('/**:\n  ros__parameters: 5\n', 'must be a mapping'),
    ('other_node:\n  ros__parameters: {}\nthird:\n  ros__parameters: {}\n',
     'no "<node>: ros__parameters:" section for the contact detector'),
])
def test_a_parameter_file_the_node_would_refuse_is_refused(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match) as err:
        read_param_file(params_file(tmp_path, text))
    assert 'params.yaml' in str(err.value)


def test_the_shipped_parameter_files_pass_the_offline_checks():
    # the files a user starts from set every parameter (the defaults) and the HSR preset
    params = Path(__file__).resolve().parents[2] / 'params'
    assert set(read_param_file(params / 'contact_detector.yaml')) == set(PARAMS_BY_NAME)
    assert read_param_file(params / 'hsr.yaml')['wrench.rate'] == 100.0


def test_an_undecodable_parameter_file_is_a_config_error(tmp_path):
    path = tmp_path / 'params.yaml'
    path.write_bytes(b'\xff\xfe\x00bad')
    with pytest.raises(ConfigError, match='cannot read parameter file'):
        read_param_file(path)


def test_a_robots_bringup_file_gives_the_detectors_sections(tmp_path):
    path = params_file(tmp_path, (
        'camera_driver:\n  ros__parameters:\n    rate: 30\n'
        '/**:\n  ros__parameters:\n    use_sim_time: true\n    warmup_s: 1\n'
        '/robot/contact_detector:\n  ros__parameters:\n    wrench:\n      rate: 200\n'))
    # the camera's section is not the detector's; integers for floats, as the node takes them;
    # rclpy's own use_sim_time is left out
    assert read_param_file(path) == {'warmup_s': 1.0, 'wrench.rate': 200.0}


def test_a_file_with_one_section_is_read_whatever_its_node_name(tmp_path):
    path = params_file(tmp_path, 'contact_detector_node:\n  ros__parameters:\n'
                                 '    release:\n      threshold: 0.9\n    empty:\n')
    with pytest.raises(ConfigError, match='empty: not a parameter'):
        read_param_file(path)
    path.write_text('my_detector:\n  ros__parameters:\n    release:\n      threshold: 0.9\n')
    assert read_param_file(path) == {'release.threshold': 0.9}


# --- recordings ----------------------------------------------------------------------------------

@pytest.fixture(scope='module')
def base_bag(tmp_path_factory) -> Path:
    trial = simulate_trial(seed=5, index=0)
    return write_trial_bag(trial=trial, path=tmp_path_factory.mktemp('base') / trial.name)


def rewrite(src: Path, dst: Path, change, *, header=None) -> Path:
    """
    Copy a rosbag2 bag, each message through ``change(store, topic, msgtype, log_ns, msg)``.

    ``header(store)`` gives messages ``(topic, msgtype, msg)`` to log first.
    """
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg('uint8[] data\n', AD))
    store.register(get_types_from_msg('uint8 channels\nuint32 sample_rate\nstring sample_format'
                                      '\nuint32 bitrate\nstring coding_format\n', AI))
    store.register(get_types_from_msg('std_msgs/Header header\naudio_common_msgs/AudioData audio'
                                      '\n', ADS))
    with Reader(src) as reader:
        messages = [(c.topic, c.msgtype, t, store.deserialize_cdr(raw, c.msgtype))
                    for c, t, raw in reader.messages()]
    start = messages[0][2] - 1
    out = [(topic, msgtype, start, msg) for topic, msgtype, msg in
           (header(store) if header else [])]
    out += [m for old in messages for m in change(store, *old)]
    with Writer(dst, version=9) as writer:
        conns = {}
        for topic, msgtype, log_ns, msg in out:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(conns[topic], log_ns, store.serialize_cdr(msg, msgtype))
    return dst


def detect(bag: Path, tmp_path: Path, capsys) -> tuple:
    out = tmp_path / 'out.jsonl'
    assert detect_cli.main([str(bag), '--out', str(out)]) == 0
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    captured = capsys.readouterr()
    return rows, captured.out + captured.err


def test_audio_header_stamps_that_never_move_are_dropped_and_counted(base_bag, tmp_path,
                                                                     capsys):
    # A driver that never fills the header: every chunk stamped 0. The node (header stamps)
    # drops a chunk whose stamp repeats; offline it must not decide frames at one instant.
    def zero_stamped(store, topic, msgtype, log_ns, msg):
        if topic != '/audio':
            return [(topic, msgtype, log_ns, msg)]
        types = store.types
        pcm = np.asarray(msg.data, dtype='<i2').tobytes()
        header = types['std_msgs/msg/Header'](
            stamp=types['builtin_interfaces/msg/Time'](sec=0, nanosec=0), frame_id='mic')
        stamped = types[ADS](header=header, audio=types[AD](data=np.frombuffer(pcm, np.uint8)))
        return [('/audio', ADS, log_ns, stamped)]

    def info(store):
        return [('/audio_info', AI, store.types[AI](channels=1, sample_rate=16000,
                                                    sample_format='S16LE', bitrate=0,
                                                    coding_format='wave'))]

    bag = rewrite(base_bag, tmp_path / 'zero_stamps', zero_stamped, header=info)
    rows, said = detect(bag, tmp_path, capsys)
    frames = [r for r in rows if 'p' in r]
    # at most the first chunk is taken; the rest are dropped, counted and said (not 1081
    # frames all at t = 0)
    assert len(frames) < 10
    assert not any(r.get('event') == 'release' for r in rows)
    dropped = int(said.split('dropped ')[1].split(' audio')[0])
    assert dropped >= 1000, said


def test_a_recording_whose_frames_cannot_be_decided_says_so(base_bag, tmp_path, capsys):
    # wrench stamps on another clock (1e6 s ahead of the audio): no frame finds F/T
    def shifted(store, topic, msgtype, log_ns, msg):
        if topic == '/wrist_wrench':
            stamp = msg.header.stamp
            msg = dataclasses.replace(msg, header=dataclasses.replace(
                msg.header, stamp=dataclasses.replace(stamp, sec=stamp.sec + 1_000_000)))
        return [(topic, msgtype, log_ns, msg)]

    rows, said = detect(rewrite(base_bag, tmp_path / 'other_clock', shifted), tmp_path, capsys)
    frames = [r for r in rows if 'p' in r]
    assert frames and all(r['p'] == 0.0 for r in frames)
    assert f'{len(frames)} of {len(frames)} frames could not be decided' in said, said
    assert 'one clock' in said
    # ... and the same recording unchanged says nothing of the kind
    _, said = detect(base_bag, tmp_path, capsys)
    assert 'could not be decided' not in said
