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
Synthesis of one placing trial: wrist force/torque, microphone audio and ground truth.

Pure numpy (no ROS, no rosbags, no wall clock). A trial imitates the paper's task (section
4.1): an arm holds an object, lifts it to a start position, descends at a few cm/s until the
object touches the table, keeps pushing until ``|T_y - T_y,baseline| >= 3 N m`` (the recorded
robot's stop rule), stays there, retreats to the start position and rests. Exogenous impacts
(hits on the robot's hand or on the table) are added as in the paper. The families of
:mod:`.conditions` change the structure: the sensor's orientation and lever arm, tared sensors,
stop rules on ``|F - F_base|`` / ``|T - T_base|`` or on the load transferred, a spring or a
compliant contact, the approach speed profile, touches / brushing / objects set down nearby,
a quiet contact and other ego noise. See ``docs/simulator.md`` for the model and
:mod:`contact_detector.sim.conditions` for every parameter range.

Frames and units
----------------
World: z up. Sensor frame (``wrist_ft_sensor_frame``): the hand axis is +z (pointing forward,
horizontal), world "up" is close to -x (plus a random tilt); in the 'geometry' family any
orientation. The sensor reports the load's
wrench on the sensor, in N and N m, so at rest ``F ~ (m_object + m_hand) g`` along +x and
``T_y ~ +L m g``; the table's reaction reduces ``T_y`` (the paper's threshold was -3 N m).

Randomness
----------
``np.random.default_rng([seed, index])`` draws the parameters (:mod:`.conditions`); independent
streams ``[seed, index, k]`` draw the hit plan (k=1), the F/T sensor noise (k=2), the audio
(k=3), the chunking (k=4), the geometry (k=5) and, for the families only, the family
parameters and hit kind (k=6); the 'real_sounds' family draws its audio (which recordings,
where they start, the microphone's AGC phase) from k=7 instead of k=3. The hit plan therefore
never changes the other parameters: ``simulate_trial(..., hits='none')`` is the same trial
without its exogenous impacts.
"""

from dataclasses import dataclass, field
import math
from typing import Iterator, Sequence

from contact_detector.errors import ConfigError
from contact_detector.sim import sound_bank
from contact_detector.sim.conditions import (DEFAULT_HIT_CYCLE, EVENT_KINDS, get_condition,
                                             resolve_conditions)
import numpy as np

#: Gravity in m/s^2.
G = 9.81
#: The recorded robot's stop rule: |T_y - baseline| >= this, in N m (paper: -3 N m on T_y).
STOP_TORQUE_NM = 3.0
#: The stop rule's baseline is the mean T_y over this many seconds before the descent starts.
BASELINE_WINDOW_S = 0.3
#: Longest push simulated while searching for the stop (s); the ranges reach it in < 3.5 s.
PUSH_HORIZON_S = 6.0
#: Fastest retreat to the start position, m/s.
MAX_RETREAT_SPEED = 0.1
#: Speed of sound in m/s (delay from the hand to the microphone).
SOUND_SPEED = 343.0
#: Descent speed at which ``contact_amp_fs`` is the contact sound's peak (m/s).
REF_SPEED = 0.04
#: Absolute start time of trial ``index``: ``T0 + TRIAL_SPACING_S * index`` seconds.
T0 = 1_700_000_000
TRIAL_SPACING_S = 100
#: Hit kinds: 'none', the paper's exogenous impacts ('hand', 'table'), the families' events
#: ('touch', 'brush', 'setdown') and 'mixed' (each event draws one of the five).
HIT_KINDS = ('none', 'hand', 'table', 'touch', 'brush', 'setdown', 'mixed')
#: Stop rules on vectors ('force', 'wrench', 'load') average the wrench over this window (s).
STOP_SMOOTH_S = 0.03
#: Phase names in order.
PHASES = ('rest', 'lift', 'hold', 'accelerate', 'descend', 'push', 'settle', 'retreat', 'rest')

_MIN_HIT_GAP_S = 0.25


@dataclass(frozen=True)
class Impact:
    """
    One exogenous impact.

    Attributes
    ----------
    t : float
        Absolute time in s of the physical hit (the sound reaches the microphone
        ``mic_distance_m / 343`` s later).
    kind : str
        'hand' (experimenter hits the robot's hand: sound and F/T pulse) or 'table' (hits the
        table: sound, and a tiny F/T vibration only while the object rests on the table).
    in_air : bool
        True if the object was not resting on the table at ``t`` (a false detection here would
        drop it).
    amplitude : float
        Peak of the hit's sound at the microphone before the microphone gain, as a fraction of
        int16 full scale (same scale as the ``contact_amp_fs`` parameter).

    """

    t: float
    kind: str
    in_air: bool
    amplitude: float


@dataclass
class Trial:
    """
    One synthesised trial. Times are absolute seconds (bag time).

    Audio sample ``i`` is at ``start_time + i / audio_rate``; wrench sample ``j`` at
    ``wrench_t[j] = start_time + j / ft_rate``.
    """

    name: str
    condition: str
    seed: int
    start_time: float
    ft_rate: float
    wrench_t: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    audio_rate: int
    audio: np.ndarray
    chunk_ends: np.ndarray
    chunk_log_t: np.ndarray
    onset_t: float
    onset_end_t: float
    contact_end_t: float
    stop_t: float
    phases: list
    impacts: list
    params: dict
    index: int = 0
    wrench_log_t: np.ndarray | None = field(default=None, repr=False)

    def audio_time(self, index) -> float:
        """Absolute time in s of audio sample ``index`` (scalar or array)."""
        return self.start_time + np.asarray(index) / self.audio_rate

    @property
    def end_time(self) -> float:
        """Absolute time in s of the trial's end (end of the final rest)."""
        return float(self.phases[-1][2])

    def phase_at(self, t: float) -> str:
        """Name of the phase containing absolute time ``t`` ('' outside the trial)."""
        for name, t0, t1 in self.phases:
            if t0 <= t < t1:
                return name
        return ''


# --------------------------------------------------------------------------------------------
# motion: sums of raised-cosine velocity ramps


def _ramps(ramps: Sequence[tuple[float, float, float]], t: np.ndarray):
    """
    Velocity, acceleration and position of a sum of raised-cosine velocity steps.

    Each ramp ``(dv, t0, d)`` changes the velocity by ``dv`` m/s over ``[t0, t0 + d]`` with
    ``v = dv (1 - cos(pi tau / d)) / 2``. Returns ``(z, v, a)`` arrays shaped like ``t``.
    """
    z = np.zeros_like(t)
    v = np.zeros_like(t)
    a = np.zeros_like(t)
    for dv, t0, d in ramps:
        tau = t - t0
        inside = (tau > 0) & (tau < d)
        after = tau >= d
        ti = np.where(inside, tau, 0.0)
        v += dv * np.where(inside, 0.5 * (1 - np.cos(np.pi * ti / d)), after.astype(float))
        a += dv * np.where(inside, 0.5 * np.pi / d * np.sin(np.pi * ti / d), 0.0)
        z += dv * np.where(inside, 0.5 * (ti - d / np.pi * np.sin(np.pi * ti / d)),
                           np.where(after, tau - 0.5 * d, 0.0))
    return z, v, a


def _ramp_pos(ramps, t: float) -> float:
    return float(_ramps(ramps, np.array([t], dtype=float))[0][0])


# --------------------------------------------------------------------------------------------
# small signal helpers


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues rotation matrix."""
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _mode_ir(*, hz: float, zeta: float, dt: float) -> np.ndarray:
    """Force impulse response of a mode: ``w exp(-zeta w t) sin(w_d t)`` until it is < 1e-3."""
    w = 2 * np.pi * hz
    wd = w * math.sqrt(1 - zeta ** 2)
    n = int(math.ceil(7.0 / (zeta * w) / dt)) + 1
    t = np.arange(n) * dt
    return w * np.exp(-zeta * w * t) * np.sin(wd * t)


def _causal_conv(x: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Linear causal convolution ``y[n] = sum_k h[k] x[n-k]`` via FFT, same length as x."""
    n = len(x) + len(h) - 1
    nfft = 1 << (n - 1).bit_length()
    y = np.fft.irfft(np.fft.rfft(x, nfft) * np.fft.rfft(h, nfft), nfft)
    return y[:len(x)]


def _half_sine(t: np.ndarray, t0: float, dur: float, peak: float) -> np.ndarray:
    tau = t - t0
    inside = (tau >= 0) & (tau <= dur)
    return np.where(inside, peak * np.sin(np.pi * np.clip(tau, 0, dur) / dur), 0.0)


def _shaped_noise(rng: np.random.Generator, n: int, rate: float, shape) -> np.ndarray:
    """Gaussian noise with amplitude spectrum ``shape(f)``, unit RMS, length ``n``."""
    nfft = 1 << max(1, (n - 1).bit_length())
    m = nfft // 2 + 1
    spec = rng.standard_normal(m) + 1j * rng.standard_normal(m)
    f = np.fft.rfftfreq(nfft, 1.0 / rate)
    spec *= shape(f)
    spec[0] = 0.0
    x = np.fft.irfft(spec, nfft)[:n]
    rms = float(np.sqrt(np.mean(x ** 2))) if n else 0.0
    return x / rms if rms > 0 else x


def _pink_shape(f: np.ndarray) -> np.ndarray:
    return np.where(f > 0, 1.0 / np.sqrt(np.maximum(f, 20.0)), 0.0) * (f / (f + 20.0))


def _band_shape(lo: float, hi: float):
    def shape(f: np.ndarray) -> np.ndarray:
        hp = (f / lo) ** 2 / (1 + (f / lo) ** 2)
        lp = 1 / (1 + (f / hi) ** 2)
        return hp * lp
    return shape


def _add_modal(buf: np.ndarray, *, rate: float, t0: float, freqs, decays, amps,
               attack_s: float, click_amp: float = 0.0, click_decay_s: float = 0.001,
               rng: np.random.Generator | None = None) -> None:
    """
    Add an impact sound (modal synthesis) to ``buf`` in place.

    ``x(t) = (1 - exp(-t / attack)) sum_k a_k exp(-t / tau_k) sin(2 pi f_k t)
    + click_amp n(t) exp(-t / click_decay)`` for ``t >= 0``, where ``t`` counts from ``t0``
    (seconds relative to ``buf[0]``). Modes above 0.45 ``rate`` are dropped (the ADC's
    anti-alias filter).
    """
    keep = [k for k, f in enumerate(freqs) if f < 0.45 * rate]
    longest = max([decays[k] for k in keep] + [click_decay_s])
    i0 = max(0, int(math.ceil(t0 * rate)))
    i1 = min(len(buf), i0 + int(math.ceil(7 * longest * rate)) + 1)
    if i1 <= i0:
        return
    t = np.arange(i0, i1) / rate - t0
    x = np.zeros(i1 - i0)
    for k in keep:
        x += amps[k] * np.exp(-t / decays[k]) * np.sin(2 * np.pi * freqs[k] * t)
    x *= 1 - np.exp(-t / max(attack_s, 1e-5))
    if click_amp > 0 and rng is not None:
        x += click_amp * rng.standard_normal(len(t)) * np.exp(-t / click_decay_s)
    buf[i0:i1] += x


def _mode_set(rng: np.random.Generator, *, n: int, lo: float, hi: float, decay: float,
              peak: float, weight: float = 1.0):
    """
    Draw ``n`` modes log-uniform in ``[lo, hi]`` Hz, decays ``~decay sqrt(f_min / f)``.

    Amplitudes have Euclidean norm ``peak * weight``, so the energy does not depend on ``n``.
    """
    freqs = np.exp(rng.uniform(math.log(lo), math.log(hi), n))
    decays = decay * rng.uniform(0.6, 1.4, n) * np.sqrt(freqs.min() / freqs)
    w = rng.uniform(0.3, 1.0, n)
    amps = peak * weight * w / np.sqrt(np.sum(w ** 2))
    return list(freqs), list(decays), list(amps)


# --------------------------------------------------------------------------------------------
# hit planning


@dataclass
class _Hit:
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
        return anchors[self.anchor] + self.t


def _plan_hits(*, kind: str, count: int, rng: np.random.Generator, p: dict, tl: dict,
               stop_est: float, R: np.ndarray, q: dict, r_obj: np.ndarray) -> list[_Hit]:
    """Place ``count`` hits of ``kind`` (see module doc); times relative to the trial start."""
    if kind == 'none':
        return []
    settle_rel = (p['stop_latency_s'] + p['stop_decel_s'] + p['settle_s'])
    windows = {
        # window name: (anchor, lo, hi, probability)
        'moving_air': ('abs', tl['t_acc0'] + 0.05, tl['onset'] - _MIN_HIT_GAP_S, 0.55),
        'premotion': ('abs', 0.3, tl['t_acc0'] - BASELINE_WINDOW_S - 0.05, 0.15),
        'contact': ('stop', 0.1, settle_rel - 0.05, 0.2),
        'post_air': ('end', 0.1, p['rest_end_s'] - 0.3, 0.1),
    }
    if kind in ('table', 'setdown', 'touch', 'mixed') \
            and stop_est - 0.05 > tl['onset'] + _MIN_HIT_GAP_S:
        windows['push'] = ('abs', tl['onset'] + _MIN_HIT_GAP_S, stop_est - 0.05, 0.1)
    nominal = {'abs': 0.0, 'stop': stop_est, 'end': stop_est + settle_rel + p['retreat_s']}
    hits: list[_Hit] = []
    for _ in range(count):
        k = kind if kind != 'mixed' else EVENT_KINDS[int(rng.integers(0, len(EVENT_KINDS)))]
        dur = 0.0
        if k == 'touch':
            dur = q['touch_s'] * float(rng.uniform(0.8, 1.2))
        elif k == 'brush':
            dur = q['brush_s'] * float(rng.uniform(0.8, 1.2))
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
            if all(abs(t_nom - h.time(nominal)) >= _MIN_HIT_GAP_S for h in hits):
                break
        else:
            continue
        if k == 'hand':
            amp = p['hand_hit_amp_fs'] * float(rng.uniform(0.6, 1.4))
            # knocks come from above or from the side, in world terms
            world = _unit([rng.normal(), rng.normal(), -abs(rng.normal()) * 1.5])
            direction = R @ world
            point = (float(rng.uniform(-0.03, 0.03)), float(rng.uniform(-0.03, 0.03)),
                     float(rng.uniform(0.05, 0.15)))
            hits.append(_Hit(kind=k, anchor=anchor, t=t, sound_amp=amp,
                             force_n=p['hand_hit_force_n'] * float(rng.uniform(0.7, 1.3)),
                             pulse_s=float(rng.uniform(0.008, 0.03)),
                             direction=tuple(direction), point=point, window=w))
        elif k == 'table':
            amp = p['table_hit_amp_fs'] * float(rng.uniform(0.6, 1.4))
            hits.append(_Hit(kind=k, anchor=anchor, t=t, sound_amp=amp,
                             vib_n=p['table_hit_vib_n'] * float(rng.uniform(0.7, 1.3)),
                             vib_hz=float(rng.uniform(15.0, 45.0)), window=w))
        elif k == 'touch':
            # a person touching or pushing: slow, smooth, little sound (a faint rustle)
            amp = float(math.exp(rng.uniform(math.log(0.0005), math.log(0.004))))
            on_object = bool(rng.uniform() < 0.6)
            direction = R @ _unit(rng.normal(size=3))
            point = r_obj + rng.uniform(-0.02, 0.02, 3)
            hits.append(_Hit(kind=k, anchor=anchor, t=t, sound_amp=amp,
                             force_n=q['touch_force_n'] * float(rng.uniform(0.7, 1.3)),
                             pulse_s=dur, dur=dur, direction=tuple(direction),
                             point=tuple(point), on_object=on_object, window=w))
        elif k == 'brush':
            # friction against the motion (the arm moves down) plus a sideways part
            world = _unit([rng.normal() * 0.7, rng.normal() * 0.7, 1.0])
            point = r_obj * float(rng.uniform(0.3, 1.0))
            hits.append(_Hit(kind=k, anchor=anchor, t=t,
                             sound_amp=q['brush_amp_fs'] * float(rng.uniform(0.7, 1.3)),
                             force_n=q['brush_force_n'] * float(rng.uniform(0.7, 1.3)),
                             pulse_s=dur, dur=dur, direction=tuple(R @ world),
                             point=tuple(point), seed=int(rng.integers(0, 2 ** 31)),
                             window=w))
        else:  # 'setdown': another object set down on the table nearby
            hits.append(_Hit(kind=k, anchor=anchor, t=t,
                             sound_amp=q['setdown_amp_fs'] * float(rng.uniform(0.6, 1.4)),
                             vib_n=q['setdown_vib_n'] * float(rng.uniform(0.7, 1.3)),
                             vib_hz=float(rng.uniform(20.0, 60.0)), window=w))
    hits.sort(key=lambda h: h.time(nominal))
    return hits


# --------------------------------------------------------------------------------------------
# force / torque


@dataclass
class _Setup:
    """Everything the F/T synthesis needs besides the stop time (derived from the params)."""

    p: dict
    ft_rate: float
    os: int                       # internal oversampling factor
    R: np.ndarray                 # world -> sensor rotation
    up: np.ndarray                # world up in the sensor frame
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
    k_eff: float
    tl: dict
    base_ramps: list
    bias_f: np.ndarray
    bias_t: np.ndarray
    drift: list                   # (amp_f (3,), amp_t (3,), period, phase) terms
    noise_f: np.ndarray           # (n_max, 3) unit normal
    noise_t: np.ndarray
    q: dict                       # family parameters (conditions.FAMILY_DEFAULTS)
    ctau: float                   # lag of the load transfer, s
    thr_f: float = 0.0            # vector stop rules' thresholds (N, N m)
    thr_t: float = 0.0


def _stop_ramps(s: _Setup, stop_rel: float) -> tuple[list, dict]:
    """Ramps and timeline after the stop rule fired at ``stop_rel`` (relative seconds)."""
    p, tl = s.p, dict(s.tl)
    v_d = tl['v_c']
    t_s = stop_rel + p['stop_latency_s']
    t_r0 = t_s + p['stop_decel_s'] + p['settle_s']
    push_depth = v_d * (t_s - tl['onset']) + 0.5 * v_d * p['stop_decel_s']
    dist = tl['descent_dist'] + push_depth
    rr = p['retreat_ramp_s']
    # retreat no faster than MAX_RETREAT_SPEED: a long descent takes longer to undo
    retreat_s = max(p['retreat_s'], dist / MAX_RETREAT_SPEED + rr)
    v_r = dist / (retreat_s - rr)
    ramps = s.base_ramps + [(v_d, t_s, p['stop_decel_s']),
                            (v_r, t_r0, rr), (-v_r, t_r0 + retreat_s - rr, rr)]
    tl.update(t_s=t_s, t_r0=t_r0, t_r1=t_r0 + retreat_s, v_r=v_r, push_depth=push_depth,
              end=t_r0 + retreat_s + p['rest_end_s'], retreat_s=retreat_s)
    return ramps, tl


def _ft(s: _Setup, *, n_out: int, ramps: list, tl: dict, hits: list[_Hit],
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
    z, v, a = _ramps(ramps, t)
    onset = tl['onset']
    z_contact = tl['z_contact']
    # lift-off: first time after the retreat starts where the hand is back above contact height
    t_end = math.inf
    if 't_r0' in tl:
        after = np.nonzero((t > tl['t_r0']) & (z >= z_contact))[0]
        if len(after):
            i = after[0]
            z0, z1 = z[i - 1], z[i]
            t_end = float(t[i - 1] + (z_contact - z0) / (z1 - z0) * dt) if z1 > z0 else t[i]
    in_contact = (t >= onset) & (t < t_end)
    depth = np.where(in_contact, np.maximum(z_contact - z, 0.0), 0.0)
    tau = np.maximum(t - onset, 0.0)
    if s.q['contact_model'] == 'spring':
        normal = s.k_eff * depth
    else:
        normal = s.k_eff * depth * (1 - np.exp(-tau / s.ctau))
    if 't_s' in tl:
        since = np.maximum(t - tl['t_s'], 0.0)
        normal *= 1 - p['creep'] * (1 - np.exp(-since / 0.3))
    a_eff = np.where(in_contact, 0.0, a)
    m_load = s.m_obj + s.m_hand
    v_d = p['descent_speed_mps']

    comps = []  # (scalar series, direction (3,), point (3,))
    comps.append((-s.m_obj * (G + a_eff), s.up, s.r_obj))
    # a tool-compensated sensor removes the hand's static weight (not its inertia)
    g_hand = 0.0 if s.q['tool_compensated'] else G
    comps.append((-s.m_hand * (g_hand + a_eff), s.up, s.r_hand))
    comps.append((normal, s.up, s.r_contact))
    comps.append((p['friction'] * normal, s.fric_dir, s.r_contact))

    # contact impact pulse
    j_imp = (s.m_obj + 0.5 * s.m_hand) * tl['v_c'] * p['impact_transmission'] * 0.5
    d_imp = p['impact_duration_s']
    comps.append((_half_sine(t, onset, d_imp, j_imp * np.pi / (2 * d_imp)), s.up, s.r_contact))

    # structural mode: impulses (N s) at motion jerks, impact, lift-off; plus hit pulses
    exc = np.zeros_like(t)

    def impulse(t0: float, j: float) -> None:
        i = int(round((t0 - t[0]) / dt))
        if 0 <= i < len(exc):
            exc[i] += j / dt

    # a velocity step dv gives a ring-down of peak ~ jerk_gain m |dv| 2 pi 8 Hz, for any mode
    jerk = p['jerk_gain'] * 2 * np.pi * 8.0 / (2 * np.pi * p['mode_hz'])
    for dv, t0, d in ramps:
        impulse(t0, jerk * m_load * abs(dv))
        impulse(t0 + d, -jerk * m_load * abs(dv) * 0.7)
    impulse(onset, -j_imp * 0.5 * p['hardness'])
    if math.isfinite(t_end):
        impulse(t_end, 0.2 * jerk * m_load * tl['v_r'])
    for h in hits:
        th = h.time(anchors)
        if h.kind == 'hand':
            pulse = _half_sine(t, th, h.pulse_s, h.force_n * hit_scale)
            comps.append((pulse, np.asarray(h.direction), np.asarray(h.point)))
            exc += 0.5 * pulse * float(np.dot(h.direction, s.mode_dir))
        elif h.kind == 'touch':
            tt = np.clip(t - th, 0.0, h.dur)
            f = np.where((t >= th) & (t <= th + h.dur),
                         h.force_n * hit_scale * 0.5 * (1 - np.cos(2 * np.pi * tt / h.dur)), 0.0)
            if h.on_object:
                comps.append((f, np.asarray(h.direction), np.asarray(h.point)))
            else:  # pushing the arm: the wrist feels the inertial reaction and the mode
                comps.append((0.15 * f, np.asarray(h.direction), s.r_load))
            exc += 0.3 * f * float(np.dot(h.direction, s.mode_dir))
        elif h.kind == 'brush':
            tt = t - th
            edge = np.clip(np.minimum(tt, h.dur - tt) / 0.03, 0.0, 1.0)
            knots = np.random.default_rng(h.seed).standard_normal(int(h.dur * 200) + 2)
            fluct = np.interp(tt, np.arange(len(knots)) / 200.0, knots)
            f = h.force_n * hit_scale * edge * np.clip(1 + 0.35 * fluct, 0.0, None)
            comps.append((f, np.asarray(h.direction), np.asarray(h.point)))
            exc += 0.2 * f * float(np.dot(h.direction, s.mode_dir))
        elif onset <= th < t_end:
            # a knock on the table (or an object set down on it) reaches the sensor only
            # through the object on it
            tt = np.maximum(t - th, 0.0)
            vib = np.where(t >= th, h.vib_n * np.exp(-tt / 0.06)
                           * np.sin(2 * np.pi * h.vib_hz * tt), 0.0)
            comps.append((vib, s.up, s.r_contact))
            impulse(th, 0.3 * h.vib_n / (2 * np.pi * p['mode_hz']))
    h_mode = _mode_ir(hz=p['mode_hz'], zeta=p['mode_zeta'], dt=dt)
    comps.append((_causal_conv(exc, h_mode) * dt, s.mode_dir, s.r_load))

    # liquid slosh, driven by the free-space acceleration
    m_liq = p['liquid_mass_kg']
    if m_liq > 0:
        ws = 2 * np.pi * p['slosh_hz']
        h_s = _mode_ir(hz=p['slosh_hz'], zeta=p['slosh_zeta'], dt=dt) * ws
        resp = _causal_conv(a_eff, h_s) * dt
        comps.append((m_liq * 0.5 * (resp - a_eff), s.slosh_dir, s.r_obj))

    # motor / gear ripple while the motors turn (also while pushing)
    speed = np.minimum(np.abs(v) / v_d, 3.0)
    phase = 2 * np.pi * np.cumsum(p['ripple_hz'] * speed) * dt
    ripple = p['ripple_n'] * np.minimum(speed, 1.0) * (np.sin(phase) + 0.5 * np.sin(2.3 * phase))
    comps.append((ripple, s.ripple_dir, s.r_load))

    force = np.zeros((len(t), 3))
    torque = np.zeros((len(t), 3))
    for f, d, r in comps:
        force += np.outer(f, d)
        torque += np.outer(f, np.cross(r, d))
    # sensor: average over each output period, then bias, drift, noise, quantisation
    force = force.reshape(n_out, s.os, 3).mean(axis=1)
    torque = torque.reshape(n_out, s.os, 3).mean(axis=1)
    to = np.arange(n_out) / s.ft_rate
    force += s.bias_f
    torque += s.bias_t
    for amp_f, amp_t, period, ph in s.drift:
        wave = np.sin(2 * np.pi * to / period + ph)[:, None]
        force += wave * amp_f
        torque += wave * amp_t
    force += p['force_noise_n'] * s.noise_f[:n_out]
    torque += p['torque_noise_nm'] * s.noise_t[:n_out]
    if s.q['tared']:
        # tared at rest before the lift: the bias cancels the static load measured then
        j0, j1 = _tare_window(s)
        force -= force[j0:j1].mean(axis=0)
        torque -= torque[j0:j1].mean(axis=0)
    force = np.round(force / p['force_quant_n']) * p['force_quant_n']
    torque = np.round(torque / p['torque_quant_nm']) * p['torque_quant_nm']
    return force, torque, t_end


def _baseline(s: _Setup, torque: np.ndarray) -> tuple[float, int, int]:
    j1 = int(math.floor(s.tl['t_acc0'] * s.ft_rate))
    j0 = max(0, j1 - int(round(BASELINE_WINDOW_S * s.ft_rate)))
    return float(torque[j0:j1, 1].mean()), j0, j1


def _tare_window(s: _Setup) -> tuple[int, int]:
    """Output samples of the tare: 0.2 s to 0.2 s before the lift (the robot at rest)."""
    j0 = int(round(0.2 * s.ft_rate))
    return j0, max(j0 + 1, int(math.floor((s.tl['t_lift0'] - 0.2) * s.ft_rate)))


def _first_crossing(s: _Setup, force: np.ndarray,
                    torque: np.ndarray) -> tuple[int | None, float]:
    """
    Index of the sample where the robot's stop rule fires, and the T_y baseline.

    'torque_y' (the recorded robot): the first sample from the start of ``accelerate`` with
    ``|T_y - base| >= 3 N m``. The vector rules use the wrench averaged over the last
    ``STOP_SMOOTH_S`` and the mean wrench of the baseline window, armed once the descent speed
    is reached: 'force' and 'load' ``|F - F_base| >= thr_f``, 'wrench' also
    ``|T - T_base| >= thr_t``.
    """
    base, j0, j_acc = _baseline(s, torque)
    rule = s.q['stop_rule']
    if rule == 'torque_y':
        hit = np.nonzero(np.abs(torque[j_acc:, 1] - base) >= STOP_TORQUE_NM)[0]
        return (int(hit[0]) + j_acc if len(hit) else None), base
    w = max(1, int(round(STOP_SMOOTH_S * s.ft_rate)))
    j_arm = max(j_acc, int(math.ceil(s.tl['t_desc0'] * s.ft_rate)))
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


# --------------------------------------------------------------------------------------------
# audio


def _audio(*, p: dict, q: dict, rng: np.random.Generator, rate: int, n: int, ramps: list,
           tl: dict, hits: list[_Hit], anchors: dict,
           duration: float) -> tuple[np.ndarray, dict]:
    """Microphone signal as int16 and a dict of audio facts for the params."""
    t = np.arange(n) / rate
    x = p['bg_rms_fs'] * _shaped_noise(rng, n, rate, _pink_shape)
    # mains hum with two harmonics, robot fan (tone + band noise)
    hum = p['hum_hz']
    for k, w in ((1, 1.0), (2, 0.5), (3, 0.3)):
        x += p['hum_rms_fs'] * math.sqrt(2) * w * np.sin(2 * np.pi * k * hum * t
                                                         + rng.uniform(0, 2 * np.pi))
    fan_hz = float(rng.uniform(90.0, 250.0))
    fan = _shaped_noise(rng, n, rate, _band_shape(150.0, 1200.0))
    x += p['fan_rms_fs'] * (0.8 * fan + 0.6 * math.sqrt(2) * np.sin(2 * np.pi * fan_hz * t))
    facts: dict = {'fan_hz': fan_hz}
    # a muted or far microphone hears only the room (kept aside here)
    room = x.copy() if q['mic_mode'] == 'noise_only' else None
    # household babble: speech-shaped noise, talkers switching on and off with syllabic AM
    if p['babble_rms_fs'] > 0:
        talkers = int(rng.integers(2, 5))
        env = np.zeros(n)
        for _ in range(talkers):
            on = np.zeros(n)
            pos = float(rng.uniform(-1.0, 0.5))
            while pos < duration:
                length = float(rng.uniform(0.8, 3.0))
                i0, i1 = max(0, int(pos * rate)), min(n, int((pos + length) * rate))
                on[i0:i1] = 1.0
                pos += length + float(rng.uniform(0.2, 1.5))
            # syllable rate wandering around 3-6 Hz, so talkers do not sound like metronomes
            syl = float(rng.uniform(3.0, 6.0)) + 1.2 * np.sin(
                2 * np.pi * float(rng.uniform(0.2, 0.5)) * t + rng.uniform(0, 2 * np.pi))
            depth = float(rng.uniform(0.3, 0.45))
            am = (1 - depth + depth * np.sin(2 * np.pi * np.cumsum(syl) / rate)) ** 2
            env += on * am * float(rng.uniform(0.5, 1.0))
        speech = _shaped_noise(rng, n, rate, _band_shape(300.0, 1500.0)) * env
        rms = float(np.sqrt(np.mean(speech ** 2)))
        if rms > 0:
            x += p['babble_rms_fs'] * speech / rms
        facts['babble_talkers'] = talkers
    # distant clatter of dishes / cutlery (no F/T)
    clatter = []
    if p['clatter_per_s'] > 0:
        count = int(rng.poisson(p['clatter_per_s'] * duration))
        for _ in range(count):
            tc = float(rng.uniform(0.2, duration - 0.2))
            amp = float(math.exp(rng.uniform(math.log(0.003), math.log(0.05))))
            fr, de, am = _mode_set(rng, n=3, lo=1500.0, hi=7000.0,
                                   decay=float(rng.uniform(0.02, 0.15)), peak=amp)
            _add_modal(x, rate=rate, t0=tc, freqs=fr, decays=de, amps=am, attack_s=0.0003,
                       click_amp=0.3 * amp, click_decay_s=0.001, rng=rng)
            clatter.append([tc, amp])
    facts['clatter'] = sorted(clatter)
    # robot ego noise while the motors turn: harmonic whine (pitch ~ speed) + broadband
    speed, level = _motion_level(p=p, ramps=ramps, t=t, duration=duration)
    phase = 2 * np.pi * np.cumsum(p['whine_hz'] * np.minimum(speed, 2.0)) / rate
    moving = np.nonzero(level > 0)[0]
    whine = np.zeros(len(moving))
    for k in range(1, 6):
        gain = float(rng.uniform(0.3, 1.0)) / k ** 1.2
        if p['whine_hz'] * k * 2.0 < 0.45 * rate:
            whine += gain * np.sin(k * phase[moving])
    full = level[moving] > 0.5
    whine /= max(1e-12, float(np.sqrt(np.mean(whine[full] ** 2))) if np.any(full) else 1.0)
    broad = _shaped_noise(rng, n, rate, _band_shape(800.0, 4000.0))
    x[moving] += level[moving] * (p['whine_rms_fs'] * whine
                                  + p['ego_broad_rms_fs'] * broad[moving])

    # the contact sound: glass modes (bright) + table modes, loudness ~ speed and hardness
    delay = p['mic_distance_m'] / SOUND_SPEED
    peak = _contact_peak(p=p, q=q, tl=tl)
    bright = p['brightness']
    lo, hi = p['table_modes_hz']
    gf, gd, ga = _mode_set(rng, n=int(rng.integers(2, 5)), lo=1000.0, hi=8000.0,
                           decay=p['glass_decay_s'], peak=peak, weight=bright)
    tf, td, ta = _mode_set(rng, n=int(rng.integers(2, 5)), lo=lo, hi=hi,
                           decay=p['table_decay_s'], peak=peak, weight=1.0 - 0.5 * bright)
    attack = p['impact_duration_s'] / 8
    contacts = [(tl['onset'] + delay, 1.0)]
    if p['bounce']:
        contacts.append((tl['onset'] + delay + float(rng.uniform(0.005, 0.04)),
                         float(rng.uniform(0.2, 0.6))))
    for tc, scale in contacts:
        _add_modal(x, rate=rate, t0=tc, freqs=gf + tf, decays=gd + td,
                   amps=[scale * a for a in ga + ta], attack_s=attack,
                   click_amp=0.3 * scale * peak * p['hardness'],
                   click_decay_s=max(0.0005, p['impact_duration_s'] / 3), rng=rng)
    facts['contact_peak_fs'] = peak
    facts['contact_modes_hz'] = [float(f) for f in gf + tf]

    # exogenous impacts
    for h in hits:
        th = h.time(anchors) + delay
        if h.kind == 'hand':
            fr, de, am = _mode_set(rng, n=3, lo=300.0, hi=3000.0,
                                   decay=float(rng.uniform(0.008, 0.04)), peak=h.sound_amp)
            _add_modal(x, rate=rate, t0=th, freqs=fr, decays=de, amps=am, attack_s=0.0005,
                       click_amp=0.4 * h.sound_amp, click_decay_s=0.0015, rng=rng)
        elif h.kind == 'table':
            fr, de, am = _mode_set(rng, n=3, lo=100.0, hi=1500.0,
                                   decay=float(rng.uniform(0.01, 0.05)), peak=0.7 * h.sound_amp)
            fr.append(float(rng.uniform(60.0, 150.0)))
            de.append(0.03)
            am.append(0.3 * h.sound_amp)
            _add_modal(x, rate=rate, t0=th, freqs=fr, decays=de, amps=am, attack_s=0.001,
                       click_amp=0.3 * h.sound_amp, click_decay_s=0.002, rng=rng)
        elif h.kind == 'setdown':
            # a cup or plate set down nearby: a contact-like sound (object and table modes)
            fr, de, am = _mode_set(rng, n=3, lo=800.0, hi=7000.0,
                                   decay=float(rng.uniform(0.01, 0.06)), peak=0.7 * h.sound_amp)
            fr2, de2, am2 = _mode_set(rng, n=2, lo=100.0, hi=1500.0,
                                      decay=float(rng.uniform(0.005, 0.04)),
                                      peak=0.5 * h.sound_amp)
            _add_modal(x, rate=rate, t0=th, freqs=fr + fr2, decays=de + de2, amps=am + am2,
                       attack_s=float(rng.uniform(0.0003, 0.003)), click_amp=0.3 * h.sound_amp,
                       click_decay_s=0.0015, rng=rng)
        else:  # 'touch' (a faint rustle) or 'brush' (scraping, stick-slip modulated)
            _add_rustle(x, h=h, th=th, rng=rng, rate=rate)

    # ego-noise families besides the motor whine
    fam = q['ego_family']
    lvl = q['ego_extra_rms_fs']
    if fam == 'fan':
        blade = float(rng.uniform(60.0, 400.0))
        x += lvl * (_shaped_noise(rng, n, rate, _band_shape(100.0, 6000.0))
                    * (1 + 0.1 * np.sin(2 * np.pi * 0.3 * t))
                    + 0.5 * math.sqrt(2) * np.sin(2 * np.pi * blade * t))
        facts['ego_fan_blade_hz'] = blade
    elif fam == 'gear':
        gear_hz = float(rng.uniform(1000.0, min(5000.0, 0.2 * rate)))
        gphase = 2 * np.pi * np.cumsum(gear_hz * np.minimum(speed, 2.0)) / rate
        comb = sum(np.sin(k * gphase[moving]) / k for k in (1, 2, 3)
                   if gear_hz * k * 2.0 < 0.45 * rate)
        x[moving] += level[moving] * lvl * math.sqrt(2) * comb
        facts['ego_gear_hz'] = gear_hz
    elif fam == 'servo':
        noise = _shaped_noise(rng, n, rate, _band_shape(1500.0, 6000.0))
        gate = np.zeros(n)
        bursts = []
        pos = float(rng.uniform(0.0, 1.0))
        per_s = float(rng.uniform(0.5, 2.0))
        while pos < duration:
            length = float(rng.uniform(0.05, 0.5))
            i0, i1 = int(pos * rate), min(n, int((pos + length) * rate))
            if i1 > i0:
                k = np.arange(i1 - i0)
                ramp = np.minimum(1.0, np.minimum(k, i1 - i0 - 1 - k) / (0.005 * rate))
                gate[i0:i1] = np.maximum(gate[i0:i1], ramp)
                bursts.append([pos, length])
            pos += length + float(rng.exponential(1.0 / per_s))
        x += lvl * gate * noise
        facts['ego_servo_bursts'] = bursts
    if room is not None:
        x = room

    audio, facts['clipped_samples'] = _microphone(x, p=p, rng=rng, t=t)
    return audio, facts


def _motion_level(*, p: dict, ramps: list, t: np.ndarray,
                  duration: float) -> tuple[np.ndarray, np.ndarray]:
    """Arm speed / descent speed at the audio times ``t``, and the ego-noise level from it."""
    v_d = p['descent_speed_mps']
    ti = np.arange(0.0, duration + 0.01, 0.001)
    _, vi, _ = _ramps(ramps, ti)
    speed = np.interp(t, ti, np.abs(vi)) / v_d
    return speed, np.minimum(speed, 1.5) ** 0.7


def _contact_peak(*, p: dict, q: dict, tl: dict) -> float:
    """Contact sound peak (fraction of full scale): ~ contact speed and hardness."""
    peak = p['contact_amp_fs'] * p['hardness'] * (tl['v_c'] / REF_SPEED)
    if q['contact_sound_db'] != 0.0:
        peak *= 10 ** (q['contact_sound_db'] / 20)
    return peak


def _add_rustle(x: np.ndarray, *, h: _Hit, th: float, rng: np.random.Generator,
                rate: int) -> None:
    """Add a touch's faint rustle or a brush's stick-slip scraping starting at ``th`` s."""
    i0 = max(0, int(th * rate))
    i1 = min(len(x), int((th + h.dur) * rate))
    if i1 - i0 < 8:
        return
    tt = np.arange(i1 - i0) / rate
    if h.kind == 'touch':
        noise = _shaped_noise(rng, i1 - i0, rate, _band_shape(200.0, 2000.0))
        env = 0.5 * (1 - np.cos(2 * np.pi * tt / h.dur))
    else:
        noise = _shaped_noise(rng, i1 - i0, rate, _band_shape(1000.0, 6000.0))
        slip = float(rng.uniform(8.0, 30.0))
        env = np.clip(np.minimum(tt, h.dur - tt) / 0.02, 0.0, 1.0) * (
            0.6 + 0.4 * np.abs(np.sin(np.pi * slip * tt + rng.uniform(0, np.pi))))
    x[i0:i1] += h.sound_amp * env * noise


def _microphone(x: np.ndarray, *, p: dict, rng: np.random.Generator,
                t: np.ndarray) -> tuple[np.ndarray, int]:
    """Gain with slow AGC-like changes, DC offset, int16 with clipping; and the clip count."""
    gain_db = p['agc_depth_db'] * np.sin(2 * np.pi * p['agc_hz'] * t + rng.uniform(0, 2 * np.pi))
    y = x * (p['mic_gain'] * 10 ** (gain_db / 20)) * 32767.0 + p['mic_dc_lsb']
    clipped = int(np.count_nonzero(np.abs(y) > 32767.0))
    return np.clip(np.round(y), -32768, 32767).astype(np.int16), clipped


def _place(x: np.ndarray, *, data: np.ndarray, onset: int, t0: float, rate: int,
           peak: float) -> None:
    """Add a recorded impulse scaled to ``peak`` with its onset sample at ``t0`` s."""
    i0 = int(round(t0 * rate)) - onset
    a, b = max(0, i0), min(len(x), i0 + len(data))
    if b > a:
        x[a:b] += peak * data[a - i0:b - i0]


def _loop(data: np.ndarray, *, n: int, rate: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` samples of a recording repeated from a random offset, equal-power cross-fades."""
    f = max(1, min(len(data) // 4, int(round(sound_bank.FADE_S * rate))))
    y = np.roll(data, -int(rng.integers(0, len(data))))
    k = np.arange(f) / f
    win = np.ones(len(y))
    win[:f] = np.sin(0.5 * np.pi * k)
    win[-f:] = np.cos(0.5 * np.pi * k)
    out = np.zeros(n + len(y))
    step = len(y) - f
    for pos in range(0, n, step):
        out[pos:pos + len(y)] += y * (win if pos else np.concatenate((np.ones(f), win[f:])))
    return out[:n]


def _audio_real(*, p: dict, q: dict, bank: 'sound_bank.SoundBank', rng: np.random.Generator,
                rate: int, n: int, ramps: list, tl: dict, hits: list[_Hit], anchors: dict,
                duration: float) -> tuple[np.ndarray, dict]:
    """
    Microphone signal of the 'real_sounds' family as int16 and a dict of audio facts.

    Recordings are placed where :func:`_audio` puts its synthetic sounds, then the same
    microphone (:func:`_microphone`) applies.

    Room: one 'room' recording looped at RMS ``real_room_rms_fs``. Drive noise: one 'ego'
    recording looped at RMS ``real_ego_rms_fs`` times the ego-noise level of the arm's speed.
    Contact (and bounce): a 'contact' recording with peak :func:`_contact_peak` and its onset
    at ``onset + mic delay``. Hits: 'hand' and 'table' recordings at peak ``sound_amp``; a
    set-down is a 'contact' recording; touches and brushes keep the synthetic rustle.
    """
    def pick(role: str) -> sound_bank.Clip:
        clips = bank.clips[role]
        return clips[int(rng.integers(0, len(clips)))]

    t = np.arange(n) / rate
    room = pick('room')
    x = q['real_room_rms_fs'] * _loop(bank.at_rate(room, rate)[0], n=n, rate=rate, rng=rng)
    room_only = x.copy() if q['mic_mode'] == 'noise_only' else None
    _, level = _motion_level(p=p, ramps=ramps, t=t, duration=duration)
    ego = pick('ego')
    x += level * q['real_ego_rms_fs'] * _loop(bank.at_rate(ego, rate)[0], n=n, rate=rate,
                                              rng=rng)
    delay = p['mic_distance_m'] / SOUND_SPEED
    peak = _contact_peak(p=p, q=q, tl=tl)
    clip = pick('contact')
    data, onset = bank.at_rate(clip, rate)
    placed = [{'role': 'contact', 'clip': clip.name, 't': tl['onset'] + delay, 'peak_fs': peak}]
    if p['bounce']:
        placed.append({'role': 'contact', 'clip': clip.name,
                       't': tl['onset'] + delay + float(rng.uniform(0.005, 0.04)),
                       'peak_fs': peak * float(rng.uniform(0.2, 0.6))})
    for item in placed:
        _place(x, data=data, onset=onset, t0=item['t'], rate=rate, peak=item['peak_fs'])
    for h in hits:
        th = h.time(anchors) + delay
        if h.kind in ('touch', 'brush'):
            _add_rustle(x, h=h, th=th, rng=rng, rate=rate)
            continue
        role = h.kind if h.kind in ('hand', 'table') else 'contact'
        clip = pick(role)
        data, onset = bank.at_rate(clip, rate)
        _place(x, data=data, onset=onset, t0=th, rate=rate, peak=h.sound_amp)
        placed.append({'role': role, 'clip': clip.name, 't': th, 'peak_fs': h.sound_amp})
    if room_only is not None:
        x = room_only
    facts = {'contact_peak_fs': peak, 'sound_bank': bank.fingerprint,
             'sound_bank_package': f'{sound_bank.PACKAGE} {bank.package_version}',
             'real_room_clip': room.name, 'real_ego_clip': ego.name, 'real_clips': placed}
    audio, facts['clipped_samples'] = _microphone(x, p=p, rng=rng, t=t)
    return audio, facts


def _chunks(*, p: dict, rng: np.random.Generator, n: int, rate: int,
            chunk_size: int | None) -> tuple[np.ndarray, np.ndarray, int]:
    """Chunk end indices (exclusive), the jitter of each chunk (s) and the used length."""
    if chunk_size is not None or p['chunking'] == 'fixed':
        c = chunk_size if chunk_size is not None else max(1, int(round(rate / 100)))
        n = (n // c) * c
        ends = np.arange(c, n + 1, c, dtype=np.int64)
        jitter = rng.uniform(0.0, p['jitter_max_s'], len(ends))
        return ends, jitter, n
    sizes = []
    total = 0
    while total < n:
        size = int(round(math.exp(rng.uniform(0.0, math.log(4000.0)))))
        sizes.append(size)
        total += size
    ends = np.minimum(np.cumsum(sizes), n).astype(np.int64)
    big = rng.uniform(0.0, 1.0, len(ends)) < 0.2
    jitter = np.where(big, rng.uniform(0.0, p['jitter_max_s'], len(ends)),
                      rng.uniform(0.0, p['jitter_max_s'] / 4, len(ends)))
    return ends, jitter, n


# --------------------------------------------------------------------------------------------
# public API


def _check_args(*, seed, index, audio_rate, ft_rate, chunk_size, label_window_s, hits) -> None:
    for name, value in (('seed', seed), ('index', index)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ConfigError(f'{name} must be an int >= 0, got {value!r}')
    if isinstance(audio_rate, bool) or not isinstance(audio_rate, (int, np.integer)) \
            or not 8000 <= audio_rate <= 192000:
        raise ConfigError(f'audio_rate must be an int in [8000, 192000] Hz, got {audio_rate!r}')
    if not isinstance(ft_rate, (int, float)) or not math.isfinite(ft_rate) \
            or not 50.0 <= ft_rate <= 5000.0:
        raise ConfigError(f'ft_rate must be in [50, 5000] Hz, got {ft_rate!r}')
    if chunk_size is not None and (isinstance(chunk_size, bool) or not isinstance(
            chunk_size, (int, np.integer)) or not 1 <= chunk_size <= 100000):
        raise ConfigError(f'chunk_size must be None or an int in [1, 100000], got {chunk_size!r}')
    if not isinstance(label_window_s, (int, float)) or not 0.0 < label_window_s <= 1.0:
        raise ConfigError(f'label_window_s must be in (0, 1] s, got {label_window_s!r}')
    if hits is not None and hits not in HIT_KINDS:
        raise ConfigError(f'hits must be None or one of {HIT_KINDS}, got {hits!r}')


def simulate_trial(*, seed: int, index: int, condition: str = 'paper', audio_rate: int = 16000,
                   ft_rate: float = 100.0, chunk_size: int | None = None,
                   label_window_s: float = 0.1, hits: str | None = None) -> Trial:
    """
    Synthesise one trial.

    Parameters
    ----------
    seed, index : int
        Parameters are drawn with ``np.random.default_rng([seed, index])``; the trial is
        named ``trial_{index:04d}`` and starts at ``1_700_000_000 + 100 * index`` s.
    condition : str
        A condition set of :mod:`contact_detector.sim.conditions`.
    audio_rate : int
        Microphone sample rate in Hz.
    ft_rate : float
        Wrist F/T sensor rate in Hz (the HSR: 100; e.g. 1000 for a fast sensor).
    chunk_size : int or None
        Audio samples per ``/audio`` message. None: the condition decides (10 ms, or random
        sizes for 'odd_chunking').
    label_window_s : float
        Length of the labelled onset window ``[onset_t, onset_t + label_window_s)`` in s.
    hits : str or None
        'none', 'hand', 'table', 'touch', 'brush', 'setdown' or 'mixed' exogenous events
        (:data:`HIT_KINDS`); None draws one of 'none', 'hand', 'table' uniformly (the
        'exogenous' set: one of its ``hit_cycle``). Changing it changes nothing else in the
        trial.

    Returns
    -------
    Trial

    Raises
    ------
    ConfigError
        An argument is out of range or the condition set is unknown.

    """
    _check_args(seed=seed, index=index, audio_rate=audio_rate, ft_rate=ft_rate,
                chunk_size=chunk_size, label_window_s=label_window_s, hits=hits)
    cond = get_condition(condition)
    seed, index, audio_rate, ft_rate = int(seed), int(index), int(audio_rate), float(ft_rate)
    rng = np.random.default_rng([seed, index])
    p = cond.sample(rng)
    drawn_kind = HIT_KINDS[int(rng.integers(0, 3))]
    fam_rng = np.random.default_rng([seed, index, 6])
    q, q_drawn = cond.sample_family(fam_rng)
    if cond.hit_cycle != DEFAULT_HIT_CYCLE:
        drawn_kind = cond.hit_cycle[int(fam_rng.integers(0, len(cond.hit_cycle)))]
    hit_kind = hits if hits is not None else drawn_kind
    # the 'real_sounds' family: recordings from the fetched bank (ConfigError if missing)
    bank = sound_bank.load_bank() if q['sound_source'] == 'real' else None
    geo_rng = np.random.default_rng([seed, index, 5])
    hit_rng = np.random.default_rng([seed, index, 1])
    noise_rng = np.random.default_rng([seed, index, 2])
    audio_rng = np.random.default_rng([seed, index, 3])
    chunk_rng = np.random.default_rng([seed, index, 4])

    # ---- geometry
    if q['frame'] == 'hsr':
        R0 = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
        tilt_axis = np.array([0.0, *geo_rng.normal(size=2)])
        R = _rotation(tilt_axis + np.array([geo_rng.normal() * 0.3, 0.0, 0.0]),
                      math.radians(p['tilt_deg'])) @ R0
        up = R @ np.array([0.0, 0.0, 1.0])
        off_dir = geo_rng.uniform(0, 2 * np.pi)
        r_obj = np.array([p['com_offset_m'] * math.cos(off_dir),
                          p['com_offset_m'] * math.sin(off_dir), p['lever_arm_m']])
        r_contact = r_obj - 0.5 * p['object_height_m'] * up \
            + np.array([0.0, 0.0, p['contact_lever_offset_m']])
        r_hand = np.array([0.01, 0.0, p['hand_lever_m']])
    else:
        R = _frame_rotation(geo_rng, q['frame'])
        up = R @ np.array([0.0, 0.0, 1.0])
        # the contact point anywhere at contact_lever_m from the sensor, not above it
        d = _unit(geo_rng.normal(size=3))
        c = float(d @ up)
        if c > 0:
            d = d - 2 * c * up
        r_contact = q['contact_lever_m'] * d
        r_obj = r_contact + 0.5 * p['object_height_m'] * up
        r_hand = p['hand_lever_m'] * d
    m_obj = p['object_mass_kg'] + p['liquid_mass_kg']
    m_hand = p['hand_mass_kg']
    r_load = (m_obj * r_obj + m_hand * r_hand) / (m_obj + m_hand)
    k_eff = 1.0 / (1.0 / p['arm_stiffness_npm'] + 1.0 / p['surface_stiffness_npm'])
    ctau = p['contact_tau_s']
    ang = geo_rng.uniform(0, 2 * np.pi, 3)
    fric_dir = R @ np.array([math.cos(ang[0]), math.sin(ang[0]), 0.0])
    slosh_dir = R @ _unit([math.cos(ang[1]), math.sin(ang[1]), 0.3])
    mode_dir = R @ _unit([0.3 * math.cos(ang[2]), 0.3 * math.sin(ang[2]), 1.0])
    ripple_dir = _unit(geo_rng.normal(size=3))

    # ---- timeline before contact (relative seconds)
    v_d = p['descent_speed_mps']
    t_lift0 = p['rest_start_s']
    ra = 0.25 * p['lift_s']
    v_l = p['lift_dist_m'] / (p['lift_s'] - ra)
    t_hold0 = t_lift0 + p['lift_s']
    t_acc0 = t_hold0 + p['hold_s']
    t_desc0 = t_acc0 + p['accel_s']
    onset = t_desc0 + p['descend_s']
    base_ramps = [(v_l, t_lift0, ra), (-v_l, t_hold0 - ra, ra), (-v_d, t_acc0, p['accel_s'])]
    v_c = v_d
    if q['decel']:
        # a careful controller slows down to v_c before the expected table height
        v_c = min(v_d, max(0.005, v_d * q['decel_ratio']))
        dec_s = min(q['decel_s'], p['descend_s'] - 0.2)
        base_ramps.append((v_d - v_c, onset - 0.05 - dec_s, dec_s))
    z_contact = _ramp_pos(base_ramps, onset)
    descent_dist = v_d * (0.5 * p['accel_s'] + p['descend_s'])
    if q['decel']:
        descent_dist = p['lift_dist_m'] - z_contact
    tl = {'t_lift0': t_lift0, 't_hold0': t_hold0, 't_acc0': t_acc0, 't_desc0': t_desc0,
          'onset': onset, 'z_contact': z_contact, 'descent_dist': descent_dist, 'v_c': v_c}
    if q['contact_model'] == 'compliant':
        # the object's weight moves to the table in about transfer_s
        k_eff = m_obj * G / (v_c * q['transfer_s'])
        ctau = q['transfer_s'] / 4
    thr_f, thr_t = 0.0, math.inf
    if q['stop_rule'] in ('force', 'wrench'):
        thr_f = q['stop_force_n']
        thr_t = q['stop_torque_nm'] if q['stop_rule'] == 'wrench' else math.inf
    elif q['stop_rule'] == 'load':
        thr_f = max(1.0, q['stop_load_frac'] * m_obj * G)

    # ---- nominal stop (noise-free) for placing hits
    if q['stop_rule'] == 'torque_y':
        lever_y = abs(float(np.cross(r_contact, up)[1]))
        n_need = STOP_TORQUE_NM / max(lever_y, 1e-3)
    else:
        lever = float(np.linalg.norm(np.cross(r_contact, up)))
        n_need = min(thr_f, thr_t / max(lever, 1e-3))
    if q['contact_model'] == 'spring':
        tau = n_need / (k_eff * v_c)
    else:
        tau = n_need / (k_eff * v_c)
        for _ in range(20):
            tau = n_need / (k_eff * v_c) / max(1e-6, 1 - math.exp(-tau / ctau))
    stop_est = onset + tau
    hit_plan = _plan_hits(kind=hit_kind, count=p['hit_count'], rng=hit_rng, p=p, tl=tl,
                          stop_est=stop_est, R=R, q=q, r_obj=r_obj)
    horizon = q['push_horizon_s']

    # ---- sensor noise for the longest possible trial (so both passes share it)
    post = p['stop_latency_s'] + p['stop_decel_s'] + p['settle_s'] + p['retreat_s'] \
        + p['rest_end_s'] + (tl['descent_dist'] + v_d * horizon) / MAX_RETREAT_SPEED
    n_max = int(math.ceil((onset + horizon + post) * ft_rate)) + 2
    bias_f = _unit(noise_rng.normal(size=3)) * p['force_bias_n']
    bias_t = _unit(noise_rng.normal(size=3)) * p['torque_bias_nm']
    drift = []
    weights = noise_rng.uniform(0.3, 1.0, 3)
    weights /= weights.sum()
    for w in weights:
        drift.append((w * p['force_drift_n'] * _unit(noise_rng.normal(size=3)),
                      w * p['torque_drift_nm'] * _unit(noise_rng.normal(size=3)),
                      float(noise_rng.uniform(4.0, 40.0)), float(noise_rng.uniform(0, 2 * np.pi))))
    noise_f = noise_rng.standard_normal((n_max, 3))
    noise_t = noise_rng.standard_normal((n_max, 3))
    os_ = max(1, int(math.ceil(1000.0 / ft_rate)))
    setup = _Setup(p=p, ft_rate=ft_rate, os=os_, R=R, up=up, r_obj=r_obj, r_contact=r_contact,
                   r_hand=r_hand, r_load=r_load, fric_dir=fric_dir, slosh_dir=slosh_dir,
                   mode_dir=mode_dir, ripple_dir=ripple_dir, m_obj=m_obj, m_hand=m_hand,
                   k_eff=k_eff, tl=tl, base_ramps=base_ramps, bias_f=bias_f, bias_t=bias_t,
                   drift=drift, noise_f=noise_f, noise_t=noise_t, q=q, ctau=ctau,
                   thr_f=thr_f, thr_t=thr_t)

    # ---- pass 1: push until the robot's stop rule fires (the recorded robot: |delta T_y| 3 N m)
    n1 = int(math.floor((onset + horizon) * ft_rate)) + 1
    hit_scale = 1.0
    thr_scale = 1.0
    pre_stop_hits = [h for h in hit_plan if h.anchor == 'abs']
    family = bool(cond.family)
    for _ in range(12 if family else 6):
        force1, torque1, _ = _ft(setup, n_out=n1, ramps=base_ramps, tl=tl, hits=pre_stop_hits,
                                 anchors={'abs': 0.0}, hit_scale=hit_scale)
        j_stop, _base = _first_crossing(setup, force1, torque1)
        if j_stop is None:
            raise RuntimeError('simulator: the stop rule was not reached within '
                               f'{horizon} s (seed={seed}, index={index})')
        if j_stop / ft_rate >= onset:
            break
        hit_scale *= 0.5  # a hand hit in the air must not trigger the robot's stop rule
        if family:
            # a controller whose threshold fires in the air would be re-tuned higher
            thr_scale *= 1.25
            setup.thr_f, setup.thr_t = thr_f * thr_scale, thr_t * thr_scale
    else:
        raise RuntimeError(f'simulator: stop rule fired before contact (seed={seed}, '
                           f'index={index})')
    stop_rel = j_stop / ft_rate

    # ---- pass 2: the whole trial with the arm stopping, settling and retreating
    ramps, tl2 = _stop_ramps(setup, stop_rel)
    duration = tl2['end']
    n_out = int(math.floor(duration * ft_rate)) + 1
    anchors = {'abs': 0.0, 'stop': stop_rel, 'end': tl2['t_r1']}
    force, torque, t_end = _ft(setup, n_out=n_out, ramps=ramps, tl=tl2, hits=hit_plan,
                               anchors=anchors, hit_scale=hit_scale)
    j_check, base = _first_crossing(setup, force, torque)
    if j_check != j_stop:
        raise RuntimeError(f'simulator: inconsistent stop ({j_check} != {j_stop})')
    if not tl2['t_r0'] < t_end < tl2['t_r1']:
        raise RuntimeError('simulator: lift-off outside the retreat phase')

    # ---- audio
    n_audio = int(math.floor(duration * audio_rate))
    ends, jitter, n_audio = _chunks(p=p, rng=chunk_rng, n=n_audio, rate=audio_rate,
                                    chunk_size=chunk_size)
    if bank is not None:
        real_rng = np.random.default_rng([seed, index, 7])
        audio, audio_facts = _audio_real(p=p, q=q, bank=bank, rng=real_rng, rate=audio_rate,
                                         n=n_audio, ramps=ramps, tl=tl2, hits=hit_plan,
                                         anchors=anchors, duration=duration)
    else:
        audio, audio_facts = _audio(p=p, q=q, rng=audio_rng, rate=audio_rate, n=n_audio,
                                    ramps=ramps, tl=tl2, hits=hit_plan, anchors=anchors,
                                    duration=duration)

    # ---- absolute times and bookkeeping
    start = float(T0 + TRIAL_SPACING_S * index)
    wrench_rel = np.arange(n_out) / ft_rate
    lat = p['ft_latency_s'] + noise_rng.uniform(0.0, 0.001, n_out)
    wrench_log = start + np.maximum.accumulate(wrench_rel + lat)
    chunk_log = start + np.maximum.accumulate((ends - 1) / audio_rate + jitter)
    bounds = [('rest', 0.0, t_lift0), ('lift', t_lift0, t_hold0), ('hold', t_hold0, t_acc0),
              ('accelerate', t_acc0, t_desc0), ('descend', t_desc0, onset),
              ('push', onset, stop_rel), ('settle', stop_rel, tl2['t_r0']),
              ('retreat', tl2['t_r0'], tl2['t_r1']), ('rest', tl2['t_r1'], duration)]
    phases = [(name, start + a, start + b) for name, a, b in bounds]
    impacts = []
    hit_info = []
    for h in hit_plan:
        th = h.time(anchors)
        in_air = not (onset <= th < t_end)
        impacts.append(Impact(t=start + th, kind=h.kind, in_air=in_air, amplitude=h.sound_amp))
        info = {'t': start + th, 'kind': h.kind, 'window': h.window, 'in_air': in_air,
                'sound_amp_fs': h.sound_amp}
        if h.kind == 'hand':
            info.update(force_n=h.force_n * hit_scale, pulse_s=h.pulse_s,
                        direction=list(h.direction), point_m=list(h.point))
        elif h.kind in ('touch', 'brush'):
            info.update(force_n=h.force_n * hit_scale, duration_s=h.dur,
                        direction=list(h.direction), point_m=list(h.point))
            if h.kind == 'touch':
                info['on_object'] = h.on_object
        else:
            info.update(vib_n=h.vib_n if not in_air else 0.0, vib_hz=h.vib_hz)
        hit_info.append(info)
    j0, j1 = _baseline(setup, torque)[1:]
    derived = {
        'hits': hit_kind,
        'object_total_kg': m_obj,
        'k_eff_npm': k_eff,
        'retreat_speed_mps': tl2['v_r'],
        'retreat_duration_s': tl2['retreat_s'],
        'descent_dist_m': tl['descent_dist'],
        'push_depth_m': tl2['push_depth'],
        'stop_force_n': float(np.interp(stop_rel, wrench_rel, force[:, 0])),
        'baseline_ty_nm': base,
        'baseline_window': [start + j0 / ft_rate, start + j1 / ft_rate],
        'stop_threshold_nm': STOP_TORQUE_NM,
        'hand_hit_scale': hit_scale,
        'up_in_sensor': [float(u) for u in up],
        'lever_contact_m': [float(u) for u in r_contact],
        'sound_delay_s': p['mic_distance_m'] / SOUND_SPEED,
        'chunk_count': int(len(ends)),
        'chunk_size_min': int(np.diff(np.concatenate(([0], ends))).min()),
        'chunk_size_max': int(np.diff(np.concatenate(([0], ends))).max()),
        'hit_details': hit_info,
    }
    derived.update(audio_facts)
    if family:
        j_t0, j_t1 = _tare_window(setup)
        j_b1 = int(math.floor(tl['t_acc0'] * ft_rate))
        j_b0 = max(0, j_b1 - int(round(BASELINE_WINDOW_S * ft_rate)))
        derived.update({
            'frame': q['frame'],
            'stop_rule': q['stop_rule'],
            'stop_threshold_n': setup.thr_f if q['stop_rule'] != 'torque_y' else None,
            'stop_threshold_torque_nm': setup.thr_t if q['stop_rule'] == 'wrench' else None,
            'stop_threshold_scale': thr_scale,
            'baseline_force_n': force[j_b0:j_b1].mean(axis=0),
            'baseline_torque_nm': torque[j_b0:j_b1].mean(axis=0),
            'tare_window': [start + j_t0 / ft_rate, start + j_t1 / ft_rate],
            'contact_speed_mps': v_c,
            'contact_tau_s': ctau,
            'weight_transfer_s': _weight_transfer_s(k_eff=k_eff, v_c=v_c, ctau=ctau,
                                                    weight=m_obj * G,
                                                    spring=q['contact_model'] == 'spring'),
        })
    params = dict(p)
    if family:
        params['family'] = _jsonable(q)
    params['derived'] = _jsonable(derived)
    return Trial(name=f'trial_{index:04d}', condition=condition, seed=seed, start_time=start,
                 ft_rate=ft_rate, wrench_t=start + wrench_rel, force=force, torque=torque,
                 audio_rate=audio_rate, audio=audio, chunk_ends=ends, chunk_log_t=chunk_log,
                 onset_t=start + onset, onset_end_t=start + onset + label_window_s,
                 contact_end_t=start + t_end, stop_t=start + stop_rel, phases=phases,
                 impacts=impacts, params=_jsonable(params), index=index,
                 wrench_log_t=wrench_log)


def simulate_trials(*, n: int, seed: int, conditions: Sequence[str] = ('paper',),
                    start_index: int = 0, **kw) -> Iterator[Trial]:
    """
    Yield ``n`` trials; trial ``i`` uses ``conditions[i % len(conditions)]``.

    Within each condition set the hit kinds cycle its ``hit_cycle``: 'hand', 'table', 'none'
    (so about a third of each set's trials get hand hits and a third table hits, as in the
    paper's 20/20/20 of 60); 'mixed', 'touch', 'brush', 'setdown' for 'exogenous'.
    ``conditions`` may contain the aliases 'all', 'families' and 'wide'. Other keywords go to
    :func:`simulate_trial`.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ConfigError(f'n must be an int >= 0, got {n!r}')
    names = resolve_conditions(conditions)
    for i in range(start_index, start_index + int(n)):
        cond = names[i % len(names)]
        kinds = get_condition(cond).hit_cycle
        hits = kw['hits'] if 'hits' in kw else kinds[(i // len(names)) % len(kinds)]
        rest = {k: v for k, v in kw.items() if k != 'hits'}
        yield simulate_trial(seed=seed, index=i, condition=cond, hits=hits, **rest)


def _frame_rotation(rng: np.random.Generator, kind: str) -> np.ndarray:
    """
    World -> sensor rotation of a sensor mounted at any orientation.

    'random': uniform over all rotations (a unit quaternion of four normals). 'axis': world
    up along one of the six signed sensor axes, then a uniform rotation about world up.
    """
    if kind == 'random':
        w, x, y, z = _unit(rng.normal(size=4))
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    k = int(rng.integers(0, 3))
    j = (k + 1 + int(rng.integers(0, 2))) % 3
    up = np.eye(3)[k] * (1.0 if rng.uniform() < 0.5 else -1.0)
    xw = np.eye(3)[j] * (1.0 if rng.uniform() < 0.5 else -1.0)
    base = np.column_stack([xw, np.cross(up, xw), up])
    return base @ _rotation(np.array([0.0, 0.0, 1.0]), float(rng.uniform(0, 2 * np.pi)))


def _weight_transfer_s(*, k_eff: float, v_c: float, ctau: float, weight: float,
                       spring: bool) -> float:
    """Noise-free time in s from the onset until the table carries the object's weight."""
    tau = np.arange(1, 200001) * 1e-5
    normal = k_eff * v_c * tau * (1.0 if spring else (1 - np.exp(-tau / ctau)))
    idx = np.nonzero(normal >= weight)[0]
    return float(tau[idx[0]]) if len(idx) else math.inf


def _jsonable(value):
    """Convert numpy scalars / arrays / tuples recursively to plain JSON types."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
