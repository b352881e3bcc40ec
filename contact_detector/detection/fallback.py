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
No blind spot when the audio stream dies: an F/T-only model stands in for the multimodal one.

:class:`AudioFallback` drives two :class:`ContactDetector` s: the multimodal one (``primary``)
gets every message, the F/T-only one (``fallback``) every wrench message, so it is warm when it
takes over. Only the *active* one's decisions are returned, and only it may release (the other
is kept disarmed). Time is stream time (stamps), never a clock:

* audio -> F/T-only: at a wrench message stamped more than ``timeout_s`` after the newest audio
  sample (after the first wrench stamp if no audio came yet);
* F/T-only -> audio: at an audio message once the audio has come back for at least the
  multimodal detector's ``warmup_s`` (the warm-up applies to the model that takes over).

A switch happens between two messages, so at a frame boundary. The model that takes over gets
the arming of the other and starts a fresh confirmation run: frames decided before the switch
never count towards its release.
"""

import math
from typing import Optional, Sequence

from contact_detector.detection.detector import ContactDetector, Decisions
from contact_detector.errors import ConfigError
from contact_detector.features.carried import CarriedLoad
import numpy as np

#: Names of the two models in :attr:`AudioFallback.active_name` and the switch messages.
MULTIMODAL, FT_ONLY = 'audio + F/T', 'F/T-only'


class AudioFallback:
    """
    A multimodal detector with an F/T-only stand-in while the audio is silent.

    Offers the part of the :class:`ContactDetector` interface the node uses (``on_audio``,
    ``on_wrench_one``, ``drop``, ``reset``, ``arm``, ``armed``, ``rule``, ``set_rule``,
    ``settings``, ``counts``, ``extractor``, ``last_error``).

    Parameters
    ----------
    primary : ContactDetector
        With a model that uses audio.
    fallback : ContactDetector
        With an F/T-only model.
    timeout_s : float
        Audio silence (s of stream time) after which the F/T-only model takes over; > 0.

    """

    def __init__(self, *, primary: ContactDetector, fallback: ContactDetector,
                 timeout_s: float) -> None:
        if primary.ft_only or not fallback.ft_only:
            raise ConfigError('AudioFallback needs a model with audio as primary and an '
                              'F/T-only model as fallback')
        if not (isinstance(timeout_s, (int, float)) and math.isfinite(timeout_s)
                and timeout_s > 0):
            raise ConfigError(f'audio timeout must be a finite number > 0 s, got {timeout_s!r}')
        self.primary, self.fallback = primary, fallback
        self.timeout_s = float(timeout_s)
        self.switches = 0
        #: One line per switch, oldest first, for the caller's log (it may clear it).
        self.switch_messages: list = []
        self._init_state(armed=primary.armed)

    def _init_state(self, *, armed: bool) -> None:
        self.active = self.primary
        self.primary.logic.arm(armed)
        self.fallback.logic.arm(False)
        self._first_wrench_t: Optional[float] = None
        self._audio_back_t: Optional[float] = None

    # --- the detector interface --------------------------------------------------------------

    @property
    def active_name(self) -> str:
        """:data:`MULTIMODAL` or :data:`FT_ONLY`: the model whose decisions are returned."""
        return MULTIMODAL if self.active is self.primary else FT_ONLY

    @property
    def settings(self):
        """Return the multimodal detector's settings."""
        return self.primary.settings

    @property
    def extractor(self):
        """Return the multimodal detector's feature extractor: audio framing, pending frames."""
        return self.primary.extractor

    @property
    def rule(self):
        """Return the active detector's decision rule."""
        return self.active.rule

    @property
    def armed(self) -> bool:
        """Whether the next contact event releases."""
        return self.active.armed

    @property
    def carried_load(self) -> Optional[CarriedLoad]:
        """Return the multimodal model's carried-load measurement, else the F/T-only model's."""
        primary = self.primary.carried_load
        return primary if primary is not None else self.fallback.carried_load

    @property
    def last_error(self) -> Optional[str]:
        """Return the last drop or reset reason of either detector."""
        return self.active.last_error or self.primary.last_error

    @property
    def counts(self) -> dict:
        """Return the multimodal counters, the F/T-only ones as ``ft_*``, and the switches."""
        out = dict(self.primary.counts)
        for name in ('frames', 'events', 'releases', 'wrench_dropped', 'stale_frames'):
            out[f'ft_{name}'] = self.fallback.counts[name]
        out['releases'] = self.primary.counts['releases'] + self.fallback.counts['releases']
        out['model_switches'] = self.switches
        return out

    def arm(self, armed: bool) -> None:
        """
        Arm or disarm the release (of the active model; the other stays disarmed).

        Arming measures the carried load again in both (either may be active at the contact).
        """
        self.active.arm(armed)
        if armed:
            self.primary.measure_carried()
            self.fallback.measure_carried()

    @property
    def bias(self) -> tuple:
        """Return the F/T sensor's zero both detectors subtract (:attr:`ContactDetector.bias`)."""
        return self.primary.bias

    def set_bias(self, bias: Sequence[float]) -> None:
        """Give both detectors a new F/T zero; if it changed, back to the multimodal model."""
        before, armed = self.bias, self.armed
        self.primary.set_bias(bias)         # each resets its own stream state (ConfigError)
        self.fallback.set_bias(bias)
        if self.bias != before:
            self._init_state(armed=armed)

    def measure_zero(self) -> None:
        """Measure the sensor's zero in the multimodal detector (both see the same samples)."""
        self.primary.measure_zero()

    @property
    def zero_measurement(self) -> Optional[CarriedLoad]:
        """Return the multimodal detector's last zero measurement, or None."""
        return self.primary.zero_measurement

    def reset(self) -> None:
        """Forget all stream state of both detectors; back to the multimodal model."""
        armed = self.armed
        self.primary.reset()
        self.fallback.reset()
        self._init_state(armed=armed)

    def drop(self, *, kind: str, reason: str, stamp: Optional[float] = None) -> Decisions:
        """Count a corrupt message in both detectors (the F/T-only one ignores audio)."""
        self.fallback.drop(kind=kind, reason=reason, stamp=stamp)
        return self.primary.drop(kind=kind, reason=reason, stamp=stamp)

    def on_audio(self, samples: np.ndarray, *, stamp: float,
                 now: Optional[float] = None) -> Decisions:
        """Process an audio chunk; the audio model takes over again once the audio is back."""
        before = self.primary.latest_audio_t
        decided = self.primary.on_audio(samples, stamp=stamp, now=now)
        latest = self.primary.latest_audio_t
        if self.active is self.fallback and latest is not None:
            if self._audio_back_t is None or before is None \
                    or latest - before > self.timeout_s:
                self._audio_back_t = latest         # the audio (re)starts here
            elif latest - self._audio_back_t >= self.primary.settings.warmup_s:
                self._switch(to=self.primary, t=latest,
                             why=f'audio back for {latest - self._audio_back_t:.2f} s')
                return Decisions.empty()            # the next frames are the audio model's
        return decided if self.active is self.primary else Decisions.empty()

    def on_wrench_one(self, *, t: float, values: Sequence[float],
                      now: Optional[float] = None) -> Decisions:
        """Process one wrench sample; the F/T-only model takes over when the audio is silent."""
        from_primary = self.primary.on_wrench_one(t=t, values=values, now=now)
        from_fallback = self.fallback.on_wrench_one(t=t, values=values, now=now)
        if self._first_wrench_t is None and isinstance(t, (int, float)) and math.isfinite(t):
            self._first_wrench_t = float(t)
        if self.active is self.primary and self._first_wrench_t is not None \
                and isinstance(t, (int, float)) and math.isfinite(t):
            heard = self.primary.latest_audio_t
            since = self._first_wrench_t if heard is None else heard
            if t - since > self.timeout_s:
                self._switch(to=self.fallback, t=float(t),
                             why=f'no audio for {t - since:.2f} s')
                self._audio_back_t = None
                return Decisions.empty()            # the next frames are the F/T-only model's
        return from_primary if self.active is self.primary else from_fallback

    def flush(self) -> Decisions:
        """Decide the frames still waiting (end of a recording): the active model's."""
        primary, fallback = self.primary.flush(), self.fallback.flush()
        return primary if self.active is self.primary else fallback

    def _switch(self, *, to: ContactDetector, t: float, why: str) -> None:
        old = self.active
        armed = old.armed
        old.logic.arm(False)
        to.logic.reset()                # a fresh confirmation run: no frame from before counts
        to.logic.arm(armed)
        self.active = to
        self.switches += 1
        name = self.active_name
        self.switch_messages.append(f'model switched to {name} at t={t:.3f} ({why}); '
                                    f'release {"armed" if armed else "disarmed"}')
