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
Independent placing-trial generator B: a held-out simulator written from first principles.

Each trial is a robot lowering a held object onto a support, recorded as a bag with a
``geometry_msgs/WrenchStamped`` topic (wrist F/T) and, for most families, a microphone topic.

Mechanics (depth axis ``z`` positive downwards, simulated at ``FS_MECH`` = 8 kHz by
semi-implicit Euler): commanded position ``z_c`` (servo: first-order velocity lag with an
acceleration limit) -- arm spring/damper ``k_arm, c_arm`` -- hand mass ``m_h`` (flange and
gripper) -- grasp spring/damper ``k_g, c_g`` -- object (mass ``m_o``, tilt ``phi`` with grasp
stiffness ``k_phi``, inertia ``I``) -- 1 or 2 contact points (Hunt-Crossley
``F = k d^n (1 + lam d')``, ``F >= 0``) -- support (rigid, or a flexing tray ``m_s, k_s``).
Structural arm/wrist modes (5-60 Hz), gear ripple, base vibration, sensor rotation, bias,
drift, temperature steps, per-sample averaging, noise and quantisation are added afterwards.
Sound: modal synthesis of every impact (contact, bounces, knocks), weighted by the spectrum of
the contact pulse (soft contacts are nearly silent), room noise, speech, HVAC, robot ego noise
following the joint speed, reverberation, propagation delay, mic gain and clipping.

The onset is the first instant at which any contact point penetrates the support
(nonzero contact force), interpolated between mechanics steps.

Usage::

    python benchmarks/independent_robots.py OUT_DIR --trials-per-family N --seed S \
        [--families a,b] [--jobs J]
"""

import argparse
from concurrent import futures
import csv
import datetime
import json
import math
from pathlib import Path
import shutil
import sys
from typing import Any
import zlib

import numpy as np
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin, Writer as Ros2Writer
from rosbags.typesys import get_typestore, Stores
from scipy import signal

G = 9.81
FS_MECH = 8000.0
C_AIR = 343.0
REF_V, REF_M = 0.05, 0.2
TS1 = get_typestore(Stores.ROS1_NOETIC)
TS2 = get_typestore(Stores.ROS2_HUMBLE)

# Material: modal band f_lo, f_hi [Hz]; decay tau_lo, tau_hi [s]; contact pulse lo, hi [s];
# loudness [Pa at 1 m for a 5 cm/s impact of 0.2 kg]; contact stiffness k [N/m^n]; exponent
# n; coefficient of restitution e.
MATERIALS = {
    'glass': (1500, 7000, 0.03, 0.25, 1e-4, 3e-4, 0.25, 3e6, 1.0, 0.6),
    'ceramic': (1000, 5500, 0.01, 0.08, 1e-4, 4e-4, 0.2, 3e6, 1.0, 0.5),
    'steel': (800, 9000, 0.08, 0.5, 5e-5, 2e-4, 0.3, 6e6, 1.0, 0.7),
    'aluminium': (700, 7000, 0.05, 0.3, 8e-5, 2.5e-4, 0.25, 4e6, 1.0, 0.6),
    'plastic': (300, 3000, 0.005, 0.03, 3e-4, 1e-3, 0.08, 6e5, 1.0, 0.4),
    'wood': (200, 2500, 0.005, 0.04, 2e-4, 8e-4, 0.12, 1e6, 1.0, 0.4),
    'cardboard': (100, 1200, 0.002, 0.012, 1e-3, 3e-3, 0.03, 1.5e5, 1.0, 0.2),
    'wood_table': (70, 900, 0.02, 0.1, 2e-4, 6e-4, 0.15, 3e6, 1.0, 0.5),
    'laminate': (90, 1500, 0.01, 0.06, 1.5e-4, 5e-4, 0.12, 3e6, 1.0, 0.5),
    'steel_fixture': (600, 6000, 0.05, 0.3, 5e-5, 2e-4, 0.2, 8e6, 1.0, 0.7),
    'plastic_tray': (150, 1500, 0.01, 0.05, 3e-4, 1e-3, 0.15, 8e5, 1.0, 0.4),
    'foam_mat': (50, 300, 0.005, 0.02, 8e-3, 3e-2, 0.01, 2e4, 1.5, 0.15),
    'towel': (50, 250, 0.003, 0.01, 2e-2, 8e-2, 0.005, 3e5, 2.5, 0.05),
}

# Parameter specs: (lo, hi) uniform, ('log', lo, hi) log-uniform, [a, b] a choice, else as is.
BASE = {
    'm_o': (0.1, 0.8), 'm_g': (0.5, 1.0), 'm_arm': (1.5, 4.0), 'k_arm': ('log', 2e4, 1.5e5),
    'zeta_arm': (0.1, 0.4), 'k_g': ('log', 1.5e4, 1e5), 'zeta_g': (0.1, 0.4),
    'k_phi': ('log', 2.0, 30.0), 'zeta_phi': (0.3, 0.8), 'comp_load': [True, False],
    'mount': 'down', 'sensor_tilt_deg': (0.0, 10.0), 'p_z_up': 0.3, 'com_lat': (0.0, 0.02),
    'com_depth': (0.06, 0.16), 'base_r': (0.025, 0.05), 'bottom': (0.03, 0.08),
    'grip_depth': (0.03, 0.07), 'tilt_deg': (0.0, 1.0), 'mu_t': (0.0, 0.15),
    'obj': ['glass', 'ceramic', 'plastic', 'cardboard'], 'surf': ['wood_table', 'laminate'],
    'tray': False, 'peg': False, 'v_app': (0.01, 0.05), 'p_slow': 0.3, 'slow_frac': (0.2, 0.5),
    'd_slow': (0.005, 0.02), 'est_err': (-0.01, 0.01), 't_desc': (1.0, 3.5),
    't_rest': (0.4, 1.5), 't_post': (1.0, 2.5), 'ctl': ['guarded'], 'thr': (3.0, 8.0),
    'thr_torque': False, 'latency': (0.005, 0.03), 'filt_tau': (0.002, 0.02),
    'react': ['hold', 'backoff', 'press'], 'a_max': (0.3, 2.0), 'a_stop': (2.0, 10.0),
    'tau_servo': (0.005, 0.03), 'v_back': (0.005, 0.02), 'd_back': (0.0003, 0.002),
    't_press': (0.05, 0.3), 'f_ref': (3.0, 12.0), 'imp_below': (0.003, 0.015),
    'k_imp': ('log', 300.0, 3000.0), 'zeta_imp': (0.6, 1.0), 'f_mode': (5.0, 60.0),
    'zeta_mode': (0.02, 0.1), 'm_mode': (2.0, 8.0), 'kappa': (0.05, 0.3),
    'ripple': (0.01, 0.08), 'base_vib': 0.0, 'on_table': True, 'noise_f': (0.02, 0.1),
    'noise_t': (0.001, 0.005), 'q_f': [0.0, 0.002, 0.01, 0.03], 'q_t': [0.0, 1e-4, 5e-4],
    'p_tared': 0.5, 'bias_f': (2.0, 15.0), 'bias_t': (0.1, 1.0), 'drift_f': (0.0, 0.2),
    'drift_t': (0.0, 0.01), 'p_drop': 0.4, 'p_gap': 0.2, 'log_lat': (0.001, 0.005),
    'mic_dist': (0.3, 1.0), 'rt60': (0.2, 0.6), 'gain_db': (-20.0, 20.0), 'pink': (5e-4, 4e-3),
    'hvac': (1e-3, 1e-2), 'hum': (0.0, 3e-3), 'fan': (0.0, 2e-3), 'whine': (2e-3, 2e-2),
    'p_pre': 0.4, 'events': {},
}

FAMILIES = {
    'franka_axial': {
        'container': 'sqlite3', 'names': 'place', 'ft_topic': '/ft_sensor/raw',
        'frame': 'ft_sensor_link', 'rates': [500, 1000],
        'audio': ('int16', [48000], [480, 960, 1024], '/mic/audio'),
        'm_g': (0.75, 0.95), 'm_o': (0.05, 0.6), 'ctl': ['impedance', 'impedance_stop'],
        'k_imp': ('log', 500.0, 3000.0), 'v_app': (0.01, 0.06),
        'p_tared': 0.7, 'noise_f': (0.02, 0.08), 'thr': (2.0, 6.0), 'react': ['hold'],
        'events': {'knock_table': (0.5, 2), 'set_down': (0.4, 2), 'speech': (0.4, 2)}},
    'ur5e_guarded': {
        'container': 'ros1', 'names': 'date', 'ft_topic': '/wrench', 'frame': 'tool0',
        'rates': [125, 500], 'audio': ('float32', [44100], [1024, 2048, 4096], '/audio/samples'),
        'm_g': (0.9, 1.1), 'm_o': (0.1, 1.5), 'obj': ['cardboard', 'plastic', 'glass', 'wood'],
        'k_arm': ('log', 4e4, 2e5), 'thr': (4.0, 12.0), 'latency': (0.008, 0.04),
        'react': ['hold', 'backoff', 'retract'], 'v_app': (0.01, 0.10), 'noise_f': (0.3, 1.0),
        'noise_t': (0.01, 0.04), 'q_f': [0.0, 0.01], 'p_pre': 0.7,
        'events': {'knock_hand': (0.7, 2), 'door_slam': (0.3, 1), 'speech': (0.4, 2),
                   'thermal_step': (0.15, 1)}},
    'hsr_side': {
        'container': 'mcap', 'names': 'ros2date', 'ft_topic': '/hsrb/wrist_wrench/raw',
        'frame': 'wrist_ft_sensor_frame', 'rates': [100],
        'audio': ('int16', [16000, 44100], [160, 320, 512], '/hsrb/head_mic/audio'),
        'mount': 'side', 'com_lat': (0.10, 0.25), 'com_depth': (-0.03, 0.06),
        'bottom': (0.04, 0.10), 'm_o': (0.1, 0.7), 'm_g': (0.4, 0.6),
        'obj': ['glass', 'ceramic', 'plastic'], 'k_arm': ('log', 5e3, 3e4),
        'k_g': ('log', 5e3, 3e4), 'k_phi': ('log', 1.0, 10.0), 'thr_torque': True,
        'thr': (1.0, 3.0), 'latency': (0.02, 0.06), 'react': ['retract', 'hold'],
        'v_app': (0.01, 0.05), 'p_tared': 0.2, 'noise_f': (0.1, 0.4), 'noise_t': (0.01, 0.04),
        'mic_dist': (0.8, 1.3), 'fan': (1e-3, 6e-3), 'on_table': False,
        'events': {'knock_hand': (0.5, 3), 'knock_table': (0.5, 3), 'push_object': (0.2, 1)}},
    'tiago_mobile': {
        'container': 'ros1', 'names': 'date', 'ft_topic': '/wrist_ft', 'frame': 'wrist_ft_link',
        'rates': [100, 200], 'audio': ('int16', [16000], [256, 512, 1024], '/audio'),
        'm_o': (0.1, 1.0), 'k_arm': ('log', 3e3, 1.5e4), 'zeta_arm': (0.05, 0.2),
        'sensor_tilt_deg': (0.0, 30.0), 'p_slow': 1.0, 'slow_frac': (0.15, 0.4),
        'est_err': (-0.02, 0.02), 'd_slow': (0.01, 0.03), 'v_app': (0.03, 0.08),
        'thr': (2.0, 5.0), 'react': ['backoff', 'hold'], 'base_vib': (0.02, 0.15),
        'on_table': False, 'mic_dist': (0.7, 1.1), 'fan': (2e-3, 1e-2),
        'obj': ['plastic', 'ceramic', 'cardboard', 'glass'], 'noise_f': (0.05, 0.2),
        'events': {'push_arm': (0.3, 1), 'push_object': (0.3, 1), 'speech': (0.5, 2),
                   'knock_object': (0.3, 1), 'thermal_step': (0.15, 1)}},
    'peg_fixture': {
        'container': 'sqlite3', 'names': 'insert', 'ft_topic': '/netft_data',
        'frame': 'ft_sensor', 'rates': [125, 500, 1000],
        'audio': ('float32', [44100, 48000], [480, 1024, 2048, 4096], '/audio/float'),
        'obj': ['steel', 'aluminium'], 'surf': ['steel_fixture'], 'peg': True,
        'm_o': (0.1, 1.0), 'com_depth': (0.02, 0.10), 'base_r': (0.005, 0.02),
        'bottom': (0.005, 0.04), 'k_arm': ('log', 5e4, 2e5),
        'ctl': ['admittance', 'admittance', 'guarded'], 'f_ref': (5.0, 20.0),
        'v_app': (0.003, 0.02), 't_desc': (1.0, 4.0), 'mic_dist': (0.2, 0.8),
        'whine': (5e-3, 3e-2), 'p_pre': 0.8,
        'events': {'brush': (0.6, 1), 'knock_table': (0.3, 2), 'speech': (0.3, 1)}},
    'soft_surface': {
        'container': 'mcap', 'names': 'place', 'ft_topic': '/wrench', 'frame': 'ft_link',
        'rates': [125, 200, 500],
        'audio': ('float32', [16000, 22050], [256, 512, 1024, 2205], '/microphone/data'),
        'surf': ['foam_mat', 'towel', 'plastic_tray'],
        'obj': ['glass', 'ceramic', 'plastic', 'cardboard', 'wood'],
        'ctl': ['guarded', 'guarded', 'impedance'], 'thr': (2.0, 6.0), 'v_app': (0.005, 0.03),
        'k_arm': ('log', 2e3, 1e5), 'react': ['hold', 'backoff'], 'mic_dist': (0.4, 1.2),
        't_post': (1.5, 3.0),
        'events': {'set_down': (0.5, 2), 'speech': (0.5, 2), 'knock_table': (0.3, 1)}},
    'tall_tip': {
        'container': 'ros1', 'names': 'place', 'ft_topic': '/ft_sensor/raw',
        'frame': 'ft_sensor_link', 'rates': [51, 100, 200],
        'audio': ('int16', [22050, 48000], [512, 2048, 4096], '/audio_raw'),
        'obj': ['glass', 'plastic', 'ceramic', 'steel'], 'm_o': (0.2, 1.2),
        'com_depth': (0.06, 0.16), 'bottom': (0.06, 0.14), 'base_r': (0.03, 0.05),
        'tilt_deg': (2.0, 8.0), 'k_phi': ('log', 0.5, 5.0), 'sensor_tilt_deg': (0.0, 60.0),
        'thr': (2.0, 6.0), 'react': ['hold', 'press'], 'mic_dist': (3.0, 6.0),
        'rt60': (0.4, 0.9), 'p_pre': 0.6,
        'events': {'brush': (0.4, 1), 'door_slam': (0.4, 1), 'knock_object': (0.3, 1),
                   'speech': (0.4, 1)}},
    'heavy_slow': {
        'container': 'sqlite3', 'names': 'ros2date', 'ft_topic': '/wrench',
        'frame': 'ft_sensor', 'rates': [51, 125], 'audio': None, 'm_o': (1.0, 3.0),
        'v_app': (0.003, 0.015), 't_desc': (1.0, 3.5), 'k_arm': ('log', 3e4, 1.5e5),
        'k_g': ('log', 3e4, 2e5), 'obj': ['steel', 'wood', 'ceramic', 'plastic'],
        'surf': ['wood_table', 'steel_fixture'], 'ctl': ['admittance', 'guarded'],
        'f_ref': (0.3, 0.9), 'thr': (5.0, 20.0), 'noise_f': (0.05, 0.3),
        'drift_f': (0.1, 0.6), 'p_pre': 0.6,
        'events': {'push_object': (0.4, 1), 'knock_hand': (0.3, 1), 'thermal_step': (0.5, 1)}},
}


def _draw(rng: np.random.Generator, spec: Any) -> Any:
    """Draw one value from a spec: ``(lo, hi)``, ``('log', lo, hi)``, a list, or a constant."""
    if isinstance(spec, tuple) and spec and spec[0] == 'log':
        return float(math.exp(rng.uniform(math.log(spec[1]), math.log(spec[2]))))
    if isinstance(spec, tuple):
        return float(rng.uniform(spec[0], spec[1]))
    if isinstance(spec, list):
        return spec[int(rng.integers(len(spec)))]
    return spec


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _tilted(rng: np.random.Generator, axis: np.ndarray, max_deg: float) -> np.ndarray:
    """Return a unit vector within ``max_deg`` degrees of ``axis`` (random azimuth)."""
    axis = _unit(axis)
    perp = _unit(np.cross(axis, rng.normal(size=3)))
    ang = math.radians(rng.uniform(0.0, max_deg))
    return _unit(math.cos(ang) * axis + math.sin(ang) * perp)


def sample_trial(*, rng: np.random.Generator, family: str) -> dict:
    """
    Sample the parameters of one trial of a family.

    Parameters
    ----------
    rng : numpy.random.Generator
        The trial's generator.
    family : str
        A key of ``FAMILIES``.

    Returns
    -------
    dict
        JSON-able parameters: masses [kg], stiffnesses [N/m, N m/rad], lengths [m], speeds
        [m/s], times [s], the sensor rotation ``R`` (3x3, sensor axes as world columns, world
        z up), lever arms (world, from the sensor origin) and the contact points.

    """
    fam = {**BASE, **FAMILIES[family]}
    p = {k: _draw(rng, v) for k, v in fam.items()
         if k not in ('events', 'audio', 'rates', 'container', 'names')}
    p['family'] = family
    p['ft_rate'] = int(_draw(rng, fam['rates']))
    if fam['audio'] is not None:
        kind, rates, chunks, topic = fam['audio']
        p['audio'] = {'type': kind, 'rate': int(_draw(rng, rates)),
                      'chunk': int(_draw(rng, chunks)), 'topic': topic,
                      'layout_dim': bool(rng.random() < 0.5),
                      'ppm': float(rng.uniform(-60, 60)), 't0': float(rng.uniform(0, 0.25))}
    p['m_h'] = p['m_arm'] + p['m_g']
    if p['ctl'].startswith('imp'):  # Cartesian impedance: the arm spring is the controller's
        p['k_arm'], p['zeta_arm'] = p['k_imp'], p['zeta_imp']
    up = np.array([0.0, 0.0, 1.0])
    if p['mount'] == 'side':
        az = rng.uniform(0, 2 * math.pi)
        tool = _tilted(rng, np.array([math.cos(az), math.sin(az), 0.0]), 15.0)
        u_com = _unit(np.array([tool[0], tool[1], 0.0]))
    else:
        tool = _tilted(rng, -up, p['sensor_tilt_deg'])
        az = rng.uniform(0, 2 * math.pi)
        u_com = np.array([math.cos(az), math.sin(az), 0.0])
    zs = tool if (p['mount'] == 'side' or rng.random() > p['p_z_up']) else -tool
    xs = _unit(np.cross(zs, rng.normal(size=3)))
    p['R'] = np.column_stack([xs, np.cross(zs, xs), zs]).tolist()
    p['r_g'] = (p['grip_depth'] * tool).tolist()
    r_com = p['com_lat'] * u_com - p['com_depth'] * up
    p['r_com'] = r_com.tolist()
    az = rng.uniform(0, 2 * math.pi)
    u_tip = np.array([math.cos(az), math.sin(az), 0.0])
    p['u_tip'] = u_tip.tolist()
    m_o, r = p['m_o'], p['base_r']
    p['inertia'] = m_o * ((2 * p['bottom']) ** 2 + 3 * r * r) / 12.0
    mo_, ms_ = MATERIALS[p['obj']], MATERIALS[p['surf']]
    n_exp = max(mo_[8], ms_[8])
    k_c = ms_[7] if ms_[8] > 1 else (mo_[7] if mo_[8] > 1 else 1 / (1 / mo_[7] + 1 / ms_[7]))
    e = min(mo_[9], ms_[9])
    p['pulse'] = float(max(rng.uniform(mo_[4], mo_[5]), rng.uniform(ms_[4], ms_[5])))
    dt = 1.0 / FS_MECH
    pts = []
    if p['peg']:  # chamfer of half-angle alpha first, seated on the bottom after d_seat
        alpha = math.radians(rng.uniform(30, 45))
        d_seat = float(rng.uniform(0.001, 0.004))
        pts.append({'lever': r, 'off': 0.0, 'k': k_c * math.cos(alpha) ** 2, 'n': 1.0,
                    'sat': float(rng.uniform(2, 8)), 'rel': d_seat, 'tan': math.tan(alpha)})
        pts.append({'lever': 0.0, 'off': d_seat, 'k': k_c, 'n': 1.0, 'sat': 1e9, 'rel': 1e9,
                    'tan': 0.0})
    else:  # two rim points; the object tilted by theta lands on the lower rim first
        theta = math.radians(p['tilt_deg'])
        d2 = 2 * r * math.sin(theta) + float(rng.uniform(0, 2e-4))
        for lever, off in ((r, 0.0), (-r, d2)):
            pts.append({'lever': lever, 'off': off, 'k': k_c, 'n': n_exp, 'sat': 1e9,
                        'rel': 1e9, 'tan': 0.0})
    for c in pts:
        m_eff = 1.0 / (1.0 / m_o + c['lever'] ** 2 / p['inertia'])
        if c['n'] == 1.0:
            c['k'] = float(min(c['k'], 0.3 * m_eff / dt ** 2))
        c['lam'] = 1.5 * (1 - e) / max(p['v_app'], 0.005)
        c['cmax'] = 0.8 * m_eff / dt
        c['mu'] = p['mu_t'] * float(rng.choice([-1, 1]))
    p['contacts'] = pts
    if p['surf'] == 'plastic_tray':
        p['tray'] = {'m_s': float(rng.uniform(0.1, 0.4)), 'k_s': _draw(rng, ('log', 5e3, 4e4)),
                     'zeta_s': float(rng.uniform(0.03, 0.1))}
    if p['surf'] in ('foam_mat', 'towel'):  # thickness and folding vary the stiffness
        scale = float(rng.uniform(0.5, 2.0) if p['surf'] == 'foam_mat' else rng.uniform(1, 10))
        for c in pts:
            c['k'] *= scale
    p['tared'] = bool(rng.random() < p['p_tared'])
    p['modes'] = [{'f': _draw(rng, fam['f_mode']), 'zeta': _draw(rng, fam['zeta_mode']),
                   'm': _draw(rng, fam['m_mode']),
                   'kappa': _draw(rng, fam['kappa']) * float(rng.choice([-1, 1]))}
                  for _ in range(3)]
    p['coupling'] = rng.uniform(-0.3, 0.3, size=(3, 3)).tolist()
    if p['ctl'] == 'admittance' and family == 'heavy_slow':
        p['f_ref'] = p['f_ref'] * m_o * G
    # admittance v = (F_ref - F) / D, D tuned for stability: loop gain k_series L / D <= 0.5
    # with L the loop's total delay, unless the approach would be slower than 3 mm/s; the
    # free-space approach is min(v_app, F_ref / D)
    k_ser = 1.0 / (1.0 / p['k_arm'] + 1.0 / p['k_g'] + 1.0 / pts[-1]['k'])
    delay = p['latency'] + 1.5 / p['ft_rate'] + p['filt_tau'] + p['tau_servo']
    p['damp'] = max(p['f_ref'] / p['v_app'], min(k_ser * delay / 0.5, p['f_ref'] / 0.003))
    if p['ctl'] == 'admittance':
        p['v_app'] = min(p['v_app'], p['f_ref'] / p['damp'])
    _plan_timing(rng, p)
    return p


def _plan_timing(rng: np.random.Generator, p: dict) -> None:
    """Set clearance ``clear`` [m], ``t_move``, expected onset ``t_on_est`` and duration ``T``."""
    p['slowing'] = bool(rng.random() < p['p_slow']) and p['ctl'] != 'admittance'
    v_fast, v_slow = p['v_app'], p['v_app'] * p['slow_frac']
    clear = p['v_app'] * p['t_desc']
    p['t_move'] = p['t_rest']
    for _ in range(30):
        z_slow = clear + p['est_err'] - p['d_slow']
        if p['slowing']:
            d1 = min(max(z_slow, 0.0), clear)
            t_d = d1 / v_fast + (clear - d1) / v_slow
        else:
            t_d = clear / v_fast
        total = p['t_move'] + t_d + p['t_post'] + 0.2
        if total <= 9.8:
            break
        clear *= 0.85
    p['clear'] = max(clear, 0.002)
    p['z_slow'] = z_slow
    p['t_on_est'] = p['t_move'] + t_d
    p['T'] = float(min(max(total, 3.0 + rng.uniform(0, 0.5)), 10.0))


def _ev_params(rng: np.random.Generator, kind: str, p: dict) -> dict:
    """Parameters of one exogenous event (forces [N], durations [s], levels [Pa at 1 m])."""
    u = rng.uniform
    d = _unit(rng.normal(size=3)).tolist()
    if kind in ('knock_hand', 'knock_object'):
        hand = kind == 'knock_hand'
        return {'peak': u(5, 40) if hand else u(3, 25), 'dur': u(0.002, 0.008), 'dir': d,
                'mat': _draw(rng, ['aluminium', 'plastic']) if hand else p['obj'],
                'level': u(0.05, 0.5), 'pulse': u(5e-4, 1.5e-3)}
    if kind == 'knock_table':
        return {'mat': p['surf'], 'level': u(0.03, 0.5), 'dist_add': u(0.2, 0.6),
                'pulse': u(5e-4, 1.5e-3), 'vib': u(0.2e-6, 2e-6), 'f_vib': u(60, 200),
                'tau_vib': u(0.02, 0.06)}
    if kind == 'set_down':
        mat = _draw(rng, ['glass', 'ceramic', 'plastic', 'wood', 'steel', 'cardboard'])
        return {'mat': mat, 'level': u(0.03, 0.4), 'dist_add': u(0.5, 3.0),
                'pulse': u(*MATERIALS[mat][4:6]), 'vib': u(0.02e-6, 0.3e-6),
                'f_vib': u(60, 200), 'tau_vib': u(0.02, 0.06)}
    if kind in ('push_object', 'push_arm'):
        d[2] *= 0.6
        return {'peak': u(1, 8) if kind == 'push_object' else u(2, 15), 'dur': u(0.2, 1.5),
                'dir': _unit(np.array(d)).tolist()}
    if kind == 'brush':
        return {'drag': u(0.3, 3), 'lat': u(0.3, 2), 'dur': u(0.1, 0.6), 'f_ss': u(20, 80),
                'dir': d, 'level': u(3e-3, 3e-2)}
    if kind == 'door_slam':
        return {'level': u(2, 10), 'dist_add': u(3, 8)}
    if kind == 'speech':
        return {'level': u(0.01, 0.06), 'dur': u(0.6, 3.0), 'dist_add': u(1, 4)}
    return {'amp_f': (rng.normal(size=3) * u(0.1, 1.0) / 1.7).tolist(),
            'amp_t': (rng.normal(size=3) * u(0.005, 0.05) / 1.7).tolist(), 'tau': u(0.3, 2.0)}


def sample_events(*, rng: np.random.Generator, family: str, p: dict) -> list:
    """
    Sample the exogenous events of a trial.

    Each family event kind ``(prob, n_max)`` occurs with ``prob``, ``1..n_max`` times, each
    time before the expected onset (during the descent) with probability ``p_pre``, else
    anywhere in the bag (a brush on an obstacle only during the descent).

    Parameters
    ----------
    rng : numpy.random.Generator
        The trial's generator.
    family : str
        A key of ``FAMILIES``.
    p : dict
        The trial's parameters (:func:`sample_trial`).

    Returns
    -------
    list
        Dicts with ``kind``, ``t`` [s from bag start] and the event's parameters, by time.

    """
    out = []
    lo, hi = p['t_move'] + 0.1, p['t_on_est'] - 0.15
    for kind, (prob, n_max) in FAMILIES[family].get('events', {}).items():
        if rng.random() >= prob:
            continue
        for _ in range(int(rng.integers(1, n_max + 1))):
            ev = {'kind': kind, **_ev_params(rng, kind, p)}
            if kind == 'brush':
                if hi - ev['dur'] <= lo:
                    continue
                ev['t'] = float(rng.uniform(lo, hi - ev['dur']))
            elif rng.random() < p['p_pre'] and hi > lo:
                ev['t'] = float(rng.uniform(lo, hi))
            else:
                ev['t'] = float(rng.uniform(0.2, p['T'] - 0.3))
            out.append(ev)
    return sorted(out, key=lambda e: e['t'])


def exogenous_forces(*, p: dict, events: list, n: int) -> dict:
    """
    Turn the events into mechanics-rate inputs.

    Knocks are half-sine pulses ``P sin(pi t / T)``, pushes raised cosines, a brush a drag
    with stick-slip ``0.6 + 0.4 sawtooth(2 pi f t)``, table knocks a ring ``A e^(-t/tau)
    sin(2 pi f t)`` of the support, base vibration band-limited noise around 8-30 Hz.

    Parameters
    ----------
    p : dict
        The trial's parameters (:func:`sample_trial`).
    events : list
        From :func:`sample_events`.
    n : int
        Number of mechanics steps.

    Returns
    -------
    dict
        ``obj`` and ``hand`` (3, n) world forces [N] on object and gripper (measured),
        ``arm_z`` (n,) depth force on the arm (not measured), ``surf_w`` (n,) support and
        ``base_z`` (n,) robot-base depth displacements [m], ``base_lat`` (2, n) [m/s^2].

    """
    t = np.arange(n) / FS_MECH
    x = {'obj': np.zeros((3, n)), 'hand': np.zeros((3, n)), 'arm_z': np.zeros(n),
         'surf_w': np.zeros(n), 'base_z': np.zeros(n), 'base_lat': np.zeros((2, n))}
    for ev in events:
        k, tau = ev['kind'], t - ev['t']
        if k in ('knock_hand', 'knock_object'):
            win = (tau >= 0) & (tau < ev['dur'])
            shape = np.where(win, np.sin(np.pi * np.clip(tau, 0, None) / ev['dur']), 0.0)
            x['hand' if k == 'knock_hand' else 'obj'] += ev['peak'] * np.outer(ev['dir'], shape)
        elif k in ('knock_table', 'set_down'):
            ring = np.where(tau >= 0, np.exp(-np.clip(tau, 0, None) / ev['tau_vib'])
                            * np.sin(2 * np.pi * ev['f_vib'] * tau), 0.0)
            x['surf_w'] += ev['vib'] * ring
            if p['on_table']:
                x['base_z'] += 0.2 * ev['vib'] * ring
        elif k in ('push_object', 'push_arm'):
            win = (tau >= 0) & (tau < ev['dur'])
            shape = np.where(win, 0.5 - 0.5 * np.cos(2 * np.pi * tau / ev['dur']), 0.0)
            if k == 'push_object':
                x['obj'] += ev['peak'] * np.outer(ev['dir'], shape)
            else:
                x['arm_z'] -= ev['peak'] * ev['dir'][2] * shape
        elif k == 'brush':
            win = (tau >= 0) & (tau < ev['dur'])
            ss = 0.6 + 0.4 * signal.sawtooth(2 * np.pi * ev['f_ss'] * tau)
            arch = np.clip(np.sin(np.pi * np.clip(tau, 0, ev['dur']) / ev['dur']), 0, 1) ** 0.5
            env = np.where(win, arch, 0.0) * ss
            lat = np.array(ev['dir'][:2]) / (np.linalg.norm(ev['dir'][:2]) + 1e-9)
            x['obj'][2] += ev['drag'] * env
            x['obj'][:2] += ev['lat'] * np.outer(lat, env)
    if p['base_vib']:
        rng = np.random.default_rng(int(p['seed_mech']))
        f_b = rng.uniform(8, 30)
        b, a = signal.butter(2, [f_b * 0.7, f_b * 1.4], 'bandpass', fs=FS_MECH)
        acc = signal.lfilter(b, a, rng.normal(size=(3, n)), axis=1)
        acc *= p['base_vib'] / (acc.std() + 1e-12)
        x['base_lat'] += acc[:2]
        x['base_z'] -= acc[2] / (2 * np.pi * f_b) ** 2
    return x


def simulate(*, p: dict, exo: dict, n: int, ctl_noise: np.ndarray) -> dict:
    """
    Integrate the placing mechanics at ``FS_MECH`` for ``n`` steps.

    Hand: ``m_h a_h = k_arm (z_c + z_base - z_h) + c_arm (v_c - v_h) + F_gr - c m_o g + F_ext``
    with ``F_gr = k_g (z_o - z_h) + c_g (v_o - v_h)``; object ``m_o a_o = m_o g - F_gr - sum F_i
    + F_obj``; tilt ``I phi'' = -k_phi phi - c_phi phi' - sum F_i l_i``; contact ``i``
    penetration ``d_i = z_o - z_o0 + l_i phi - z_s - w - clear - off_i``. The controller runs
    at the F/T rate on the load ``m_g (g - a_h) + F_gr`` delayed by ``latency`` and low-passed.

    Parameters
    ----------
    p : dict
        The trial's parameters (:func:`sample_trial`).
    exo : dict
        From :func:`exogenous_forces`.
    n : int
        Number of steps.
    ctl_noise : numpy.ndarray
        Measurement noise [N or N m] the controller sees, cycled.

    Returns
    -------
    dict
        Arrays (n,): ``vc`` commanded velocity [m/s], ``ac`` its acceleration, ``ah``, ``ao``
        depth accelerations [m/s^2], ``al`` tilt acceleration [rad/s^2], ``fc`` (2, n) vertical
        contact forces [N], ``slide``; ``onset`` [s] or None, ``impacts`` [(t, i, speed)],
        ``t_trig`` controller trigger times.

    """
    dt = 1.0 / FS_MECH
    mh, mo, mg, inertia = p['m_h'], p['m_o'], p['m_g'], p['inertia']
    ka, kg, kph = p['k_arm'], p['k_g'], p['k_phi']
    ca = 2 * p['zeta_arm'] * math.sqrt(ka * mh)
    cg = 2 * p['zeta_g'] * math.sqrt(kg * mo)
    cph = 2 * p['zeta_phi'] * math.sqrt(kph * inertia)
    ff = mo * G if p['comp_load'] else 0.0
    cps = [(c['lever'], c['off'], c['k'], c['n'], c['lam'], c['sat'], c['rel'], c['cmax'])
           for c in p['contacts']]
    nc = len(cps)
    tray = p['tray']
    if tray:
        m_s, k_s = tray['m_s'], tray['k_s']
        c_s = 2 * tray['zeta_s'] * math.sqrt(k_s * m_s)
    fo = (-exo['obj'][2]).tolist()
    fh = (-exo['hand'][2]).tolist()
    fa, sw, bz = exo['arm_z'].tolist(), exo['surf_w'].tolist(), exo['base_z'].tolist()
    cn = ctl_noise.tolist()
    mode, react = p['ctl'], p['react']
    n_ctl = max(1, int(round(FS_MECH / p['ft_rate'])))
    n_lat = int(round(p['latency'] * FS_MECH))
    a_f = 1.0 - math.exp(-n_ctl * dt / p['filt_tau'])
    lever_ctl = abs(p['com_lat']) + p['base_r'] if p['thr_torque'] else 1.0
    use_thr = mode in ('guarded', 'impedance_stop')
    z_lim = p['clear'] + (p['imp_below'] if mode.startswith('imp') else 0.03)
    damp = p['damp']
    dvmax, dvstop = p['a_max'] * dt, p['a_stop'] * dt
    zc = vc = vt = vh = vo = ph = om = zs = vs = 0.0
    zh = (mo * G - ff) / ka
    zo = zh + mo * G / kg
    zo0 = zo
    phase, tare, filt, k_n, t_trig, z_trig = 0, 0.0, 0.0, 0, -1.0, 0.0
    onset, impacts, trig_times, rearmed = None, [], [], False
    inc = [False] * nc
    prev = [-1.0] * nc
    rec = {key: [0.0] * n for key in ('vc', 'ac', 'ah', 'ao', 'al', 'ld', 'slide')}
    fcs = [[0.0] * n for _ in range(nc)]
    ld = rec['ld']
    for i in range(n):
        t = i * dt
        if i % n_ctl == 0:
            meas = ld[i - n_lat] if i >= n_lat else ld[0] if i else mg * G + mo * G
            filt += a_f * (meas + cn[k_n % len(cn)] - filt)
            k_n += 1
            fext = tare - filt
            if phase == 0:
                vt = 0.0
                if t >= p['t_move']:
                    phase, tare = 1, filt
            elif phase == 1:
                if mode == 'admittance':
                    vt = min(max((p['f_ref'] - fext) / damp, -p['v_app']), p['v_app'])
                else:
                    vt = p['v_app'] * (p['slow_frac'] if p['slowing'] and zc > p['z_slow']
                                       else 1.0)
                    if zc >= z_lim:
                        vt = 0.0
                if use_thr and abs(fext) * lever_ctl > p['thr']:
                    phase, t_trig, z_trig = 2, t, zc
                    trig_times.append(t)
            else:
                if react == 'hold':
                    vt = 0.0
                elif react == 'backoff':
                    vt = -p['v_back'] if zc > z_trig - p['d_back'] else 0.0
                elif react == 'retract':
                    vt = -3 * p['v_app'] if zc > z_trig - 0.04 else 0.0
                else:
                    vt = 0.3 * p['v_app'] if t < t_trig + p['t_press'] else 0.0
                # a guarded move stopped in the air by a push is resumed (once) by the operator
                if (onset is None and not rearmed and t > t_trig + 0.5
                        and abs(fext) * lever_ctl < 0.5 * p['thr']):
                    phase, rearmed = 1, True
        dv = (vt - vc) * dt / p['tau_servo']
        lim = dvstop if (phase == 2 and vc > 0.0 and dv < 0.0) else dvmax  # guarded stop
        dv = lim if dv > lim else -lim if dv < -lim else dv
        vc += dv
        zc += vc * dt
        zb = zo - zo0 - zs - sw[i] - p['clear']
        vb = vo - vs
        ftot = mom = 0.0
        for j in range(nc):
            lev, off, k, ex, lam, sat, rel, cmax = cps[j]
            d = zb + lev * ph - off
            f = 0.0
            if d > 0.0:
                fe = k * d if ex == 1.0 else k * d ** ex
                fd = fe * lam
                f = fe + (cmax if fd > cmax else fd) * (vb + lev * om)
                f = 0.0 if f < 0.0 else f
                if f > sat:
                    f = sat
                    rec['slide'][i] = 1.0
                if d > rel:
                    f *= max(0.0, 1.0 - (d - rel) / 5e-4)
                if not inc[j]:
                    t_c = t - dt * d / (d - prev[j]) if prev[j] < 0 else t
                    impacts.append((t_c, j, vb + lev * om))
                    inc[j] = True
                    onset = t_c if onset is None else onset
            elif inc[j] and d < -1e-6:
                inc[j] = False
            prev[j] = d
            fcs[j][i] = f
            ftot += f
            mom += f * lev
        fgr = kg * (zo - zh) + cg * (vo - vh)
        ao = G - (fgr + ftot - fo[i]) / mo
        al = (-kph * ph - cph * om - mom) / inertia
        ah = (ka * (zc + bz[i] - zh) + ca * (vc - vh) + fgr - ff + fh[i] + fa[i]) / mh
        if tray:
            vs += (ftot - k_s * zs - c_s * vs) / m_s * dt
            zs += vs * dt
        vo, om, vh = vo + ao * dt, om + al * dt, vh + ah * dt
        zo, ph, zh = zo + vo * dt, ph + om * dt, zh + vh * dt
        ld[i] = mg * (G - ah) + fgr + fh[i]
        rec['vc'][i], rec['ac'][i], rec['ah'][i], rec['ao'][i], rec['al'][i] = (
            vc, dv / dt, ah, ao, al)
    out = {key: np.asarray(v) for key, v in rec.items()}
    out['fc'] = np.asarray(fcs)
    out.update(onset=onset, impacts=impacts, t_trig=trig_times)
    return out


def _modal_accel(u: np.ndarray, md: dict) -> np.ndarray:
    """Return a mode's acceleration [m/s^2] under force ``u`` [N]: ``s^2/(m(s^2+2zws+w^2))``."""
    w = 2 * math.pi * md['f']
    b, a = signal.bilinear([1.0, 0.0, 0.0], [md['m'], 2 * md['zeta'] * w * md['m'],
                                             w * w * md['m']], FS_MECH)
    return signal.lfilter(b, a, u)


def world_wrench(*, p: dict, mech: dict, exo: dict) -> np.ndarray:
    """
    Wrench (6, n) the tool exerts on the sensor, world frame (z up) at ``FS_MECH``.

    ``F = m_g (g - a_g) + F_hand + m_o (g - a_o) + sum F_i (n_i) + F_obj`` and ``M = r_g x
    (m_g (g - a_g) + F_hand) + r_com x (m_o (g - a_o) + F_obj) + sum r_i x F_i n_i - I phi''
    e_t``; accelerations include three structural modes (driven by the commanded acceleration,
    the contact and the external forces), gear ripple following the joint speed and base
    vibration.

    Parameters
    ----------
    p : dict
        The trial's parameters (:func:`sample_trial`).
    mech : dict
        From :func:`simulate`.
    exo : dict
        From :func:`exogenous_forces`.

    Returns
    -------
    numpy.ndarray
        (6, n) ``[Fx, Fy, Fz, Mx, My, Mz]`` [N, N m] about the sensor origin.

    """
    n = mech['vc'].size
    fc = mech['fc']
    u_tip = np.array(p['u_tip'])
    up = np.array([0.0, 0.0, 1.0])
    vec_c = []
    for j, c in enumerate(p['contacts']):
        nv = up - c['tan'] * np.sign(c['lever'] or 1.0) * u_tip + c['mu'] * u_tip
        vec_c.append(np.outer(nv, fc[j]))
    f_contact = sum(vec_c)
    drive = np.asarray(p['coupling']) @ (f_contact + exo['obj'] + exo['hand'])
    drive += f_contact + exo['obj'] + exo['hand']
    mode_acc = np.zeros((3, n))
    for ax, md in enumerate(p['modes']):
        u = drive[ax] + md['kappa'] * p['m_h'] * mech['ac']
        if ax < 2:
            u = u + md['m'] * exo['base_lat'][ax]
        mode_acc[ax] = _modal_accel(u, md)
    speed = np.abs(mech['vc'])
    phase = 2 * np.pi * np.cumsum(p['ripple_hz_per_mps'] * speed) / FS_MECH
    wobble = signal.lfilter([1.0], [1, -0.998], np.random.default_rng(p['seed_mech']).normal(
        size=n))
    wobble /= wobble.std() + 1e-12  # slowly varying amplitude, unit rms
    ripple = p['ripple'] * np.minimum(speed / p['v_app'], 2.0) * (1 + 0.5 * wobble) * np.sin(phase)
    g_vec = np.array([0.0, 0.0, -G])[:, None]
    a_g = mode_acc + np.vstack([np.zeros((2, n)), -(mech['ah'] + ripple)])
    a_o = mode_acc + np.vstack([np.zeros((2, n)), -(mech['ao'] + ripple)])
    load_g = p['m_g'] * (g_vec - a_g) + exo['hand']
    load_o = p['m_o'] * (g_vec - a_o) + exo['obj']
    force = load_g + load_o + f_contact
    r_g, r_com = np.array(p['r_g'])[:, None], np.array(p['r_com'])[:, None]
    torque = np.cross(r_g, load_g, axis=0) + np.cross(r_com, load_o, axis=0)
    for j, c in enumerate(p['contacts']):
        r_c = r_com[:, 0] + c['lever'] * u_tip - p['bottom'] * up
        torque += np.cross(r_c[:, None], vec_c[j], axis=0)
    e_t = np.cross(up, u_tip)
    torque -= np.outer(e_t, p['inertia'] * mech['al'])
    return np.vstack([force, torque])


def sensor_samples(*, rng: np.random.Generator, p: dict, wrench_w: np.ndarray,
                   events: list) -> tuple:
    """
    Sample the sensor as a driver publishes it.

    Rotate to the sensor frame, average over each period, add bias/tare, drift, temperature
    steps, noise and quantisation, drop messages and maybe leave a gap.

    Parameters
    ----------
    rng : numpy.random.Generator
        The trial's generator.
    p : dict
        The trial's parameters (:func:`sample_trial`).
    wrench_w : numpy.ndarray
        (6, n) world wrench at ``FS_MECH`` (:func:`world_wrench`).
    events : list
        The trial's events (``thermal_step`` ones are applied).

    Returns
    -------
    tuple
        ``(t, values, losses)``: sample times (m,) [s from bag start] (the end of each
        averaging period), values (m, 6) ``[Fx, Fy, Fz, Tx, Ty, Tz]`` [N, N m] and a list of
        dropped-data dicts.

    """
    rot = np.asarray(p['R'])
    n = wrench_w.shape[1]
    ws = np.vstack([rot.T @ wrench_w[:3], rot.T @ wrench_w[3:]])
    period = 1.0 / p['ft_rate']
    t = np.arange(rng.uniform(period, 2 * period), n / FS_MECH, period)
    cum = np.concatenate([np.zeros((6, 1)), np.cumsum(ws, axis=1)], axis=1) / FS_MECH
    grid = np.arange(n + 1) / FS_MECH
    val = np.stack([(np.interp(t, grid, c) - np.interp(t - period, grid, c)) / period
                    for c in cum], axis=1)
    if p['tared']:
        val -= val[t < 0.2].mean(axis=0) + rng.normal(0, 0.02, 6) * [1, 1, 1, .05, .05, .05]
    else:
        val += np.concatenate([rng.normal(0, p['bias_f'], 3), rng.normal(0, p['bias_t'], 3)])
    drift = np.concatenate([rng.normal(0, p['drift_f'], 3), rng.normal(0, p['drift_t'], 3)])
    val += np.outer(t / 60.0, drift)
    for ev in events:
        if ev['kind'] == 'thermal_step':
            step = np.where(t > ev['t'], 1 - np.exp(-np.clip(t - ev['t'], 0, None) / ev['tau']),
                            0.0)
            val += np.outer(step, ev['amp_f'] + ev['amp_t'])
    sig = np.array([p['noise_f']] * 3 + [p['noise_t']] * 3)
    val += rng.normal(size=val.shape) * sig
    for cols, q in ((slice(0, 3), p['q_f']), (slice(3, 6), p['q_t'])):
        if q:
            val[:, cols] = np.round(val[:, cols] / q) * q
    keep = np.ones(t.size, bool)
    losses = []
    if rng.random() < p['p_drop']:
        for k in rng.integers(10, t.size - 10, size=int(rng.integers(1, 4))):
            keep[k] = False
            losses.append({'kind': 'ft_dropped_message', 't': float(t[k])})
    if rng.random() < p['p_gap']:
        t0, dur = rng.uniform(0.3, t[-1] - 0.3), rng.uniform(0.02, 0.05)
        keep &= ~((t >= t0) & (t < t0 + dur))
        losses.append({'kind': 'ft_gap', 't': float(t0), 'dur': float(dur)})
    return t[keep], val[keep], losses


def _modal_sound(rng: np.random.Generator, fs: float, mat: str, peak: float,
                 pulse: float) -> np.ndarray:
    """
    Impact sound [Pa at 1 m] of ``mat``: ``sum_k a_k W(f_k) exp(-t/tau_k) sin(2 pi f_k t)``.

    ``W(f) = (1 + (f pulse / 0.6)^4)^-1/2`` is the low-pass of a contact pulse of duration
    ``pulse`` [s], so long (soft) contacts excite no high mode; ``peak`` is the level of a
    hard impact, plus a click of the pulse's own duration.
    """
    f_lo, f_hi, t_lo, t_hi = MATERIALS[mat][:4]
    nm = int(rng.integers(4, 11))
    f = np.exp(rng.uniform(math.log(f_lo), math.log(f_hi), nm))
    f = f[f < 0.45 * fs]
    if f.size == 0 or peak <= 0:
        return np.zeros(1)
    tau = np.exp(rng.uniform(math.log(t_lo), math.log(t_hi), f.size)) * (f_lo / f) ** 0.3
    amp = rng.uniform(0.3, 1.0, f.size) * (f / f_lo) ** -0.3
    amp *= peak / np.sqrt(np.sum(amp ** 2))
    w = (1 + (f * pulse / 0.6) ** 4) ** -0.5
    nclick = max(int(pulse * fs), 2)
    tt = np.arange(max(int(fs * min(4 * tau.max(), 1.5)), nclick) + 1) / fs
    y = (amp * w) @ (np.exp(-tt[None, :] / tau[:, None]) * np.sin(2 * np.pi * np.outer(f, tt)))
    click = rng.normal(size=nclick) * np.hanning(nclick) * peak * 0.3 * min(1.0, 3e-4 / pulse)
    y[:nclick] += click
    return y


def _speech(rng: np.random.Generator, fs: float, dur: float, level: float) -> np.ndarray:
    """Speech-like sound [Pa at 1 m, rms ``level``]: a voiced source through syllable formants."""
    n = int(dur * fs)
    tt = np.arange(n) / fs
    f0 = rng.uniform(90, 240) * (1 + 0.12 * np.sin(2 * np.pi * rng.uniform(0.3, 1.2) * tt))
    src = signal.sawtooth(2 * np.pi * np.cumsum(f0) / fs) + 0.3 * rng.normal(size=n)
    out = np.zeros(n)
    pos = 0
    while pos < n:
        seg = int(rng.uniform(0.08, 0.3) * fs)
        x = src[pos:pos + seg]
        y = np.zeros(x.size)
        for lo_hi in ((300, 850), (850, 2300), (2300, 3200)):
            fr = rng.uniform(*lo_hi)
            if fr < 0.45 * fs:
                b, a = signal.iirpeak(fr, fr / 90.0, fs)
                y += signal.lfilter(b, a, x) / (1 + lo_hi[0] / 1000)
        if rng.random() < 0.3 and fs > 12000:  # fricative
            b, a = signal.butter(2, [3000, min(8000, 0.45 * fs)], 'bandpass', fs=fs)
            y += 0.5 * signal.lfilter(b, a, rng.normal(size=x.size))
        out[pos:pos + x.size] = y * np.hanning(x.size)
        pos += seg + int(rng.uniform(0.02, 0.15) * fs)
    return out * level / (out.std() + 1e-12)


def _event_sound(rng: np.random.Generator, fs: float, ev: dict) -> np.ndarray:
    """Dry sound [Pa at 1 m] of one exogenous event."""
    k = ev['kind']
    if k in ('knock_hand', 'knock_object', 'knock_table', 'set_down'):
        return _modal_sound(rng, fs, ev['mat'], ev['level'], ev['pulse'])
    if k == 'door_slam':
        thump = _modal_sound(rng, fs, 'wood_table', ev['level'], 2e-3)
        rattle = _modal_sound(rng, fs, 'wood', 0.3 * ev['level'], 5e-4)
        m = max(thump.size, rattle.size)
        return np.pad(thump, (0, m - thump.size)) + np.pad(rattle, (0, m - rattle.size))
    if k == 'speech':
        return _speech(rng, fs, ev['dur'], ev['level'])
    if k == 'brush':
        n = int(ev['dur'] * fs)
        b, a = signal.butter(2, [400, min(4000, 0.45 * fs)], 'bandpass', fs=fs)
        tt = np.arange(n) / fs
        env = np.sin(np.pi * tt / ev['dur']) * (0.6 + 0.4 * signal.sawtooth(
            2 * np.pi * ev['f_ss'] * tt))
        y = signal.lfilter(b, a, rng.normal(size=n)) * env
        return y * ev['level'] / (y.std() + 1e-12)
    return np.zeros(1)


def synth_audio(*, rng: np.random.Generator, p: dict, mech: dict, events: list) -> dict:
    """
    Microphone signal over the bag.

    Sound pressure at the mic [Pa] = room noise (pink, HVAC rumble, mains hum, fans) + ego
    noise (motor whine and gear mesh at frequencies proportional to the joint speed ``|v_c|``)
    + every source ``s(t - r/c) / r`` (direct) + its reverberant part (exponential tail of
    ``rt60``, critical distance ``r_c``); digital = clip(pressure 10^((-32 + gain)/20)).

    Parameters
    ----------
    rng : numpy.random.Generator
        The trial's generator.
    p : dict
        The trial's parameters (:func:`sample_trial`).
    mech : dict
        From :func:`simulate` (impacts with their speeds, commanded velocity).
    events : list
        The trial's events.

    Returns
    -------
    dict
        ``x`` samples (int16 or float32), ``t_first`` [s] time of sample 0, ``fs_true``
        [Hz] the device's actual rate, ``clipped`` bool, ``gain_db``.

    """
    ap = p['audio']
    fs = float(ap['rate'])
    fs_true = fs * (1 + ap['ppm'] * 1e-6)
    n = int((p['T'] - ap['t0']) * fs_true)
    tt = ap['t0'] + np.arange(n) / fs_true
    freqs = np.fft.rfftfreq(n, 1 / fs)
    spec = np.fft.rfft(rng.normal(size=n)) / np.sqrt(np.maximum(freqs, 20.0))
    room = np.fft.irfft(spec, n)
    room *= p['pink'] / room.std()
    b, a = signal.butter(2, 200, fs=fs)
    hv = signal.lfilter(b, a, rng.normal(size=n))
    room += p['hvac'] * hv / hv.std() * (1 + 0.2 * np.sin(2 * np.pi * 0.2 * tt))
    mains = float(rng.choice([50.0, 60.0]))
    for h in (1, 2, 3):
        room += p['hum'] / h * np.sin(2 * np.pi * mains * h * tt + rng.uniform(0, 6.3))
    f_fan = rng.uniform(80, 250)
    for h in (1, 2, 3, 4):
        room += p['fan'] / h * np.sin(2 * np.pi * f_fan * h * tt + rng.uniform(0, 6.3))
    r_mic = p['mic_dist']
    speed = np.abs(np.interp(tt, np.arange(mech['vc'].size) / FS_MECH, mech['vc']))
    rel = np.minimum(speed / p['v_app'], 2.0)
    f_w = rng.uniform(200, 900) * rel
    ph = 2 * np.pi * np.cumsum(f_w) / fs
    gear = rng.uniform(3, 8)
    ego = sum(np.sin(h * ph) / h * (h * f_w < 0.45 * fs) for h in (1, 2, 3, gear))
    ego *= p['whine'] / max(r_mic, 0.2) * rel ** 0.8
    direct, rev = np.zeros(n), np.zeros(n)
    r_crit = rng.uniform(0.5, 1.5)

    def place(y: np.ndarray, t_emit: float, dist: float) -> None:
        i0 = int(round((t_emit + dist / C_AIR - ap['t0']) * fs_true))
        if i0 >= n or i0 + y.size <= 0:
            return
        lo, hi = max(i0, 0), min(i0 + y.size, n)
        direct[lo:hi] += y[lo - i0:hi - i0] / max(dist, 0.1)
        rev[lo:hi] += y[lo - i0:hi - i0] / r_crit

    for t_c, j, v in mech['impacts']:
        if v <= 1e-4:
            continue
        scale = (v / REF_V) * math.sqrt(p['m_o'] / REF_M)
        pulse = p['pulse'] * (max(v, 1e-3) / REF_V) ** -0.2
        for mat in (p['obj'], p['surf']):
            place(_modal_sound(rng, fs, mat, MATERIALS[mat][6] * scale, pulse), t_c, r_mic)
    slide = mech['slide']
    if slide.any():  # metal-on-chamfer scraping while the peg slides
        env = np.interp(tt, np.arange(slide.size) / FS_MECH, slide)
        b, a = signal.butter(2, [1500, min(8000, 0.45 * fs)], 'bandpass', fs=fs)
        direct += 0.01 / r_mic * env * signal.lfilter(b, a, rng.normal(size=n))
    for ev in events:
        if ev['kind'] not in ('thermal_step', 'push_arm', 'push_object'):
            place(_event_sound(rng, fs, ev), ev['t'], max(r_mic + ev.get('dist_add', 0.0), 0.2))
    nr = int(p['rt60'] * fs)
    tail = rng.normal(size=nr) * np.exp(-6.9 * np.arange(nr) / nr)
    tail[:int(0.004 * fs)] = 0.0
    tail /= np.sqrt(np.sum(tail ** 2))
    pa = room + ego + direct + signal.fftconvolve(rev, tail)[:n]
    gain_db = p['gain_db']
    x = pa * 10 ** ((-32.0 + gain_db) / 20) + rng.normal(0, 10 ** (rng.uniform(-85, -70) / 20), n)
    b, a = signal.butter(1, rng.uniform(20, 80), 'highpass', fs=fs)
    x = signal.lfilter(b, a, x) + rng.uniform(-0.002, 0.002)
    clipped = bool(np.any(np.abs(x) > 1.0))
    x = np.clip(x, -1.0, 1.0)
    if ap['type'] == 'int16':
        x = np.round(x * 32767).astype(np.int16)
    else:
        x = x.astype(np.float32)
    return {'x': x, 't_first': ap['t0'], 'fs_true': fs_true, 'clipped': clipped,
            'gain_db': gain_db}


def write_bag(*, path: Path, container: str, p: dict, t0_ns: int, ft: tuple,
              audio: dict, rng: np.random.Generator) -> None:
    """
    Write the trial's bag: ROS 1 ``.bag`` (``container='ros1'``) or a rosbag2 directory.

    Wrench header stamps are the sample times, log times stamp + 0.5-5 ms; an audio chunk's
    log time is its last sample's time + 1-5 ms (audio messages carry no stamp).

    Parameters
    ----------
    path : pathlib.Path
        The ``.bag`` file or rosbag2 directory (replaced if it exists).
    container : str
        ``'ros1'``, ``'sqlite3'`` or ``'mcap'``.
    p : dict
        The trial's parameters (:func:`sample_trial`).
    t0_ns : int
        Absolute time [ns] of the bag's start.
    ft : tuple
        From :func:`sensor_samples`.
    audio : dict or None
        From :func:`synth_audio`, None for no microphone.
    rng : numpy.random.Generator
        For log-time jitter and ROS 1 chunk compression.

    """
    ros1 = container == 'ros1'
    ts = TS1 if ros1 else TS2
    T = ts.types
    t, val, _ = ft
    msgs = []
    lat_hi = p['log_lat']
    stamps = (t0_ns + np.round(t * 1e9)).astype(np.int64)
    logs = stamps + (rng.uniform(0.0005, lat_hi, t.size) * 1e9).astype(np.int64)
    logs = np.maximum.accumulate(logs)
    wt = 'geometry_msgs/msg/WrenchStamped'
    for k in range(t.size):
        sec, nsec = divmod(int(stamps[k]), 10 ** 9)
        hdr = {'stamp': T['builtin_interfaces/msg/Time'](sec=sec, nanosec=nsec),
               'frame_id': p['frame']}
        if ros1:
            hdr['seq'] = k
        v = val[k].tolist()
        msg = T[wt](header=T['std_msgs/msg/Header'](**hdr), wrench=T['geometry_msgs/msg/Wrench'](
            force=T['geometry_msgs/msg/Vector3'](x=v[0], y=v[1], z=v[2]),
            torque=T['geometry_msgs/msg/Vector3'](x=v[3], y=v[4], z=v[5])))
        msgs.append((int(logs[k]), 0, ts.serialize_ros1(msg, wt) if ros1
                     else ts.serialize_cdr(msg, wt)))
    topics = [(p['ft_topic'], wt)]
    if audio is not None:
        ap = p['audio']
        at = ('std_msgs/msg/Int16MultiArray' if ap['type'] == 'int16'
              else 'std_msgs/msg/Float32MultiArray')
        topics.append((ap['topic'], at))
        x, ch = audio['x'], ap['chunk']
        prev = 0
        for c in range(x.size // ch):
            data = x[c * ch:(c + 1) * ch]
            t_last = audio['t_first'] + ((c + 1) * ch - 1) / audio['fs_true']
            log = max(t0_ns + int((t_last + rng.uniform(0.001, 0.005)) * 1e9), prev + 1)
            prev = log
            dims = [T['std_msgs/msg/MultiArrayDimension'](label='samples', size=ch, stride=ch)]
            msg = T[at](layout=T['std_msgs/msg/MultiArrayLayout'](
                dim=dims if ap['layout_dim'] else [], data_offset=0), data=data)
            msgs.append((log, 1, (ts.serialize_ros1 if ros1 else ts.serialize_cdr)(msg, at)))
    msgs.sort(key=lambda m: m[0])
    if path.exists():
        shutil.rmtree(path) if path.is_dir() else path.unlink()
    if ros1:
        writer = Ros1Writer(path)
        comp = _draw(rng, [None, None, Ros1Writer.CompressionFormat.LZ4,
                           Ros1Writer.CompressionFormat.BZ2])
        if comp is not None:
            writer.set_compression(comp)
    else:
        plugin = StoragePlugin.MCAP if container == 'mcap' else StoragePlugin.SQLITE3
        writer = Ros2Writer(path, version=9, storage_plugin=plugin)
    with writer:
        conns = [writer.add_connection(tp, ty, typestore=ts) for tp, ty in topics]
        for log, c, data in msgs:
            writer.write(conns[c], log, data)


def _run_task(task: tuple) -> dict:
    """Call :func:`run_trial` on ``(out_dir, family, index, seed)`` (for ``Executor.map``)."""
    out_dir, family, idx, seed = task
    return run_trial(out_dir=out_dir, family=family, idx=idx, seed=seed)


def run_trial(*, out_dir: str, family: str, idx: int, seed: int) -> dict:
    """
    Generate, simulate and write one trial.

    Parameters
    ----------
    out_dir : str
        Output folder; the bag goes to ``out_dir/family/name``.
    family : str
        A key of ``FAMILIES``.
    idx : int
        Trial index within the family.
    seed : int
        Base seed; the generator is seeded with ``(seed, crc32(family), idx)``.

    Returns
    -------
    dict
        The trial record for ``trials.json`` (parameters, events with absolute times, onset).

    """
    fam_key = zlib.crc32(family.encode())
    rng = np.random.default_rng([seed, fam_key, idx])
    for attempt in range(6):
        p = sample_trial(rng=rng, family=family)
        p['seed_mech'] = int(rng.integers(2 ** 31))
        p['ripple_hz_per_mps'] = float(rng.uniform(20, 80)) / p['v_app']
        events = sample_events(rng=rng, family=family, p=p)
        n = int(p['T'] * FS_MECH)
        exo = exogenous_forces(p=p, events=events, n=n)
        sig_ctl = (p['noise_t'] if p['thr_torque'] else p['noise_f'])
        mech = simulate(p=p, exo=exo, n=n, ctl_noise=rng.normal(0, sig_ctl, 4096))
        if mech['onset'] is not None and mech['onset'] < p['T'] - 0.8:
            break
    else:
        raise RuntimeError(f'{family} {idx}: no contact after {attempt + 1} attempts')
    wrench = world_wrench(p=p, mech=mech, exo=exo)
    ft = sensor_samples(rng=rng, p=p, wrench_w=wrench, events=events)
    audio = synth_audio(rng=rng, p=p, mech=mech, events=events) if 'audio' in p else None
    start = datetime.datetime(2026, 5, 3, 9, 0, 0, tzinfo=datetime.timezone.utc)
    start += datetime.timedelta(seconds=int(fam_key % 3600) * 7 + idx * 420
                                + int(rng.integers(0, 400)))  # unique, increasing names
    t0_ns = int(start.timestamp()) * 10 ** 9 + int(rng.integers(0, 10 ** 9))
    style, container = FAMILIES[family]['names'], FAMILIES[family]['container']
    if style == 'date':
        name = start.strftime('%Y-%m-%d-%H-%M-%S')
    elif style == 'ros2date':
        name = start.strftime('rosbag2_%Y_%m_%d-%H_%M_%S')
    else:
        name = f'{style}_{idx:03d}'
    name += '.bag' if container == 'ros1' else ''
    rel = f'{family}/{name}'
    path = Path(out_dir) / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bag(path=path, container=container, p=p, t0_ns=t0_ns, ft=ft, audio=audio, rng=rng)
    t0 = t0_ns / 1e9
    for ev in events + ft[2]:
        ev['t_abs'] = t0 + ev['t']
        ev['before_onset'] = ev['t'] < mech['onset']
    return {'bag': rel, 'family': family, 'index': idx, 'container': container,
            'onset': t0 + mech['onset'], 'onset_rel': mech['onset'], 't_start': t0,
            'duration': p['T'], 'attempts': attempt + 1, 'params': p,
            'events': events, 'data_losses': ft[2],
            'impacts': [{'t_abs': t0 + a, 'point': b, 'speed': c} for a, b, c in mech['impacts']],
            'controller_triggers_abs': [t0 + x for x in mech['t_trig']],
            'audio': None if audio is None else {
                'clipped': audio['clipped'], 'fs_true': audio['fs_true'],
                'first_sample_abs': t0 + audio['t_first']}}


def main(argv: list | None = None) -> int:
    """Parse arguments, generate the trials (in parallel with ``--jobs``), write the labels."""
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    ap.add_argument('out_dir', type=Path)
    ap.add_argument('--trials-per-family', type=int, default=20)
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--families', default=','.join(FAMILIES))
    ap.add_argument('--jobs', type=int, default=1)
    args = ap.parse_args(argv)
    fams = [f for f in args.families.split(',') if f]
    bad = [f for f in fams if f not in FAMILIES]
    if bad:
        print(f'unknown families {bad}; known: {", ".join(FAMILIES)}', file=sys.stderr)
        return 2
    args.out_dir.mkdir(parents=True, exist_ok=True)
    tasks = [(str(args.out_dir), f, i, args.seed) for f in fams
             for i in range(args.trials_per_family)]
    if args.jobs > 1:
        with futures.ProcessPoolExecutor(args.jobs) as pool:
            records = list(pool.map(_run_task, tasks, chunksize=1))
    else:
        records = [_run_task(t) for t in tasks]
    with open(args.out_dir / 'labels.csv', 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['bag', 'onset_start', 'onset_end'])
        for r in records:
            w.writerow([r['bag'], f'{r["onset"]:.6f}', f'{r["onset"]:.6f}'])
    with open(args.out_dir / 'trials.json', 'w') as fh:
        json.dump({'generator': 'benchmarks/independent_robots.py', 'seed': args.seed,
                   'fs_mech': FS_MECH, 'trials': records}, fh, indent=1,
                  default=lambda o: o.item() if isinstance(o, np.generic) else o.tolist())
    print(f'{len(records)} trials in {args.out_dir}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
