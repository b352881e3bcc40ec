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
The node's audio-format negotiation: the format audio is decoded with, and whether it is taken.

Pure (no rclpy): it takes messages as plain objects and returns what the node must do (log a
line, rebuild its detector for a new rate, drop a chunk). Three sources of the format, by
``audio.msg_type`` (:data:`~contact_detector.io.messages.AUDIO_MSG_TYPES`):

* the ``audio.*`` parameters (``std_msgs/Int16MultiArray`` and the like);
* an ``audio_info`` topic (ros-drivers ``AudioInfo``): until one confirms raw S16LE audio the
  chunks are dropped (``audio.wait_for_info``), and an unsupported one (mp3, another sample
  format, a rate out of range) refuses the audio until a good one arrives;
* the message itself (mgonzs13 ``AudioStamped``): every chunk's embedded format is checked,
  and a new one is adopted.
"""

from dataclasses import dataclass
from typing import Any, Optional

from contact_detector.errors import ConfigError
from contact_detector.io.messages import (AudioFormat, check_audio_info,
                                          embedded_audio_format)


@dataclass(frozen=True)
class AudioDrop:
    """Why an audio chunk is dropped before decoding: node counter, log key and message."""

    counter: str
    key: str
    message: str


@dataclass(frozen=True)
class InfoOutcome:
    """
    What an ``audio_info`` message asks of the node.

    Attributes
    ----------
    accepted : AudioFormat or None
        The format now in force (the node rebuilds its detector if the rate changed); None
        when the message was refused.
    error : str or None
        A line to log as an error (a new refusal).
    info : str or None
        A line to log as information (a new or newly confirmed format).

    """

    accepted: Optional[AudioFormat]
    error: Optional[str] = None
    info: Optional[str] = None


class AudioFormatNegotiation:
    """
    The audio format in force and whether audio is accepted.

    Parameters
    ----------
    configured : AudioFormat
        The format of the ``audio.sample_rate`` and ``audio.channels`` parameters.
    info_topic : bool
        The format comes from an ``audio_info`` topic (ros-drivers types).
    wait_for_info : bool
        With ``info_topic``: drop audio until ``audio_info`` confirms the format.
    channel : int or None
        The channel read (None: channels mixed), for :meth:`describe`.

    Attributes
    ----------
    format : AudioFormat
        The format chunks are decoded with.
    info_ok : bool or None
        ``audio_info`` confirmed the format (True), refused it (False), or not yet (None);
        True when no confirmation is awaited.
    refused : str or None
        Why the audio is refused (every chunk dropped), else None.

    """

    def __init__(self, *, configured: AudioFormat, info_topic: bool, wait_for_info: bool,
                 channel: Optional[int]) -> None:
        self.format = configured
        self.info_ok: Optional[bool] = None if info_topic and wait_for_info else True
        self.refused: Optional[str] = None
        self._info_topic = info_topic
        self._channel = channel

    def gate(self) -> Optional[AudioDrop]:
        """Return why the next audio chunk must be dropped, or None to decode it."""
        if self.refused is not None:
            return AudioDrop('audio_refused', 'audio-refused', f'audio dropped: {self.refused}')
        if not self.info_ok:
            return AudioDrop('audio_waiting_info', 'audio-info',
                             'audio dropped: waiting for audio_info (transient local) to confirm '
                             'raw S16LE audio; set audio.wait_for_info:=false to trust the '
                             'audio.* parameters')
        return None

    def on_info(self, info: Any) -> InfoOutcome:
        """Take an ``audio_info`` message: accept its format or refuse the audio."""
        try:
            fmt = check_audio_info(info)
        except ConfigError as err:
            error = None if self.refused == str(err) else f'audio refused: {err}'
            self.refused = str(err)
            self.info_ok = False
            return InfoOutcome(accepted=None, error=error)
        line = None
        if self.refused is not None or not self.info_ok or fmt != self.format:
            line = f'audio_info: {fmt.sample_rate:g} Hz, {fmt.channels} channel(s), raw S16LE'
        self.refused = None
        self.info_ok = True
        self.format = fmt
        return InfoOutcome(accepted=fmt, info=line)

    def on_embedded(self, msg: Any, msg_type: str) -> bool:
        """
        Take the format a message carries (``AudioStamped``); return whether it changed.

        Raises
        ------
        InputError
            The embedded rate or channel count is out of range (the chunk is dropped).

        """
        fmt = embedded_audio_format(msg, msg_type)
        if fmt == self.format:
            return False
        self.format = fmt
        return True

    def refuse(self, reason: str) -> None:
        """Refuse the audio (e.g. the model cannot run at the new rate) until a new format."""
        self.refused = reason

    def describe(self) -> str:
        """Return the format in force, e.g. ``16000 Hz x 2 ch (channel 0)``."""
        which = 'mixed' if self._channel is None else f'channel {self._channel}'
        return f'{self.format.sample_rate:g} Hz x {self.format.channels} ch ({which})'

    def info_status(self, *, use_audio: bool) -> str:
        """Return the ``audio_info`` state for diagnostics: refused, n/a, ok or waiting."""
        if self.refused:
            return 'refused: ' + self.refused
        if not self._info_topic or not use_audio:
            return 'n/a'
        return 'ok' if self.info_ok else 'waiting'
