#!/usr/bin/env python3
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
Independent placing trials: a second simulator, written apart from ``contact_detector.sim``.

A trial: a robot holds an object still, lowers it onto a surface, presses, stops or settles,
and may lift away; its wrist F/T sensor and a microphone go into a rosbag2 (sqlite3) bag::

    independent_trials.py OUT_DIR --trials-per-family N --seed S [--families a,b] [--jobs J]

writes ``OUT_DIR/<family>/trial_NNNN`` (bags), ``OUT_DIR/labels.csv`` (``bag,onset_start,
onset_end`` in absolute seconds on the bags' clock) and ``OUT_DIR/trials.json`` (every sampled
parameter, the onset, every exogenous event, simulated outcomes).

Model (world frame, z up, SI units):

- arm: the commanded height z_c(t) comes from a guarded move, a force regulator, an admittance
  law or a position target, acting on the controller's own delayed, filtered view of the load;
  the hand (m_h) hangs from z_c on the arm spring (k_a: a lightly damped 5-40 Hz mode), the
  object (m_o) from the hand on the grasp spring (k_g); laterally one spring-damper mode.
- contact: F = F_e(d) (1 + alpha d') + c d' + F_m for penetration d > 0, F_e Hunt-Crossley
  k d^n (hard) or a densifying layer over a table (soft), F_m a relaxing Maxwell branch;
  stick-slip Coulomb friction; for fixtures a chamfered bore.
- F/T: W = R^T [sum_i m_i (g - a_i) + F_c + F_ext ; sum_i r_i x (...)] averaged over each
  sample period (the ADC), plus tare or bias, thermal drift, noise and quantisation.
- sound: modal synthesis scaled by the simulated impact speed and filtered by the contact
  time, room noise, hum, ventilation, babble, motor harmonics following the commanded speed, a
  synthetic room response, microphone gain, high-pass and int16 clipping.

The onset is the first instant of nonzero contact force: the zero crossing of the penetration,
interpolated linearly between simulation steps (1/8000 s).
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import csv
from dataclasses import dataclass
import json
import math
from pathlib import Path
import shutil
import sys
import time
from typing import Any, Sequence
import zlib

import numpy as np
from numpy.typing import NDArray
from rosbags.rosbag2 import Writer
from rosbags.typesys import get_typestore, Stores
from scipy import signal
from scipy.spatial.transform import Rotation

Float = NDArray[np.float64]
Params = dict[str, Any]

FS_SIM = 8000  # Hz; a multiple of every F/T rate, so each ADC window holds whole steps
G = 9.81  # m/s^2
SOUND_SPEED = 343.0  # m/s
EPOCH = 1_700_000_000  # s; bag clock of trial 0 of the first family

#: Hard materials: modal band (Hz), modal decay (s), loudness factor, Hunt-Crossley k (N/m^1.5).
HARD: dict[str, Params] = {
    'glass': {'f': (1800, 6500), 'decay': (0.05, 0.4), 'loud': 1.0, 'k': (2e8, 1e9)},
    'ceramic': {'f': (1200, 5000), 'decay': (0.02, 0.15), 'loud': 0.9, 'k': (2e8, 1e9)},
    'metal': {'f': (900, 7000), 'decay': (0.1, 0.8), 'loud': 1.0, 'k': (5e8, 2e9)},
    'hard_plastic': {'f': (400, 3000), 'decay': (0.008, 0.04), 'loud': 0.5, 'k': (3e7, 2e8)},
    'wood': {'f': (300, 2500), 'decay': (0.005, 0.03), 'loud': 0.5, 'k': (5e7, 3e8)},
    'cardboard': {'f': (150, 1500), 'decay': (0.003, 0.015), 'loud': 0.15, 'k': (5e6, 3e7)},
    'wood_table': {'f': (80, 900), 'decay': (0.015, 0.08), 'loud': 1.0, 'k': (1e8, 5e8)},
    'laminate': {'f': (150, 1500), 'decay': (0.01, 0.05), 'loud': 0.8, 'k': (1e8, 5e8)},
    'stone': {'f': (400, 4000), 'decay': (0.005, 0.03), 'loud': 0.9, 'k': (5e8, 2e9)},
    'glass_table': {'f': (600, 4000), 'decay': (0.03, 0.2), 'loud': 1.0, 'k': (5e8, 2e9)},
    'metal_table': {'f': (200, 3000), 'decay': (0.06, 0.4), 'loud': 1.1, 'k': (5e8, 2e9)},
}
#: Soft layers over a wooden table: thickness (m), initial stiffness (N/m), damping (N s/m),
#: loudness factor of the impact relative to the bare table.
SOFT: dict[str, Params] = {
    'foam': {'h': (0.008, 0.03), 'k': (500.0, 6000.0), 'c': (2.0, 15.0), 'loud': (0.002, 0.015)},
    'cloth': {'h': (0.001, 0.004), 'k': (3e3, 3e4), 'c': (5.0, 30.0), 'loud': (0.02, 0.08)},
    'felt': {'h': (0.002, 0.006), 'k': (2e3, 1.5e4), 'c': (5.0, 25.0), 'loud': (0.01, 0.05)},
    'rubber_mat': {'h': (0.002, 0.006), 'k': (2e4, 1.2e5), 'c': (20.0, 80.0),
                   'loud': (0.03, 0.12)},
}
HARD_SURFACES = ('wood_table', 'laminate', 'stone', 'glass_table', 'metal_table')
OBJECTS = ('glass', 'ceramic', 'metal', 'hard_plastic', 'wood', 'cardboard')
AUDIO_STD = ((44100, 1024), (16000, 512), (48000, 1024), (44100, 2048), (48000, 960),
             (16000, 256))
EVENT_KINDS = ('knock_hand', 'knock_table', 'touch', 'brush', 'set_down_nearby')


@dataclass(frozen=True)
class Family:
    """
    Ranges one family samples from; pairs are (low, high), SI units.

    ``goal`` is the controller's load goal as a fraction of the object's weight: the stop
    threshold (``stop``), the pressing target (``regulate``) or the admittance set-point.
    """

    name: str
    objects: tuple[str, ...]
    surfaces: tuple[str, ...]
    mass: tuple[float, float]  # kg, log-uniform
    speed: tuple[float, float]  # m/s, log-uniform
    k_arm: tuple[float, float]  # N/m, log-uniform
    k_grasp: tuple[float, float]  # N/m, log-uniform
    controllers: tuple[str, ...]
    goal: tuple[float, float]
    latency: tuple[float, float]  # s, sensing + reaction delay of the controller
    ft_rates: tuple[int, ...]
    topics: tuple[str, ...]
    audio: tuple[tuple[int, int], ...] = AUDIO_STD
    f_min: float = 0.5  # N, lowest stop threshold
    mount: str = 'standard'
    lever: tuple[float, float] = (0.08, 0.2)  # m, sensor to object centre of mass
    tared_p: float = 0.7
    drift_p: float = 0.2
    events: tuple[int, int] = (0, 0)
    event_p: float = 0.0
    event_kinds: tuple[str, ...] = ()
    room_db: tuple[float, float] = (35.0, 50.0)  # dB SPL at the microphone
    babble_p: float = 0.15
    motor_db: tuple[float, float] = (36.0, 50.0)  # dB SPL at full speed; (0, 0): silent
    gain_db: tuple[float, float] = (-20.0, 20.0)
    gain_extreme: bool = False
    hears_contact: bool = True
    k_lat: tuple[float, float] | None = None  # N/m; None: 0.3-1.5 k_arm


_HSR = ('/hsrb/wrist_wrench/raw',)
FAMILIES: dict[str, Family] = {f.name: f for f in (
    Family('rigid', OBJECTS[:5], HARD_SURFACES, (0.1, 1.0), (0.005, 0.05), (2e4, 1e5),
           (2e4, 1e5), ('stop',), (0.3, 1.0), (0.005, 0.03), (100, 125, 200, 250),
           ('/ft_sensor/wrench', '/wrist_ft/wrench'), events=(1, 1), event_p=0.25,
           event_kinds=('knock_table', 'set_down_nearby')),
    Family('soft_layer', ('glass', 'ceramic', 'hard_plastic', 'cardboard', 'metal'),
           tuple(SOFT), (0.1, 1.0), (0.005, 0.04), (2e3, 3e4), (5e3, 5e4),
           ('stop', 'admittance'), (0.5, 1.2), (0.01, 0.05), (100, 125), _HSR,
           audio=((44100, 1024), (16000, 512), (48000, 1024))),
    Family('press_beyond', OBJECTS[:5], HARD_SURFACES + ('rubber_mat', 'cloth'), (0.2, 2.0),
           (0.005, 0.03), (5e3, 1e5), (1e4, 1e5), ('regulate',), (1.2, 2.0), (0.005, 0.03),
           (125, 200, 250), ('/force_torque_sensor_broadcaster/wrench', '/ft_sensor/wrench')),
    Family('partial_stop', OBJECTS, HARD_SURFACES + ('felt',), (0.3, 2.0), (0.005, 0.03),
           (2e3, 5e4), (5e3, 5e4), ('stop', 'regulate'), (0.2, 0.6), (0.005, 0.015), (100, 200),
           ('/hsrb/wrist_wrench/compensated',) + _HSR, f_min=0.3),
    Family('tilted', OBJECTS, HARD_SURFACES + ('felt', 'cloth'), (0.05, 1.5), (0.01, 0.06),
           (3e3, 1e5), (5e3, 1e5), ('stop', 'regulate', 'admittance'), (0.4, 1.5),
           (0.005, 0.04), (100, 125, 200, 250, 500),
           ('/wrist_ft/wrench', '/ati/ft_sensor/wrench') + _HSR, mount='random',
           lever=(0.05, 0.3), tared_p=0.5, drift_p=0.5),
    Family('fixture', ('metal',), ('fixture',), (0.05, 0.5), (0.005, 0.02), (2e4, 1e5),
           (2e4, 1e5), ('position',), (1.0, 2.0), (0.005, 0.02), (200,), ('/ft_sensor/wrench',),
           motor_db=(0.0, 0.0), hears_contact=False, k_lat=(1e3, 5e3),
           babble_p=0.0),
    Family('disturbed', OBJECTS[:5], HARD_SURFACES + ('felt', 'rubber_mat'), (0.1, 1.5),
           (0.01, 0.1), (3e3, 1e5), (1e4, 1e5), ('stop', 'admittance'), (0.5, 1.2),
           (0.005, 0.03), (100, 125, 200), _HSR + ('/ft_sensor/wrench',), events=(2, 5),
           event_p=1.0, event_kinds=EVENT_KINDS, room_db=(48.0, 62.0), babble_p=0.7,
           motor_db=(48.0, 62.0)),
    Family('formats', OBJECTS, HARD_SURFACES + tuple(SOFT), (0.05, 2.0), (0.005, 0.1),
           (2e3, 1e5), (5e3, 1e5), ('stop', 'regulate', 'admittance'), (0.4, 1.6),
           (0.005, 0.03), (500, 1000),
           ('/force_torque_sensor_broadcaster/wrench', '/ft_sensor/wrench'),
           audio=((16000, 512), (44100, 1024), (48000, 480)), events=(1, 1), event_p=0.3,
           event_kinds=('knock_table', 'set_down_nearby', 'knock_hand'), gain_extreme=True),
)}


# ----------------------------------------------------------------------------- sampling
def _lu(rng: np.random.Generator, lo: float, hi: float) -> float:
    """Draw log-uniformly from [lo, hi]."""
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def _pick(rng: np.random.Generator, items: Sequence[Any]) -> Any:
    """Draw one item uniformly."""
    return items[int(rng.integers(len(items)))]


def _unit(rng: np.random.Generator) -> Float:
    """Draw a uniformly distributed unit 3-vector."""
    v = rng.standard_normal(3)
    return v / np.linalg.norm(v)


def _mount(rng: np.random.Generator, fam: Family) -> tuple[Float, Float, str]:
    """
    Draw the sensor orientation R and the tool axis.

    R: 3x3, columns = sensor axes in the world frame (wrench_sensor = R^T wrench_world); the
    tool axis: unit 3-vector (world) from the sensor towards the fingers.
    """
    if fam.mount == 'random':  # any orientation; the tool points sideways or down
        tool = _unit(rng)
        tool[2] = -abs(tool[2]) if tool[2] > 0.2 else tool[2]
        return Rotation.from_quat(rng.standard_normal(4)).as_matrix(), tool, 'random'
    az = rng.uniform(0, 2 * math.pi)
    if rng.uniform() < 0.6:  # hand pointing down, sensor z along the tool axis
        name, tool = 'z_down', np.array([0.0, 0.0, -1.0])
        rot = Rotation.from_rotvec([0, 0, az]).as_matrix() @ np.diag([1.0, -1.0, -1.0])
    else:  # HSR-like side grasp: tool axis horizontal, sensor x along or against gravity
        name, tool = 'side', np.array([math.cos(az), math.sin(az), 0.0])
        x_axis = np.array([0.0, 0.0, _pick(rng, (-1.0, 1.0))])
        rot = np.column_stack([x_axis, np.cross(tool, x_axis), tool])
    tilt = Rotation.from_rotvec(_unit(rng) * math.radians(rng.uniform(0, 5))).as_matrix()
    return tilt @ rot, tool, name  # with up to 5 degrees of mounting error


def _surface(rng: np.random.Generator, *, name: str, obj: str) -> Params:
    """Draw the contact law of ``obj`` against surface ``name`` (see :func:`_contact_table`)."""
    if name == 'fixture':
        e = rng.uniform(0.3e-3, 1.0e-3)  # lateral misalignment of the peg, m
        return {'kind': 'fixture', 'material': 'steel', 'n': 1.5,
                'k': _lu(rng, 5e8, 2e9), 'alpha': rng.uniform(0.1, 0.5), 'offset': e,
                'direction': rng.uniform(0, 2 * math.pi), 'clearance': rng.uniform(2e-5, 1e-4),
                'chamfer': e + rng.uniform(0.2e-3, 1.0e-3),
                'chamfer_angle': math.radians(rng.uniform(35, 60)), 'zeta': rng.uniform(0.05, 0.3),
                'seat_depth': rng.uniform(2e-3, 5e-3), 'mu': 0.0, 'k_t': 0.0}
    if name in SOFT:
        s = SOFT[name]
        k_l = _lu(rng, *s['k'])
        return {'kind': 'soft', 'material': name, 'n': 1.5, 'k': HARD['wood_table']['k'][0],
                'thickness': rng.uniform(*s['h']), 'k_layer': k_l,
                'c': rng.uniform(*s['c']), 'k_maxwell': k_l * rng.uniform(0.3, 2.0),
                'tau_maxwell': rng.uniform(0.05, 0.5), 'alpha': rng.uniform(0.0, 0.2),
                'loud': _lu(rng, *s['loud']), 'mu': rng.uniform(0.4, 0.9),
                'k_t': k_l * rng.uniform(0.5, 2.0)}
    k = min(_lu(rng, *HARD[name]['k']), _lu(rng, *HARD[obj]['k']))  # softer body dominates
    n = _pick(rng, (1.0, 1.5, 1.5))  # n = 1: a linear spring (pad, flat base), k in N/m
    k = _lu(rng, 2e5, 2e6) if n == 1.0 else k
    return {'kind': 'hard', 'material': name, 'n': n,
            'k': k, 'alpha': rng.uniform(0.1, 1.5), 'zeta': rng.uniform(0.05, 0.3),
            'loud': 1.0, 'mu': rng.uniform(0.2, 0.6), 'k_t': _lu(rng, 2e4, 2e5)}


def sample_trial(*, fam: Family, rng: np.random.Generator, index: int) -> Params:
    """
    Draw every parameter of one trial of family ``fam``.

    Parameters
    ----------
    fam : Family
        The family's ranges.
    rng : numpy.random.Generator
        The trial's generator; the draw order fixes the trial.
    index : int
        The trial number in its family (sets the bag clock's epoch).

    Returns
    -------
    dict
        Nested parameters: object, surface, arm, motion, controller, sensor, audio, timing.

    """
    obj = _pick(rng, fam.objects)
    m_o = _lu(rng, *fam.mass)
    surf = _surface(rng, name=_pick(rng, fam.surfaces), obj=obj)
    k_a = _lu(rng, *fam.k_arm)
    m_t = k_a / (2 * math.pi * rng.uniform(*np.clip(  # arm mode 5-40 Hz, hand mass 0.3-1.5 kg
        np.sqrt(k_a / (np.array([1.5, 0.3]) + m_o)) / (2 * math.pi), 5.0, 40.0))) ** 2
    m_h = float(np.clip(m_t - m_o, 0.3, 1.5))
    m_t = m_h + m_o
    k_lat = _lu(rng, *fam.k_lat) if fam.k_lat else k_a * rng.uniform(0.3, 1.5)
    k_lat = float(np.clip(k_lat, m_t * (2 * math.pi * 5) ** 2, m_t * (2 * math.pi * 40) ** 2))
    arm = {'m_hand': m_h, 'k_arm': k_a, 'f_arm': math.sqrt(k_a / m_t) / (2 * math.pi),
           'zeta_arm': _lu(rng, 0.01, 0.1), 'k_lat': k_lat,
           'f_lat': math.sqrt(k_lat / m_t) / (2 * math.pi), 'zeta_lat': _lu(rng, 0.01, 0.1),
           'k_grasp': _lu(rng, *fam.k_grasp), 'zeta_grasp': rng.uniform(0.05, 0.3),
           'lat_frac': rng.uniform(0.0, 0.2), 'lat_dir': rng.uniform(0, 2 * math.pi),
           'ripple_n': _lu(rng, 0.01, 0.3), 'ripple_per_m': _lu(rng, 200.0, 1000.0)}
    t_hold = rng.uniform(1.0, 3.0)
    motion = {'t_hold': t_hold, 'speed': _lu(rng, *fam.speed), 't_acc': rng.uniform(0.08, 0.3),
              'profile': 'decelerating' if rng.uniform() < 0.4 else 'constant',
              'end_frac': rng.uniform(0.15, 0.5), 'tau_decel': rng.uniform(0.2, 1.0),
              't_desc': rng.uniform(0.4, min(3.0, 5.0 - t_hold)),
              'servo_tau': rng.uniform(0.005, 0.02), 'goal_depth': rng.uniform(0.005, 0.02),
              'lift': bool(rng.uniform() < 0.6), 'hold_after': rng.uniform(0.5, 2.0),
              'v_lift': rng.uniform(0.01, 0.05)}
    weight = m_o * G
    kind = _pick(rng, fam.controllers)
    goal = rng.uniform(*fam.goal)
    ctrl = {'kind': kind, 'goal_frac': goal, 'latency': rng.uniform(*fam.latency),
            'filter_hz': rng.uniform(5.0, 20.0), 'a_stop': rng.uniform(1.0, 5.0)}
    if kind == 'admittance':  # a fast force loop (short latency, light filtering) on an arm
        ctrl.update(latency=rng.uniform(0.002, 0.01), filter_hz=rng.uniform(15.0, 40.0))
        motion['servo_tau'] = rng.uniform(0.005, 0.01)  # whose joint control damps its mode
        arm['zeta_arm'] = rng.uniform(0.05, 0.1)
    # Force loops are tuned to the arm: closed-loop time constant 3-6x the loop's delays,
    # tau = 1 / (K k_s) with k_s the arm and grasp in series (the contact only adds compliance),
    # and loop gain K k_s Q |H_filter H_servo| / w <= 0.5 at the arm's modes (Q = 1 / 2 zeta),
    # free and with the object held by the surface, so the lightly damped arm stays stable.
    k_ser = 1 / (1 / k_a + 1 / arm['k_grasp'])
    delay = ctrl['latency'] + 1 / (2 * math.pi * ctrl['filter_hz']) + motion['servo_tau']
    k_force = 1 / (k_ser * rng.uniform(3.0, 6.0) * delay)  # m/s per N
    for w in (2 * math.pi * arm['f_arm'], math.sqrt((k_a + arm['k_grasp']) / m_h)):
        lag = math.hypot(1, w / (2 * math.pi * ctrl['filter_hz'])) * math.hypot(
            1, w * motion['servo_tau'])
        k_force = min(k_force, 0.5 * w * 2 * arm['zeta_arm'] * lag / k_ser)
    ctrl['k_force'] = k_force
    if kind == 'admittance' and ctrl['k_force'] * max(goal * weight, fam.f_min) < 0.005:
        kind = ctrl['kind'] = 'regulate'  # too stiff to approach under admittance
    if kind == 'position':  # insertion to a planned depth past the seat, no force guard
        motion['goal_depth'] = surf['seat_depth'] + rng.uniform(1e-4, 8e-4)
    elif kind == 'stop':
        ctrl['f_trigger'] = max(goal * weight, fam.f_min)
    elif kind == 'regulate':  # detect contact first, then regulate to the pressing goal
        ctrl['f_trigger'] = max(rng.uniform(0.2, 0.5) * weight, fam.f_min)
        ctrl['f_goal'] = goal * weight
    else:  # admittance from the start: the approach speed is K F_goal
        ctrl['f_goal'] = max(goal * weight, fam.f_min)
        motion['speed'] = min(motion['speed'], ctrl['k_force'] * ctrl['f_goal'])
        ctrl['k_force'] = motion['speed'] / ctrl['f_goal']
    rot, tool, mount = _mount(rng, fam)
    lever = rng.uniform(*fam.lever)
    half_h = rng.uniform(0.02, 0.08)
    r_hand = tool * rng.uniform(0.03, 0.08) + rng.normal(0, 0.005, 3)
    r_obj = tool * lever + np.array([*rng.normal(0, 0.01, 2), -rng.uniform(0.0, 0.03)])
    r_contact = r_obj + np.array([*rng.uniform(-0.03, 0.03, 2), -half_h])
    topic = _pick(rng, fam.topics)
    hsr = topic.startswith('/hsrb')
    tared = topic.endswith('compensated') or bool(rng.uniform() < fam.tared_p)
    drift = bool(rng.uniform() < fam.drift_p)
    sensor = {'topic': topic, 'frame_id': 'wrist_ft_sensor_frame' if hsr else 'ft_sensor_link',
              'rate': int(_pick(rng, fam.ft_rates)), 'mount': mount, 'R': rot,
              'r_hand': r_hand, 'r_obj': r_obj, 'r_contact': r_contact, 'tared': tared,
              'bias_f': rng.normal(0, 4.0, 3), 'bias_t': rng.normal(0, 0.2, 3),
              'drift_rate': rng.normal(0, 0.01, 6) * np.repeat([1.0, 0.05], 3) * drift,
              'drift_amp': rng.normal(0, 0.2, 6) * np.repeat([1.0, 0.05], 3) * drift,
              'drift_tau': rng.uniform(2.0, 20.0),
              'sigma_f': _lu(rng, 0.08, 0.3) if hsr else _lu(rng, 0.005, 0.05),
              'sigma_t': _lu(rng, 0.004, 0.02) if hsr else _lu(rng, 3e-4, 3e-3),
              'lsb_f': _lu(rng, 0.02, 0.06) if hsr else _lu(rng, 1e-3, 8e-3)}
    sensor['lsb_t'] = sensor['lsb_f'] / 20.0
    rate, chunk = _pick(rng, fam.audio)
    gain = rng.uniform(*fam.gain_db)
    if fam.gain_extreme:
        gain = _pick(rng, (-1.0, 1.0)) * rng.uniform(12.0, 20.0)
    audio = {'rate': int(rate), 'chunk': int(chunk), 'gain_db': gain,
             'fs_spl': rng.uniform(90.0, 106.0), 'mic_dist': rng.uniform(0.4, 1.5),
             'room_db': rng.uniform(*fam.room_db), 'room_slope': rng.uniform(0.8, 2.0),
             'hum_hz': _pick(rng, (50.0, 60.0)), 'hum_db': rng.uniform(15.0, 40.0),
             'vent_db': rng.uniform(30.0, 50.0) if rng.uniform() < 0.5 else 0.0,
             'babble_voices': int(rng.integers(2, 7)) if rng.uniform() < fam.babble_p else 0,
             'babble_db': rng.uniform(45.0, 65.0),
             'motor_db': rng.uniform(*fam.motor_db) if fam.motor_db[1] > 0 else 0.0,
             'motor_hz_per_mps': _lu(rng, 2000.0, 8000.0), 'gear_teeth': int(rng.integers(8, 26)),
             'hp_hz': rng.uniform(20.0, 100.0), 'rt60': rng.uniform(0.2, 0.8),
             'reverb_db': rng.uniform(-16.0, -6.0), 'self_noise_dbfs': rng.uniform(-96, -80),
             'dc': rng.normal(0, 20.0), 'hears_contact': fam.hears_contact}
    t_nom = t_hold + motion['t_desc']
    timing = {'t0': EPOCH + 100_000 * list(FAMILIES).index(fam.name) + 20 * index
              + round(rng.uniform(0, 5), 6),
              't_nominal': t_nom, 'duration': float(np.clip(t_nom + rng.uniform(1.5, 3.0), 4, 8))}
    return {'family': fam.name, 'object': {'material': obj, 'mass': m_o, 'half_height': half_h},
            'surface': surf, 'arm': arm, 'motion': motion, 'controller': ctrl,
            'sensor': sensor, 'audio': audio, 'timing': timing}


def sample_events(*, fam: Family, p: Params, rng: np.random.Generator) -> list[Params]:
    """
    Draw the exogenous events of a trial (times in seconds from the trial start).

    The first two events of a family with several precede the nominal onset (the hard case);
    knocks on the hand happen in the air and brushes during the descent.

    Parameters
    ----------
    fam : Family
        The family (event count, probability and kinds).
    p : dict
        The trial's parameters (timing, motion).
    rng : numpy.random.Generator
        The trial's generator.

    Returns
    -------
    list of dict
        One dict per event: ``kind``, ``t`` (s), and the event's own parameters.

    """
    if not fam.event_kinds or rng.uniform() >= fam.event_p:
        return []
    t_nom, dur = p['timing']['t_nominal'], p['timing']['duration']
    t_desc0 = p['motion']['t_hold'] + p['motion']['t_acc']
    events = []
    for k in range(int(rng.integers(fam.events[0], fam.events[1] + 1))):
        kind = _pick(rng, fam.event_kinds)
        before = k < 2 or rng.uniform() < 0.5
        if kind == 'brush' and t_nom - t_desc0 < 0.5:
            kind = 'knock_table'  # descent too short to brush anything
        e: Params = {'kind': kind, 'length': 0.0}
        if kind in ('touch', 'brush'):
            e['length'] = rng.uniform(0.2, 1.0) if kind == 'touch' else rng.uniform(0.1, 0.5)
        if kind == 'knock_hand' or (before and kind != 'brush'):
            lo, hi = 0.3, t_nom - 0.3 - e['length']
        elif kind == 'brush':
            lo, hi = t_desc0, t_nom - 0.2 - e['length']
        else:
            lo, hi = t_nom + 0.15, dur - 0.2 - e['length']
        if hi <= lo:
            continue
        e['t'] = rng.uniform(lo, hi)
        if kind == 'knock_hand':
            e.update(force=rng.uniform(5.0, 40.0), pulse=rng.uniform(0.001, 0.004),
                     direction=_unit(rng), amp_pa=_lu(rng, 0.1, 0.8),
                     material=_pick(rng, ('hard_plastic', 'metal')))
        elif kind == 'knock_table':
            e.update(accel=_lu(rng, 0.01, 0.2), freq=rng.uniform(15.0, 80.0),
                     decay=rng.uniform(0.02, 0.1), amp_pa=_lu(rng, 0.1, 1.0),
                     dist=rng.uniform(0.5, 2.0), direction=np.array([*rng.normal(0, 0.3, 2), 1]))
        elif kind == 'touch':
            d = np.array([*rng.normal(0, 1, 2), rng.uniform(-0.3, 0.5)])
            e.update(force=rng.uniform(1.0, 8.0), direction=d / np.linalg.norm(d),
                     target=_pick(rng, ('object', 'arm')), tremor_hz=rng.uniform(8.0, 12.0),
                     amp_pa=_lu(rng, 0.001, 0.006))
        elif kind == 'brush':
            a = rng.uniform(0, 2 * math.pi)
            e.update(force=rng.uniform(0.5, 4.0), mu=rng.uniform(0.2, 0.5),
                     direction=np.array([math.cos(a), math.sin(a), 0.0]),
                     amp_pa=_lu(rng, 0.003, 0.03), seed=int(rng.integers(2**31)))
        else:
            e.update(amp_pa=_lu(rng, 0.02, 0.3), dist=rng.uniform(0.5, 3.0),
                     material=_pick(rng, OBJECTS), surface=_pick(rng, HARD_SURFACES),
                     tau_c=_lu(rng, 2e-4, 2e-3))
        events.append(e)
    return events


# ----------------------------------------------------------------------------- mechanics
def _contact_table(surf: Params, m_o: float) -> tuple[list[float], float, float]:
    """
    Tabulate the elastic normal force F_e(d) (N) of penetration d (m).

    Hard: F_e = k d^n. Soft: a layer of thickness h, F_e = k_l d / (1 - d/h)^1.5 (foam
    densifying), plus the table's k (d - h)^n below it. The tangent stiffness is capped at
    m_o (0.45 FS_SIM)^2 to keep the explicit integrator stable: contact modes above ~570 Hz,
    beyond every F/T band, are slowed to it. Returns F_e on 4001 points from d = 0 (to 600 N),
    the grid step (m) and the stiffness beyond the grid (N/m).
    """
    k_cap = m_o * (0.45 * FS_SIM) ** 2
    d = np.geomspace(1e-9, 0.08, 20000)
    f = surf['k'] * d ** surf['n']
    if surf['kind'] == 'soft':
        h = surf['thickness']
        f = surf['k_layer'] * np.minimum(d, 0.97 * h) / (1 - np.minimum(d, 0.97 * h) / h) ** 1.5
        f = f + surf['k'] * np.clip(d - h, 0, None) ** surf['n']
    slope = np.minimum(np.diff(f, prepend=0.0) / np.diff(d, prepend=0.0), k_cap)
    f = np.cumsum(slope * np.diff(d, prepend=0.0))
    d_max = float(np.interp(600.0, f, d))  # grid up to 600 N of load
    grid = np.linspace(0.0, d_max, 4001)
    return np.interp(grid, d, f).tolist(), d_max / 4000, float(slope[d <= d_max][-1])


def _descent_speed(*, motion: Params, t: Float) -> Float:
    """
    Planned downward speed v(t) (m/s, >= 0; t, s) before any reaction to contact.

    Zero during the hold, a raised-cosine ramp to v0 over ``t_acc``, then constant or
    decelerating as v0 (e + (1 - e) exp(-t'/tau)), e = ``end_frac``.
    """
    tr = t - motion['t_hold']
    v0 = motion['speed']
    ramp = 0.5 * (1 - np.cos(math.pi * np.clip(tr / motion['t_acc'], 0, 1)))
    v = v0 * ramp
    if motion['profile'] == 'decelerating':
        e = motion['end_frac']
        tail = np.clip(tr - motion['t_acc'], 0, None) / motion['tau_decel']
        v = v * (e + (1 - e) * np.exp(-tail))
    return v


def _external_loads(*, events: list[Params], p: Params, n: int) -> dict[str, Float]:
    """
    Turn mechanical events into per-step arrays (n, 3), world frame.

    ``f_obj`` and ``f_hand``: forces (N) on the object and on the hand (knocks, touches,
    brushes); ``base``: displacement (m) of the arm's base added to the command (a knock on the
    table through the floor, a push on the arm).
    """
    t = np.arange(n) / FS_SIM
    out = {k: np.zeros((n, 3)) for k in ('f_obj', 'f_hand', 'base')}
    for e in events:
        tau = t - e['t']
        if e['kind'] == 'knock_hand':  # half-sine force pulse
            pulse = np.sin(math.pi * np.clip(tau / e['pulse'], 0, 1))
            out['f_hand'] += np.outer(pulse * e['force'], e['direction'])
        elif e['kind'] == 'knock_table':  # decaying floor vibration
            amp = e['accel'] / (2 * math.pi * e['freq']) ** 2
            ring = np.where(tau >= 0, np.exp(-np.clip(tau, 0, None) / e['decay'])
                            * np.sin(2 * math.pi * e['freq'] * tau), 0)
            out['base'] += np.outer(amp * ring, e['direction'] / np.linalg.norm(e['direction']))
        elif e['kind'] == 'touch':  # smooth push with physiological tremor
            x = np.clip(tau / e['length'], 0, 1)
            env = 0.5 * (1 - np.cos(math.pi * np.clip(np.minimum(x, 1 - x) / 0.25, 0, 1)))
            env = env * (1 + 0.05 * np.sin(2 * math.pi * e['tremor_hz'] * tau))
            f = np.outer(env * e['force'], e['direction'])
            if e['target'] == 'arm':  # a push on the arm bends it (2x stiffer mid-link)
                out['base'] += f / (2 * np.array([p['arm']['k_lat']] * 2 + [p['arm']['k_arm']]))
            else:
                out['f_obj'] += f
        elif e['kind'] == 'brush':  # rough normal force, friction resisting the descent
            env = np.sin(math.pi * np.clip(tau / e['length'], 0, 1)) ** 2
            rough = signal.lfilter([0.06], [1, -0.98], np.random.default_rng(
                e['seed']).standard_normal(n))
            fn = env * e['force'] * np.clip(1 + rough, 0.2, None)
            out['f_obj'] += np.outer(fn, e['direction']) + np.outer(fn * e['mu'], [0, 0, 1])
    return out


def simulate_mechanics(*, p: Params, ext: dict[str, Float]) -> dict[str, Any]:
    """
    Integrate the arm, grasp, object and contact (symplectic Euler at FS_SIM).

    Vertical: m_h z_h'' = F_a + F_g - m_h g + F_ext,h,  m_o z_o'' = -F_g - m_o g + F_c,z + F_ext,o
    with F_a = k_a (z_c + b - z_h) + c_a (z_c' - z_h') and F_g = k_g (z_o - z_h) + c_g (...).
    Lateral (hand and object move together): M x'' = k_l (x_c + b - x) + c_l (x_c' - x') + F_c
    + F_ext. The controller sees load = m_t g - F_a, delayed and low-pass filtered.

    Parameters
    ----------
    p : dict
        Trial parameters.
    ext : dict
        Outputs of :func:`external_loads`, arrays (n, 3).

    Returns
    -------
    dict
        ``t`` (n,) s; ``acc_hand``, ``acc_obj``, ``f_contact`` (n, 3) world; ``v_cmd`` (n,)
        m/s; ``gap`` (n,) penetration (m, > 0 in contact); ``v_obj`` (n,) m/s; ``t_trigger``.

    """
    dt = 1.0 / FS_SIM
    n = ext['base'].shape[0]
    arm, sf, mo, ct = p['arm'], p['surface'], p['motion'], p['controller']
    m_o, m_h = p['object']['mass'], arm['m_hand']
    m_t = m_o + m_h
    ka, kl, kg = arm['k_arm'], arm['k_lat'], arm['k_grasp']
    ca = 2 * arm['zeta_arm'] * math.sqrt(ka * m_t)
    cl = 2 * arm['zeta_lat'] * math.sqrt(kl * m_t)
    cg = 2 * arm['zeta_grasp'] * math.sqrt(kg * m_o)
    tab, step, k_end = _contact_table(sf, m_o)
    inv, last, d_end = 1.0 / step, len(tab) - 1, step * (len(tab) - 1)
    alpha, cvis, km = sf['alpha'], sf.get('c', 0.0), sf.get('k_maxwell', 0.0)
    if 'zeta' in sf:  # structural damping, ratio zeta at the tangent stiffness under the weight
        j = min(int(np.searchsorted(tab, m_o * G)), len(tab) - 2)
        cvis = 2 * sf['zeta'] * math.sqrt((tab[j + 1] - tab[j]) / step * m_o)
        if sf['kind'] == 'fixture':  # the chamfer's normal moves the hand laterally too
            cvis *= (m_t / m_o) ** 0.25
    tau_m, mu = sf.get('tau_maxwell', 1.0), sf['mu']
    kt = min(sf['k_t'], m_t * (0.45 * FS_SIM) ** 2)
    ctf = 2 * 0.3 * math.sqrt(kt * m_t)
    fixture = sf['kind'] == 'fixture'
    if fixture:
        ux, uy = math.cos(sf['direction']), math.sin(sf['direction'])
        clr, wch, tanb = sf['clearance'], sf['chamfer'], math.tan(sf['chamfer_angle'])
        cosb, sinb = math.cos(sf['chamfer_angle']), math.sin(sf['chamfer_angle'])
    t = np.arange(n) * dt
    vdes = _descent_speed(motion=mo, t=t).tolist()
    zg = -m_t * G / ka
    zo = zg - m_o * G / kg
    drop = float(np.sum(_descent_speed(motion=mo, t=t[t < p['timing']['t_nominal']]))) * dt
    zs = zo - drop
    z_goal = -drop - mo['goal_depth']  # planner's worst-case target for the command
    bx, by, bz = (ext['base'][:, i].tolist() for i in range(3))
    hx, hy, hz = (ext['f_hand'][:, i].tolist() for i in range(3))
    ox, oy, oz = (ext['f_obj'][:, i].tolist() for i in range(3))
    lat_x = arm['lat_frac'] * math.cos(arm['lat_dir'])
    lat_y = arm['lat_frac'] * math.sin(arm['lat_dir'])
    hx0, hy0 = lat_x * drop, lat_y * drop  # where the oblique path meets the fixture
    zc = vc = vg = vo = px = py = vx = vy = cx = cy = ph = lf = fm = 0.0
    ax_, ay_ = 0.0, 0.0  # friction anchor
    touching = False
    rip_a, rip_k, v0 = arm['ripple_n'] / ka, 2 * math.pi * arm['ripple_per_m'], mo['speed']
    a_srv = dt / mo['servo_tau']
    a_flt = 1 - math.exp(-2 * math.pi * ct['filter_hz'] * dt)
    lag = max(1, int(round(ct['latency'] * FS_SIM)))
    kind = ct['kind']
    f_trig, f_goal, k_f = ct.get('f_trigger', 0.0), ct.get('f_goal', 1.0), ct['k_force']
    t_arm = mo['t_hold'] + mo['t_acc'] + 0.1  # guard ignores the start-up transient
    phase, t_trig, v_trig, t_lift, lifting, t_lifted = 0, None, 0.0, math.inf, False, None
    load = [0.0] * n
    r_agz, r_aoz, r_alx, r_aly, r_fcx, r_fcy, r_fcz, r_gap, r_vc, r_vo = (
        [0.0] * n for _ in range(10))
    for i in range(n):
        ti = i * dt
        # controller: acts on its own delayed, filtered view of the load
        if i >= lag:
            lf += a_flt * (load[i - lag] - lf)
        if lifting:
            vt = mo['v_lift']
        elif kind == 'admittance':  # descend at K (F_goal - F), capped by the planned speed
            vt = -min(vdes[i], max(-v0, k_f * (f_goal - lf)))
            if t_trig is None and lf > 0.9 * f_goal:
                t_trig, t_lift = ti, ti + 0.3 + mo['hold_after']
        elif phase == 0:  # planned descent, guarded by the load threshold
            vt = -vdes[i]
            if kind == 'position' and zc <= z_goal:
                phase, t_trig, t_lift = 2, ti, ti + mo['hold_after']
            elif kind != 'position' and ti > t_arm and lf >= f_trig:
                phase, t_trig, v_trig = 1, ti, -vc
                t_lift = ti + 0.5 + mo['hold_after'] if kind == 'regulate' else math.inf
        elif kind == 'stop':  # decelerate to rest, then hold the position
            vt = -max(0.0, v_trig - ct['a_stop'] * (ti - t_trig))
            if vt == 0.0 and phase == 1:
                phase, t_lift = 2, ti + mo['hold_after']
        elif kind == 'regulate':  # press towards F_goal at up to the approach speed
            vt = -max(-v_trig, min(v_trig, k_f * (f_goal - lf)))
        else:
            vt = 0.0
        if mo['lift'] and ti >= t_lift and not lifting:
            lifting, t_lifted = True, ti
        if zc <= z_goal and vt < 0.0:
            vt = 0.0
        vc += (vt - vc) * a_srv
        zc += vc * dt
        cx -= lat_x * vc * dt
        cy -= lat_y * vc * dt
        ph += rip_k * abs(vc) * dt  # joint ripple follows the joint angle
        # forces on the hand and the object
        zce = zc + bz[i] + rip_a * min(1.0, abs(vc) / v0) * math.sin(ph)
        fa = ka * (zce - zg) + ca * (vc - vg)
        fg = kg * (zo - zg) + cg * (vo - vg)
        fcx = fcy = fcz = 0.0
        if fixture:
            s = (px - hx0) * ux + (py - hy0) * uy + sf['offset']
            vs = (vx * ux + vy * uy) * (1.0 if s >= 0 else -1.0)  # speed away from the axis
            zr = zo - zs
            wall = abs(s) - clr
            if zr > -wch * tanb and wall >= 0.0:  # top face or chamfer
                h = -max(0.0, clr + wch - abs(s)) * tanb
                pen, nz, nl = ((h - zr) * cosb, cosb, sinb) if h < 0.0 else (-zr, 1.0, 0.0)
            else:  # over or in the bore: the seat below, the walls beside
                pen, nz, nl = -sf['seat_depth'] - zr, 1.0, 0.0
                if wall > 0.0 and zr < 0.0:
                    j = min(int(wall * inv), last - 1)  # walls: damping ratio 0.3, lateral mass
                    c_wall = 0.6 * math.sqrt((tab[j + 1] - tab[j]) * inv * m_t)
                    fw = max(0.0, tab[j] * (1 + alpha * vs) + c_wall * vs)
                    fcx, fcy = -math.copysign(fw, s) * ux, -math.copysign(fw, s) * uy
        else:
            pen, nz, nl = zs - zo, 1.0, 0.0
        if pen > 0.0:
            x = pen * inv
            if x < last:
                j = int(x)
                fe = tab[j] + (tab[j + 1] - tab[j]) * (x - j)
            else:
                fe = tab[last] + k_end * (pen - d_end)
            vp = -vo * nz + (vs * nl if nl else 0.0)  # penetration rate along the normal
            fm += (km * vp - fm / tau_m) * dt
            fn = max(0.0, fe * (1.0 + alpha * vp) + cvis * vp + fm)
            fcz = fn * nz
            if nl:
                fl = -math.copysign(fn * nl, s)
                fcx, fcy = fl * ux, fl * uy
            elif mu > 0.0:  # stick-slip: a tangential spring anchored where the object sticks
                if not touching:
                    ax_, ay_ = px, py
                fcx, fcy = -kt * (px - ax_) - ctf * vx, -kt * (py - ay_) - ctf * vy
                mag = math.hypot(fcx, fcy)
                if mag > mu * fn:  # slip: the anchor follows, the force stays on the cone
                    fcx, fcy = fcx * mu * fn / mag, fcy * mu * fn / mag
                    ax_, ay_ = px + fcx / kt, py + fcy / kt
            touching = True
        else:
            fm, touching = 0.0, False
        agz = (fa + fg - m_h * G + hz[i]) / m_h
        aoz = (-fg - m_o * G + fcz + oz[i]) / m_o
        alx = (kl * (cx + bx[i] - px) - cl * vx + fcx + hx[i] + ox[i]) / m_t
        aly = (kl * (cy + by[i] - py) - cl * vy + fcy + hy[i] + oy[i]) / m_t
        vg += agz * dt
        zg += vg * dt
        vo += aoz * dt
        zo += vo * dt
        vx += alx * dt
        px += vx * dt
        vy += aly * dt
        py += vy * dt
        load[i] = m_t * G - fa
        r_agz[i], r_aoz[i], r_alx[i], r_aly[i] = agz, aoz, alx, aly
        r_fcx[i], r_fcy[i], r_fcz[i] = fcx, fcy, fcz
        r_gap[i], r_vc[i], r_vo[i] = pen, vc, vo
    return {'t': t, 'acc_hand': np.column_stack([r_alx, r_aly, r_agz]),
            'acc_obj': np.column_stack([r_alx, r_aly, r_aoz]),
            'f_contact': np.column_stack([r_fcx, r_fcy, r_fcz]), 'v_cmd': np.asarray(r_vc),
            'gap': np.asarray(r_gap), 'v_obj': np.asarray(r_vo), 't_trigger': t_trig,
            't_lift': t_lifted}


def _contact_starts(*, mech: dict[str, Any]) -> list[tuple[float, float]]:
    """
    List the contact episodes: (start time (s), impact speed (m/s)) each.

    A start is the zero crossing of the penetration, interpolated between steps; a
    separation shorter than 1 ms does not start a new episode (chatter of one contact).
    """
    gap, t = mech['gap'], mech['t']
    on = gap > 0
    idx = np.flatnonzero(on[1:] & ~on[:-1]) + 1
    out: list[tuple[float, float]] = []
    last_off = -1.0
    for i in idx:
        t_on = t[i - 1] + (t[i] - t[i - 1]) * -gap[i - 1] / (gap[i] - gap[i - 1])
        if out and t_on - last_off < 1e-3:
            continue
        out.append((float(t_on), float(max(0.0, -mech['v_obj'][i]))))
        after = np.flatnonzero(~on[i:])
        last_off = t[i + after[0]] if after.size else math.inf
    return out


def ft_samples(*, p: Params, mech: dict[str, Any], ext: dict[str, Float],
               rng: np.random.Generator) -> tuple[Float, Float]:
    """
    Produce the F/T sensor's samples.

    World wrench from the bodies beyond the sensor: F = f_h + f_o + F_c with
    f_i = m_i (g - a_i) (+ external force on body i), tau = r_h x f_h + r_o x f_o + r_c x F_c;
    sensor frame W_s = R^T W; each sample is the mean over its period (ADC integration), then
    offset (tare: minus the reading with the object held; else a bias plus the load), drift
    rate t + A (1 - exp(-t/tau)), white noise and quantisation.

    Parameters
    ----------
    p : dict
        Trial parameters.
    mech : dict
        Output of :func:`simulate_mechanics`.
    ext : dict
        Output of :func:`external_loads`.
    rng : numpy.random.Generator
        The trial's generator (noise).

    Returns
    -------
    t : ndarray, shape (m,)
        Sample times (s from the trial start), the end of each averaging window.
    wrench : ndarray, shape (m, 6)
        Fx, Fy, Fz (N), Tx, Ty, Tz (N m) in the sensor frame.

    """
    s = p['sensor']
    gv = np.array([0.0, 0.0, -G])
    f_h = p['arm']['m_hand'] * (gv - mech['acc_hand']) + ext['f_hand']
    f_o = p['object']['mass'] * (gv - mech['acc_obj']) + ext['f_obj']
    f_c = mech['f_contact']
    torque = (np.cross(s['r_hand'], f_h) + np.cross(s['r_obj'], f_o)
              + np.cross(s['r_contact'], f_c))
    w = np.hstack([(f_h + f_o + f_c) @ s['R'], torque @ s['R']])  # rows: R^T w
    k = FS_SIM // s['rate']
    m = w.shape[0] // k
    w = w[:m * k].reshape(m, k, 6).mean(axis=1)
    t = (np.arange(m) + 1.0) * k / FS_SIM
    if s['tared']:
        w -= w[:max(1, int(0.3 * s['rate']))].mean(axis=0)
    else:
        w += np.concatenate([s['bias_f'], s['bias_t']])
    w += np.outer(t, s['drift_rate']) + np.outer(1 - np.exp(-t / s['drift_tau']), s['drift_amp'])
    sigma = np.repeat([s['sigma_f'], s['sigma_t']], 3)
    lsb = np.repeat([s['lsb_f'], s['lsb_t']], 3)
    return t, np.round((w + rng.standard_normal(w.shape) * sigma) / lsb) * lsb


# ----------------------------------------------------------------------------- sound
def _spl(db: float) -> float:
    """Convert dB SPL to Pa (RMS)."""
    return 2e-5 * 10 ** (db / 20)


def _colored(n: int, fs: int, slope: float, rng: np.random.Generator) -> Float:
    """Unit-RMS noise with power spectral density ~ max(f, 20 Hz)^-slope."""
    spec = rng.standard_normal(n // 2 + 1) + 1j * rng.standard_normal(n // 2 + 1)
    x = np.fft.irfft(spec * np.maximum(np.fft.rfftfreq(n, 1 / fs), 20.0) ** (-slope / 2), n)
    return x / (x.std() + 1e-12)


def _band(x: Float, fs: int, lo: float, hi: float) -> Float:
    """Band-pass ``x`` (2nd-order Butterworth), the band clipped below Nyquist."""
    hi = min(hi, 0.45 * fs)
    return signal.sosfilt(signal.butter(2, [lo, hi], 'bandpass', fs=fs, output='sos'), x)


def _modes(material: str, count: int, fs: int,
           rng: np.random.Generator) -> list[tuple[float, float, float]]:
    """Draw ``count`` modes (frequency Hz, decay time s, weight) of a material."""
    m = HARD[material]
    return [(f, _lu(rng, *m['decay']), _lu(rng, 0.3, 1.0)) for f in
            (_lu(rng, *m['f']) for _ in range(count)) if f < 0.45 * fs]


def _impact(fs: int, modes: list[tuple[float, float, float]], amp_pa: float, tau_c: float,
            rng: np.random.Generator) -> Float:
    """
    Synthesise an impact (Pa, from its instant, at ``fs`` Hz): damped modes and a noise burst.

    y(t) = sum_i w_i |P(f_i)| exp(-t/d_i) sin(2 pi f_i t) + burst, for modes (f_i Hz, d_i s,
    w_i), P the spectrum of a half-sine force pulse lasting tau_c (s):
    |P(f)| = |cos(pi f tau_c) / (1 - (2 f tau_c)^2)|, so long (soft) contacts excite high modes
    little; the burst is low-passed at 1/tau_c. Scaled so that the unfiltered sound (P = 1)
    peaks at ``amp_pa``: a softer contact at the same speed is quieter.
    """
    longest = max([d for _, d, _ in modes] + [0.01])
    t = np.arange(int(min(1.5, 5 * longest) * fs)) / fs
    flat = np.zeros_like(t)
    shaped = np.zeros_like(t)
    for f, d, w in modes:
        x = 2 * f * tau_c
        pf = math.pi / 4 if abs(1 - x * x) < 1e-6 else abs(math.cos(math.pi * x / 2) / (1 - x * x))
        ring = w * np.exp(-t / d) * np.sin(2 * math.pi * f * t)
        flat += ring
        shaped += pf * ring
    burst = rng.standard_normal(t.size) * np.exp(-t / (tau_c + rng.uniform(5e-4, 3e-3)))
    burst *= rng.uniform(0.2, 0.8) * np.abs(flat).max() / (np.abs(burst).max() + 1e-12)
    cut = min(0.45 * fs, 1.0 / tau_c)
    lp = signal.sosfilt(signal.butter(2, cut, fs=fs, output='sos'), burst)
    return (shaped + lp) * amp_pa / (np.abs(flat + burst).max() + 1e-12)


def _contact_sound(*, p: Params, v: float, fs: int, rng: np.random.Generator) -> Float:
    """Impact of the held object on the surface at speed ``v`` (m/s), at the microphone (Pa)."""
    ob, sf, m = p['object'], p['surface'], p['object']['mass']
    m_eff = min(m, 0.005)  # the sound's contact time is set by the local mass at the contact
    table = sf['material'] if sf['kind'] == 'hard' else 'wood_table'
    if sf['kind'] == 'soft':
        tau_c = math.pi * math.sqrt(m_eff / (sf['k_layer'] + sf['k_maxwell']))
    else:  # Hertz-like: d_max = ((n+1) m v^2 / 2k)^(1/(n+1)), k_eff = k d_max^(n-1)
        n_ = sf['n']
        d_max = ((n_ + 1) * m_eff * max(v, 1e-4) ** 2 / (2 * sf['k'])) ** (1 / (n_ + 1))
        tau_c = math.pi * math.sqrt(m_eff / (sf['k'] * d_max ** (n_ - 1)))
    modes = (_modes(ob['material'], int(rng.integers(3, 6)), fs, rng)
             + _modes(table, int(rng.integers(2, 4)), fs, rng))
    amp = (0.1 * math.sqrt(HARD[ob['material']]['loud'] * HARD[table]['loud']) * v / 0.05
           * math.sqrt(m / 0.3) * sf.get('loud', 1.0) / p['audio']['mic_dist'])
    return _impact(fs, modes, amp, float(np.clip(tau_c, 5e-5, 0.05)), rng)


def _event_sound(*, e: Params, p: Params, fs: int, rng: np.random.Generator) -> Float:
    """Sound (Pa at the microphone) of one exogenous event, from its start."""
    dist = e.get('dist', p['audio']['mic_dist'])
    if e['kind'] == 'knock_hand':
        return _impact(fs, _modes(e['material'], 4, fs, rng), e['amp_pa'] / dist, 5e-4, rng)
    if e['kind'] == 'knock_table':
        return _impact(fs, _modes('wood_table', 4, fs, rng), e['amp_pa'] / dist, 3e-4, rng)
    if e['kind'] == 'set_down_nearby':
        modes = _modes(e['material'], 4, fs, rng) + _modes(e['surface'], 3, fs, rng)
        return _impact(fs, modes, e['amp_pa'] / dist, e['tau_c'], rng)
    x = np.arange(int(e['length'] * fs)) / (e['length'] * fs)
    lo, hi = (300.0, 3000.0) if e['kind'] == 'touch' else (800.0, 6000.0)  # rustle / scrape
    y = _band(rng.standard_normal(x.size), fs, lo, hi) * np.sin(math.pi * x) ** 2
    return y * e['amp_pa'] / dist / (y.std() + 1e-12)


def render_audio(*, p: Params, mech: dict[str, Any], events: list[Params],
                 impacts: list[tuple[float, float]],
                 rng: np.random.Generator) -> tuple[NDArray[np.int16], Params]:
    """
    Render the microphone's int16 samples for the whole trial.

    Room noise (PSD ~ f^-slope), mains hum, ventilation, babble, motor harmonics of
    f0 = c |v_cmd| with a gear-mesh tone, and the sources (impacts, events, delayed by
    distance / 343 m/s, through a synthetic room response) are summed in Pa, then scaled by
    32768 / p_fullscale * gain, high-passed, offset, and rounded and clipped to int16.

    Parameters
    ----------
    p : dict
        Trial parameters.
    mech : dict
        Output of :func:`simulate_mechanics` (commanded speed for the motor noise).
    events : list of dict
        Exogenous events (their ``t`` in s from the trial start).
    impacts : list of (float, float)
        Contact starts (s) and impact speeds (m/s) of the held object.
    rng : numpy.random.Generator
        The trial's generator.

    Returns
    -------
    samples : ndarray of int16, shape (n,)
        Microphone samples at ``p['audio']['rate']``.
    stats : dict
        ``clipped_fraction``, ``contact_peak_pa`` (the first impact's peak at the microphone).

    """
    a = p['audio']
    fs = a['rate']
    n = int(p['timing']['duration'] * fs)
    t = np.arange(n) / fs
    x = _spl(a['room_db']) * _colored(n, fs, a['room_slope'], rng)
    ph = rng.uniform(0, 2 * math.pi, 3)
    x += _spl(a['hum_db']) * sum(w * np.sin(2 * math.pi * k * a['hum_hz'] * t + ph[k - 1])
                                 for k, w in ((1, 1.0), (2, 0.5), (3, 0.3)))
    if a['vent_db'] > 0:
        v = _band(_colored(n, fs, 1.5, rng), fs, 60.0, 500.0)
        v *= 1 + 0.2 * np.sin(2 * math.pi * rng.uniform(0.1, 0.5) * t)
        x += _spl(a['vent_db']) * v / v.std()
    if a['babble_voices']:
        b = np.zeros(n)
        for _ in range(a['babble_voices']):
            wobble = _band(rng.standard_normal(n), fs, 0.5, 3.0)  # intonation, +-8 % RMS
            f0 = rng.uniform(90, 240) * (1 + 0.08 * wobble / (wobble.std() + 1e-12))
            src = np.mod(np.cumsum(f0) / fs, 1.0) - 0.5  # glottal-like sawtooth
            voice = sum(_band(src, fs, f * 0.9, f * 1.1) for f in (
                rng.uniform(300, 900), rng.uniform(900, 2500), rng.uniform(2400, 3200)))
            gate = signal.sosfilt(signal.butter(2, 4.0, fs=fs, output='sos'),
                                  rng.standard_normal(n))
            voice *= np.clip(2 * gate / (gate.std() + 1e-12) + 0.3, 0, 1)
            b += voice / (voice.std() + 1e-12)
        x += _spl(a['babble_db']) * b / math.sqrt(a['babble_voices'])
    if a['motor_db'] > 0:
        speed = np.abs(np.interp(t, mech['t'], mech['v_cmd']))
        phase = 2 * math.pi * np.cumsum(a['motor_hz_per_mps'] * speed) / fs
        f0 = a['motor_hz_per_mps'] * speed
        tones = sum(np.sin(k * phase + rng.uniform(0, 6.3)) / k for k in range(1, 6))
        tones = tones + 0.5 * np.where(a['gear_teeth'] * f0 < 0.45 * fs,
                                       np.sin(a['gear_teeth'] * phase), 0.0)
        hiss = _band(rng.standard_normal(n), fs, 1000.0, 6000.0)
        env = np.clip(speed / p['motion']['speed'], 0, 1.5) ** 0.7
        x += _spl(a['motor_db']) * env * (tones / 1.2 + 0.5 * hiss / hiss.std())
    src = np.zeros(n + fs)
    peak = 0.0
    sounds = [(e['t'] + e.get('dist', a['mic_dist']) / SOUND_SPEED,
               _event_sound(e=e, p=p, fs=fs, rng=rng)) for e in events]
    if a['hears_contact']:
        for t_on, v in impacts:
            y = _contact_sound(p=p, v=v, fs=fs, rng=rng)
            peak = peak or float(np.abs(y).max())
            sounds.append((t_on + a['mic_dist'] / SOUND_SPEED, y))
    for t_s, y in sounds:
        i = int(round(t_s * fs))
        m = min(y.size, src.size - i)
        src[i:i + m] += y[:m]
    ti = np.arange(int(a['rt60'] * fs)) / fs  # room: direct sound + exponential diffuse tail
    tail = rng.standard_normal(ti.size) * np.exp(-6.91 * ti / a['rt60']) * (ti > 0.004)
    tail *= math.sqrt(10 ** (a['reverb_db'] / 10) / (np.sum(tail ** 2) + 1e-12))
    tail[0] = 1.0
    x += signal.fftconvolve(src, tail)[:n]
    c = x * 32768 / _spl(a['fs_spl']) * 10 ** (a['gain_db'] / 20)
    c = signal.sosfilt(signal.butter(2, a['hp_hz'], 'highpass', fs=fs, output='sos'), c)
    c += a['dc'] + 32768 * 10 ** (a['self_noise_dbfs'] / 20) * rng.standard_normal(n)
    c = np.clip(np.round(c), -32768, 32767)
    return c.astype(np.int16), {'clipped_fraction': float(np.mean(np.abs(c) >= 32767)),
                                'contact_peak_pa': peak}


# ----------------------------------------------------------------------------- bags
def write_bag(*, path: Path, p: Params, ft_t: Float, wrench: Float,
              audio: NDArray[np.int16], rng: np.random.Generator) -> None:
    """
    Write one rosbag2 (sqlite3) bag: the F/T topic and ``/audio``.

    F/T: header.stamp = t0 + sample time, log time = stamp + U(0.5, 3) ms (monotonic).
    Audio: ``std_msgs/Int16MultiArray`` chunks (empty layout), log time = time of the chunk's
    last sample + U(1, 5) ms; a trailing partial chunk is dropped.

    Parameters
    ----------
    path : pathlib.Path
        Bag directory to create (removed first if it exists).
    p : dict
        Trial parameters (topic, frame, rates, t0).
    ft_t : ndarray, shape (m,)
        F/T sample times (s from the trial start).
    wrench : ndarray, shape (m, 6)
        F/T samples (N, N m).
    audio : ndarray of int16, shape (n,)
        Microphone samples.
    rng : numpy.random.Generator
        Generator of the transport delays.

    """
    ts = get_typestore(Stores.ROS2_JAZZY)
    ty = ts.types
    t0_ns = int(round(p['timing']['t0'] * 1e6)) * 1000
    stamps = t0_ns + np.round(ft_t * 1e9).astype(np.int64)
    logs = np.maximum.accumulate(stamps + (rng.uniform(0.5e6, 3e6, stamps.size)).astype(np.int64))
    msgs: list[tuple[int, int, bytes]] = []
    s = p['sensor']
    for st, lg, w in zip(stamps.tolist(), logs.tolist(), wrench.tolist()):
        msg = ty['geometry_msgs/msg/WrenchStamped'](
            header=ty['std_msgs/msg/Header'](
                stamp=ty['builtin_interfaces/msg/Time'](sec=st // 10**9, nanosec=st % 10**9),
                frame_id=s['frame_id']),
            wrench=ty['geometry_msgs/msg/Wrench'](
                force=ty['geometry_msgs/msg/Vector3'](x=w[0], y=w[1], z=w[2]),
                torque=ty['geometry_msgs/msg/Vector3'](x=w[3], y=w[4], z=w[5])))
        msgs.append((lg, 0, ts.serialize_cdr(msg, 'geometry_msgs/msg/WrenchStamped')))
    fs, ch = p['audio']['rate'], p['audio']['chunk']
    layout = ty['std_msgs/msg/MultiArrayLayout'](dim=[], data_offset=0)
    for j in range(audio.size // ch):
        last = t0_ns + int(round(((j + 1) * ch - 1) / fs * 1e9))
        msg = ty['std_msgs/msg/Int16MultiArray'](layout=layout, data=audio[j * ch:(j + 1) * ch])
        msgs.append((last + int(rng.uniform(1e6, 5e6)), 1,
                     ts.serialize_cdr(msg, 'std_msgs/msg/Int16MultiArray')))
    msgs.sort(key=lambda m: (m[0], m[1]))
    if path.exists():
        shutil.rmtree(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with Writer(path, version=8) as writer:
        conns = [writer.add_connection(s['topic'], 'geometry_msgs/msg/WrenchStamped',
                                       typestore=ts),
                 writer.add_connection('/audio', 'std_msgs/msg/Int16MultiArray', typestore=ts)]
        for lg, c, raw in msgs:
            writer.write(conns[c], lg, raw)


# ----------------------------------------------------------------------------- trials
def _jsonable(x: Any) -> Any:
    """Convert numpy values inside nested containers to JSON types."""
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float):
        return round(x, 9)
    return x


def generate_trial(*, out_dir: Path, family: str, index: int, seed: int) -> Params:
    """
    Generate, write and describe one trial.

    The generator is ``default_rng([seed, crc32(family), index, attempt])``: any trial can be
    regenerated alone. An attempt whose object never touches, or touches outside
    [0.8 s, duration - 1 s] (e.g. the guarded move stopped in the air), is drawn again.

    Parameters
    ----------
    out_dir : pathlib.Path
        Output folder; the bag goes to ``out_dir/family/trial_NNNN``.
    family : str
        A key of :data:`FAMILIES`.
    index : int
        Trial number within the family.
    seed : int
        Run seed.

    Returns
    -------
    dict
        The trial's record for ``trials.json`` (bag, onset, parameters, events, outcome).

    """
    fam = FAMILIES[family]
    for attempt in range(40):
        rng = np.random.default_rng([seed, zlib.crc32(family.encode()), index, attempt])
        p = sample_trial(fam=fam, rng=rng, index=index)
        events = sample_events(fam=fam, p=p, rng=rng)
        ext = _external_loads(events=events, p=p, n=int(round(p['timing']['duration'] * FS_SIM)))
        mech = simulate_mechanics(p=p, ext=ext)
        impacts = _contact_starts(mech=mech)
        if impacts and 0.8 <= impacts[0][0] <= p['timing']['duration'] - 1.0:
            break
    else:
        raise RuntimeError(f'{family} trial {index}: no valid contact in 40 attempts')
    ft_t, wrench = ft_samples(p=p, mech=mech, ext=ext, rng=rng)
    audio, stats = render_audio(p=p, mech=mech, events=events, impacts=impacts, rng=rng)
    rel = f'{family}/trial_{index:04d}'
    write_bag(path=out_dir / rel, p=p, ft_t=ft_t, wrench=wrench, audio=audio, rng=rng)
    t0, onset = p['timing']['t0'], impacts[0][0]
    t, fz = mech['t'], mech['f_contact'][:, 2]
    t_end = mech['t_lift'] or t[-1]
    final = float(np.median(fz[(t >= t_end - 0.2) & (t < t_end)]))
    reach = np.flatnonzero((t >= onset) & (fz >= 0.9 * final) & (final > 0.05))
    outcome = {'impact_speed': impacts[0][1], 'n_contact_starts': len(impacts),
               'peak_contact_force': float(fz.max()), 'final_contact_force': final,
               'final_load_frac': final / (p['object']['mass'] * G),
               'transfer_time_90': float(t[reach[0]] - onset) if reach.size else None,
               't_trigger': mech['t_trigger'], 't_lift': mech['t_lift'], **stats}
    for e in events:
        e['t_abs'] = round(t0 + e['t'], 6)
        e['before_onset'] = bool(e['t'] < onset)
    return _jsonable({'bag': rel, 'family': family, 'seed': seed, 'index': index,
                      'attempt': attempt, 'onset': round(t0 + onset, 6),
                      'onset_rel': onset, 'params': p, 'events': events, 'outcome': outcome})


def _run(job: tuple[str, int, int, str]) -> Params:
    """Run one trial in a worker process: (family, index, seed, out_dir)."""
    family, index, seed, out_dir = job
    return generate_trial(out_dir=Path(out_dir), family=family, index=index, seed=seed)


def main(argv: Sequence[str] | None = None) -> int:
    """
    Generate the trials, ``labels.csv`` and ``trials.json``.

    Parameters
    ----------
    argv : sequence of str, optional
        Command-line arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status (0 on success, 2 on a bad family name).

    """
    ap = argparse.ArgumentParser(prog='independent_trials.py', description=__doc__.split('\n')[1])
    ap.add_argument('out_dir', type=Path)
    ap.add_argument('--trials-per-family', type=int, default=20)
    ap.add_argument('--seed', type=int, default=3301)
    ap.add_argument('--families', default=','.join(FAMILIES))
    ap.add_argument('--jobs', type=int, default=2)
    args = ap.parse_args(argv)
    families = [f for f in args.families.split(',') if f]
    unknown = sorted(set(families) - set(FAMILIES))
    if unknown:
        print(f'unknown families: {unknown}; known: {list(FAMILIES)}', file=sys.stderr)
        return 2
    args.out_dir.mkdir(parents=True, exist_ok=True)
    jobs = [(f, i, args.seed, str(args.out_dir)) for f in families
            for i in range(args.trials_per_family)]
    start = time.monotonic()
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        records = list(pool.map(_run, jobs))
    with open(args.out_dir / 'labels.csv', 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['bag', 'onset_start', 'onset_end'])
        w.writerows([r['bag'], f"{r['onset']:.6f}", f"{r['onset']:.6f}"] for r in records)
    (args.out_dir / 'trials.json').write_text(json.dumps(
        {'generator': 'benchmarks/independent_trials.py', 'seed': args.seed,
         'fs_sim': FS_SIM, 'trials': records}, indent=1))
    print(f'{len(records)} trials in {time.monotonic() - start:.1f} s -> {args.out_dir}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
