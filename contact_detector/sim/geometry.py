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
Where things are in a simulated trial: the sensor's orientation, lever arms, masses, directions.

All vectors are in the sensor frame (``wrist_ft_sensor_frame``), in m; see the frames in
:mod:`contact_detector.sim.trial`.
"""

from dataclasses import dataclass
import math

from contact_detector.sim.params import FamilyParams, TrialParams
from contact_detector.sim.signals import rotation, unit
import numpy as np


@dataclass(frozen=True)
class Geometry:
    """
    The mechanical layout of one trial, in the sensor frame.

    Attributes
    ----------
    R : np.ndarray, shape (3, 3)
        World -> sensor rotation.
    up : np.ndarray, shape (3,)
        World up in the sensor frame (unit).
    r_obj, r_contact, r_hand, r_load : np.ndarray, shape (3,)
        Sensor -> object centre of mass, contact point, hand centre of mass, and the centre of
        mass of object and hand together, m.
    fric_dir, slosh_dir, mode_dir, ripple_dir : np.ndarray, shape (3,)
        Directions of the contact friction, the liquid slosh, the structural mode and the
        motor ripple (unit).
    m_obj, m_hand : float
        Object (with its liquid) and hand masses, kg.

    """

    R: np.ndarray
    up: np.ndarray
    r_obj: np.ndarray
    r_contact: np.ndarray
    r_hand: np.ndarray
    r_load: np.ndarray
    fric_dir: np.ndarray
    slosh_dir: np.ndarray
    mode_dir: np.ndarray
    ripple_dir: np.ndarray
    m_obj: float
    m_hand: float


def draw_geometry(*, p: TrialParams, q: FamilyParams, rng: np.random.Generator) -> Geometry:
    """
    Draw the layout of a trial from its parameters and the geometry stream ``rng``.

    Frame 'hsr': the hand along +z, world up close to -x (tilted by ``tilt_deg``), the object
    ``lever_arm_m`` along the hand. Frames 'axis' and 'random' (:func:`frame_rotation`): the
    contact point anywhere at ``contact_lever_m`` from the sensor, not above it.
    """
    if q.frame == 'hsr':
        R0 = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
        tilt_axis = np.array([0.0, *rng.normal(size=2)])
        R = rotation(tilt_axis + np.array([rng.normal() * 0.3, 0.0, 0.0]),
                     math.radians(p.tilt_deg)) @ R0
        up = R @ np.array([0.0, 0.0, 1.0])
        off_dir = rng.uniform(0, 2 * np.pi)
        r_obj = np.array([p.com_offset_m * math.cos(off_dir),
                          p.com_offset_m * math.sin(off_dir), p.lever_arm_m])
        r_contact = r_obj - 0.5 * p.object_height_m * up \
            + np.array([0.0, 0.0, p.contact_lever_offset_m])
        r_hand = np.array([0.01, 0.0, p.hand_lever_m])
    else:
        R = frame_rotation(rng, q.frame)
        up = R @ np.array([0.0, 0.0, 1.0])
        # the contact point anywhere at contact_lever_m from the sensor, not above it
        d = unit(rng.normal(size=3))
        c = float(d @ up)
        if c > 0:
            d = d - 2 * c * up
        r_contact = q.contact_lever_m * d
        r_obj = r_contact + 0.5 * p.object_height_m * up
        r_hand = p.hand_lever_m * d
    m_obj = p.object_mass_kg + p.liquid_mass_kg
    m_hand = p.hand_mass_kg
    r_load = (m_obj * r_obj + m_hand * r_hand) / (m_obj + m_hand)
    ang = rng.uniform(0, 2 * np.pi, 3)
    fric_dir = R @ np.array([math.cos(ang[0]), math.sin(ang[0]), 0.0])
    slosh_dir = R @ unit([math.cos(ang[1]), math.sin(ang[1]), 0.3])
    mode_dir = R @ unit([0.3 * math.cos(ang[2]), 0.3 * math.sin(ang[2]), 1.0])
    ripple_dir = unit(rng.normal(size=3))
    return Geometry(R=R, up=up, r_obj=r_obj, r_contact=r_contact, r_hand=r_hand, r_load=r_load,
                    fric_dir=fric_dir, slosh_dir=slosh_dir, mode_dir=mode_dir,
                    ripple_dir=ripple_dir, m_obj=m_obj, m_hand=m_hand)


def frame_rotation(rng: np.random.Generator, kind: str) -> np.ndarray:
    """
    World -> sensor rotation of a sensor mounted at any orientation.

    'random': uniform over all rotations (a unit quaternion of four normals). 'axis': world
    up along one of the six signed sensor axes, then a uniform rotation about world up.
    """
    if kind == 'random':
        w, x, y, z = unit(rng.normal(size=4))
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    k = int(rng.integers(0, 3))
    j = (k + 1 + int(rng.integers(0, 2))) % 3
    up = np.eye(3)[k] * (1.0 if rng.uniform() < 0.5 else -1.0)
    xw = np.eye(3)[j] * (1.0 if rng.uniform() < 0.5 else -1.0)
    base = np.column_stack([xw, np.cross(up, xw), up])
    return base @ rotation(np.array([0.0, 0.0, 1.0]), float(rng.uniform(0, 2 * np.pi)))
