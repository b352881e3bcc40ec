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

This module assembles a trial; each job has its module: the drawn values
(:mod:`.params`: :class:`~.params.TrialParams`, :class:`~.params.FamilyParams`), the motion's
times (:mod:`.timeline`), the layout (:mod:`.geometry`), the events (:mod:`.hits`), the
force/torque and the stop rule (:mod:`.loads`), the microphone (:mod:`.sounds`) and their
signal building blocks (:mod:`.signals`).

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
where they start, the microphone's AGC phase) from k=7 instead of k=3. ``events='everywhere'``
draws the missing event parameters from k=8, ``tared='everywhere'`` the missing ``tared``
from k=9 and ``contact_sound='everywhere'`` the missing ``contact_sound_db`` from k=10. The hit
plan therefore never changes the other parameters: ``simulate_trial(..., hits='none')`` is the
same trial without its exogenous impacts.
"""

from dataclasses import dataclass, field, replace
import math
from typing import Iterator, Sequence

from contact_detector.errors import ConfigError
from contact_detector.sim import sound_bank
from contact_detector.sim.conditions import (BRUSH_MODES, CONTACT_SOUND_MODES,
                                             CONTACT_SOUND_RANGE, DEFAULT_HIT_CYCLE,
                                             EVENT_MODES, EVENT_RANGES, get_condition,
                                             resolve_conditions, TARED_MODES, TARED_RANGE)
from contact_detector.sim.geometry import draw_geometry
from contact_detector.sim.hits import friction_brush, Hit, plan_hits
from contact_detector.sim.loads import (contact_law, draw_sensor_errors, first_crossing, G,
                                        nominal_stop, Setup, STOP_TORQUE_NM, tare_window,
                                        torque_baseline, weight_transfer_s, wrench)
from contact_detector.sim.params import TrialParams
from contact_detector.sim.sounds import recorded_audio, SOUND_SPEED, synthetic_audio
from contact_detector.sim.timeline import (approach_timeline, BASELINE_WINDOW_S,
                                           MAX_RETREAT_SPEED, stop_timeline)
import numpy as np

#: Absolute start time of trial ``index``: ``T0 + TRIAL_SPACING_S * index`` seconds.
T0 = 1_700_000_000
TRIAL_SPACING_S = 100
#: Hit kinds: 'none', the paper's exogenous impacts ('hand', 'table'), the families' events
#: ('touch', 'brush', 'setdown') and 'mixed' (each event draws one of the five).
HIT_KINDS = ('none', 'hand', 'table', 'touch', 'brush', 'setdown', 'mixed')
#: Phase names in order.
PHASES = ('rest', 'lift', 'hold', 'accelerate', 'descend', 'push', 'settle', 'retreat', 'rest')


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


def _chunks(*, p: TrialParams, rng: np.random.Generator, n: int, rate: int,
            chunk_size: int | None) -> tuple[np.ndarray, np.ndarray, int]:
    """Chunk end indices (exclusive), the jitter of each chunk (s) and the used length."""
    if chunk_size is not None or p.chunking == 'fixed':
        c = chunk_size if chunk_size is not None else max(1, int(round(rate / 100)))
        n = (n // c) * c
        ends = np.arange(c, n + 1, c, dtype=np.int64)
        jitter = rng.uniform(0.0, p.jitter_max_s, len(ends))
        return ends, jitter, n
    sizes = []
    total = 0
    while total < n:
        size = int(round(math.exp(rng.uniform(0.0, math.log(4000.0)))))
        sizes.append(size)
        total += size
    ends = np.minimum(np.cumsum(sizes), n).astype(np.int64)
    big = rng.uniform(0.0, 1.0, len(ends)) < 0.2
    jitter = np.where(big, rng.uniform(0.0, p.jitter_max_s, len(ends)),
                      rng.uniform(0.0, p.jitter_max_s / 4, len(ends)))
    return ends, jitter, n


#: The parameters :func:`simulate_trial`'s ``sensor_offset`` scales, force then torque.
OFFSET_PARAMS = ('force_bias_n', 'torque_bias_nm')

#: The largest ``sensor_offset`` accepted, N and N m: beyond a wrist sensor's range.
MAX_SENSOR_OFFSET = (1000.0, 100.0)


def _scaled_offsets(*, p, ranges: dict, largest: tuple) -> dict:
    """
    Map the drawn offset lengths onto ``[0, largest]``, at the same quantiles.

    ``v' = (v - lo) / (hi - lo) * largest`` for the set's range ``[lo, hi]`` of each of
    :data:`OFFSET_PARAMS` (both uniform), so that no other draw changes.
    """
    out = {}
    for name, top in zip(OFFSET_PARAMS, largest):
        spec = ranges[name]
        share = (getattr(p, name) - spec.low) / (spec.high - spec.low)
        out[name] = float(share * top)
    return out


def _check_args(*, seed, index, audio_rate, ft_rate, chunk_size, label_window_s, hits,
                events, tared, contact_sound, brushes, sensor_offset=None) -> None:
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
    if events not in EVENT_MODES:
        raise ConfigError(f'events must be one of {EVENT_MODES}, got {events!r}')
    if tared not in TARED_MODES:
        raise ConfigError(f'tared must be one of {TARED_MODES}, got {tared!r}')
    if contact_sound not in CONTACT_SOUND_MODES:
        raise ConfigError(f'contact_sound must be one of {CONTACT_SOUND_MODES}, '
                          f'got {contact_sound!r}')
    if brushes not in BRUSH_MODES:
        raise ConfigError(f'brushes must be one of {BRUSH_MODES}, got {brushes!r}')
    if sensor_offset is not None:
        try:
            force, torque = (float(v) for v in sensor_offset)
        except (TypeError, ValueError) as err:
            raise ConfigError(f'sensor_offset must be (N, N m), got {sensor_offset!r}') from err
        if not (0.0 <= force <= MAX_SENSOR_OFFSET[0] and 0.0 <= torque <= MAX_SENSOR_OFFSET[1]):
            raise ConfigError(f'sensor_offset must be in [0, {MAX_SENSOR_OFFSET[0]:g}] N and '
                              f'[0, {MAX_SENSOR_OFFSET[1]:g}] N m, got {sensor_offset!r}')


def simulate_trial(*, seed: int, index: int, condition: str = 'paper', audio_rate: int = 16000,
                   ft_rate: float = 100.0, chunk_size: int | None = None,
                   label_window_s: float = 0.1, hits: str | None = None,
                   events: str = 'family', tared: str = 'family',
                   contact_sound: str = 'family', brushes: str = 'lifting',
                   sensor_offset: tuple[float, float] | None = None) -> Trial:
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
    events : str
        'family' (default) or 'everywhere' (``EVENT_MODES`` of :mod:`.conditions`): with
        'everywhere', a set whose family does not draw the touch, brush and set-down
        parameters draws them from the 'exogenous' ranges, in a stream of their own
        (``default_rng([seed, index, 8])``), and ``hits=None`` draws from the set's
        ``ConditionSet.cycle``. The rest of the trial is the one ``events='family'`` gives.
    tared : str
        'family' (default), 'everywhere', 'all' or 'none' (``TARED_MODES`` of
        :mod:`.conditions`): whether the F/T sensor is tared (zeroed at rest before the lift,
        so it reads the load's change since then). 'family': only the sets whose family draws
        it ('geometry', 'slow_partial'); 'everywhere': a set whose family does not draw it
        draws it (untared or tared, equal odds) in a stream of its own
        (``default_rng([seed, index, 9])``); 'all': every sensor is tared; 'none': no sensor
        is. An untared trial's wrench and audio are the ones ``tared='family'`` gives, and
        the tare changes nothing else. With 'everywhere', 'all' and 'none' every trial's
        ``params['family']`` is recorded, its ``tared`` the draw.
    contact_sound : str
        'family' (default) or 'everywhere' (``CONTACT_SOUND_MODES`` of :mod:`.conditions`):
        with 'everywhere', a set whose family does not draw ``contact_sound_db`` draws it from
        ``CONTACT_SOUND_RANGE`` (-24 to 0 dB on the contact sound's peak) in a stream of its
        own (``default_rng([seed, index, 10])``); the rest of the trial is the one 'family'
        gives, and ``params['family']`` is recorded.
    brushes : str
        'lifting' (default) or 'friction' (``BRUSH_MODES`` of :mod:`.conditions`): with
        'friction', every brush is the friction against the motion plus the sideways push that
        makes it, with a friction coefficient of 0.2-1.0
        (:func:`~contact_detector.sim.hits.friction_brush`); the rest of the trial is the one
        'lifting' gives.
    sensor_offset : (float, float) or None
        The largest length of the untared sensor's constant offset (bias) vector, force in N
        and torque in N m: a sensor that was never zeroed. None (default): the set's ranges
        (up to 3 N and 0.3 N m: a sensor zeroed with the empty hand, then drifting). The
        lengths are the same quantiles of the new ranges ``[0, N]``, ``[0, NM]`` as the set's
        draw of its own, and their directions are unchanged, so the trial is the one None
        gives but for the offset. A tared sensor reads no offset either way.

    Returns
    -------
    Trial

    Raises
    ------
    ConfigError
        An argument is out of range or the condition set is unknown.

    """
    _check_args(seed=seed, index=index, audio_rate=audio_rate, ft_rate=ft_rate,
                chunk_size=chunk_size, label_window_s=label_window_s, hits=hits,
                events=events, tared=tared, contact_sound=contact_sound, brushes=brushes,
                sensor_offset=sensor_offset)
    cond = get_condition(condition)
    seed, index, audio_rate, ft_rate = int(seed), int(index), int(audio_rate), float(ft_rate)
    rng = np.random.default_rng([seed, index])
    p = cond.sample(rng)
    if sensor_offset is not None:
        p = replace(p, **_scaled_offsets(p=p, ranges=cond.ranges, largest=sensor_offset))
    drawn_kind = HIT_KINDS[int(rng.integers(0, 3))]
    fam_rng = np.random.default_rng([seed, index, 6])
    q, _drawn = cond.sample_family(fam_rng)
    if cond.hit_cycle != DEFAULT_HIT_CYCLE:
        drawn_kind = cond.hit_cycle[int(fam_rng.integers(0, len(cond.hit_cycle)))]
    missing = sorted(set(EVENT_RANGES) - set(cond.family)) if events == 'everywhere' else []
    if missing:
        # a stream of its own, so every other parameter stays what 'family' draws
        ev_rng = np.random.default_rng([seed, index, 8])
        q = replace(q, **{name: EVENT_RANGES[name].sample(ev_rng) for name in missing})
        cycle = cond.cycle(events=events)
        drawn_kind = cycle[int(ev_rng.integers(0, len(cycle)))] if hits is None else drawn_kind
    if tared in ('all', 'none'):
        q = replace(q, tared=tared == 'all')
    elif tared == 'everywhere' and 'tared' not in cond.family:
        # a stream of its own, so every other parameter stays what 'family' draws
        q = replace(q, tared=bool(TARED_RANGE.sample(np.random.default_rng([seed, index, 9]))))
    if contact_sound == 'everywhere' and 'contact_sound_db' not in cond.family:
        # a stream of its own, so every other parameter stays what 'family' draws
        q = replace(q, contact_sound_db=float(CONTACT_SOUND_RANGE.sample(
            np.random.default_rng([seed, index, 10]))))
    hit_kind = hits if hits is not None else drawn_kind
    # the 'real_sounds' family: recordings from the fetched bank (ConfigError if missing)
    bank = sound_bank.load_bank() if q.sound_source == 'real' else None
    noise_rng = np.random.default_rng([seed, index, 2])

    # ---- geometry, the approach, the contact law and the events
    geo = draw_geometry(p=p, q=q, rng=np.random.default_rng([seed, index, 5]))
    tl, base_ramps = approach_timeline(p=p, q=q)
    contact = contact_law(p=p, q=q, m_obj=geo.m_obj, v_c=tl.v_c)
    hit_plan = plan_hits(kind=hit_kind, count=p.hit_count,
                         rng=np.random.default_rng([seed, index, 1]), p=p, tl=tl,
                         stop_est=nominal_stop(q=q, geo=geo, contact=contact, tl=tl),
                         R=geo.R, q=q, r_obj=geo.r_obj)
    if brushes == 'friction':
        hit_plan = [friction_brush(h, R=geo.R) if h.kind == 'brush' else h for h in hit_plan]
    horizon = q.push_horizon_s

    # ---- sensor errors for the longest possible trial (so both passes share them)
    post = p.stop_latency_s + p.stop_decel_s + p.settle_s + p.retreat_s \
        + p.rest_end_s + (tl.descent_dist + p.descent_speed_mps * horizon) / MAX_RETREAT_SPEED
    n_max = int(math.ceil((tl.onset + horizon + post) * ft_rate)) + 2
    setup = Setup(p=p, q=q, ft_rate=ft_rate, os=max(1, int(math.ceil(1000.0 / ft_rate))),
                  geo=geo, sensor=draw_sensor_errors(p=p, rng=noise_rng, n_max=n_max), tl=tl,
                  base_ramps=base_ramps, k_eff=contact.k_eff, ctau=contact.ctau,
                  thr_f=contact.thr_f, thr_t=contact.thr_t)

    # ---- pass 1: push until the robot's stop rule fires (the recorded robot: |delta T_y| 3 N m)
    family = bool(cond.family)
    setup, j_stop, hit_scale, thr_scale = _find_stop(
        setup, hits=[h for h in hit_plan if h.anchor == 'abs'], family=family,
        where=f'seed={seed}, index={index}')
    stop_rel = j_stop / ft_rate

    # ---- pass 2: the whole trial with the arm stopping, settling and retreating
    ramps, tl2 = stop_timeline(p=p, tl=tl, base_ramps=base_ramps, stop_rel=stop_rel)
    duration = tl2.end
    n_out = int(math.floor(duration * ft_rate)) + 1
    anchors = {'abs': 0.0, 'stop': stop_rel, 'end': tl2.t_r1}
    force, torque, t_end = wrench(setup, n_out=n_out, ramps=ramps, tl=tl2, hits=hit_plan,
                                  anchors=anchors, hit_scale=hit_scale)
    j_check, base = first_crossing(setup, force, torque)
    if j_check != j_stop:
        raise RuntimeError(f'simulator: inconsistent stop ({j_check} != {j_stop})')
    if not tl2.t_r0 < t_end < tl2.t_r1:
        raise RuntimeError('simulator: lift-off outside the retreat phase')

    # ---- audio
    n_audio = int(math.floor(duration * audio_rate))
    ends, jitter, n_audio = _chunks(p=p, rng=np.random.default_rng([seed, index, 4]),
                                    n=n_audio, rate=audio_rate, chunk_size=chunk_size)
    if bank is not None:
        real_rng = np.random.default_rng([seed, index, 7])
        audio, audio_facts = recorded_audio(p=p, q=q, bank=bank, rng=real_rng, rate=audio_rate,
                                            n=n_audio, ramps=ramps, tl=tl2, hits=hit_plan,
                                            anchors=anchors, duration=duration)
    else:
        audio, audio_facts = synthetic_audio(p=p, q=q, rng=np.random.default_rng([seed, index, 3]),
                                             rate=audio_rate, n=n_audio, ramps=ramps, tl=tl2,
                                             hits=hit_plan, anchors=anchors, duration=duration)

    # ---- absolute times and bookkeeping
    start = float(T0 + TRIAL_SPACING_S * index)
    wrench_rel = np.arange(n_out) / ft_rate
    lat = p.ft_latency_s + noise_rng.uniform(0.0, 0.001, n_out)
    wrench_log = start + np.maximum.accumulate(wrench_rel + lat)
    chunk_log = start + np.maximum.accumulate((ends - 1) / audio_rate + jitter)
    bounds = [('rest', 0.0, tl.t_lift0), ('lift', tl.t_lift0, tl.t_hold0),
              ('hold', tl.t_hold0, tl.t_acc0), ('accelerate', tl.t_acc0, tl.t_desc0),
              ('descend', tl.t_desc0, tl.onset), ('push', tl.onset, stop_rel),
              ('settle', stop_rel, tl2.t_r0), ('retreat', tl2.t_r0, tl2.t_r1),
              ('rest', tl2.t_r1, duration)]
    phases = [(name, start + a, start + b) for name, a, b in bounds]
    impacts, hit_info = _hit_records(hit_plan, anchors=anchors, onset=tl.onset, t_end=t_end,
                                     hit_scale=hit_scale, start=start)
    j0, j1 = torque_baseline(setup, torque)[1:]
    derived = {
        'hits': hit_kind,
        'object_total_kg': geo.m_obj,
        'k_eff_npm': setup.k_eff,
        'retreat_speed_mps': tl2.v_r,
        'retreat_duration_s': tl2.retreat_s,
        'descent_dist_m': tl.descent_dist,
        'push_depth_m': tl2.push_depth,
        'stop_force_n': float(np.interp(stop_rel, wrench_rel, force[:, 0])),
        'baseline_ty_nm': base,
        'baseline_window': [start + j0 / ft_rate, start + j1 / ft_rate],
        'stop_threshold_nm': STOP_TORQUE_NM,
        'hand_hit_scale': hit_scale,
        'up_in_sensor': [float(u) for u in geo.up],
        'lever_contact_m': [float(u) for u in geo.r_contact],
        'sound_delay_s': p.mic_distance_m / SOUND_SPEED,
        'chunk_count': int(len(ends)),
        'chunk_size_min': int(np.diff(np.concatenate(([0], ends))).min()),
        'chunk_size_max': int(np.diff(np.concatenate(([0], ends))).max()),
        'hit_details': hit_info,
    }
    derived.update(audio_facts)
    if family:
        derived.update(_family_facts(setup, force=force, torque=torque, start=start,
                                     thr_scale=thr_scale))
    params = p.as_dict()
    if family or tared != 'family' or contact_sound != 'family':
        params['family'] = _jsonable(q.as_dict())
    params['derived'] = _jsonable(derived)
    return Trial(name=f'trial_{index:04d}', condition=condition, seed=seed, start_time=start,
                 ft_rate=ft_rate, wrench_t=start + wrench_rel, force=force, torque=torque,
                 audio_rate=audio_rate, audio=audio, chunk_ends=ends, chunk_log_t=chunk_log,
                 onset_t=start + tl.onset, onset_end_t=start + tl.onset + label_window_s,
                 contact_end_t=start + t_end, stop_t=start + stop_rel, phases=phases,
                 impacts=impacts, params=_jsonable(params), index=index,
                 wrench_log_t=wrench_log)


def _find_stop(setup: Setup, *, hits: list[Hit], family: bool,
               where: str) -> tuple[Setup, int, float, float]:
    """
    Push until the robot's stop rule fires; return the setup used, the stop sample and scales.

    A hand hit in the air must not trigger the stop rule: such hits are halved (and a family's
    thresholds raised by 25 %, as a controller firing in the air would be re-tuned) until the
    stop comes after the onset. Returns ``(setup, j_stop, hit_scale, thr_scale)``.
    """
    tl, ft_rate = setup.tl, setup.ft_rate
    horizon = setup.q.push_horizon_s
    n1 = int(math.floor((tl.onset + horizon) * ft_rate)) + 1
    thr_f, thr_t = setup.thr_f, setup.thr_t
    hit_scale = 1.0
    thr_scale = 1.0
    for _ in range(12 if family else 6):
        force1, torque1, _ = wrench(setup, n_out=n1, ramps=setup.base_ramps, tl=tl, hits=hits,
                                    anchors={'abs': 0.0}, hit_scale=hit_scale)
        j_stop, _base = first_crossing(setup, force1, torque1)
        if j_stop is None:
            raise RuntimeError('simulator: the stop rule was not reached within '
                               f'{horizon} s ({where})')
        if j_stop / ft_rate >= tl.onset:
            return setup, j_stop, hit_scale, thr_scale
        hit_scale *= 0.5  # a hand hit in the air must not trigger the robot's stop rule
        if family:
            # a controller whose threshold fires in the air would be re-tuned higher
            thr_scale *= 1.25
            setup = replace(setup, thr_f=thr_f * thr_scale, thr_t=thr_t * thr_scale)
    raise RuntimeError(f'simulator: stop rule fired before contact ({where})')


def _hit_records(hit_plan: list[Hit], *, anchors: dict, onset: float, t_end: float,
                 hit_scale: float, start: float) -> tuple[list, list]:
    """Return the :class:`Impact` of each event and its manifest details (absolute times)."""
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
    return impacts, hit_info


def _family_facts(setup: Setup, *, force: np.ndarray, torque: np.ndarray, start: float,
                  thr_scale: float) -> dict:
    """Return the derived facts the family sets add to the manifest."""
    q, tl, ft_rate = setup.q, setup.tl, setup.ft_rate
    j_t0, j_t1 = tare_window(setup)
    j_b1 = int(math.floor(tl.t_acc0 * ft_rate))
    j_b0 = max(0, j_b1 - int(round(BASELINE_WINDOW_S * ft_rate)))
    return {
        'frame': q.frame,
        'stop_rule': q.stop_rule,
        'stop_threshold_n': setup.thr_f if q.stop_rule != 'torque_y' else None,
        'stop_threshold_torque_nm': setup.thr_t if q.stop_rule == 'wrench' else None,
        'stop_threshold_scale': thr_scale,
        'baseline_force_n': force[j_b0:j_b1].mean(axis=0),
        'baseline_torque_nm': torque[j_b0:j_b1].mean(axis=0),
        'tare_window': [start + j_t0 / ft_rate, start + j_t1 / ft_rate],
        'contact_speed_mps': tl.v_c,
        'contact_tau_s': setup.ctau,
        'weight_transfer_s': weight_transfer_s(k_eff=setup.k_eff, v_c=tl.v_c, ctau=setup.ctau,
                                               weight=setup.geo.m_obj * G,
                                               spring=q.contact_model == 'spring'),
    }


def simulate_trials(*, n: int, seed: int, conditions: Sequence[str] = ('paper',),
                    start_index: int = 0, hits: str | None = None, events: str = 'family',
                    tared: str = 'family', **kw) -> Iterator[Trial]:
    """
    Yield ``n`` trials; trial ``i`` uses ``conditions[i % len(conditions)]``.

    With ``hits=None`` the hit kinds cycle, within each condition set, its
    :meth:`~contact_detector.sim.conditions.ConditionSet.cycle` for ``events``: 'hand',
    'table', 'none' (so about a third of each set's trials get hand hits and a third table
    hits, as in the paper's 20/20/20 of 60), plus 'mixed' with ``events='everywhere'``;
    'mixed', 'touch', 'brush', 'setdown' for 'exogenous'. A ``hits`` kind is given to every
    trial. ``conditions`` may contain the aliases 'all', 'families' and 'wide'. ``hits``,
    ``events``, ``tared`` and the other keywords go to :func:`simulate_trial`.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ConfigError(f'n must be an int >= 0, got {n!r}')
    names = resolve_conditions(conditions)
    for i in range(start_index, start_index + int(n)):
        cond = names[i % len(names)]
        kinds = get_condition(cond).cycle(events=events)
        kind = hits if hits is not None else kinds[(i // len(names)) % len(kinds)]
        yield simulate_trial(seed=seed, index=i, condition=cond, hits=kind, events=events,
                             tared=tared, **kw)


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
