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
The decision rule a model ships with: how per-frame P(contact) becomes a contact event.

The rule is data chosen on validation data together with the forest, so it is stored in the
model card and sits in the model layer; :class:`~contact_detector.detection.release.ReleaseLogic`
applies it.
"""

import dataclasses
from dataclasses import dataclass
import math
from typing import Any, Mapping

from contact_detector.errors import ConfigError
import numpy as np


#: The load path's fields (written by :meth:`DecisionRule.to_dict` only when it is on).
LOAD_FIELDS = ('load_threshold', 'load_frames', 'load_support', 'load_support_frames',
               'load_direction')
#: The second load path's fields (written by :meth:`DecisionRule.to_dict` only when it is on).
LOAD2_FIELDS = ('load2_threshold', 'load2_frames', 'load2_support', 'load2_support_frames',
                'load2_direction')
#: Frames over which ``DecisionRule.load2_steady`` judges the load steady (0.1 s at 100 Hz).
STEADY_FRAMES = 10


@dataclass(frozen=True)
class DecisionRule:
    """
    How per-frame probabilities become contact events (applied by the detection layer).

    Attributes
    ----------
    threshold : float
        Contact when P(contact) >= ``threshold``, in [0, 1].
    confirm_frames : int
        Consecutive frames at or above the threshold needed to report a contact, >= 1.
    refractory_s : float
        Seconds after a reported contact during which no new one is reported, >= 0.
    average_frames : int
        Frames averaged before the comparison with ``threshold``, >= 1.
    sustain_frames, sustain_threshold : int, float
        Slow path: contact when the mean P(contact) of the newest ``sustain_frames`` frames is
        ``>= sustain_threshold`` (0 frames = off).
    evidence_threshold, evidence_drift : float
        Evidence path (a CUSUM): ``S_i = max(0, S_{i-1} + p_i - evidence_drift)`` over
        consecutive valid frames, contact when ``S_i >= evidence_threshold`` (0 = off). A
        forest that is only 0.6-0.9 sure for a few frames accumulates evidence, while frames
        below ``evidence_drift`` take it away again.
    load_threshold, load_frames : float, int
        Load path (0 N = off): contact when the force has stayed at least ``load_threshold``
        N away from the load carried after the start or the arming (``force_carried_shift``,
        the distance of a guard ``|F - F_rest|``) for the newest ``load_frames`` consecutive
        frames, and the forest backs it (``load_support``). The whole load transfer since the
        arming, however slowly it came: a soft surface or a fixture that the forest, trained
        on the simulator's contacts, is only 0.2-0.6 sure of.
    load_support, load_support_frames : float, int
        The backing the load path needs: the mean P(contact) of the newest
        ``load_support_frames`` frames ``>= load_support``. A knock on the hand does not hold
        the load away for ``load_frames``; a push that does, the forest calls no contact.
    load_direction : float
        The load path's direction gate, in [-1, 1] (1 = off): the frame's
        ``force_carried_shift_cos``, the cosine between the force's distance from the carried
        load and the carried load, must be ``<= load_direction``. A table takes the load off
        the hand, against the carried load (near -1 on an untared sensor); a person pushing
        the object sideways moves the force across it (near 0), pressing it down along it
        (+1). Exactly 0 also passes: it is the feature's value when no carried load was
        measured (a tared sensor), where the gate has no direction to judge.
    load2_threshold, load2_frames, load2_support, load2_support_frames
        Second load path (0 N = off): the load path's test with its own values: the force
        ``>= load2_threshold`` N from the carried load for the newest ``load2_frames`` frames
        (float, int), and the mean P(contact) of the newest ``load2_support_frames`` frames
        ``>= load2_support`` (float, int). The shipped F/T-only model uses it as a long hold
        that needs no backing (2 N for 40 frames, 0.4 s, gated by ``load2_direction``): the
        contacts its forest vetoes (fixtures, pegs, soft surfaces) hold the load off for
        that long, a knock's push and rebound do not.
    load2_direction : float
        The second load path's direction gate, as ``load_direction`` (1 = off).
    load2_steady : float
        The second load path also needs a steady load (0 = off): the distances from the
        carried load of the newest :data:`STEADY_FRAMES` frames lie within a range of at most
        ``load2_steady`` times their median, ``max - min <= load2_steady * median``. A load
        the table took off changes little from frame to frame once it has moved; white noise
        on the reading (a loose connector) does not: the distance of 5 N per axis ranges over
        about its median in 10 frames. The shipped F/T-only model uses 0.5
        (docs/decisions/2026-11-29-steady-gated-hold.md).

    """

    threshold: float = 0.5
    confirm_frames: int = 1
    refractory_s: float = 1.0
    average_frames: int = 1
    sustain_frames: int = 0
    sustain_threshold: float = 0.5
    evidence_threshold: float = 0.0
    evidence_drift: float = 0.5
    load_threshold: float = 0.0
    load_frames: int = 20
    load_support: float = 0.15
    load_support_frames: int = 25
    load_direction: float = 1.0
    load2_threshold: float = 0.0
    load2_frames: int = 3
    load2_support: float = 0.3
    load2_support_frames: int = 5
    load2_direction: float = 1.0
    load2_steady: float = 0.0

    def __post_init__(self) -> None:
        """Validate and normalise; raise :class:`ConfigError` naming the bad field."""
        for name, low, high in (('threshold', 0.0, 1.0), ('refractory_s', 0.0, math.inf),
                                ('sustain_threshold', 0.0, 1.0),
                                ('evidence_threshold', 0.0, 1000.0),
                                ('evidence_drift', 0.0, 1.0),
                                ('load_threshold', 0.0, 1000.0), ('load_support', 0.0, 1.0),
                                ('load2_threshold', 0.0, 1000.0),
                                ('load2_support', 0.0, 1.0),
                                ('load_direction', -1.0, 1.0),
                                ('load2_direction', -1.0, 1.0),
                                ('load2_steady', 0.0, 100.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or not low <= value <= high:
                raise ConfigError(f'DecisionRule.{name} must be a finite number in '
                                  f'[{low}, {high}], got {value!r}')
            object.__setattr__(self, name, float(value))
        for name, low in (('confirm_frames', 1), ('average_frames', 1), ('sustain_frames', 0),
                          ('load_frames', 1), ('load_support_frames', 1),
                          ('load2_frames', 1), ('load2_support_frames', 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                    or value < low:
                raise ConfigError(f'DecisionRule.{name} must be an int >= {low}, got {value!r}')
            object.__setattr__(self, name, int(value))

    def describe(self) -> str:
        """Return the rule as one line for logs and diagnostics."""
        text = (f'threshold={self.threshold:.3f} confirm_frames={self.confirm_frames} '
                f'refractory_s={self.refractory_s:.3f}')
        if self.average_frames > 1:
            text += f' average_frames={self.average_frames}'
        if self.sustain_frames > 0:
            text += (f' sustain_frames={self.sustain_frames} '
                     f'sustain_threshold={self.sustain_threshold:.3f}')
        if self.evidence_threshold > 0:
            text += (f' evidence_threshold={self.evidence_threshold:.3f} '
                     f'evidence_drift={self.evidence_drift:.3f}')
        for path in self._load_paths_on():
            for name, value in zip(path, self._values(path)):
                text += f' {name}={value:.3f}' if isinstance(value, float) else f' {name}={value}'
        if self._steady_on():
            text += f' load2_steady={self.load2_steady:.3f}'
        return text

    def short(self) -> str:
        """Return the rule as a table label, e.g. ``p>=0.85 x1 or mean10>=0.4``."""
        text = f'p>={self.threshold:g} x{self.confirm_frames}'
        if self.average_frames > 1:
            text = f'mean{self.average_frames} ' + text
        if self.sustain_frames > 0:
            text += f' or mean{self.sustain_frames}>={self.sustain_threshold:g}'
        if self.evidence_threshold > 0:
            text += f' or sum(p-{self.evidence_drift:g})>={self.evidence_threshold:g}'
        for path in self._load_paths_on():
            threshold, frames, support, support_frames, direction = self._values(path)
            text += (f' or load>={threshold:g}N x{frames}'
                     f' & mean{support_frames}>={support:g}')
            if direction < 1.0:
                text += f' & cos<={direction:g}'
            if path is LOAD2_FIELDS and self._steady_on():
                text += f' & steady{STEADY_FRAMES}<={self.load2_steady:g}'
        return text

    def _steady_on(self) -> bool:
        """Return True when the second load path is on and needs a steady load."""
        return self.load2_threshold > 0 and self.load2_steady > 0

    def _load_paths_on(self) -> list:
        """Return the field names of each load path that is on (threshold first)."""
        return [names for names in (LOAD_FIELDS, LOAD2_FIELDS) if getattr(self, names[0]) > 0]

    def _values(self, names: tuple) -> tuple:
        """Return the values of the fields ``names``."""
        return tuple(getattr(self, name) for name in names)

    @property
    def uses_load(self) -> bool:
        """Return True when a load path is on (it needs ``force_carried_shift`` per frame)."""
        return self.load_threshold > 0 or self.load2_threshold > 0

    @property
    def uses_direction(self) -> bool:
        """Return True when an active load path has a gate (``force_carried_shift_cos``)."""
        return any(getattr(self, names[-1]) < 1.0 for names in self._load_paths_on())

    @property
    def load_history(self) -> int:
        """Return the most P(contact) frames the load paths average (0 when both are off)."""
        return max(self.load_support_frames if self.load_threshold > 0 else 0,
                   self.load2_support_frames if self.load2_threshold > 0 else 0)

    def to_dict(self) -> dict:
        """
        Plain-JSON form, stored in bundles and cards.

        Each load path's fields are written only when it is on, and ``load2_steady`` only when
        the second load path needs a steady load, so the rules of models written before they
        existed are stored as they were.
        """
        data = dataclasses.asdict(self)
        on = self._load_paths_on()
        for names in (LOAD_FIELDS, LOAD2_FIELDS):
            if names not in on:
                for name in names:
                    del data[name]
        if not self._steady_on():
            del data['load2_steady']
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> 'DecisionRule':
        """Inverse of :meth:`to_dict`; unknown keys are a :class:`ConfigError`."""
        if not isinstance(data, Mapping):
            raise ConfigError(f'DecisionRule must be a mapping, got {type(data).__name__}')
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ConfigError(f'unknown DecisionRule keys: {unknown} (known: {sorted(known)})')
        return cls(**dict(data))
