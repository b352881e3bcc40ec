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

"""mp3 audio in bags (audio_common's default): decoded offline with its sample times right."""

import io
from types import SimpleNamespace as NS

from contact_detector.cli import detect as detect_cli
from contact_detector.detection import factory
from contact_detector.errors import ConfigError
from contact_detector.io.discovery import discover_streams
from contact_detector.io.messages import check_audio_info
from contact_detector.io.mp3 import LAME_DELAY, mp3_format, mp3_frames
from contact_detector.io.sensor_stream import AudioEvent, load_events, WrenchEvent
import numpy as np
import pytest
import soundfile
from test_discovery import AD, AI, ROS_DRIVERS_MSGS, store_with, wrench_series, write_bag

pytestmark = pytest.mark.slow   # writes and decodes mp3 bags

T_START_NS = 1_700_000_000 * 10**9
CLICK_S = 1.0


def mp3_stream(rate: int, *, seconds: float = 2.0, tagged: bool = True) -> bytes:
    """Encode an mp3 (soundfile / LAME) of silence with a click ``CLICK_S`` after the start."""
    x = np.zeros(int(seconds * rate), np.float32)
    x[int(CLICK_S * rate)] = 0.9
    buf = io.BytesIO()
    soundfile.write(buf, x, rate, format='MP3')
    raw = buf.getvalue()
    if not tagged:          # a streaming encoder: no Xing/LAME header frame
        first = mp3_frames(raw)[0]
        raw = raw[first[0] + first[1]:]
    return raw


def audio_messages(store, raw: bytes, rate: int, *, piece: int, seed: int = 0) -> list:
    """
    Split the stream into AudioData messages of ``piece`` bytes, logged when sent.

    A message goes out when the encoder has produced its bytes: after the input sample the
    last complete frame in it needs (``frames * spf - LAME_DELAY``), plus 0-2 ms transport.
    """
    frames = mp3_frames(raw)
    header = 1 if b'Xing' in raw[:200] or b'Info' in raw[:200] else 0
    ends = np.array([start + size for start, size, _ in frames[header:]])
    spf = frames[-1][2]
    rng = np.random.default_rng(seed)
    out = []
    for lo in range(0, len(raw), piece):
        hi = min(lo + piece, len(raw))
        done = int(np.searchsorted(ends, hi, side='right'))
        last = max(done * spf - LAME_DELAY - 1, 0)
        log_ns = T_START_NS + int(last / rate * 1e9) + int(rng.uniform(0, 2e6))
        data = np.frombuffer(raw[lo:hi], np.uint8)
        out.append(('/audio/audio', AD, log_ns, store.types[AD](data=data)))
    for k in range(1, len(out)):                 # a bag logs in order
        if out[k][2] <= out[k - 1][2]:
            out[k] = out[k][:2] + (out[k - 1][2] + 1,) + out[k][3:]
    return out


def click_time(events) -> float:
    audio = [e for e in events if isinstance(e, AudioEvent)]
    samples = np.concatenate([e.samples for e in audio])
    idx = int(np.argmax(np.abs(samples)))
    ends = np.cumsum([e.samples.size for e in audio])
    k = int(np.searchsorted(ends, idx, side='right'))
    rate = 1.0 / np.median([np.diff([audio[i].stamp, audio[i + 1].stamp])[0]
                            / audio[i + 1].samples.size for i in range(len(audio) - 1)])
    return audio[k].stamp - (ends[k] - 1 - idx) / rate


@pytest.mark.parametrize('rate, tagged, piece, kind', [
    (16000, True, 600, 'sqlite3'),
    (44100, True, 1024, 'ros1'),
    (44100, False, 417, 'sqlite3'),
    (22050, False, 1000, 'mcap'),
])
def test_mp3_click_keeps_its_time(tmp_path, rate, tagged, piece, kind):
    store = store_with(kind, ROS_DRIVERS_MSGS)
    raw = mp3_stream(rate, tagged=tagged)
    info = ('/audio/audio_info', AI, T_START_NS, store.types[AI](
        channels=1, sample_rate=rate, sample_format='S16LE', bitrate=64,
        coding_format='mp3'))
    messages = (audio_messages(store, raw, rate, piece=piece) + [info]
                + wrench_series(store, rate=100.0, seconds=2.0, start_ns=T_START_NS))
    bag = write_bag(tmp_path / ('b.bag' if kind == 'ros1' else 'b'), kind, store, messages)
    found = discover_streams(bag)
    assert (found.coding, found.audio_rate) == ('mp3', rate)
    assert found.audio_rate_source == 'AudioInfo'
    events = load_events(bag, spec=factory.stream_spec(found, {}))
    audio = [e for e in events if isinstance(e, AudioEvent)]
    total = sum(e.samples.size for e in audio)
    # every input sample is there once (the end padding of an untagged stream at most more)
    assert 2 * rate <= total <= 2 * rate + (0 if tagged else 1152)
    assert abs(click_time(events) - (T_START_NS * 1e-9 + CLICK_S)) < 1e-3
    # no audio event before its message arrived; the events come in log-time order
    assert all(e.stamp <= e.now + 1e-9 for e in audio)
    nows = [e.now for e in events if isinstance(e, (AudioEvent, WrenchEvent))]
    assert nows == sorted(nows)


def test_detect_reads_an_mp3_bag_and_says_so(tmp_path, capsys):
    store = store_with('sqlite3', ROS_DRIVERS_MSGS)
    raw = mp3_stream(16000)
    info = ('/audio/audio_info', AI, T_START_NS, store.types[AI](
        channels=1, sample_rate=16000, sample_format='S16LE', bitrate=64,
        coding_format='mp3'))
    messages = (audio_messages(store, raw, 16000, piece=500) + [info]
                + wrench_series(store, rate=125.0, seconds=2.0, start_ns=T_START_NS))
    bag = write_bag(tmp_path / 'mp3', 'sqlite3', store, messages)
    out = tmp_path / 'o.jsonl'
    assert detect_cli.main([str(bag), '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    assert '16000 Hz, 1 ch, mp3 (AudioInfo)' in printed and 'at 125 Hz' in printed
    assert len(out.read_text().splitlines()) > 100


def test_the_live_node_keeps_refusing_mp3_and_names_the_fix():
    info = NS(channels=1, sample_rate=16000, sample_format='S16LE', bitrate=64,
              coding_format='mp3')
    with pytest.raises(ConfigError, match='format:=wave'):
        check_audio_info(info)


@pytest.mark.parametrize('rate, tagged, kind', [(16000, False, 'ros1'), (44100, True, 'sqlite3')])
def test_mp3_without_audio_info_is_found_from_its_frame_headers(tmp_path, rate, tagged, kind):
    store = store_with(kind, ROS_DRIVERS_MSGS)
    raw = mp3_stream(rate, tagged=tagged)
    messages = (audio_messages(store, raw, rate, piece=500)
                + wrench_series(store, rate=125.0, seconds=2.0, start_ns=T_START_NS))
    bag = write_bag(tmp_path / ('b.bag' if kind == 'ros1' else 'b'), kind, store, messages)
    found = discover_streams(bag)
    assert (found.coding, found.audio_rate, found.channels) == ('mp3', rate, 1)
    assert found.audio_rate_source == 'mp3 header' and not found.warnings
    events = load_events(bag, spec=factory.stream_spec(found, {}))
    assert abs(click_time(events) - (T_START_NS * 1e-9 + CLICK_S)) < 1e-3


def test_pcm_bytes_are_not_taken_for_mp3():
    rng = np.random.default_rng(3)
    for pcm in (rng.normal(0, 3000, 8000).astype('<i2').tobytes(),
                np.zeros(8000, '<i2').tobytes(),
                np.full(8000, -1, '<i2').tobytes()):
        assert mp3_format(pcm) is None
    assert mp3_format(mp3_stream(16000)) == (16000.0, 1)
