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
The microphone signal of a simulated trial: room, ego noise, the contact and the events.

:func:`synthetic_audio` synthesises every sound (pink background, hum, fan, babble, clatter,
motor whine, the contact's glass and table modes, knocks, rustles, the ego-noise families);
:func:`recorded_audio` (the 'real_sounds' family) places recordings of the sound bank where the
synthetic sounds would be. Both end in the same :func:`microphone` (gain, AGC, DC, int16).
"""

import math

from contact_detector.sim import sound_bank
from contact_detector.sim.hits import Hit
from contact_detector.sim.params import FamilyParams, TrialParams
from contact_detector.sim.signals import (add_modal, band_shape, mode_set, pink_shape,
                                          ramp_motion, shaped_noise)
from contact_detector.sim.timeline import Timeline
import numpy as np

#: Speed of sound in m/s (delay from the hand to the microphone).
SOUND_SPEED = 343.0
#: Descent speed at which ``contact_amp_fs`` is the contact sound's peak (m/s).
REF_SPEED = 0.04


def synthetic_audio(*, p: TrialParams, q: FamilyParams, rng: np.random.Generator, rate: int,
                    n: int, ramps: list, tl: Timeline, hits: list[Hit], anchors: dict,
                    duration: float) -> tuple[np.ndarray, dict]:
    """Microphone signal as int16 and a dict of audio facts for the params."""
    t = np.arange(n) / rate
    x = p.bg_rms_fs * shaped_noise(rng, n, rate, pink_shape)
    # mains hum with two harmonics, robot fan (tone + band noise)
    hum = p.hum_hz
    for k, w in ((1, 1.0), (2, 0.5), (3, 0.3)):
        x += p.hum_rms_fs * math.sqrt(2) * w * np.sin(2 * np.pi * k * hum * t
                                                      + rng.uniform(0, 2 * np.pi))
    fan_hz = float(rng.uniform(90.0, 250.0))
    fan = shaped_noise(rng, n, rate, band_shape(150.0, 1200.0))
    x += p.fan_rms_fs * (0.8 * fan + 0.6 * math.sqrt(2) * np.sin(2 * np.pi * fan_hz * t))
    facts: dict = {'fan_hz': fan_hz}
    # a muted or far microphone hears only the room (kept aside here)
    room = x.copy() if q.mic_mode == 'noise_only' else None
    # household babble: speech-shaped noise, talkers switching on and off with syllabic AM
    if p.babble_rms_fs > 0:
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
        speech = shaped_noise(rng, n, rate, band_shape(300.0, 1500.0)) * env
        rms = float(np.sqrt(np.mean(speech ** 2)))
        if rms > 0:
            x += p.babble_rms_fs * speech / rms
        facts['babble_talkers'] = talkers
    # distant clatter of dishes / cutlery (no F/T)
    clatter = []
    if p.clatter_per_s > 0:
        count = int(rng.poisson(p.clatter_per_s * duration))
        for _ in range(count):
            tc = float(rng.uniform(0.2, duration - 0.2))
            amp = float(math.exp(rng.uniform(math.log(0.003), math.log(0.05))))
            fr, de, am = mode_set(rng, n=3, lo=1500.0, hi=7000.0,
                                  decay=float(rng.uniform(0.02, 0.15)), peak=amp)
            add_modal(x, rate=rate, t0=tc, freqs=fr, decays=de, amps=am, attack_s=0.0003,
                      click_amp=0.3 * amp, click_decay_s=0.001, rng=rng)
            clatter.append([tc, amp])
    facts['clatter'] = sorted(clatter)
    # robot ego noise while the motors turn: harmonic whine (pitch ~ speed) + broadband
    speed, level = motion_level(p=p, ramps=ramps, t=t, duration=duration)
    phase = 2 * np.pi * np.cumsum(p.whine_hz * np.minimum(speed, 2.0)) / rate
    moving = np.nonzero(level > 0)[0]
    whine = np.zeros(len(moving))
    for k in range(1, 6):
        gain = float(rng.uniform(0.3, 1.0)) / k ** 1.2
        if p.whine_hz * k * 2.0 < 0.45 * rate:
            whine += gain * np.sin(k * phase[moving])
    full = level[moving] > 0.5
    whine /= max(1e-12, float(np.sqrt(np.mean(whine[full] ** 2))) if np.any(full) else 1.0)
    broad = shaped_noise(rng, n, rate, band_shape(800.0, 4000.0))
    x[moving] += level[moving] * (p.whine_rms_fs * whine
                                  + p.ego_broad_rms_fs * broad[moving])

    # the contact sound: glass modes (bright) + table modes, loudness ~ speed and hardness
    delay = p.mic_distance_m / SOUND_SPEED
    peak = contact_peak(p=p, q=q, tl=tl)
    bright = p.brightness
    lo, hi = p.table_modes_hz
    gf, gd, ga = mode_set(rng, n=int(rng.integers(2, 5)), lo=1000.0, hi=8000.0,
                          decay=p.glass_decay_s, peak=peak, weight=bright)
    tf, td, ta = mode_set(rng, n=int(rng.integers(2, 5)), lo=lo, hi=hi,
                          decay=p.table_decay_s, peak=peak, weight=1.0 - 0.5 * bright)
    attack = p.impact_duration_s / 8
    contacts = [(tl.onset + delay, 1.0)]
    if p.bounce:
        contacts.append((tl.onset + delay + float(rng.uniform(0.005, 0.04)),
                         float(rng.uniform(0.2, 0.6))))
    for tc, scale in contacts:
        add_modal(x, rate=rate, t0=tc, freqs=gf + tf, decays=gd + td,
                  amps=[scale * a for a in ga + ta], attack_s=attack,
                  click_amp=0.3 * scale * peak * p.hardness,
                  click_decay_s=max(0.0005, p.impact_duration_s / 3), rng=rng)
    facts['contact_peak_fs'] = peak
    facts['contact_modes_hz'] = [float(f) for f in gf + tf]

    # exogenous impacts
    for h in hits:
        th = h.time(anchors) + delay
        if h.kind == 'hand':
            fr, de, am = mode_set(rng, n=3, lo=300.0, hi=3000.0,
                                  decay=float(rng.uniform(0.008, 0.04)), peak=h.sound_amp)
            add_modal(x, rate=rate, t0=th, freqs=fr, decays=de, amps=am, attack_s=0.0005,
                      click_amp=0.4 * h.sound_amp, click_decay_s=0.0015, rng=rng)
        elif h.kind == 'table':
            fr, de, am = mode_set(rng, n=3, lo=100.0, hi=1500.0,
                                  decay=float(rng.uniform(0.01, 0.05)), peak=0.7 * h.sound_amp)
            fr.append(float(rng.uniform(60.0, 150.0)))
            de.append(0.03)
            am.append(0.3 * h.sound_amp)
            add_modal(x, rate=rate, t0=th, freqs=fr, decays=de, amps=am, attack_s=0.001,
                      click_amp=0.3 * h.sound_amp, click_decay_s=0.002, rng=rng)
        elif h.kind == 'setdown':
            # a cup or plate set down nearby: a contact-like sound (object and table modes)
            fr, de, am = mode_set(rng, n=3, lo=800.0, hi=7000.0,
                                  decay=float(rng.uniform(0.01, 0.06)), peak=0.7 * h.sound_amp)
            fr2, de2, am2 = mode_set(rng, n=2, lo=100.0, hi=1500.0,
                                     decay=float(rng.uniform(0.005, 0.04)),
                                     peak=0.5 * h.sound_amp)
            add_modal(x, rate=rate, t0=th, freqs=fr + fr2, decays=de + de2, amps=am + am2,
                      attack_s=float(rng.uniform(0.0003, 0.003)), click_amp=0.3 * h.sound_amp,
                      click_decay_s=0.0015, rng=rng)
        else:  # 'touch' (a faint rustle) or 'brush' (scraping, stick-slip modulated)
            add_rustle(x, h=h, th=th, rng=rng, rate=rate)

    # ego-noise families besides the motor whine
    fam = q.ego_family
    lvl = q.ego_extra_rms_fs
    if fam == 'fan':
        blade = float(rng.uniform(60.0, 400.0))
        x += lvl * (shaped_noise(rng, n, rate, band_shape(100.0, 6000.0))
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
        noise = shaped_noise(rng, n, rate, band_shape(1500.0, 6000.0))
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

    audio, facts['clipped_samples'] = microphone(x, p=p, rng=rng, t=t)
    return audio, facts


def motion_level(*, p: TrialParams, ramps: list, t: np.ndarray,
                 duration: float) -> tuple[np.ndarray, np.ndarray]:
    """Arm speed / descent speed at the audio times ``t``, and the ego-noise level from it."""
    v_d = p.descent_speed_mps
    ti = np.arange(0.0, duration + 0.01, 0.001)
    _, vi, _ = ramp_motion(ramps, ti)
    speed = np.interp(t, ti, np.abs(vi)) / v_d
    return speed, np.minimum(speed, 1.5) ** 0.7


def contact_peak(*, p: TrialParams, q: FamilyParams, tl: Timeline) -> float:
    """Contact sound peak (fraction of full scale): ~ contact speed and hardness."""
    peak = p.contact_amp_fs * p.hardness * (tl.v_c / REF_SPEED)
    if q.contact_sound_db != 0.0:
        peak *= 10 ** (q.contact_sound_db / 20)
    return peak


def add_rustle(x: np.ndarray, *, h: Hit, th: float, rng: np.random.Generator,
               rate: int) -> None:
    """Add a touch's faint rustle or a brush's stick-slip scraping starting at ``th`` s."""
    i0 = max(0, int(th * rate))
    i1 = min(len(x), int((th + h.dur) * rate))
    if i1 - i0 < 8:
        return
    tt = np.arange(i1 - i0) / rate
    if h.kind == 'touch':
        noise = shaped_noise(rng, i1 - i0, rate, band_shape(200.0, 2000.0))
        env = 0.5 * (1 - np.cos(2 * np.pi * tt / h.dur))
    else:
        noise = shaped_noise(rng, i1 - i0, rate, band_shape(1000.0, 6000.0))
        slip = float(rng.uniform(8.0, 30.0))
        env = np.clip(np.minimum(tt, h.dur - tt) / 0.02, 0.0, 1.0) * (
            0.6 + 0.4 * np.abs(np.sin(np.pi * slip * tt + rng.uniform(0, np.pi))))
    x[i0:i1] += h.sound_amp * env * noise


def microphone(x: np.ndarray, *, p: TrialParams, rng: np.random.Generator,
               t: np.ndarray) -> tuple[np.ndarray, int]:
    """Gain with slow AGC-like changes, DC offset, int16 with clipping; and the clip count."""
    gain_db = p.agc_depth_db * np.sin(2 * np.pi * p.agc_hz * t + rng.uniform(0, 2 * np.pi))
    y = x * (p.mic_gain * 10 ** (gain_db / 20)) * 32767.0 + p.mic_dc_lsb
    clipped = int(np.count_nonzero(np.abs(y) > 32767.0))
    return np.clip(np.round(y), -32768, 32767).astype(np.int16), clipped


def place(x: np.ndarray, *, data: np.ndarray, onset: int, t0: float, rate: int,
          peak: float) -> None:
    """Add a recorded impulse scaled to ``peak`` with its onset sample at ``t0`` s."""
    i0 = int(round(t0 * rate)) - onset
    a, b = max(0, i0), min(len(x), i0 + len(data))
    if b > a:
        x[a:b] += peak * data[a - i0:b - i0]


def loop(data: np.ndarray, *, n: int, rate: int, rng: np.random.Generator) -> np.ndarray:
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


def recorded_audio(*, p: TrialParams, q: FamilyParams, bank: 'sound_bank.SoundBank',
                   rng: np.random.Generator, rate: int, n: int, ramps: list, tl: Timeline,
                   hits: list[Hit], anchors: dict, duration: float) -> tuple[np.ndarray, dict]:
    """
    Microphone signal of the 'real_sounds' family as int16 and a dict of audio facts.

    Recordings are placed where :func:`synthetic_audio` puts its synthetic sounds, then the same
    microphone (:func:`microphone`) applies.

    Room: one 'room' recording looped at RMS ``real_room_rms_fs``. Drive noise: one 'ego'
    recording looped at RMS ``real_ego_rms_fs`` times the ego-noise level of the arm's speed.
    Contact (and bounce): a 'contact' recording with peak :func:`contact_peak` and its onset
    at ``onset + mic delay``. Hits: 'hand' and 'table' recordings at peak ``sound_amp``; a
    set-down is a 'contact' recording; touches and brushes keep the synthetic rustle.
    """
    def pick(role: str) -> sound_bank.Clip:
        clips = bank.clips[role]
        return clips[int(rng.integers(0, len(clips)))]

    t = np.arange(n) / rate
    room = pick('room')
    x = q.real_room_rms_fs * loop(bank.at_rate(room, rate)[0], n=n, rate=rate, rng=rng)
    room_only = x.copy() if q.mic_mode == 'noise_only' else None
    _, level = motion_level(p=p, ramps=ramps, t=t, duration=duration)
    ego = pick('ego')
    x += level * q.real_ego_rms_fs * loop(bank.at_rate(ego, rate)[0], n=n, rate=rate,
                                          rng=rng)
    delay = p.mic_distance_m / SOUND_SPEED
    peak = contact_peak(p=p, q=q, tl=tl)
    clip = pick('contact')
    data, onset = bank.at_rate(clip, rate)
    placed = [{'role': 'contact', 'clip': clip.name, 't': tl.onset + delay, 'peak_fs': peak}]
    if p.bounce:
        placed.append({'role': 'contact', 'clip': clip.name,
                       't': tl.onset + delay + float(rng.uniform(0.005, 0.04)),
                       'peak_fs': peak * float(rng.uniform(0.2, 0.6))})
    for item in placed:
        place(x, data=data, onset=onset, t0=item['t'], rate=rate, peak=item['peak_fs'])
    for h in hits:
        th = h.time(anchors) + delay
        if h.kind in ('touch', 'brush'):
            add_rustle(x, h=h, th=th, rng=rng, rate=rate)
            continue
        role = h.kind if h.kind in ('hand', 'table') else 'contact'
        clip = pick(role)
        data, onset = bank.at_rate(clip, rate)
        place(x, data=data, onset=onset, t0=th, rate=rate, peak=h.sound_amp)
        placed.append({'role': role, 'clip': clip.name, 't': th, 'peak_fs': h.sound_amp})
    if room_only is not None:
        x = room_only
    facts = {'contact_peak_fs': peak, 'sound_bank': bank.fingerprint,
             'sound_bank_package': f'{sound_bank.PACKAGE} {bank.package_version}',
             'real_room_clip': room.name, 'real_ego_clip': ego.name, 'real_clips': placed}
    audio, facts['clipped_samples'] = microphone(x, p=p, rng=rng, t=t)
    return audio, facts
