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

r"""
Hindsight labelling: propose a recording's contact onset from its whole F/T and audio.

Pure numpy/scipy (no ROS, no rosbags): arrays in, a :class:`Proposal` out. Unlike the node,
which must decide causally, this sees the whole recording and works in three steps.

1. **The largest lasting load change.** Each F/T sample is a 6-vector
   ``w = (F / sigma_F, T / sigma_T)`` in units of the sensor's noise (``sigma`` from the
   median absolute deviation of the first differences, per group). Its running median over
   ``smooth_s`` (which removes knocks and taps lasting tens of ms) is compared with the
   recording's median ``w_ref``: the *shift* ``E(t) = |median_smooth(w)(t) - w_ref|`` is the
   length of the vector change, so the sensor's orientation and tare do not matter. Runs with
   ``E > level`` lasting at least ``min_lasting_s`` are candidates; the one with the largest
   area ``sum E dt`` is the contact (a touch or a brush is shorter and smaller; the retreat
   returns to ``w_ref`` and is the end of the same run). A run that starts less than
   ``pre_s`` plus half of ``smooth_s`` after the recording's first sample is no candidate: a
   bag begun during a lift or a grasp has no rest to measure that change from, and its onset
   would be the first sample. For the same reason
   ``peak`` is the largest ``E`` after the first sample within ``max(4 s_E, 1)`` of ``E``'s
   median (``s_E`` its MAD-based spread). If every run is such a change, or ``E`` never
   comes to rest, no onset is proposed (``NO_REST``).
2. **Where the F/T leaves its baseline.** Walking back from the run's start to where ``E``
   falls to its floor gives the pre-event baseline ``b``: the median of ``w`` over ``pre_s``
   before that point. With ``u`` the unit direction of the change, ``y_j = (w_j - b) . u`` is
   the load change along it and ``sigma_y`` its MAD-based standard deviation in the baseline.
   When ``sigma_y > whiten_sigma`` (liquid slosh, a structural mode or motor ripple many times
   the sensor's noise) ``y`` is the projection on the whitened direction ``u_w`` instead
   (:func:`whitened_direction`, from the covariance of ``w`` over ``whiten_s`` before the
   window's end), if that lowers ``sigma_y``: each of those moves the load along its own
   direction of the 6-D space, a slosh sideways at the object, the contact along the table's
   normal at the contact point, so the projection that cancels the baseline's own variation
   keeps the contact's change and drops most of the oscillation.
   Searching backwards from where ``y`` reaches ``fit_frac`` of the change, sample ``m`` is the
   first after the latest run of ``quiet_s`` in the band: every sample's 3-sample running
   median ``<= k_sigma sigma_y`` and the sample itself ``<= spike_k sigma_y`` (a dip after an
   impact spike does not stop the search; an isolated noise sample of 4 sigma does not end the
   quiet run, an impact's one-sample spike of more than ``spike_k`` sigma does). A rise
   that creeps out of the noise (a soft or compliant contact) crosses that band late, so on
   a calm baseline (``sigma_y <= busy_sigma``) a one-sided CUSUM of ``z = y / sigma_y``
   (Page's test, :func:`cusum_start`: ``S_j = max(0, S_(j-1) + z_j - cusum_k)`` from the
   baseline window on, alarm at ``S > cusum_h`` from sample ``m`` on) marks where the mean of
   ``y`` started to climb, the sample after its last zero; that sample ``n0`` replaces ``m``
   if it is earlier and at most ``cusum_back_s`` before it (else ``n0 = m``). After a *jump*
   (sample ``m`` at ``jump_k`` sigma or more, the two before it inside the band: an impact) it
   may be one sample before ``m`` at most: a ramp from the band to ``jump_k`` sigma in one
   sample started within sample ``m - 1``'s period, and the excursions inside the band before
   it are vibration or noise, not a creeping rise. If ``y`` then
   reaches ``rise_k k_sigma sigma_y`` within ``fast_samples`` samples of ``m`` (a stiff
   contact) the onset is the middle of sample ``n0``'s averaging period, ``t_n0 - dt / 2``,
   unless the rise, steep at first, is gradual after it (a soft surface: ``y`` takes
   ``gradual_s`` or longer from ``m`` to a quarter of the change): then the hinge below,
   fitted up to sample ``m + 2`` with ``t0`` in ``[t_n0 - dt, t_n0]``, places it inside the
   sample (a stiff contact's impact, all in one sample, keeps the middle).
   Otherwise (a soft or compliant contact, whose load rises slowly) a hinge
   ``y_j = c + a g_p(t_j; t0)``, ``a >= 0``, is fitted by least squares from ``fit_pre_s``
   before ``n0`` to that level, where ``g_p`` is the ramp ``(t - t0)_+^p`` (p = 1 or 2)
   averaged over the sample's period ``(t_j - dt, t_j]`` (the sensor's ADC average),

   .. math:: g_p(t_j; t_0) = \frac{(t_j - t_0)_+^{p+1} - (t_j - dt - t_0)_+^{p+1}}{(p+1)\,dt}

   and ``t0`` is searched in ``[t_n0 - back_samples dt, t_n0]`` on a grid of ``dt / 20``
   (sub-sample resolution), ``c, a`` solved in closed form, the least squared residual winning; a
   rise that *steps out* of the noise (sample ``m`` at ``spike_k`` sigma or more, the two before it
   within ``sharp_prev`` sigma, the CUSUM not moving it) started within ``step_back_samples`` (1.5)
   sample periods of ``t_m``; when the CUSUM moved the onset and ``y`` climbs at least
   ``cusum_k`` sigma per sample from the sample before ``n0`` to ``m``, within
   ``moved_back_samples`` (1) of ``t_n0`` (such a rise passed the allowance within a sample of
   its start; ``back_samples`` makes up for the band's late crossing, which the CUSUM has
   undone). That short fit cannot reach back past ``back_samples`` on a rise that
   creeps out of the noise, so a second, linear (p = 1) hinge, the knee of flat-then-rising, is
   fitted over the whole early rise, from ``knee_pre_s`` before ``n0`` (not before the baseline
   window) to where ``y`` reaches ``knee_frac`` of the change, with ``t0`` in
   ``[t_n0 - cusum_back_s, t_n0]``; the earlier of the two onsets is kept. On a busy baseline
   (``sigma_y > busy_sigma``: motor ripple or slosh many times the sensor's noise, where the
   ``k_sigma`` band is late by the oscillation's size) a linear hinge through the ``busy_back_s``
   before ``m`` up to where the search started sets ``t0`` anywhere in that span.
3. **The contact sound.** If there is audio, its power in ``frame_s`` frames is compared with its
   noise floor (median power over ``[t0 - 0.35 s, t0 - 0.06 s]``). The first frame in
   ``[t0 + audio_lo_s, t0 + audio_hi_s]`` whose power exceeds ``audio_rise`` times the floor, with
   the mean of it and the next three frames above ``audio_hold`` times that, marks a sound; its
   onset is the first sample in that frame or the one before with
   ``|x - median| > audio_k * sigma_noise`` (MAD-based). When the CUSUM moved the F/T onset before
   ``t_m - dt / 2``, the window's end stays at ``t_m - dt / 2 + audio_hi_s`` (the earlier onset
   widens the window, it does not move a sound out of it). A sound sets the time (audio has sample
   resolution); the sound's travel time from the hand to the microphone is unknown and not removed.
   When the window holds several sounds (each starting after ``audio_gap`` frames under the level),
   the first whose peak power over ``audio_peak_frames`` frames is at least ``1 / audio_dominance``
   of the loudest one's is the contact: a sound 10 times weaker than a later one in the window is a
   knock or a transient of the room. A contact sound and its force change start at the same
   instant, so after a *sharp departure* (sample ``m`` at ``sharp_k`` sigma or more, the two before
   it within ``sharp_prev`` sigma: the contact is inside sample ``m``'s period or the one before)
   the window starts no earlier than ``t_m - sharp_back dt``; after a *jump* (step 2), whose
   contact is in sample ``m``'s period or the one before, no sound starting before
   ``t_m - jump_back dt`` is the contact. Both bounds hold for the sound's onset itself: it is
   refined into the frame before the window's first loud frame, so a knock that starts just
   before the bound and rings into the window would otherwise be taken. After a slow or busy
   rise (step 2's hinge fits), which are found late rather than early, the window starts at
   ``audio_slow_lo_s``;
   after a fast rise (F/T onset good to a sample) at ``max(audio_lo_s, -2 dt)``. Without a sound in
   that window, a strong one (``audio_strong`` times the floor, +15 dB) in
   ``(t0 + audio_hi_s, t0 + audio_strong_hi_s]`` sets the time: the F/T then left its baseline
   before the contact (a push on the object, a brush, the approach's deceleration), and a loud
   impact just after is the contact, which the F/T step alone would put tens of ms early. After a
   rise that creeps out of the noise (calm baseline, ``y`` takes at least ``faint_samples`` samples
   from sample ``m`` to the fast-rise level), which is found late, a faint click (``audio_faint``
   times the floor, +5 dB) from ``audio_slow_lo_s`` before the F/T onset up to it sets the time
   when no sound was found; one after the F/T onset adds nothing (a dull thud crosses the level
   late), and after a fast or busy rise a faint sound is more likely something else (a knock,
   noise). A contact's load grows at most like the square of the time since the touch (the
   lagged spring of the simulator between ``s`` and ``s^2``, a Hertzian or conical contact like
   ``s^1.5`` or ``s^2``), so a sound is dropped when the rise from sample ``m`` over the next
   ``growth_s`` climbs faster than a start at the sound allows (:func:`rise_fits_start`, power
   ``growth_power``, ``growth_margin`` sigma of noise allowed): a clatter tens of ms before a
   rise that leaves the noise steeply is not the contact's.
   A sound's onset is late by its travel to the microphone (1-4 ms at 0.3-1.2 m) and, for a
   dull thud, by the frames it takes to build up over the level; the hinge of a slow or a
   gradual rise on a calm baseline (step 2) has no such lag, only the noise of a few samples.
   When that hinge is at most ``agree_s`` before the sound both mark the same touch, and the
   onset is their mean (a hinge earlier than that, or after the sound, is the hinge's error:
   the sound stands; a stiff contact's F/T onset, the middle of a sample, is coarser than its
   sound).

The confidence in [0, 1] multiplies the step's size in noise units (``min(1, E / 20)``),
how clearly it is the largest (``1 - area_2 / area_1``, ``area_2`` the largest other run's,
one without rest before it included; 0 if that one is larger) and, with audio, 1 if a sound
was found near the F/T onset, else 0.8.
"""

import dataclasses
from dataclasses import dataclass, field
import math
from typing import Optional

from contact_detector.errors import InputError
import numpy as np

#: Reasons a recording gets no onset.
NO_CHANGE = 'no lasting load change'
NO_REST = 'every lasting load change is under way when the recording starts: no rest before it'
TOO_SHORT = 'recording shorter than 1 s of F/T'


@dataclass(frozen=True)
class LabelSettings:
    """
    Settings of :func:`propose_onset` (seconds unless stated).

    Attributes
    ----------
    smooth_s : float
        Running-median length for the shift ``E`` (removes knocks of tens of ms).
    min_lasting_s : float
        Shortest run of ``E > level`` that counts as a lasting load change.
    min_shift : float
        Lowest ``level`` in noise units.
    level_frac : float
        ``level = max(min_shift, level_frac * max E)``.
    pre_s : float
        Pre-event baseline window before the run's start.
    fit_pre_s : float
        The hinge fit starts this long (at least 12 samples) before sample ``m``.
    fit_frac : float
        The backward search starts where ``y`` first reaches this fraction of the change.
    k_sigma : float
        Baseline band in robust standard deviations of ``y``.
    spike_k : float
        A single sample this many robust standard deviations out leaves the band by itself;
        a smaller excursion must hold in the 3-sample median.
    cusum_k, cusum_h : float
        Allowance and alarm level (in robust standard deviations) of the CUSUM that moves
        the onset of a rise that creeps out of the noise back to where it started.
    cusum_back_s : float
        The CUSUM moves the onset at most this far before sample ``m``.
    quiet_s : float
        Length of the quiet run (at least 3 samples) that ends the backward search.
    rise_k : float
        A rise to ``rise_k * k_sigma`` sigmas within ``fast_samples`` samples is fast.
    fast_samples : int
        See ``rise_k``.
    back_samples : float
        The hinge's onset is searched up to this many sample periods before ``t_m``.
    busy_sigma : float
        A baseline whose ``sigma_y`` exceeds this many sensor-noise units is busy.
    busy_back_s : float
        On a busy baseline, a linear hinge through ``busy_back_s`` before ``m`` up to where
        the search started sets the onset, anywhere in that span.
    audio_lo_s, audio_hi_s : float
        Window around the F/T onset where a contact sound may start.
    audio_slow_lo_s : float
        ``audio_lo_s`` after a slow or busy rise; after a fast one it is at most two sample
        periods.
    frame_s : float
        Audio power frame.
    audio_rise : float
        Power ratio over the noise floor that marks a sound (5 = +7 dB).
    audio_hold : float
        The mean power of that frame and the next three must exceed ``audio_hold *
        audio_rise``.
    audio_k : float
        Sample threshold in robust noise standard deviations for the sound's first sample.
    audio_strong_hi_s : float
        After a fast rise with no sound in the window, a strong sound up to this long after
        the F/T onset sets the time (the F/T left its baseline before the contact: a push,
        a brush, the approach).
    audio_strong : float
        Power ratio over the noise floor of such a strong sound (30 = +15 dB).
    audio_faint : float
        Power ratio over the noise floor of a faint click (3 = +5 dB), looked for before the
        F/T onset of a creeping rise when there is no sound.
    faint_samples : int
        A calm rise that takes at least this many samples from sample ``m`` to
        ``rise_k * k_sigma`` sigmas creeps (the faint click is looked for).
    knee_frac : float
        The knee fit of a slow rise runs up to where ``y`` reaches this fraction of the
        change.
    knee_pre_s : float
        The knee fit starts this long before sample ``n0`` (not before the baseline window).
    sharp_k, sharp_prev : float
        A sharp departure: sample ``m`` at ``sharp_k`` robust standard deviations or more, the
        two samples before it within ``sharp_prev``; ``sharp_prev`` also bounds the two
        samples before a rise that steps out of the noise.
    sharp_back : float
        After a sharp departure no sound starts more than this many sample periods before
        ``t_m`` (the contact is in sample ``m``'s period or the one before, plus the sound's
        travel time).
    jump_k : float
        A jump: sample ``m`` at ``jump_k`` robust standard deviations or more, the two before
        it within ``k_sigma``; the CUSUM then moves the onset one sample back at most.
    gradual_s : float
        A fast rise whose ``y`` takes this long or longer from sample ``m`` to a quarter of
        the change is gradual: a hinge places its onset inside sample ``n0``'s period.
    step_back_samples : float
        The short hinge of a rise that steps out of the noise (sample ``m`` at ``spike_k``
        sigma or more) searches its onset up to this many sample periods before ``t_m``.
    audio_dominance : float
        A sound whose peak power is more than this many times weaker than a later sound's in
        the window is passed over.
    audio_gap : int
        A sound starting after this many frames under ``audio_rise`` is a new one.
    audio_peak_frames : int
        A sound's peak power is its largest frame power over this many frames from its start.
    whiten_sigma : float
        A baseline whose ``sigma_y`` exceeds this many sensor-noise units is projected on the
        whitened change direction (:func:`whitened_direction`) when that lowers ``sigma_y``.
    moved_back_samples : float
        When the CUSUM moved the onset before sample ``m`` and ``y`` climbs at least ``cusum_k``
        sigma per sample from there to ``m``, the short hinge searches its onset up to this
        many sample periods before the CUSUM's sample (instead of ``back_samples``).
    whiten_s : float
        Length of the baseline before the pre-event window's end whose covariance whitens it
        (at least one period of the slowest slosh, 1.5 Hz).
    growth_power : float
        A contact's load grows at most like this power of the time since the touch; a sound
        before which the rise would have to grow faster is not the contact's.
    growth_margin : float
        Noise allowance of that test in robust standard deviations of ``y``.
    growth_s : float
        The test checks the samples after ``m`` up to where ``y`` reaches ``fit_frac`` of
        the change or the fast-rise level, whichever is later, at most this long after ``m``.
    jump_back : float
        After a jump no sound starting more than this many sample periods before ``t_m`` is
        the contact (the contact is in sample ``m``'s period or the one before).
    agree_s : float
        When the hinge of a slow or gradual rise on a calm baseline is at most this long
        before the sound's onset, the onset is their mean.

    """

    smooth_s: float = 0.1
    min_lasting_s: float = 0.25
    min_shift: float = 8.0
    level_frac: float = 0.3
    pre_s: float = 0.3
    fit_pre_s: float = 0.1
    fit_frac: float = 0.5
    k_sigma: float = 3.5
    spike_k: float = 5.0
    cusum_k: float = 2.0
    cusum_h: float = 8.0
    cusum_back_s: float = 0.05
    quiet_s: float = 0.07
    back_samples: float = 2.0
    busy_sigma: float = 4.0
    busy_back_s: float = 0.3
    rise_k: float = 3.0
    fast_samples: int = 2
    sharp_k: float = 7.0
    sharp_prev: float = 2.0
    sharp_back: float = 3.0
    jump_k: float = 14.0
    gradual_s: float = 0.06
    step_back_samples: float = 1.5
    audio_dominance: float = 10.0
    audio_gap: int = 3
    audio_peak_frames: int = 5
    audio_lo_s: float = -0.05
    audio_slow_lo_s: float = -0.08
    audio_hi_s: float = 0.03
    frame_s: float = 0.002
    audio_rise: float = 5.0
    audio_hold: float = 0.8
    audio_k: float = 5.0
    audio_strong_hi_s: float = 0.08
    audio_strong: float = 30.0
    audio_faint: float = 3.0
    faint_samples: int = 4
    knee_frac: float = 0.25
    knee_pre_s: float = 0.2
    whiten_sigma: float = 3.0
    moved_back_samples: float = 1.0
    whiten_s: float = 1.0
    growth_power: float = 2.0
    growth_margin: float = 2.0
    growth_s: float = 0.1
    jump_back: float = 2.0
    agree_s: float = 0.01


@dataclass
class Proposal:
    """
    The proposed onset of one recording.

    Attributes
    ----------
    onset_t : float or None
        Proposed contact onset, s (None: see ``reason``).
    confidence : float
        In [0, 1]; 0 when there is no onset.
    reason : str
        Why there is no onset ('' when there is one).
    source : str
        'audio' (the contact sound set the time, alone or with the F/T hinge), 'ft' or ''.
    ft_onset_t, audio_onset_t : float or None
        The F/T hinge's ``t0`` and the sound's onset, s.
    shift_t, shift : np.ndarray
        Times (s) and the vector shift ``E`` (noise units) for review figures.
    step : float
        The run's peak shift in noise units.

    """

    onset_t: Optional[float]
    confidence: float
    reason: str = ''
    source: str = ''
    ft_onset_t: Optional[float] = None
    audio_onset_t: Optional[float] = None
    step: float = 0.0
    shift_t: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    shift: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)


def noise_sigma(x: np.ndarray) -> float:
    """
    Robust noise standard deviation of a group of channels, shape (n, k).

    ``sigma = sqrt(mean_k s_k^2)`` with ``s_k = 1.4826 MAD(diff x_k) / sqrt 2``; a channel
    whose MAD is 0 (quantised, flat) uses the standard deviation of its differences; the
    result is at least 1e-9.
    """
    d = np.diff(np.asarray(x, dtype=float), axis=0)
    if len(d) == 0:
        return 1e-9
    mad = 1.4826 * np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    s = np.where(mad > 0, mad, np.std(d, axis=0)) / math.sqrt(2.0)
    return max(float(np.sqrt(np.mean(s ** 2))), 1e-9)


def _robust_sd(x: np.ndarray) -> float:
    """MAD-based standard deviation of ``x`` (at least 1e-9)."""
    return max(1.4826 * float(np.median(np.abs(x - np.median(x)))), 1e-9)


def whitened_direction(*, w: np.ndarray, u: np.ndarray) -> np.ndarray:
    r"""
    Whiten the change direction ``u`` by the covariance of the baseline ``w``.

    .. math:: u_w = \frac{(C + I)^{-1} u}{u^\top (C + I)^{-1} u}, \quad
              C = \frac{1}{n} \sum_j (w_j - \bar w)(w_j - \bar w)^\top

    ``y_w = (w - b) . u_w`` is the matched filter for a change along ``u`` in interference
    with covariance ``C`` (slosh, a structural mode, ripple: each moves the load along its own
    direction of the 6-D space). It keeps the change's scale (``change . u_w = |change|``)
    and cancels the interference's part that lies outside ``u``. ``I`` is the sensor's noise
    (``w`` is in its units) once more: directions the baseline did not explore are not
    trusted more than the noise allows.

    Parameters
    ----------
    w : np.ndarray, shape (n, k)
        Baseline samples in sensor-noise units.
    u : np.ndarray, shape (k,)
        Unit direction of the change.

    Returns
    -------
    np.ndarray, shape (k,)

    """
    d = w - w.mean(axis=0)
    cov = d.T @ d / max(len(d), 1) + np.eye(len(u))
    v = np.linalg.solve(cov, u)
    return v / float(u @ v)


def _running_median(x: np.ndarray, n: int) -> np.ndarray:
    from scipy.ndimage import median_filter
    if n <= 1:
        return x
    return median_filter(x, size=(n, 1), mode='nearest')


def _median3(y: np.ndarray) -> np.ndarray:
    """Centred running median of 3 samples (the end samples kept)."""
    out = np.array(y, dtype=float)
    if len(out) >= 3:
        out[1:-1] = np.median(np.stack([out[:-2], out[1:-1], out[2:]]), axis=0)
    return out


def cusum_start(*, z: np.ndarray, start: int, alarm_from: int, kappa: float,
                h: float) -> Optional[int]:
    r"""
    First sample of a rise in ``z`` by a one-sided CUSUM (Page's test), or None.

    .. math:: S_j = \max(0, S_{j-1} + z_j - \kappa), \quad S_{start - 1} = 0

    The alarm is the first ``j >= alarm_from`` with ``S_j > h``; the rise starts at the
    sample after the last ``S_j = 0`` before it (the estimate of the change point).

    Parameters
    ----------
    z : np.ndarray, shape (n,)
        The signal in units of its baseline noise (baseline mean 0).
    start : int
        First sample summed.
    alarm_from : int
        Alarms before this sample are ignored (the sum goes on).
    kappa : float
        Allowance: the drift per sample that counts as no change.
    h : float
        Alarm level.

    Returns
    -------
    int or None
        Index of the rise's first sample; None without an alarm.

    """
    acc = 0.0
    last_zero = start - 1
    for j in range(start, len(z)):
        acc = max(0.0, acc + float(z[j]) - kappa)
        if acc == 0.0:
            last_zero = j
        elif j >= alarm_from and acc > h:
            return last_zero + 1
    return None


def rise_fits_start(*, t: np.ndarray, y: np.ndarray, sd: float, m: int, end: int,
                    start: float, power: float, margin: float) -> bool:
    r"""
    Whether the rise of ``y`` from sample ``m`` to ``end`` can have started at ``start`` (s).

    A contact's load grows at most like a power of the time since the touch: the
    simulator's lagged spring ``k v s (1 - exp(-s / lag))`` grows between ``s`` and
    ``s^2``, a Hertzian or conical contact like ``s^1.5`` or ``s^2``, and a slowing hand only
    less. Sample ``j`` averages the load over ``(t_j - dt, t_j]`` and the load rises, so
    ``y_m >= f(t_m - dt)`` and ``y_j <= f(t_j)``; with ``f(s) <= f(s_1) (s / s_1)^power``
    for ``s >= s_1``, a start at ``start`` allows at most

    .. math:: y_j \le (y_m + \text{margin}\,\sigma)
              \left(\frac{t_j - start}{t_m - dt - start}\right)^{power} + \text{margin}\,\sigma

    A rise that climbs faster than that started later (a sound tens of ms before a rise that
    leaves the noise steeply is not the contact's).

    Parameters
    ----------
    t, y : np.ndarray, shape (n,)
        Sample times (s) and the load change along the change direction.
    sd : float
        Robust standard deviation of ``y`` in the baseline.
    m, end : int
        First sample out of the baseline band and the last sample checked.
    start : float
        Candidate onset, s.
    power : float
        Largest growth exponent of a contact's load.
    margin : float
        Noise allowance in units of ``sd``.

    Returns
    -------
    bool
        False when some sample climbs faster than a start at ``start`` allows.

    """
    dt = float(t[m] - t[m - 1]) if m >= 1 else 0.0
    span = float(t[m]) - dt - start
    if span <= 0 or end <= m:
        return True
    j = np.arange(m + 1, min(end, len(y) - 1) + 1)
    cap = (max(float(y[m]), 0.0) + margin * sd) * ((t[j] - start) / span) ** power
    return not bool(np.any(y[j] > cap + margin * sd))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index runs where ``mask`` is True."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.nonzero(d == 1)[0].tolist(), np.nonzero(d == -1)[0].tolist()))


def hinge_fit(*, t: np.ndarray, y: np.ndarray, dt: float, lo: float, hi: float,
              powers: tuple = (1, 2), step_frac: float = 0.05) -> tuple[float, int, float]:
    """
    Least-squares hinge ``y = c + a g_p(t; t0)`` (module doc), ``t0`` in ``[lo, hi]``.

    Parameters
    ----------
    t, y : np.ndarray, shape (n,)
        Sample times (s) and values.
    dt : float
        Sample period, s (the averaging period of ``g_p``).
    lo, hi : float
        Search range of ``t0``, s.
    powers : tuple of int
        Ramp powers tried.
    step_frac : float
        Grid step of ``t0`` as a fraction of ``dt``.

    Returns
    -------
    (t0, p, sse) : tuple
        Best onset (s), its power and squared residual.

    """
    grid = np.arange(lo, hi + 1e-12, dt * step_frac)
    best = (float(lo), powers[0], math.inf)
    n = len(y)
    if n < 3 or len(grid) == 0:
        return best
    ym = y.mean()
    yc = y - ym
    syy = float(yc @ yc)
    for p in powers:
        a1 = np.maximum(t[None, :] - grid[:, None], 0.0) ** (p + 1)
        a0 = np.maximum(t[None, :] - dt - grid[:, None], 0.0) ** (p + 1)
        g = (a1 - a0) / ((p + 1) * dt)
        gc = g - g.mean(axis=1, keepdims=True)
        sgg = np.einsum('ij,ij->i', gc, gc)
        sgy = gc @ yc
        ok = (sgg > 0) & (sgy > 0)
        sse = np.where(ok, syy - sgy ** 2 / np.where(sgg > 0, sgg, 1.0), syy)
        k = int(np.argmin(sse))
        if sse[k] < best[2]:
            best = (float(grid[k]), p, float(sse[k]))
    return best


def audio_onset(*, audio: np.ndarray, rate: float, t0: float, around: float,
                settings: LabelSettings = LabelSettings()) -> tuple[Optional[float], float]:
    """
    Onset of a sound near ``around`` (s), and its power ratio over the noise floor.

    Parameters
    ----------
    audio : np.ndarray, shape (n,)
        Samples (any scale).
    rate : float
        Sample rate, Hz.
    t0 : float
        Time of sample 0, s.
    around : float
        The F/T onset, s; the sound may start in ``[around + audio_lo_s, around +
        audio_hi_s]``.
    settings : LabelSettings
        Thresholds and windows of the search.

    Returns
    -------
    (onset, ratio) : tuple
        Onset time in s (None without a sound) and the largest frame power in the window
        divided by the floor.

    """
    s = settings
    x = np.asarray(audio, dtype=float)
    fl = max(1, int(round(s.frame_s * rate)))

    def idx(tt: float) -> int:
        return int(round((tt - t0) * rate))

    n0, n1 = idx(around - 0.35), idx(around - 0.06)
    w0, w1 = idx(around + s.audio_lo_s), idx(around + s.audio_hi_s)
    if n0 < 0 or w1 + 4 * fl > len(x) or n1 - n0 < 4 * fl:
        return None, 0.0
    noise = x[n0:n1]
    nf = (len(noise) // fl) * fl
    floor = float(np.median(np.mean(noise[:nf].reshape(-1, fl) ** 2, axis=1)))
    floor = max(floor, 1e-20)
    seg = x[w0:min(len(x), w1 + max(4, s.audio_peak_frames) * fl)]
    m = (len(seg) // fl) * fl
    power = np.mean(seg[:m].reshape(-1, fl) ** 2, axis=1) / floor
    n_win = max(1, (w1 - w0) // fl)
    ratio = float(power[:n_win + 1].max()) if len(power) else 0.0
    hot = power > s.audio_rise
    # the sounds starting in the window: the first frame that holds the rise, then each one
    # after audio_gap frames under it (a new event, not the same sound's ring)
    starts = [k for k in range(min(n_win, len(power) - 4))
              if hot[k] and power[k:k + 4].mean() > s.audio_hold * s.audio_rise]
    starts = [k for i, k in enumerate(starts)
              if i == 0 or not np.any(hot[max(0, k - s.audio_gap):k])]
    if starts:
        # the contact is the dominant sound: one more than audio_dominance times weaker than
        # a later one (a knock, a transient of the room) is passed over
        peaks = [float(power[k:k + s.audio_peak_frames].max()) for k in starts]
        k = next(k for k, pk in zip(starts, peaks) if pk * s.audio_dominance >= max(peaks))
        med = np.median(noise)
        sd = max(1.4826 * float(np.median(np.abs(noise - med))), 1e-12)
        a = max(w0 + (k - 1) * fl, 0)
        seg2 = np.abs(x[a:w0 + (k + 1) * fl] - med)
        over = np.nonzero(seg2 > s.audio_k * sd)[0]
        j = a + (int(over[0]) if len(over) else fl)
        return t0 + j / rate, ratio
    return None, ratio


def propose_onset(*, ft_t: np.ndarray, force: np.ndarray, torque: np.ndarray,
                  audio: Optional[np.ndarray] = None, audio_rate: Optional[float] = None,
                  audio_t0: Optional[float] = None,
                  settings: LabelSettings = LabelSettings()) -> Proposal:
    """
    Propose the contact onset of one recording (module doc for the method).

    Parameters
    ----------
    ft_t : np.ndarray, shape (n,)
        F/T sample times, s, increasing.
    force, torque : np.ndarray, shape (n, 3)
        N and N m, any frame and tare.
    audio : np.ndarray or None, shape (m,)
        Audio samples (None: F/T only).
    audio_rate : float or None
        Audio sample rate, Hz.
    audio_t0 : float or None
        Time of audio sample 0, s.
    settings : LabelSettings
        Thresholds and windows of the search.

    Returns
    -------
    Proposal

    Raises
    ------
    InputError
        Shapes disagree or the times are not increasing.

    """
    s = settings
    t = np.asarray(ft_t, dtype=float)
    f = np.asarray(force, dtype=float)
    q = np.asarray(torque, dtype=float)
    if f.shape != (len(t), 3) or q.shape != (len(t), 3):
        raise InputError(f'force {f.shape} and torque {q.shape} must be ({len(t)}, 3)')
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        raise InputError('F/T times must increase')
    if len(t) < 3 or t[-1] - t[0] < 1.0:
        return Proposal(None, 0.0, reason=TOO_SHORT)
    dt = float(np.median(np.diff(t)))
    w = np.hstack([f / noise_sigma(f), q / noise_sigma(q)])
    smooth = _running_median(w, int(round(s.smooth_s / dt)) | 1)
    ref = np.median(w, axis=0)
    shift = np.linalg.norm(smooth - ref, axis=1)
    # the shift's floor: the recording's typical shift
    floor = float(np.median(shift))
    spread = 1.4826 * float(np.median(np.abs(shift - floor)))
    rest_band = max(4.0 * spread, 1.0)
    # a bag begun during a lift or a grasp starts with a change under way: the level that
    # makes a run is set by the peak after the load first came to rest, so that such a change
    # does not hide the contact under a level of its own size
    at_rest = np.nonzero(shift <= floor + rest_band)[0]
    if not len(at_rest):
        return Proposal(None, 0.0, reason=NO_REST, shift_t=t, shift=shift)
    peak = float(shift[int(at_rest[0]):].max())
    level = max(s.min_shift, s.level_frac * peak)
    runs = [(a, b) for a, b in _runs(shift > level) if (b - a) * dt >= s.min_lasting_s]
    if not runs:
        return Proposal(None, 0.0, reason=NO_CHANGE, shift_t=t, shift=shift)
    areas = [float(shift[a:b].sum() * dt) for a, b in runs]
    order = [int(k) for k in np.argsort(areas)[::-1]]
    # back to where the shift left its floor
    floor_lvl = floor + min(rest_band, 0.1 * (level - floor))
    n_pre = max(3, int(round(s.pre_s / dt)))
    half = int(round(0.5 * s.smooth_s / dt))
    # a change already under way when the recording starts (a bag begun during a lift or a
    # grasp) has no rest before it to measure from: its "onset" would be the first sample
    rested = [k for k in order if runs[k][0] >= half + n_pre]
    if not rested:
        return Proposal(None, 0.0, reason=NO_REST, shift_t=t, shift=shift)
    chosen = rested[0]
    a, b = runs[chosen]
    # how clearly it is the largest: a larger change without rest before it counts against it
    other = max((areas[k] for k in order if k != chosen), default=0.0)
    clarity = max(0.0, 1.0 - other / areas[chosen])
    i = a
    while i > 0 and shift[i - 1] > floor_lvl:
        i -= 1
    j1 = max(1, i - half)
    j0 = max(0, j1 - n_pre)
    base = np.median(w[j0:j1], axis=0)
    change = np.median(w[a:min(b, a + int(round(s.smooth_s / dt)) + 1)], axis=0) - base
    u = change / max(float(np.linalg.norm(change)), 1e-12)
    y = (w - base) @ u
    sd = _robust_sd(y[j0:j1])
    if sd > s.whiten_sigma:
        # a busy baseline (slosh, a structural mode, ripple) moves the load along its own
        # directions: project on the change direction whitened by the baseline's covariance
        k0 = max(0, j1 - int(round(s.whiten_s / dt)))
        u_w = whitened_direction(w=w[k0:j1], u=u)
        y_w = (w - base) @ u_w
        sd_w = _robust_sd(y_w[j0:j1])
        if sd_w < sd:
            y, sd = y_w, sd_w
    target = max(s.fit_frac * float(np.linalg.norm(change)), s.k_sigma * sd)
    reach = np.nonzero(y[i:b] >= target)[0]
    r = i + (int(reach[0]) if len(reach) else 0)
    # the latest sample ending a run of n_quiet samples within k_sigma of the baseline: the
    # next one is the first that left it (short dips after an impact do not stop the search)
    n_quiet = max(3, int(round(s.quiet_s / dt)))
    # "out of the band": its 3-sample median is (an isolated noise sample is not), or the
    # sample itself is by spike_k sigmas (an impact's one-sample spike is)
    out = (_median3(y[:r + 2])[:r + 1] > s.k_sigma * sd) | (y[:r + 1] > s.spike_k * sd)
    quiet = np.convolve(out.astype(float), np.ones(n_quiet), mode='full')[:r + 1] == 0
    quiet[:n_quiet - 1] = False
    ends = np.nonzero(quiet)[0]
    m = int(ends[-1]) + 1 if len(ends) else max(r, 1)
    level_hi = min(s.rise_k * s.k_sigma * sd, 0.5 * float(np.linalg.norm(change)))
    above = np.nonzero(y[m:b] >= level_hi)[0]
    e = m + (int(above[0]) if len(above) else 0)
    # a sharp departure (a jump from the noise to sharp_k sigmas in one sample): the contact
    # is inside the averaging period of sample m or the one before; a sound cannot precede it
    sharp = (2 <= m < len(y) and y[m] >= s.sharp_k * sd
             and max(y[m - 1], y[m - 2]) <= s.sharp_prev * sd)
    # a jump (sample m jump_k sigmas out, the two before it inside the band) is an impact:
    # the contact is in sample m's averaging period or the one before, and excursions inside
    # the band before them are vibration or noise, not the start of a creeping rise
    jump = (2 <= m < len(y) and y[m] >= s.jump_k * sd
            and max(y[m - 1], y[m - 2]) <= s.k_sigma * sd)
    # a rise that creeps out of the noise crosses the band late: a CUSUM of y finds where its
    # mean started to climb, up to cusum_back_s before sample m (calm baselines only)
    n0 = m
    if sd <= s.busy_sigma:
        c = cusum_start(z=y[:max(r, m) + 1] / sd, start=j0, alarm_from=m, kappa=s.cusum_k,
                        h=s.cusum_h)
        if (c is not None and c < m and t[m] - t[c] <= s.cusum_back_s
                and not (jump and c < m - 1)):
            n0 = c
    # fast rise: the onset is within the averaging period of sample n0 (its middle); slow
    # rise: a hinge fit up to where y reaches rise_k * k_sigma extrapolates back
    ft_onset = float(t[n0]) - 0.5 * dt
    gradual = False
    if sd > s.busy_sigma:
        # a busy baseline (ripple, slosh: many times the sensor noise): the k_sigma search
        # is late by up to the oscillation's size; a ramp fitted through it averages it out
        k_start = max(0, m - int(round(s.busy_back_s / dt)))
        ft_onset = hinge_fit(t=t[k_start:r + 1], y=y[k_start:r + 1], dt=dt,
                             lo=float(t[k_start]), hi=float(t[m]), powers=(1,))[0]
    elif e - m >= s.fast_samples:
        k_start = max(0, n0 - max(12, int(round(s.fit_pre_s / dt))))
        # a rise whose first sample out stands spike_k sigmas clear of a baseline still in
        # the noise stepped out: it started within step_back_samples before that sample
        stepped = (n0 == m and m >= 2 and y[m] >= s.spike_k * sd
                   and max(y[m - 1], y[m - 2]) <= s.sharp_prev * sd)
        back = s.step_back_samples if stepped else s.back_samples
        if n0 < m and (y[m] - y[max(n0 - 1, 0)]) / (m - n0 + 1) >= s.cusum_k * sd:
            # the CUSUM moved the onset to the first sample of a rise that climbs at least
            # its allowance per sample: that sample passed the allowance within one sample
            # period of the rise's start (back_samples makes up for the band's late crossing,
            # which the CUSUM has already undone; a slower creep keeps it)
            back = min(back, s.moved_back_samples)
        ft_onset = hinge_fit(t=t[k_start:e + 1], y=y[k_start:e + 1], dt=dt,
                             lo=float(t[n0]) - back * dt, hi=float(t[n0]))[0]
        # the knee of flat-then-linear over the whole early rise (to knee_frac of the
        # change) averages the noise of many samples: on a rise that creeps out of the noise
        # it finds the start that the short fit, limited to back_samples, cannot reach
        reached = np.nonzero(y[m:b] >= s.knee_frac * float(np.linalg.norm(change)))[0]
        k_end = max(e, m + (int(reached[0]) if len(reached) else 0))
        k_start = max(j0, n0 - int(round(s.knee_pre_s / dt)))
        knee = hinge_fit(t=t[k_start:k_end + 1], y=y[k_start:k_end + 1], dt=dt,
                         lo=float(t[n0]) - s.cusum_back_s, hi=float(t[n0]), powers=(1,))[0]
        ft_onset = min(ft_onset, knee)
    else:
        # a rise that is steep at first but gradual (soft surfaces: a quarter of the change
        # takes gradual_s or longer) starts anywhere in sample n0's averaging period: the
        # hinge through its first samples places it (a stiff contact's impact keeps the middle)
        quarter = np.nonzero(y[m:b] >= 0.25 * float(np.linalg.norm(change)))[0]
        gradual = bool(len(quarter) and int(quarter[0]) >= round(s.gradual_s / dt))
        if gradual:
            k_start = max(0, n0 - max(12, int(round(s.fit_pre_s / dt))))
            k_end = min(len(y) - 1, m + 2)
            ft_onset = hinge_fit(t=t[k_start:k_end + 1], y=y[k_start:k_end + 1], dt=dt,
                                 lo=float(t[n0]) - dt, hi=float(t[n0]))[0]
    slow = sd > s.busy_sigma or e - m >= s.fast_samples
    confidence = min(1.0, peak / 20.0) * max(clarity, 0.0)
    onset, source, a_on = ft_onset, 'ft', None
    if audio is not None and audio_rate and audio_t0 is not None and len(audio):
        # a slow or busy rise is found late rather than early: look further back for its sound
        # after a fast rise the F/T onset is good to a sample: a sound starting much earlier
        # is something else (a clatter, a knock)
        lo = s.audio_slow_lo_s if slow else max(s.audio_lo_s, -2.0 * dt)
        if sharp:
            lo = max(lo, float(t[m]) - s.sharp_back * dt - ft_onset)
        # the window reaches from before the onset to after where y left the band (sample m)
        around = max(ft_onset, float(t[m]) - 0.5 * dt)
        a_on, _ratio = audio_onset(audio=audio, rate=float(audio_rate), t0=float(audio_t0),
                                   around=around, settings=dataclasses.replace(
                                       s, audio_lo_s=lo + ft_onset - around))
        if a_on is None and sd <= s.busy_sigma and e - m >= s.faint_samples:
            # a rise that creeps out of the noise is found late: a faint click before its
            # F/T onset marks the contact better (one after it adds nothing)
            a_on, _ratio = audio_onset(audio=audio, rate=float(audio_rate), t0=float(audio_t0),
                                       around=ft_onset, settings=dataclasses.replace(
                                           s, audio_lo_s=lo, audio_hi_s=0.0,
                                           audio_rise=s.audio_faint))
        if a_on is None:
            # no sound where a fast rise puts the contact: the F/T may have left its baseline
            # early (a push, a brush); a loud impact just after it is the contact
            a_on, _ratio = audio_onset(
                audio=audio, rate=float(audio_rate), t0=float(audio_t0), around=ft_onset,
                settings=dataclasses.replace(s, audio_lo_s=s.audio_hi_s,
                                             audio_hi_s=s.audio_strong_hi_s,
                                             audio_rise=s.audio_strong))
        if a_on is not None and not rise_fits_start(
                t=t, y=y, sd=sd, m=m, end=min(max(r, e), m + int(round(s.growth_s / dt))),
                start=a_on, power=s.growth_power, margin=s.growth_margin):
            a_on = None
        # the departure's bound holds for the sound's onset, not only for the window: the
        # onset is refined into the frame before the window's first hot frame, which may
        # start before the bound
        if a_on is not None and (
                (sharp and a_on < float(t[m]) - s.sharp_back * dt)
                or (jump and a_on < float(t[m]) - s.jump_back * dt)):
            a_on = None
        if a_on is not None:
            onset, source = a_on, 'audio'
            if ((slow or gradual) and sd <= s.busy_sigma
                    and 0.0 < a_on - ft_onset <= s.agree_s):
                # the sound is late by its travel and build-up, the hinge of a slow or
                # gradual rise only noisy: when they agree within agree_s, both mark the touch
                onset = 0.5 * (a_on + ft_onset)
        else:
            confidence *= 0.8
    return Proposal(onset_t=float(onset), confidence=float(round(confidence, 3)),
                    source=source, ft_onset_t=float(ft_onset), audio_onset_t=a_on,
                    step=peak, shift_t=t, shift=shift)
