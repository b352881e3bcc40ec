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
Signal building blocks of the simulator: motion ramps, rotations, modes, shaped noise, impacts.

Pure functions of their arguments (randomness comes in as a ``np.random.Generator``), shared by
the force/torque synthesis (:mod:`.loads`) and the sounds (:mod:`.sounds`).
"""

import math
from typing import Sequence

import numpy as np

# motion: sums of raised-cosine velocity ramps


def ramp_motion(ramps: Sequence[tuple[float, float, float]], t: np.ndarray):
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


def ramp_pos(ramps, t: float) -> float:
    return float(ramp_motion(ramps, np.array([t], dtype=float))[0][0])


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues rotation matrix."""
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def mode_ir(*, hz: float, zeta: float, dt: float) -> np.ndarray:
    """Force impulse response of a mode: ``w exp(-zeta w t) sin(w_d t)`` until it is < 1e-3."""
    w = 2 * np.pi * hz
    wd = w * math.sqrt(1 - zeta ** 2)
    n = int(math.ceil(7.0 / (zeta * w) / dt)) + 1
    t = np.arange(n) * dt
    return w * np.exp(-zeta * w * t) * np.sin(wd * t)


def causal_conv(x: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Linear causal convolution ``y[n] = sum_k h[k] x[n-k]`` via FFT, same length as x."""
    n = len(x) + len(h) - 1
    nfft = 1 << (n - 1).bit_length()
    y = np.fft.irfft(np.fft.rfft(x, nfft) * np.fft.rfft(h, nfft), nfft)
    return y[:len(x)]


def half_sine(t: np.ndarray, t0: float, dur: float, peak: float) -> np.ndarray:
    tau = t - t0
    inside = (tau >= 0) & (tau <= dur)
    return np.where(inside, peak * np.sin(np.pi * np.clip(tau, 0, dur) / dur), 0.0)


def shaped_noise(rng: np.random.Generator, n: int, rate: float, shape) -> np.ndarray:
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


def pink_shape(f: np.ndarray) -> np.ndarray:
    return np.where(f > 0, 1.0 / np.sqrt(np.maximum(f, 20.0)), 0.0) * (f / (f + 20.0))


def band_shape(lo: float, hi: float):
    def shape(f: np.ndarray) -> np.ndarray:
        hp = (f / lo) ** 2 / (1 + (f / lo) ** 2)
        lp = 1 / (1 + (f / hi) ** 2)
        return hp * lp
    return shape


def add_modal(buf: np.ndarray, *, rate: float, t0: float, freqs, decays, amps,
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


def mode_set(rng: np.random.Generator, *, n: int, lo: float, hi: float, decay: float,
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
