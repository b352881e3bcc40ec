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
Two models on one robot: the F/T-only model decides beside the multimodal one, or stands in.

:class:`AudioFallback` drives two :class:`ContactDetector` s: the multimodal one (``primary``)
gets every message, the F/T-only one (``fallback``) every wrench message, so it is warm when it
takes over. Only the *active* one's frames are returned. Time is stream time (stamps), never a
clock:

* audio -> F/T-only: at a wrench message stamped more than ``timeout_s`` after the newest audio
  sample (after the first wrench stamp if no audio came yet);
* F/T-only -> audio: at an audio message once the audio has come back for at least the
  multimodal detector's ``warmup_s`` (the warm-up applies to the model that takes over).

A switch happens between two messages, so at a frame boundary. The model that takes over gets
the arming of the other and starts a fresh confirmation run: frames decided before the switch
never count towards its release.

With ``both_decide`` the F/T-only model also *decides* while the multimodal model is active:
both are armed, and the first release of either is the release, once per arming (the other is
disarmed). It catches the slow, quiet load transfers the multimodal forest is unsure of (soft
surfaces, fixtures, partial stops) with the F/T-only model's load paths, and releases early
after a few more brushes (the node's ``model.ft_also_decides``, off by default;
docs/decisions/2026-11-29-both-models-decide.md). The frames returned stay the active model's;
a release of the F/T-only model is added to them, and the audio model's hold-off after a
corrupt message holds the F/T-only model too.
"""

import dataclasses
import math
from typing import List, Optional, Sequence, Tuple

from contact_detector.detection.detector import ContactDetector, Decisions
from contact_detector.errors import ConfigError
from contact_detector.features.carried import CarriedLoad
import numpy as np

#: Names of the two models in :attr:`AudioFallback.active_name` and the switch messages.
MULTIMODAL, FT_ONLY = 'audio + F/T', 'F/T-only'


class AudioFallback:
    """
    A multimodal detector with an F/T-only model that decides beside it, or stands in for it.

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
        Audio silence (s of stream time) after which the F/T-only model takes over alone;
        > 0, or 0 = never (only with ``both_decide``).
    both_decide : bool
        Whether the F/T-only model also releases while the multimodal model is active: the
        first release of either is the release.

    """

    def __init__(self, *, primary: ContactDetector, fallback: ContactDetector,
                 timeout_s: float, both_decide: bool = False) -> None:
        if primary.ft_only or not fallback.ft_only:
            raise ConfigError('AudioFallback needs a model with audio as primary and an '
                              'F/T-only model as fallback')
        if not (isinstance(timeout_s, (int, float)) and math.isfinite(timeout_s)
                and timeout_s >= 0):
            raise ConfigError(f'audio timeout must be a finite number >= 0 s, got {timeout_s!r}')
        if timeout_s == 0 and not both_decide:
            raise ConfigError('audio timeout 0 (the F/T-only model never takes over) leaves '
                              'the F/T-only model nothing to do without both_decide')
        self.primary, self.fallback = primary, fallback
        self.timeout_s = float(timeout_s)
        self.both_decide = bool(both_decide)
        self.switches = 0
        #: Releases returned, and how many of them the F/T-only model made.
        self.releases = self.ft_releases = 0
        #: :data:`MULTIMODAL` or :data:`FT_ONLY`: the model that made the last release.
        self.last_release_by: Optional[str] = None
        #: One line per switch, oldest first, for the caller's log (it may clear it).
        self.switch_messages: list = []
        self._init_state(armed=primary.armed)

    def _init_state(self, *, armed: bool) -> None:
        self.active = self.primary
        self.primary.logic.arm(armed)
        self.fallback.logic.arm(armed and self.both_decide)
        self._first_wrench_t: Optional[float] = None
        self._audio_back_t: Optional[float] = None
        self._last_event_t = -math.inf

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
    def deciding(self) -> tuple:
        """Return the detectors whose releases count: the active one; with both_decide both."""
        if self.both_decide and self.active is self.primary:
            return self.primary, self.fallback
        return (self.active,)

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
        for name in ('frames', 'events', 'wrench_dropped', 'stale_frames'):
            out[f'ft_{name}'] = self.fallback.counts[name]
        out['releases'], out['ft_releases'] = self.releases, self.ft_releases
        out['model_switches'] = self.switches
        return out

    def arm(self, armed: bool) -> None:
        """
        Arm or disarm the release of the deciding models (the other stays disarmed).

        Arming measures the carried load again in both (either may be active at the contact).
        """
        for detector in self.deciding:
            detector.logic.arm(armed)
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
        """
        Count a corrupt message in both detectors (the F/T-only one ignores audio).

        While both decide, the audio model's hold-off holds the F/T-only model's release too:
        corrupt input of either kind blocks the release as it does with one model.
        """
        self.fallback.drop(kind=kind, reason=reason, stamp=stamp)
        dropped = self.primary.drop(kind=kind, reason=reason, stamp=stamp)
        self._share_holdoff()
        return dropped

    def _share_holdoff(self) -> None:
        if self.both_decide:
            self.fallback.hold_off_until(self.primary.holdoff_until)

    def on_audio(self, samples: np.ndarray, *, stamp: float,
                 now: Optional[float] = None) -> Decisions:
        """Process an audio chunk; the audio model takes over again once the audio is back."""
        before = self.primary.latest_audio_t
        decided = self.primary.on_audio(samples, stamp=stamp, now=now)
        self._share_holdoff()                   # a refused chunk (wrong rate, bad stamp)
        latest = self.primary.latest_audio_t
        if self.active is self.fallback and latest is not None:
            if self._audio_back_t is None or before is None \
                    or latest - before > self.timeout_s:
                self._audio_back_t = latest         # the audio (re)starts here
            elif latest - self._audio_back_t >= self.primary.settings.warmup_s:
                self._switch(to=self.primary, t=latest,
                             why=f'audio back for {latest - self._audio_back_t:.2f} s')
                return Decisions.empty()            # the next frames are the audio model's
        if self.active is not self.primary:
            return Decisions.empty()
        return self.combine(decided, Decisions.empty())

    def on_wrench_one(self, *, t: float, values: Sequence[float],
                      now: Optional[float] = None) -> Decisions:
        """Process one wrench sample; the F/T-only model takes over when the audio is silent."""
        from_primary = self.primary.on_wrench_one(t=t, values=values, now=now)
        self._share_holdoff()
        from_fallback = self.fallback.on_wrench_one(t=t, values=values, now=now)
        if self._first_wrench_t is None and isinstance(t, (int, float)) and math.isfinite(t):
            self._first_wrench_t = float(t)
        if self.active is self.primary and self.timeout_s > 0 \
                and self._first_wrench_t is not None \
                and isinstance(t, (int, float)) and math.isfinite(t):
            heard = self.primary.latest_audio_t
            since = self._first_wrench_t if heard is None else heard
            if t - since > self.timeout_s:
                self._switch(to=self.fallback, t=float(t),
                             why=f'no audio for {t - since:.2f} s')
                self._audio_back_t = None
                return Decisions.empty()            # the next frames are the F/T-only model's
        if self.active is self.primary:
            return self.combine(from_primary, from_fallback)
        return self.combine(from_fallback, Decisions.empty())

    def on_wrench(self, *, t, force, torque, now: Optional[float] = None) -> Decisions:
        """
        Process a wrench message of one or more samples, one sample at a time (as the node).

        Parameters
        ----------
        t : array_like, shape (n,)
            Sample stamps, s.
        force, torque : array_like, shape (n, 3)
            N and N m.
        now : float, optional
            Receive time, s.

        Returns
        -------
        Decisions
            The frames of every sample, in order, with their releases and events (and the
            first drop reason, if a sample was dropped).

        """
        blocks = [self.on_wrench_one(t=float(ti), values=[*f, *q], now=now)
                  for ti, f, q in zip(np.atleast_1d(t), np.atleast_2d(force),
                                      np.atleast_2d(torque))]
        return blocks[0] if len(blocks) == 1 else Decisions.concat(blocks)

    def combine(self, active: Decisions, other: Decisions) -> Decisions:
        """
        Return the active model's frames with the deciding models' events and first release.

        Called on every message's two blocks, and by
        :func:`~contact_detector.detection.offline.run_both` on two whole runs.

        ``other`` is the F/T-only model's block while both decide (its frames are not
        returned, its contact events and release are). A release disarms every deciding
        model: one release per arming. When both release on the same message the earlier
        frame time is the release, so the outcome is that of two separate runs combined at
        once.
        """
        events = list(active.events)
        if self.both_decide and (events or other.events):
            events, self._last_event_t = merge_events(
                first=active.events, second=other.events, after=self._last_event_t,
                refractory_s=self.primary.rule.refractory_s)
        theirs = list(other.releases) if self.both_decide else []
        released = first_release(active.releases, theirs)
        if not released:
            return (active if events == active.events
                    else dataclasses.replace(active, events=events))
        for detector in (self.primary, self.fallback):
            detector.logic.arm(False)
        self.releases += 1
        self.last_release_by = MULTIMODAL
        if self.active is self.fallback or released[0] not in active.releases:
            self.ft_releases += 1
            self.last_release_by = FT_ONLY
        return dataclasses.replace(active, releases=released, events=events)

    def flush(self) -> Decisions:
        """Decide the frames still waiting (end of a recording): the active model's."""
        primary, fallback = self.primary.flush(), self.fallback.flush()
        if self.active is self.primary:
            return self.combine(primary, fallback)
        return self.combine(fallback, Decisions.empty())

    def _switch(self, *, to: ContactDetector, t: float, why: str) -> None:
        old = self.active
        armed = old.armed
        old.logic.arm(False)
        if not (self.both_decide and to is self.fallback):
            # A fresh confirmation run: no frame from before counts. With both_decide the
            # F/T-only model has been deciding all along: its run stands.
            to.logic.reset()
        to.logic.arm(armed)
        if self.both_decide:
            self.fallback.logic.arm(armed)
        self.active = to
        self.switches += 1
        name = self.active_name
        self.switch_messages.append(f'model switched to {name} at t={t:.3f} ({why}); '
                                    f'release {"armed" if armed else "disarmed"}')


def first_release(first: Sequence[float], second: Sequence[float]) -> List[float]:
    """
    Return the release of two models deciding one arming: the earlier of their first releases.

    Parameters
    ----------
    first, second : sequence of float
        Each model's release times, s (at most one per arming).

    Returns
    -------
    list of float
        ``[min(first[0], second[0])]`` over the models that released, or ``[]``.

    """
    firsts = [r[0] for r in (sorted(first), sorted(second)) if r]
    return [min(firsts)] if firsts else []


def merge_events(*, first: Sequence[float], second: Sequence[float], after: float,
                 refractory_s: float) -> Tuple[List[float], float]:
    """
    Return two models' contact events as one model's, and the newest event time.

    An event less than ``refractory_s`` after the last one kept is the same contact seen by
    the other model (each model's own events are already that far apart).

    Parameters
    ----------
    first, second : sequence of float
        Each model's event times, s.
    after : float
        The last event kept before these, s (``-inf`` for none).
    refractory_s : float
        Minimum time between two contact events, s (the decision rule's).

    Returns
    -------
    events : list of float
        Sorted, each at least ``refractory_s`` after the one before (and after ``after``).
    after : float
        The newest event kept, or ``after``.

    """
    kept = []
    for t in sorted([*first, *second]):
        if t - after >= refractory_s:
            kept.append(t)
            after = t
    return kept, after
