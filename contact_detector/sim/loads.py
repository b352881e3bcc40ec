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
The wrist force/torque of a simulated trial: loads on the sensor, the contact, the stop rule.

:func:`wrench` sums the loads (weights, inertia, the table's reaction and friction, the impact
pulse, the structural mode, liquid slosh, motor ripple, the events of :mod:`.hits`) as
``(scalar series, direction, point)`` terms into force and ``r x F`` torque, then applies the
sensor (averaging, bias, drift, noise, tare, quantisation). :func:`first_crossing` is the
robot's stop rule on the measured wrench.
"""

from dataclasses import dataclass
import math

from contact_detector.sim.geometry import Geometry
from contact_detector.sim.hits import Hit
from contact_detector.sim.params import FamilyParams, TrialParams
from contact_detector.sim.signals import (causal_conv, half_sine, mode_ir, ramp_motion,
                                          unit)
from contact_detector.sim.timeline import BASELINE_WINDOW_S, Timeline
import numpy as np

#: Gravity in m/s^2.
G = 9.81
#: The recorded robot's stop rule: |T_y - baseline| >= this, in N m (paper: -3 N m on T_y).
STOP_TORQUE_NM = 3.0
#: Stop rules on vectors ('force', 'wrench', 'load') average the wrench over this window (s).
STOP_SMOOTH_S = 0.03


@dataclass(frozen=True)
class SensorErrors:
    """
    What the F/T sensor adds to the true wrench, drawn once for the longest possible trial.

    Attributes
    ----------
    bias_f, bias_t : np.ndarray, shape (3,)
        Constant bias, N and N m.
    drift : list of (np.ndarray, np.ndarray, float, float)
        Slow sinusoidal drift terms: force and torque amplitudes (3,), period in s, phase.
    noise_f, noise_t : np.ndarray, shape (n_max, 3)
        Unit normal noise per output sample (scaled by ``force_noise_n``, ``torque_noise_nm``).

    """

    bias_f: np.ndarray
    bias_t: np.ndarray
    drift: list
    noise_f: np.ndarray
    noise_t: np.ndarray


def draw_sensor_errors(*, p: TrialParams, rng: np.random.Generator,
                       n_max: int) -> SensorErrors:
    """Draw the bias, drift and noise of ``n_max`` output samples from the noise stream."""
    bias_f = unit(rng.normal(size=3)) * p.force_bias_n
    bias_t = unit(rng.normal(size=3)) * p.torque_bias_nm
    drift = []
    weights = rng.uniform(0.3, 1.0, 3)
    weights /= weights.sum()
    for w in weights:
        drift.append((w * p.force_drift_n * unit(rng.normal(size=3)),
                      w * p.torque_drift_nm * unit(rng.normal(size=3)),
                      float(rng.uniform(4.0, 40.0)), float(rng.uniform(0, 2 * np.pi))))
    noise_f = rng.standard_normal((n_max, 3))
    noise_t = rng.standard_normal((n_max, 3))
    return SensorErrors(bias_f=bias_f, bias_t=bias_t, drift=drift, noise_f=noise_f,
                        noise_t=noise_t)


@dataclass(frozen=True)
class Contact:
    """
    The contact law and the robot's stop thresholds.

    Attributes
    ----------
    k_eff : float
        Stiffness of arm and surface in series, N/m (the compliant family: set so the weight
        moves to the table in ``transfer_s``).
    ctau : float
        Lag of the load transfer, s.
    thr_f, thr_t : float
        Thresholds of the vector stop rules on ``|F - F_base|`` (N) and ``|T - T_base|``
        (N m); ``inf`` where the rule does not use it.

    """

    k_eff: float
    ctau: float
    thr_f: float
    thr_t: float


def contact_law(*, p: TrialParams, q: FamilyParams, m_obj: float, v_c: float) -> Contact:
    """Return the stiffness, lag and stop thresholds of a trial (contact speed ``v_c`` m/s)."""
    k_eff = 1.0 / (1.0 / p.arm_stiffness_npm + 1.0 / p.surface_stiffness_npm)
    ctau = p.contact_tau_s
    if q.contact_model == 'compliant':
        # the object's weight moves to the table in about transfer_s
        k_eff = m_obj * G / (v_c * q.transfer_s)
        ctau = q.transfer_s / 4
    thr_f, thr_t = 0.0, math.inf
    if q.stop_rule in ('force', 'wrench'):
        thr_f = q.stop_force_n
        thr_t = q.stop_torque_nm if q.stop_rule == 'wrench' else math.inf
    elif q.stop_rule == 'load':
        thr_f = max(1.0, q.stop_load_frac * m_obj * G)
    return Contact(k_eff=k_eff, ctau=ctau, thr_f=thr_f, thr_t=thr_t)


def nominal_stop(*, q: FamilyParams, geo: Geometry, contact: Contact, tl: Timeline) -> float:
    """Noise-free time of the stop in s from the trial start (to place the events)."""
    r_contact, up, onset, v_c = geo.r_contact, geo.up, tl.onset, tl.v_c
    k_eff, ctau, thr_f, thr_t = contact.k_eff, contact.ctau, contact.thr_f, contact.thr_t
    if q.stop_rule == 'torque_y':
        lever_y = abs(float(np.cross(r_contact, up)[1]))
        n_need = STOP_TORQUE_NM / max(lever_y, 1e-3)
    else:
        lever = float(np.linalg.norm(np.cross(r_contact, up)))
        n_need = min(thr_f, thr_t / max(lever, 1e-3))
    if q.contact_model == 'spring':
        tau = n_need / (k_eff * v_c)
    else:
        tau = n_need / (k_eff * v_c)
        for _ in range(20):
            tau = n_need / (k_eff * v_c) / max(1e-6, 1 - math.exp(-tau / ctau))
    stop_est = onset + tau
    return stop_est


@dataclass(frozen=True)
class Setup:
    """
    Everything the F/T synthesis needs besides the stop time (derived from the parameters).

    Attributes
    ----------
    p, q : TrialParams, FamilyParams
        The trial's parameters.
    ft_rate : float
        Output rate, Hz.
    os : int
        Internal oversampling factor.
    geo : Geometry
    sensor : SensorErrors
    tl : Timeline
        The approach (before the stop).
    base_ramps : list of (dv, t0, d)
        Velocity ramps of the approach.
    k_eff, ctau : float
        Contact stiffness in N/m and lag in s (:class:`Contact`).
    thr_f, thr_t : float
        The vector stop rules' thresholds in N and N m, as used (possibly raised).

    """

    p: TrialParams
    q: FamilyParams
    ft_rate: float
    os: int
    geo: Geometry
    sensor: SensorErrors
    tl: Timeline
    base_ramps: list
    k_eff: float
    ctau: float
    thr_f: float = 0.0
    thr_t: float = 0.0


def wrench(s: Setup, *, n_out: int, ramps: list, tl: Timeline, hits: list[Hit],
           anchors: dict, hit_scale: float) -> tuple[np.ndarray, np.ndarray, float]:
    """
    Measured force and torque on the output grid ``j / ft_rate``, j < n_out.

    Physical signals are built at ``os * ft_rate`` and averaged over each output period (the
    sensor's ADC decimation, causal), then bias, drift, noise and quantisation are added.
    Returns ``(force (n_out, 3), torque (n_out, 3), contact_end_rel)``.
    """
    p = s.p
    rate = s.ft_rate * s.os
    dt = 1.0 / rate
    t = (np.arange(n_out * s.os) - s.os + 1) * dt
    z, v, a = ramp_motion(ramps, t)
    onset = tl.onset
    z_contact = tl.z_contact
    # lift-off: first time after the retreat starts where the hand is back above contact height
    t_end = math.inf
    if tl.t_r0 is not None:
        after = np.nonzero((t > tl.t_r0) & (z >= z_contact))[0]
        if len(after):
            i = after[0]
            z0, z1 = z[i - 1], z[i]
            t_end = float(t[i - 1] + (z_contact - z0) / (z1 - z0) * dt) if z1 > z0 else t[i]
    in_contact = (t >= onset) & (t < t_end)
    depth = np.where(in_contact, np.maximum(z_contact - z, 0.0), 0.0)
    tau = np.maximum(t - onset, 0.0)
    if s.q.contact_model == 'spring':
        normal = s.k_eff * depth
    else:
        normal = s.k_eff * depth * (1 - np.exp(-tau / s.ctau))
    if tl.t_s is not None:
        since = np.maximum(t - tl.t_s, 0.0)
        normal *= 1 - p.creep * (1 - np.exp(-since / 0.3))
    a_eff = np.where(in_contact, 0.0, a)
    m_load = s.geo.m_obj + s.geo.m_hand
    v_d = p.descent_speed_mps

    comps = []  # (scalar series, direction (3,), point (3,))
    comps.append((-s.geo.m_obj * (G + a_eff), s.geo.up, s.geo.r_obj))
    # a tool-compensated sensor removes the hand's static weight (not its inertia)
    g_hand = 0.0 if s.q.tool_compensated else G
    comps.append((-s.geo.m_hand * (g_hand + a_eff), s.geo.up, s.geo.r_hand))
    comps.append((normal, s.geo.up, s.geo.r_contact))
    comps.append((p.friction * normal, s.geo.fric_dir, s.geo.r_contact))

    # contact impact pulse
    j_imp = (s.geo.m_obj + 0.5 * s.geo.m_hand) * tl.v_c * p.impact_transmission * 0.5
    d_imp = p.impact_duration_s
    comps.append((half_sine(t, onset, d_imp, j_imp * np.pi / (2 * d_imp)), s.geo.up,
                  s.geo.r_contact))

    # structural mode: impulses (N s) at motion jerks, impact, lift-off; plus hit pulses
    exc = np.zeros_like(t)

    def impulse(t0: float, j: float) -> None:
        i = int(round((t0 - t[0]) / dt))
        if 0 <= i < len(exc):
            exc[i] += j / dt

    # a velocity step dv gives a ring-down of peak ~ jerk_gain m |dv| 2 pi 8 Hz, for any mode
    jerk = p.jerk_gain * 2 * np.pi * 8.0 / (2 * np.pi * p.mode_hz)
    for dv, t0, d in ramps:
        impulse(t0, jerk * m_load * abs(dv))
        impulse(t0 + d, -jerk * m_load * abs(dv) * 0.7)
    impulse(onset, -j_imp * 0.5 * p.hardness)
    if math.isfinite(t_end):
        impulse(t_end, 0.2 * jerk * m_load * tl.v_r)
    for h in hits:
        th = h.time(anchors)
        if h.kind == 'hand':
            pulse = half_sine(t, th, h.pulse_s, h.force_n * hit_scale)
            comps.append((pulse, np.asarray(h.direction), np.asarray(h.point)))
            exc += 0.5 * pulse * float(np.dot(h.direction, s.geo.mode_dir))
        elif h.kind == 'touch':
            tt = np.clip(t - th, 0.0, h.dur)
            f = np.where((t >= th) & (t <= th + h.dur),
                         h.force_n * hit_scale * 0.5 * (1 - np.cos(2 * np.pi * tt / h.dur)), 0.0)
            if h.on_object:
                comps.append((f, np.asarray(h.direction), np.asarray(h.point)))
            else:  # pushing the arm: the wrist feels the inertial reaction and the mode
                comps.append((0.15 * f, np.asarray(h.direction), s.geo.r_load))
            exc += 0.3 * f * float(np.dot(h.direction, s.geo.mode_dir))
        elif h.kind == 'brush':
            tt = t - th
            edge = np.clip(np.minimum(tt, h.dur - tt) / 0.03, 0.0, 1.0)
            knots = np.random.default_rng(h.seed).standard_normal(int(h.dur * 200) + 2)
            fluct = np.interp(tt, np.arange(len(knots)) / 200.0, knots)
            f = h.force_n * hit_scale * edge * np.clip(1 + 0.35 * fluct, 0.0, None)
            comps.append((f, np.asarray(h.direction), np.asarray(h.point)))
            exc += 0.2 * f * float(np.dot(h.direction, s.geo.mode_dir))
        elif onset <= th < t_end:
            # a knock on the table (or an object set down on it) reaches the sensor only
            # through the object on it
            tt = np.maximum(t - th, 0.0)
            vib = np.where(t >= th, h.vib_n * np.exp(-tt / 0.06)
                           * np.sin(2 * np.pi * h.vib_hz * tt), 0.0)
            comps.append((vib, s.geo.up, s.geo.r_contact))
            impulse(th, 0.3 * h.vib_n / (2 * np.pi * p.mode_hz))
    h_mode = mode_ir(hz=p.mode_hz, zeta=p.mode_zeta, dt=dt)
    comps.append((causal_conv(exc, h_mode) * dt, s.geo.mode_dir, s.geo.r_load))

    # liquid slosh, driven by the free-space acceleration
    m_liq = p.liquid_mass_kg
    if m_liq > 0:
        ws = 2 * np.pi * p.slosh_hz
        h_s = mode_ir(hz=p.slosh_hz, zeta=p.slosh_zeta, dt=dt) * ws
        resp = causal_conv(a_eff, h_s) * dt
        comps.append((m_liq * 0.5 * (resp - a_eff), s.geo.slosh_dir, s.geo.r_obj))

    # motor / gear ripple while the motors turn (also while pushing)
    speed = np.minimum(np.abs(v) / v_d, 3.0)
    phase = 2 * np.pi * np.cumsum(p.ripple_hz * speed) * dt
    ripple = p.ripple_n * np.minimum(speed, 1.0) * (np.sin(phase) + 0.5 * np.sin(2.3 * phase))
    comps.append((ripple, s.geo.ripple_dir, s.geo.r_load))

    force = np.zeros((len(t), 3))
    torque = np.zeros((len(t), 3))
    for f, d, r in comps:
        force += np.outer(f, d)
        torque += np.outer(f, np.cross(r, d))
    # sensor: average over each output period, then bias, drift, noise, quantisation
    force = force.reshape(n_out, s.os, 3).mean(axis=1)
    torque = torque.reshape(n_out, s.os, 3).mean(axis=1)
    to = np.arange(n_out) / s.ft_rate
    force += s.sensor.bias_f
    torque += s.sensor.bias_t
    for amp_f, amp_t, period, ph in s.sensor.drift:
        wave = np.sin(2 * np.pi * to / period + ph)[:, None]
        force += wave * amp_f
        torque += wave * amp_t
    force += p.force_noise_n * s.sensor.noise_f[:n_out]
    torque += p.torque_noise_nm * s.sensor.noise_t[:n_out]
    if s.q.tared:
        # tared at rest before the lift: the bias cancels the static load measured then
        j0, j1 = tare_window(s)
        force -= force[j0:j1].mean(axis=0)
        torque -= torque[j0:j1].mean(axis=0)
    force = np.round(force / p.force_quant_n) * p.force_quant_n
    torque = np.round(torque / p.torque_quant_nm) * p.torque_quant_nm
    return force, torque, t_end


def torque_baseline(s: Setup, torque: np.ndarray) -> tuple[float, int, int]:
    j1 = int(math.floor(s.tl.t_acc0 * s.ft_rate))
    j0 = max(0, j1 - int(round(BASELINE_WINDOW_S * s.ft_rate)))
    return float(torque[j0:j1, 1].mean()), j0, j1


def tare_window(s: Setup) -> tuple[int, int]:
    """Output samples of the tare: 0.2 s to 0.2 s before the lift (the robot at rest)."""
    j0 = int(round(0.2 * s.ft_rate))
    return j0, max(j0 + 1, int(math.floor((s.tl.t_lift0 - 0.2) * s.ft_rate)))


def first_crossing(s: Setup, force: np.ndarray,
                   torque: np.ndarray) -> tuple[int | None, float]:
    """
    Index of the sample where the robot's stop rule fires, and the T_y baseline.

    'torque_y' (the recorded robot): the first sample from the start of ``accelerate`` with
    ``|T_y - base| >= 3 N m``. The vector rules use the wrench averaged over the last
    ``STOP_SMOOTH_S`` and the mean wrench of the baseline window, armed once the descent speed
    is reached: 'force' and 'load' ``|F - F_base| >= thr_f``, 'wrench' also
    ``|T - T_base| >= thr_t``.
    """
    base, j0, j_acc = torque_baseline(s, torque)
    rule = s.q.stop_rule
    if rule == 'torque_y':
        hit = np.nonzero(np.abs(torque[j_acc:, 1] - base) >= STOP_TORQUE_NM)[0]
        return (int(hit[0]) + j_acc if len(hit) else None), base
    w = max(1, int(round(STOP_SMOOTH_S * s.ft_rate)))
    j_arm = max(j_acc, int(math.ceil(s.tl.t_desc0 * s.ft_rate)))
    over = np.zeros(len(force), dtype=bool)
    for sig, thr in ((force, s.thr_f), (torque, s.thr_t if rule == 'wrench' else math.inf)):
        if not math.isfinite(thr):
            continue
        c = np.cumsum(np.vstack([np.zeros((1, 3)), sig]), axis=0)
        smooth = np.empty_like(sig)
        idx = np.arange(len(sig))
        lo = np.maximum(idx + 1 - w, 0)
        smooth[:] = (c[idx + 1] - c[lo]) / (idx + 1 - lo)[:, None]
        ref = sig[j0:j_acc].mean(axis=0)
        over |= np.linalg.norm(smooth - ref, axis=1) >= thr
    hit = np.nonzero(over[j_arm:])[0]
    return (int(hit[0]) + j_arm if len(hit) else None), base


def weight_transfer_s(*, k_eff: float, v_c: float, ctau: float, weight: float,
                      spring: bool) -> float:
    """Noise-free time in s from the onset until the table carries the object's weight."""
    tau = np.arange(1, 200001) * 1e-5
    normal = k_eff * v_c * tau * (1.0 if spring else (1 - np.exp(-tau / ctau)))
    idx = np.nonzero(normal >= weight)[0]
    return float(tau[idx[0]]) if len(idx) else math.inf
