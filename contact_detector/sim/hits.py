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
Exogenous events of a simulated trial: knocks on the hand or table, touches, brushes, set-downs.

:func:`plan_hits` places them in the trial (its own random stream, so the plan never changes the
other parameters); :mod:`.loads` and :mod:`.sounds` turn each :class:`Hit` into force/torque
and sound.
"""

from dataclasses import dataclass, replace
import math

from contact_detector.sim.conditions import BRUSH_FRICTION_RANGE, EVENT_KINDS
from contact_detector.sim.params import FamilyParams, TrialParams
from contact_detector.sim.signals import unit
from contact_detector.sim.timeline import BASELINE_WINDOW_S, Timeline
import numpy as np

#: Shortest time between two planned events, s.
MIN_HIT_GAP_S = 0.25


@dataclass(frozen=True)
class Hit:
    """One planned exogenous event; see :func:`plan_hits` for the kinds and their fields."""

    kind: str
    anchor: str          # 'abs' (trial time), 'stop' (after stop_t), 'end' (after the retreat)
    t: float             # seconds relative to the anchor
    sound_amp: float
    force_n: float = 0.0
    pulse_s: float = 0.0
    direction: tuple = (0.0, 0.0, 1.0)
    point: tuple = (0.0, 0.0, 0.1)
    vib_n: float = 0.0
    vib_hz: float = 30.0
    window: str = ''
    dur: float = 0.0          # duration of a touch or a brush, s
    seed: int = 0             # stream of a brush's force fluctuation
    on_object: bool = True    # a touch on the object (else on the arm)

    def time(self, anchors: dict) -> float:
        """Return the event's time in s from the trial start, given the anchors' times."""
        return anchors[self.anchor] + self.t


def plan_hits(*, kind: str, count: int, rng: np.random.Generator, p: TrialParams,
              tl: Timeline, stop_est: float, R: np.ndarray, q: FamilyParams,
              r_obj: np.ndarray) -> list[Hit]:
    """
    Place ``count`` events of ``kind``; times relative to their anchor.

    ``kind`` is one of :data:`contact_detector.sim.trial.HIT_KINDS` ('mixed' draws one of
    :data:`~contact_detector.sim.conditions.EVENT_KINDS` per event). Each event falls in a
    window drawn by probability: the arm moving in the air, before the motion, in contact
    (after the nominal stop ``stop_est``), after the retreat, and for table knocks, set-downs
    and touches also while pushing; events keep :data:`MIN_HIT_GAP_S` apart (one without room
    is dropped). Brushes happen only while the arm moves. ``R`` (world -> sensor) and ``r_obj``
    (m) orient and place the forces.
    """
    if kind == 'none':
        return []
    settle_rel = (p.stop_latency_s + p.stop_decel_s + p.settle_s)
    windows = {
        # window name: (anchor, lo, hi, probability)
        'moving_air': ('abs', tl.t_acc0 + 0.05, tl.onset - MIN_HIT_GAP_S, 0.55),
        'premotion': ('abs', 0.3, tl.t_acc0 - BASELINE_WINDOW_S - 0.05, 0.15),
        'contact': ('stop', 0.1, settle_rel - 0.05, 0.2),
        'post_air': ('end', 0.1, p.rest_end_s - 0.3, 0.1),
    }
    if kind in ('table', 'setdown', 'touch', 'mixed') \
            and stop_est - 0.05 > tl.onset + MIN_HIT_GAP_S:
        windows['push'] = ('abs', tl.onset + MIN_HIT_GAP_S, stop_est - 0.05, 0.1)
    nominal = {'abs': 0.0, 'stop': stop_est, 'end': stop_est + settle_rel + p.retreat_s}
    hits: list[Hit] = []
    for _ in range(count):
        k = kind if kind != 'mixed' else EVENT_KINDS[int(rng.integers(0, len(EVENT_KINDS)))]
        dur = 0.0
        if k == 'touch':
            dur = q.touch_s * float(rng.uniform(0.8, 1.2))
        elif k == 'brush':
            dur = q.brush_s * float(rng.uniform(0.8, 1.2))
        if k == 'brush':
            names = ['moving_air']  # brushing something needs the arm to move
        else:
            names = [w for w in windows if w != 'push' or k in ('table', 'setdown', 'touch')]
        probs = np.array([windows[w][3] for w in names])
        probs /= probs.sum()
        for _attempt in range(30):
            w = names[int(rng.choice(len(names), p=probs))]
            anchor, lo, hi, _p = windows[w]
            hi = hi - dur
            if hi <= lo:
                continue
            t = float(rng.uniform(lo, hi))
            t_nom = t + nominal[anchor]
            if all(abs(t_nom - h.time(nominal)) >= MIN_HIT_GAP_S for h in hits):
                break
        else:
            continue
        if k == 'hand':
            amp = p.hand_hit_amp_fs * float(rng.uniform(0.6, 1.4))
            # knocks come from above or from the side, in world terms
            world = unit([rng.normal(), rng.normal(), -abs(rng.normal()) * 1.5])
            direction = R @ world
            point = (float(rng.uniform(-0.03, 0.03)), float(rng.uniform(-0.03, 0.03)),
                     float(rng.uniform(0.05, 0.15)))
            hits.append(Hit(kind=k, anchor=anchor, t=t, sound_amp=amp,
                            force_n=p.hand_hit_force_n * float(rng.uniform(0.7, 1.3)),
                            pulse_s=float(rng.uniform(0.008, 0.03)),
                            direction=tuple(direction), point=point, window=w))
        elif k == 'table':
            amp = p.table_hit_amp_fs * float(rng.uniform(0.6, 1.4))
            hits.append(Hit(kind=k, anchor=anchor, t=t, sound_amp=amp,
                            vib_n=p.table_hit_vib_n * float(rng.uniform(0.7, 1.3)),
                            vib_hz=float(rng.uniform(15.0, 45.0)), window=w))
        elif k == 'touch':
            # a person touching or pushing: slow, smooth, little sound (a faint rustle)
            amp = float(math.exp(rng.uniform(math.log(0.0005), math.log(0.004))))
            on_object = bool(rng.uniform() < 0.6)
            direction = R @ unit(rng.normal(size=3))
            point = r_obj + rng.uniform(-0.02, 0.02, 3)
            hits.append(Hit(kind=k, anchor=anchor, t=t, sound_amp=amp,
                            force_n=q.touch_force_n * float(rng.uniform(0.7, 1.3)),
                            pulse_s=dur, dur=dur, direction=tuple(direction),
                            point=tuple(point), on_object=on_object, window=w))
        elif k == 'brush':
            # friction against the motion (the arm moves down) plus a sideways part
            world = unit([rng.normal() * 0.7, rng.normal() * 0.7, 1.0])
            point = r_obj * float(rng.uniform(0.3, 1.0))
            hits.append(Hit(kind=k, anchor=anchor, t=t,
                            sound_amp=q.brush_amp_fs * float(rng.uniform(0.7, 1.3)),
                            force_n=q.brush_force_n * float(rng.uniform(0.7, 1.3)),
                            pulse_s=dur, dur=dur, direction=tuple(R @ world),
                            point=tuple(point), seed=int(rng.integers(0, 2 ** 31)),
                            window=w))
        else:  # 'setdown': another object set down on the table nearby
            hits.append(Hit(kind=k, anchor=anchor, t=t,
                            sound_amp=q.setdown_amp_fs * float(rng.uniform(0.6, 1.4)),
                            vib_n=q.setdown_vib_n * float(rng.uniform(0.7, 1.3)),
                            vib_hz=float(rng.uniform(20.0, 60.0)), window=w))
    hits.sort(key=lambda h: h.time(nominal))
    return hits


def friction_brush(hit: Hit, *, R: np.ndarray) -> Hit:
    """
    Return a brush as friction: the push that makes it, and the friction against the motion.

    The arm brushing something while it moves down feels the friction ``f`` against the motion
    (up, the brush's planned ``force_n``) and the sideways push ``N = f / mu`` without which
    there is no friction, along the horizontal part ``n`` of the planned direction:

    ``F = f (z + n / mu)``, so ``|F| = f sqrt(1 + mu^2) / mu``

    (world frame, ``z`` up). ``mu`` is drawn from :data:`BRUSH_FRICTION_RANGE` in a stream of
    the brush's own (``default_rng([hit.seed, 11])``), so every other draw of the trial stays.

    Parameters
    ----------
    hit : Hit
        A planned brush (``kind == 'brush'``); its ``direction`` is in the sensor frame.
    R : numpy.ndarray, shape (3, 3)
        Rotation world -> sensor that oriented ``hit.direction``.

    Returns
    -------
    Hit
        The brush with its ``direction`` and ``force_n`` (N) replaced.

    """
    world = R.T @ np.asarray(hit.direction, dtype=float)
    side = np.array([world[0], world[1], 0.0])
    n = unit(side) if float(np.linalg.norm(side)) > 1e-9 else np.array([1.0, 0.0, 0.0])
    mu = float(BRUSH_FRICTION_RANGE.sample(np.random.default_rng([hit.seed, 11])))
    vec = np.array([0.0, 0.0, 1.0]) + n / mu
    return replace(hit, direction=tuple(R @ unit(vec)),
                   force_n=hit.force_n * float(np.linalg.norm(vec)))
