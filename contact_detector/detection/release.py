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
Release logic: from per-frame contact probabilities to release events.

Pure state machine, no ROS, no clock: frame times are passed in.
"""

from collections import deque
from itertools import islice, repeat
import math
import statistics
from typing import Any, Dict, Mapping, Optional, Sequence

from contact_detector.errors import ConfigError
from contact_detector.features.config import RULE_FEATURES
from contact_detector.model.rule import DecisionRule, STEADY_FRAMES
import numpy as np

#: Node parameter -> (DecisionRule field, smallest value that overrides the model's rule).
#: Below it (negative, or 0 for the frame counts that must be >= 1) the model's field applies.
RULE_PARAMETERS = {
    'release.threshold': ('threshold', 0.0),
    'release.confirm_frames': ('confirm_frames', 1),
    'release.refractory_s': ('refractory_s', 0.0),
    'release.average_frames': ('average_frames', 1),
    'release.sustain_frames': ('sustain_frames', 0),
    'release.sustain_threshold': ('sustain_threshold', 0.0),
    'release.evidence_threshold': ('evidence_threshold', 0.0),
    'release.evidence_drift': ('evidence_drift', 0.0),
    'release.load_threshold': ('load_threshold', 0.0),
    'release.load_frames': ('load_frames', 1),
    'release.load_support': ('load_support', 0.0),
    'release.load_support_frames': ('load_support_frames', 1),
    'release.load_direction': ('load_direction', -1.0),
    'release.load2_threshold': ('load2_threshold', 0.0),
    'release.load2_frames': ('load2_frames', 1),
    'release.load2_support': ('load2_support', 0.0),
    'release.load2_support_frames': ('load2_support_frames', 1),
    'release.load2_direction': ('load2_direction', -1.0),
    'release.load2_steady': ('load2_steady', 0.0),
}


def rule_overrides(params: Mapping[str, Any]) -> Dict[str, Any]:
    """
    Return the DecisionRule fields that node parameters set (the node and ``detect`` share it).

    Parameters
    ----------
    params : mapping
        Flat node parameters (``'release.threshold'`` -> value); missing names are unset.

    Returns
    -------
    dict
        Field name -> value, for ``dataclasses.replace(model_rule, **overrides)``.

    Raises
    ------
    ConfigError
        A value that is not a number.

    """
    out = {}
    for name, (field, lowest) in RULE_PARAMETERS.items():
        value = params.get(name)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f'parameter {name} must be a number, got {value!r}')
        if value >= lowest:
            out[field] = value
    return out


def rule_inputs(*, names: Sequence[str], x: np.ndarray) -> Dict[str, Optional[np.ndarray]]:
    """
    Return the columns of a frame matrix that :meth:`ReleaseLogic.step` reads beside P.

    Parameters
    ----------
    names : sequence of str
        The names of the columns of ``x``.
    x : np.ndarray, shape (n, len(names))
        Feature frames.

    Returns
    -------
    dict
        ``load`` (``force_carried_shift``, N) and ``load_cos`` (``force_carried_shift_cos``), each
        shape (n,), or None where ``names`` lacks the column: keyword arguments of
        :meth:`ReleaseLogic.step`.

    """
    return {key: (x[:, list(names).index(name)] if name in names else None)
            for key, name in zip(('load', 'load_cos'), RULE_FEATURES)}


def _gate_passes(gate: float, cos: float) -> bool:
    """
    Return whether a load path's direction gate lets a frame through.

    ``gate >= 1`` is off (even a NaN ``cos`` passes); otherwise ``cos <= gate``, or exactly 0,
    the value of ``force_carried_shift_cos`` when no carried load was measured (a tared
    sensor): the gate judges only a direction there is. A NaN never passes a gate that is on.
    """
    return gate >= 1.0 or cos <= gate or cos == 0.0


def _steady(loads: deque, spread: float) -> bool:
    """
    Return whether the newest loads are steady: ``max - min <= spread * median``.

    ``loads`` holds the distances from the carried load (N) of the newest
    :data:`~contact_detector.model.rule.STEADY_FRAMES` consecutive valid frames; fewer, or a
    NaN among them, is not steady.
    """
    if len(loads) < STEADY_FRAMES:
        return False
    if any(math.isnan(v) for v in loads):
        return False
    return max(loads) - min(loads) <= spread * statistics.median(loads)


class ReleaseLogic:
    """
    Turn per-frame probabilities into contact decisions and release events.

    A frame is *contact* when it is valid, not blocked and either

    - the mean P(contact) of the last ``rule.average_frames`` frames is ``>= rule.threshold``
      (with the default ``average_frames=1``: ``p >= threshold``), or
    - ``rule.sustain_frames > 0`` and the mean P(contact) of the last ``rule.sustain_frames``
      frames is ``>= rule.sustain_threshold`` (a slower path for quiet, sustained contacts),
      or
    - ``rule.evidence_threshold > 0`` and the evidence ``S_i = max(0, S_{i-1} + p_i -
      rule.evidence_drift)`` accumulated over consecutive valid frames reaches
      ``rule.evidence_threshold`` (a forest that is fairly sure for a few frames), or
    - ``rule.load_threshold > 0`` (the load path) and the frame's ``load`` (the distance of
      the force from the carried load, ``force_carried_shift``, N) has been
      ``>= rule.load_threshold`` in the newest ``rule.load_frames`` consecutive frames, and
      the mean P(contact) of the newest ``rule.load_support_frames`` frames is
      ``>= rule.load_support``, or
    - ``rule.load2_threshold > 0`` (the second load path) and the same holds with
      ``rule.load2_threshold``, ``rule.load2_frames``, ``rule.load2_support``,
      ``rule.load2_support_frames`` and ``rule.load2_direction``, and, with
      ``rule.load2_steady > 0``, the ``load`` of the newest
      :data:`~contact_detector.model.rule.STEADY_FRAMES` frames lies within
      ``max - min <= rule.load2_steady * median`` (a steady load, not noise on the reading).

    The means, the evidence and the load runs need consecutive valid, unblocked frames: an
    invalid or blocked frame empties the history, the evidence and the runs. A contact *event*
    starts when ``rule.confirm_frames`` consecutive frames are contact and at least
    ``rule.refractory_s`` have passed since the previous event.
    An event releases only while armed, and a release disarms: at most one release per arming.

    Parameters
    ----------
    rule : DecisionRule
        Thresholds, averaging windows, confirmation frames and refractory period.
    armed : bool
        Whether a release may fire before the first :meth:`arm` call.

    """

    def __init__(self, *, rule: DecisionRule, armed: bool) -> None:
        self.rule = rule
        self.armed = bool(armed)
        self.events = 0
        self.releases = 0
        self.last_events: list = []
        self._recent: deque = deque()
        self._loads: deque = deque(maxlen=STEADY_FRAMES)
        self.reset()

    def reset(self) -> None:
        """Forget the confirmation run, the probability history and the last event."""
        self._run = 0
        self._last_event_t = -math.inf
        self._recent.clear()
        self._evidence = 0.0
        self._load_run = 0
        self._load2_run = 0
        self._loads.clear()

    def arm(self, armed: bool) -> None:
        """Allow (True) or forbid (False) the next release."""
        self.armed = bool(armed)

    def _is_contact(self, p: float, load: float, cos: float) -> bool:
        """Push one valid frame's probability, load and cosine; return whether it is contact."""
        rule = self.rule
        recent = self._recent
        recent.append(p)
        while len(recent) > max(rule.average_frames, rule.sustain_frames, rule.load_history):
            recent.popleft()
        evidence = self._evidence + p - rule.evidence_drift
        self._evidence = evidence if evidence > 0.0 else 0.0
        # not >= on the negation: a NaN load never counts
        self._load_run = self._load_run + 1 if load >= rule.load_threshold else 0
        self._load2_run = self._load2_run + 1 if load >= rule.load2_threshold else 0
        self._loads.append(load)
        if self._mean_of_last(rule.average_frames) >= rule.threshold:
            return True
        if rule.evidence_threshold > 0 and self._evidence >= rule.evidence_threshold:
            return True
        if rule.load_threshold > 0 and self._load_run >= rule.load_frames \
                and self._mean_of_last(rule.load_support_frames) >= rule.load_support \
                and _gate_passes(rule.load_direction, cos):
            return True
        if rule.load2_threshold > 0 and self._load2_run >= rule.load2_frames \
                and self._mean_of_last(rule.load2_support_frames) >= rule.load2_support \
                and _gate_passes(rule.load2_direction, cos) \
                and (rule.load2_steady <= 0 or _steady(self._loads, rule.load2_steady)):
            return True
        return rule.sustain_frames > 0 and (
            self._mean_of_last(rule.sustain_frames) >= rule.sustain_threshold)

    def _mean_of_last(self, k: int) -> float:
        """Mean of the newest ``k`` probabilities; -1 while fewer are there."""
        n = len(self._recent)
        if n < k:
            return -1.0
        if k == 1:
            return self._recent[-1]
        return sum(islice(self._recent, n - k, n)) / k

    def step(self, *, t: np.ndarray, p: np.ndarray, valid: np.ndarray,
             blocked: Optional[np.ndarray] = None,
             load: Optional[np.ndarray] = None,
             load_cos: Optional[np.ndarray] = None) -> tuple[np.ndarray, list]:
        """
        Decide a block of frames.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Frame times, seconds.
        p : np.ndarray, shape (n,)
            P(contact) per frame.
        valid : np.ndarray, shape (n,), bool
            Frames with fresh, sound input.
        blocked : np.ndarray, shape (n,), bool, optional
            Frames that may not count towards a release (warm-up, after corrupt input).
        load : np.ndarray, shape (n,), optional
            The distance of the force from the carried load per frame, N
            (``force_carried_shift``); the load path's input. None: the load path never fires.
        load_cos : np.ndarray, shape (n,), optional
            The cosine between the force's distance from the carried load and the carried load
            per frame (``force_carried_shift_cos``); the direction gates' input. None: a load
            path with a gate (< 1) never fires.

        Returns
        -------
        contact : np.ndarray, shape (n,), bool
            The per-frame decision.
        releases : list of float
            Times of the frames at which a release fired.

        The times of all events in the block, armed or not, are left in ``self.last_events``.

        """
        ok = np.asarray(valid, dtype=bool)
        if blocked is not None:
            ok = ok & ~np.asarray(blocked, dtype=bool)
        contact = np.zeros(ok.shape[0], dtype=bool)
        releases = []
        self.last_events = []
        loads = (repeat(0.0) if load is None
                 else np.asarray(load, dtype=np.float64).tolist())
        cosines = (repeat(math.nan) if load_cos is None
                   else np.asarray(load_cos, dtype=np.float64).tolist())
        for i, (ti, pi, oki, li, ci) in enumerate(zip(np.asarray(t, dtype=np.float64).tolist(),
                                                      np.asarray(p, dtype=np.float64).tolist(),
                                                      ok.tolist(), loads, cosines)):
            contact[i] = self._frame(ti, pi, oki, releases, li, ci)
        return contact, releases

    def step_one(self, *, t: float, p: float, ok: bool, load: float = 0.0,
                 load_cos: float = math.nan) -> tuple[bool, list]:
        """
        Decide one frame: :meth:`step` for scalars.

        Parameters
        ----------
        t : float
            Frame time, s.
        p : float
            P(contact).
        ok : bool
            Valid and not blocked.
        load : float
            The distance of the force from the carried load, N (:meth:`step`'s ``load``).
        load_cos : float
            The cosine of the direction gates (:meth:`step`'s ``load_cos``).

        Returns
        -------
        contact : bool
        releases : list of float
            The frame's time if a release fired, else empty.

        """
        releases: list = []
        self.last_events = []
        return (self._frame(float(t), float(p), bool(ok), releases, float(load),
                            float(load_cos)), releases)

    def _frame(self, t: float, p: float, ok: bool, releases: list, load: float,
               cos: float) -> bool:
        """Advance the state machine by one frame; return whether it is contact."""
        if not ok:
            self._recent.clear()
            self._evidence = 0.0
            self._run = 0
            self._load_run = 0
            self._load2_run = 0
            self._loads.clear()
            return False
        if not self._is_contact(p, load, cos):
            self._run = 0
            return False
        self._run += 1
        if self._run == self.rule.confirm_frames \
                and t - self._last_event_t >= self.rule.refractory_s:
            self._last_event_t = t
            self.events += 1
            self.last_events.append(t)
            if self.armed:
                self.armed = False
                self.releases += 1
                releases.append(t)
        return True
