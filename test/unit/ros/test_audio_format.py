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

"""The node's audio-format negotiation, without ROS: messages are plain objects."""

from types import SimpleNamespace as NS

from contact_detector.errors import InputError
from contact_detector.io.messages import AudioFormat
from contact_detector.ros.audio_format import AudioFormatNegotiation
import pytest

AS = 'audio_common_msgs/msg/AudioStamped'
CONFIGURED = AudioFormat(sample_rate=16000.0, channels=1)


def info(*, rate=44100, channels=2, coding='wave', sample_format='S16LE'):
    """Return a ros-drivers AudioInfo."""
    return NS(channels=channels, sample_rate=rate, sample_format=sample_format, bitrate=0,
              coding_format=coding)


def stamped(*, rate=16000, channels=1):
    """Return an mgonzs13 AudioStamped that carries its own format."""
    return NS(audio=NS(info=NS(format=8, channels=channels, rate=rate, chunk=160)))


def negotiation(**kwargs):
    settings = {'configured': CONFIGURED, 'info_topic': True, 'wait_for_info': True,
                'channel': None}
    settings.update(kwargs)
    return AudioFormatNegotiation(**settings)


def test_audio_waits_for_audio_info_then_takes_its_format():
    n = negotiation()
    drop = n.gate()
    assert drop.counter == 'audio_waiting_info' and 'audio.wait_for_info:=false' in drop.message
    assert n.info_status(use_audio=True) == 'waiting'
    outcome = n.on_info(info())
    assert outcome.accepted == AudioFormat(sample_rate=44100.0, channels=2)
    assert outcome.error is None
    assert outcome.info == 'audio_info: 44100 Hz, 2 channel(s), raw S16LE'
    assert n.gate() is None and n.format == outcome.accepted
    assert n.info_status(use_audio=True) == 'ok'
    assert n.describe() == '44100 Hz x 2 ch (mixed)'
    # The same info again (transient local, a reconnect) is taken without a new log line.
    assert n.on_info(info()).info is None


def test_parameters_are_trusted_without_an_info_topic_or_without_waiting():
    for kwargs in ({'info_topic': False}, {'wait_for_info': False}):
        n = negotiation(**kwargs)
        assert n.gate() is None and n.format == CONFIGURED
    assert negotiation(info_topic=False).info_status(use_audio=True) == 'n/a'
    assert negotiation().info_status(use_audio=False) == 'n/a'
    assert negotiation(channel=1).describe() == '16000 Hz x 1 ch (channel 1)'


def test_mp3_audio_info_refuses_the_audio_until_a_raw_one_arrives():
    n = negotiation()
    outcome = n.on_info(info(coding='mp3'))
    assert outcome.accepted is None and 'format:=wave' in outcome.error
    drop = n.gate()
    assert drop.counter == 'audio_refused' and 'mp3' in drop.message
    assert n.info_status(use_audio=True).startswith('refused: ')
    # Refused again for the same reason: logged once.
    assert n.on_info(info(coding='mp3')).error is None
    outcome = n.on_info(info(rate=16000, channels=1))
    assert outcome.accepted == CONFIGURED and outcome.info is not None
    assert n.gate() is None


def test_refusal_by_the_node_lasts_until_a_new_format():
    n = negotiation(info_topic=False)
    n.refuse('cannot run model m at 50 Hz')
    assert n.gate().message == 'audio dropped: cannot run model m at 50 Hz'
    assert n.info_status(use_audio=True) == 'refused: cannot run model m at 50 Hz'


def test_embedded_format_is_adopted_when_it_changes():
    n = negotiation(info_topic=False)
    assert not n.on_embedded(stamped(), AS)                  # the configured one
    assert n.on_embedded(stamped(rate=48000, channels=2), AS)
    assert n.format == AudioFormat(sample_rate=48000.0, channels=2)
    assert not n.on_embedded(stamped(rate=48000, channels=2), AS)
    with pytest.raises(InputError, match='info.rate=0'):
        n.on_embedded(stamped(rate=0), AS)
    assert n.format == AudioFormat(sample_rate=48000.0, channels=2)
