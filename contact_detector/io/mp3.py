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
Decode an mp3 stream carried in ``audio_common_msgs/AudioData`` messages, with sample times.

audio_common's capture node (ros-drivers) publishes mp3 by default: each message holds the
next bytes of one mp3 stream, and ``AudioInfo`` says ``coding_format: mp3``. The messages carry
no stamp, so the decoded samples are timed from the bag's log times, as raw audio without
stamps is (:meth:`contact_detector.io.bags.AudioSeries.t0`).

Decoding uses libsndfile (>= 1.1, mpg123 inside) through ``soundfile``, on the whole stream.

Delay. An mp3 encoder (LAME) starts with 576 samples of priming and the decoder adds 529
(:data:`LAME_DELAY`): sample ``i`` of the input comes out as decoded sample ``i + 1105``.
A stream that begins with a Xing/Info frame carrying a LAME tag says so, and libsndfile removes
the delay and the end padding itself; a stream without one (an encoder that streams, the
header frame lost) gets the first :data:`LAME_DELAY` decoded samples dropped here. Either way
decoded sample ``i`` is input sample ``i``.

Times. Each mp3 frame decodes to a fixed number of samples (1152 for MPEG-1, 576 for MPEG-2
and 2.5 Layer III), so the frames complete in the bytes up to message ``k`` hold the input
samples ``[0, e_k)``, ``e_k = f_k * spf - LAME_DELAY`` (``f_k`` complete audio frames, the
header frame not counted). The encoder could not send them before it had the last of them, so
the log time ``l_k`` is at or after the time of sample ``e_k - 1``; the time of sample 0 is
``t_0 = min_k (l_k - (e_k - 1) / rate)`` (the lower envelope: exact up to the smallest
transport delay) and sample ``i`` is at ``t_0 + i / rate``.
"""

import io
from typing import NamedTuple, Sequence

from contact_detector.errors import InputError
import numpy as np

#: LAME's encoder delay (576) plus the mp3 decoder's delay (529), in samples.
LAME_DELAY = 576 + 529


class Mp3Audio(NamedTuple):
    """Decoded mono samples (float32, full scale 1), the rate (Hz), per message the end index."""

    samples: np.ndarray
    rate: float
    ends: np.ndarray
    t0: float


_BITRATES_KBPS = {
    1: (0, 32, 40, 48, 56, 64, 80, 96, 112, 128, 160, 192, 224, 256, 320),   # MPEG-1
    2: (0, 8, 16, 24, 32, 40, 48, 56, 64, 80, 96, 112, 128, 144, 160),       # MPEG-2 and 2.5
}
_RATES = {3: (44100, 48000, 32000), 2: (22050, 24000, 16000), 0: (11025, 12000, 8000)}


def mp3_frames(raw: bytes) -> list:
    """
    Find the Layer III frames of an mp3 byte stream (resynchronising over junk).

    Returns
    -------
    list of (int, int, int)
        ``(first byte, bytes, samples per frame)`` of each frame, in order.

    """
    frames, pos, n = [], 0, len(raw)
    while pos + 4 <= n:
        b1, b2 = raw[pos + 1], raw[pos + 2]
        version, layer = (b1 >> 3) & 3, (b1 >> 1) & 3
        bitrate_i, rate_i, pad = b2 >> 4, (b2 >> 2) & 3, (b2 >> 1) & 1
        if raw[pos] != 0xFF or (b1 & 0xE0) != 0xE0 or layer != 1 or version == 1 \
                or bitrate_i in (0, 15) or rate_i == 3:
            pos += 1
            continue
        kbps = _BITRATES_KBPS[1 if version == 3 else 2][bitrate_i]
        rate = _RATES[version][rate_i]
        per = 144 if version == 3 else 72
        size = per * kbps * 1000 // rate + pad
        frames.append((pos, size, 1152 if version == 3 else 576))
        pos += size
    return frames


def mp3_format(raw: bytes) -> tuple[float, int] | None:
    """
    Sample rate (Hz) and channels of a byte stream that is mp3, else None.

    The bytes are mp3 when Layer III frames of one sample rate follow each other from the
    first frame (at most 64 bytes of anything, e.g. an ID3 tag start, before it) and cover at
    least 90 % of the bytes after it: PCM samples almost never chain frame headers like that.
    Used for ``AudioData`` without ``AudioInfo``, whose coding the bag does not say.

    Parameters
    ----------
    raw : bytes
        The first bytes of the stream (a few messages).

    Returns
    -------
    (float, int) or None
        ``(rate, channels)`` from the first frame header (channel mode 3 = mono).

    """
    frames = mp3_frames(raw)
    if len(frames) < 2 or frames[0][0] > 64:
        return None
    chained = sum(size for (start, size, _), (nxt, _, _) in zip(frames, frames[1:])
                  if start + size == nxt)
    if chained + frames[-1][1] < 0.9 * (len(raw) - frames[0][0]):
        return None
    rates = set()
    for start, _, _ in frames:
        b1, b2 = raw[start + 1], raw[start + 2]
        rates.add(_RATES[(b1 >> 3) & 3][(b2 >> 2) & 3])
    if len(rates) != 1:
        return None
    mode = raw[frames[0][0] + 3] >> 6
    return float(rates.pop()), 1 if mode == 3 else 2


def decode_mp3(*, chunks: Sequence[bytes], log_t: Sequence[float],
               channel: int | None = None) -> Mp3Audio:
    """
    Decode the mp3 stream of consecutive messages and time its samples (module docstring).

    Parameters
    ----------
    chunks : sequence of bytes
        The ``data`` of each AudioData message, in order.
    log_t : sequence of float
        Each message's log (receive) time, s.
    channel : int or None
        Channel to keep; None averages all (the stream says how many there are).

    Returns
    -------
    Mp3Audio

    Raises
    ------
    InputError
        soundfile is missing, or the bytes are not a decodable mp3 stream.

    """
    try:
        import soundfile
    except ImportError as err:             # an install without the offline extras
        raise InputError('mp3 audio needs the soundfile package (pip install soundfile, or '
                         'rosdep key python3-soundfile)') from err
    raw = b''.join(bytes(c) for c in chunks)
    try:
        decoded, rate = soundfile.read(io.BytesIO(raw), dtype='float32', always_2d=True)
    except Exception as err:               # libsndfile raises its own error types
        raise InputError(f'cannot decode the mp3 stream ({len(raw)} bytes): {err}') from err
    if channel is not None and not 0 <= channel < decoded.shape[1]:
        raise InputError(f'audio channel {channel} does not exist in a {decoded.shape[1]}-'
                         'channel mp3 stream')
    mono = decoded[:, channel] if channel is not None else decoded.mean(axis=1,
                                                                        dtype=np.float32)
    frames = mp3_frames(raw)
    tagged = False
    first = raw[frames[0][0]:frames[0][0] + 200] if frames else b''
    if b'Xing' in first or b'Info' in first:
        head = raw[frames[0][0]:frames[0][0] + frames[0][1]]
        tagged = b'LAME' in head or b'Lavc' in head
        frames = frames[1:]             # the header frame decodes to nothing
    if not tagged:
        mono = mono[LAME_DELAY:]        # libsndfile removed the delay itself when tagged
    # decoded samples complete after each message's bytes
    frame_end = np.array([start + size for start, size, _ in frames], dtype=np.int64)
    spf = np.array([per for _, _, per in frames], dtype=np.int64)
    done = np.searchsorted(frame_end, np.cumsum([len(c) for c in chunks]), side='right')
    decoded_done = np.concatenate([[0], np.cumsum(spf)])[done]
    ends = np.clip(decoded_done - LAME_DELAY, 0, mono.size)
    log_t = np.asarray(log_t, dtype=float)
    have = ends > 0
    t0 = (float(np.min(log_t[have] - (ends[have] - 1) / rate)) if have.any()
          else float(log_t[0]))
    ends[-1] = mono.size                # the decoder's tail (end padding) with the last one
    return Mp3Audio(samples=np.ascontiguousarray(mono, dtype=np.float32), rate=float(rate),
                    ends=ends, t0=t0)
