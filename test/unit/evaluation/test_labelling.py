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
Hindsight labelling on synthetic F/T and audio: slow rises, noise before a contact, faint clicks.

Also: sounds before a sharp F/T departure or a jump, a late thud that agrees with the hinge
of a slow or gradual rise, the dominant sound in the window, the onset of a gradual soft rise
inside its first sample and of a rise that steps out of the noise, a rise the CUSUM moved
back, and a baseline busy with liquid slosh.

The wrench is built at 20 times the sensor rate and averaged over each 10 ms sample period (as
the sensor's ADC does), then white noise is added: 0.15 N per force axis, 6 mN m per torque
axis. The load acts along -z with a lever arm, so force and torque change together. The audio
is white noise at 16 kHz with, where a test adds one, a faint click (a decaying noise burst).
"""

from contact_detector.evaluation.labelling import (cusum_start, NO_REST, propose_onset,
                                                   rise_fits_start,
                                                   whitened_direction)
import numpy as np
import pytest

RATE = 100.0
OVERSAMPLE = 20
ONSET = 3.0137
DT = 1.0 / RATE
AUDIO_RATE = 16000.0


def _wrench(load_fn, *, seed: int, outliers: tuple = ()) -> tuple:
    """Return ``(t, force, torque)``: 6 s, ``load_fn(tau)`` in N from ONSET, lift-off at 5 s."""
    rng = np.random.default_rng(seed)
    fine = np.arange(int(6.0 * RATE * OVERSAMPLE)) / (RATE * OVERSAMPLE)
    load = np.where(fine >= ONSET, load_fn(np.maximum(fine - ONSET, 0.0)), 0.0)
    load[fine > 5.0] = 0.0
    n = len(fine) // OVERSAMPLE
    fz = -load[:n * OVERSAMPLE].reshape(n, OVERSAMPLE).mean(axis=1)
    t = (np.arange(n) + 1) * DT
    force = np.zeros((n, 3))
    torque = np.zeros((n, 3))
    force[:, 2] = fz - 5.0
    torque[:, 0] = 0.05 * fz
    force += rng.normal(0.0, 0.15, (n, 3))
    torque += rng.normal(0.0, 0.006, (n, 3))
    for seconds_before, sigmas in outliers:
        # one sample out along the load's direction (force z and torque x together) by
        # `sigmas` of the noise along it
        j = int(np.searchsorted(t, ONSET - seconds_before))
        force[j, 2] -= sigmas / np.sqrt(2.0) * 0.15
        torque[j, 0] -= sigmas / np.sqrt(2.0) * 0.006
    return t, force, torque


def _soft(tau: np.ndarray) -> np.ndarray:
    """Return a compliant contact's load, N: k v tau (1 - exp(-tau / ctau)), to 8 N."""
    return np.minimum(80.0 * tau * (1.0 - np.exp(-tau / 0.12)), 8.0)


@pytest.mark.parametrize('seed', [5, 6, 7])
def test_a_slow_rise_without_a_sound_is_found_within_20_ms(seed):
    # the load creeps out of the noise: it crosses 3.5 sigma about 40 ms after the onset
    t, force, torque = _wrench(_soft, seed=seed)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert p.source == 'ft'
    assert abs(p.onset_t - ONSET) <= 0.020, (p.onset_t - ONSET) * 1e3


@pytest.mark.parametrize('seed', [4, 5])
def test_isolated_noise_samples_before_a_stiff_contact_do_not_move_it_early(seed):
    # two single samples of 3.5 sigma, 40 ms and 100 ms before the contact, break every run
    # of 7 quiet samples in between: neither leaves the baseline, the contact's step is the
    # onset (with the raw samples in the band test, the onset went 35 or 95 ms early)
    t, force, torque = _wrench(lambda tau: np.minimum(400.0 * tau, 8.0), seed=seed,
                               outliers=((0.10, 3.5), (0.04, 3.5)))
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert abs(p.onset_t - ONSET) <= 0.010, (p.onset_t - ONSET) * 1e3


def test_cusum_start_finds_a_ramp_before_it_leaves_the_band():
    rng = np.random.default_rng(0)
    z = rng.normal(0.0, 1.0, 400)
    z[250:] += 0.15 * np.arange(150)     # a ramp of 0.15 sigma per sample from sample 250
    # its mean passes kappa = 2 at sample 263 and the 3.5-sigma band at 273
    start = cusum_start(z=z, start=0, alarm_from=270, kappa=2.0, h=8.0)
    assert start is not None and 255 <= start <= 268
    # no change: no alarm
    assert cusum_start(z=rng.normal(0.0, 1.0, 400), start=0, alarm_from=0, kappa=2.0,
                       h=8.0) is None


def _audio(*, seed: int, click_at: float, ratio: float) -> np.ndarray:
    """Return 6 s of noise (sd 0.01) and a click from ``click_at`` (s): ``ratio`` x its power."""
    rng = np.random.default_rng(seed + 100)
    x = rng.normal(0.0, 0.01, int(6.0 * AUDIO_RATE))
    k, n = int(click_at * AUDIO_RATE), int(0.03 * AUDIO_RATE)
    decay = np.exp(-np.arange(n) / (0.015 * AUDIO_RATE))
    x[k:k + n] += rng.normal(0.0, 0.01 * np.sqrt(ratio - 1.0), n) * decay
    return x


def _transfer(slope: float):
    """Return a compliant wrist's load, N: the weight moves at ``slope`` N/s, to 3 N."""
    return lambda tau: np.minimum(slope * tau, 3.0)


@pytest.mark.parametrize('seed', [3, 4, 6, 7])
def test_a_slow_linear_weight_transfer_is_found_within_20_ms(seed):
    # 6 N/s (0.5 sigma per sample along the change): the 2-sample hinge and the CUSUM stopped
    # 26-36 ms late; the knee of flat-then-linear over the early rise is within 15 ms
    t, force, torque = _wrench(_transfer(6.0), seed=seed)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert p.source == 'ft'
    assert abs(p.onset_t - ONSET) <= 0.020, (p.onset_t - ONSET) * 1e3


@pytest.mark.parametrize('seed', [0, 5, 7])
def test_a_faint_click_before_a_late_slow_rise_sets_the_onset(seed):
    # 4 N/s: the F/T onset is 26-56 ms late; the click at the contact is 4 times the noise's
    # power (+6 dB, under the 5 times of a sound) and sets the onset
    t, force, torque = _wrench(_transfer(4.0), seed=seed)
    audio = _audio(seed=seed, click_at=ONSET, ratio=4.0)
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'audio'
    assert abs(p.onset_t - ONSET) <= 0.005, (p.onset_t - ONSET) * 1e3


@pytest.mark.parametrize('seed', [0, 1])
def test_a_faint_click_before_a_stiff_contact_is_not_its_onset(seed):
    # a stiff contact's F/T onset is good to a sample: a faint click 15 ms before is something
    # else and does not move it
    t, force, torque = _wrench(lambda tau: np.minimum(400.0 * tau, 8.0), seed=seed)
    audio = _audio(seed=seed, click_at=ONSET - 0.015, ratio=4.0)
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'ft'
    assert abs(p.onset_t - ONSET) <= 0.010, (p.onset_t - ONSET) * 1e3


def _sounds(*, seed: int, events: tuple) -> np.ndarray:
    """Return 6 s of noise (sd 0.01) plus ``(start s, power ratio, decay s)`` noise bursts."""
    rng = np.random.default_rng(seed + 100)
    x = rng.normal(0.0, 0.01, int(6.0 * AUDIO_RATE))
    n = int(0.03 * AUDIO_RATE)
    for start, ratio, decay_s in events:
        k = int(start * AUDIO_RATE)
        x[k:k + n] += (rng.normal(0.0, 0.01 * np.sqrt(ratio - 1.0), n)
                       * np.exp(-np.arange(n) / (decay_s * AUDIO_RATE)))
    return x


def _bump_then(*, peak: float, width: float, slope: float, lag: float, top: float,
               delay: float = 0.0):
    """Return an impact's half-sine bump (N, s) and a lagged ramp to ``top`` N, from ``delay``."""
    def load(tau: np.ndarray) -> np.ndarray:
        tau = np.maximum(tau - delay, 0.0)
        bump = np.where(tau < width, peak * np.sin(np.pi * tau / width), 0.0)
        ramp = np.minimum(slope * tau * (1.0 - np.exp(-tau / max(lag, 1e-9))), top)
        return np.where(tau > 0.0, bump + ramp, 0.0)
    return load


@pytest.mark.parametrize('seed', [0, 3])
def test_a_sound_well_before_a_sharp_departure_is_not_the_contact(seed):
    # the F/T jumps from the noise to 8 sigma in one sample (a 3 ms impact), then creeps:
    # a slow rise, whose sound was looked for from 80 ms before. A knock 60 ms before, as
    # loud as the contact, was taken; a sound cannot precede a sharp departure, the one at
    # the contact (2 ms of travel) is the onset
    t, force, torque = _wrench(_bump_then(peak=4.0, width=0.003, slope=5.0, lag=0.0, top=8.0),
                               seed=seed)
    audio = _sounds(seed=seed, events=((ONSET - 0.06, 200.0, 0.005),
                                       (ONSET + 0.002, 200.0, 0.005)))
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'audio'
    assert 0.0 <= p.onset_t - ONSET <= 0.005, (p.onset_t - ONSET) * 1e3


# (bump peak N, ramp slope N/s, ramp lag s, start of a sound before the contact s): the
# contact, 3.7 ms into the sample period ending at t_m, makes no sound; a knock starts just
# before the bound of its departure and rings into the sound window, whose first hot frame
# is after the bound, but the sound's onset is refined into the frame before it:
# - a sharp departure (a 3 N impact, 8 sigma out of the noise, then a lagged 40 N/s ramp, a
#   slow rise; with these seeds the two samples before it are within 2 sigma): no sound
#   starts more than 3 sample periods before t_m; the knock 0.8 ms before that was taken,
#   25 ms early;
# - a jump (an 8 N impact and a 1000 N/s ramp, over 14 sigma out of the noise): the contact
#   is in sample m's period or the one before; the knock 0.3 ms before that was taken, 20 ms
#   early.
EARLY_SOUNDS = [
    pytest.param(seed, (3.0, 40.0, 0.03, 0.0255), id=f'sharp-departure-{seed}')
    for seed in (0, 9)] + [
    pytest.param(seed, (8.0, 1000.0, 0.0, 0.020), id=f'jump-{seed}') for seed in (0, 3)]


@pytest.mark.parametrize('seed, shape', EARLY_SOUNDS)
def test_a_sound_starting_before_its_departures_bound_is_not_the_contact(seed, shape):
    peak, slope, lag, before = shape
    t, force, torque = _wrench(_bump_then(peak=peak, width=0.003, slope=slope, lag=lag,
                                          top=8.0), seed=seed)
    audio = _sounds(seed=seed, events=((ONSET - before, 200.0, 0.005),))
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'ft'
    assert abs(p.onset_t - ONSET) <= 0.010, (p.onset_t - ONSET) * 1e3


# (bump peak N, bump width s, ramp slope N/s, lag s, top N, contact's delay s) of a soft
# contact whose dull thud crosses the level 8 ms after the touch (it set the onset 8 ms late)
# and whose F/T hinge is less than 10 ms before it: both mark the touch, their mean is 3-5 ms
# late.
# - a small bump, then a lagged 60 N/s ramp: a slow rise on a calm baseline, hinge within 2 ms;
# - a soft surface (a bump, then a lagged ramp to 40 N, a quarter of the change after more
#   than 60 ms): a gradual fast rise, hinge within 1 ms.
AGREEING_THUDS = [
    pytest.param(seed, (0.5, 0.02, 60.0, 0.05, 20.0, 0.0), id=f'slow-rise-{seed}')
    for seed in (0, 2, 4)] + [
    pytest.param(seed, (1.5, 0.03, 60.0, 0.08, 40.0, 0.0068), id=f'gradual-rise-{seed}')
    for seed in (0, 1, 4)]


@pytest.mark.parametrize('seed, shape', AGREEING_THUDS)
def test_a_late_thud_and_a_hinge_that_agree_give_their_mean(seed, shape):
    peak, width, slope, lag, top, delay = shape
    t, force, torque = _wrench(_bump_then(peak=peak, width=width, slope=slope, lag=lag,
                                          top=top, delay=delay), seed=seed)
    audio = _sounds(seed=seed, events=((ONSET + delay + 0.008, 200.0, 0.01),))
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'audio'
    assert 0.0 <= p.onset_t - ONSET - delay <= 0.005, (p.onset_t - ONSET - delay) * 1e3


@pytest.mark.parametrize('seed', [0, 1])
def test_the_dominant_sound_is_the_contact_not_a_faint_one_before_it(seed):
    # a slow transfer's sound window opens 80 ms before its F/T onset: a click 10 times the
    # noise's power 45 ms before the contact was taken; the contact's sound is 2000 times
    t, force, torque = _wrench(_transfer(6.0), seed=seed)
    audio = _sounds(seed=seed, events=((ONSET - 0.045, 10.0, 0.015),
                                       (ONSET + 0.002, 2000.0, 0.01)))
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'audio'
    assert 0.0 <= p.onset_t - ONSET <= 0.005, (p.onset_t - ONSET) * 1e3


# (bump peak N, bump width s, ramp slope N/s, lag s, top N, tolerance s) of a contact 5-6.8 ms
# into a sample period:
# - a soft surface: a small impact bump, then a lagged ramp to 40 N (a quarter of the change
#   after more than 60 ms). The middle of the first sample out was 4.5 ms late; the hinge
#   through the first samples is within 2 ms.
# - a 15 ms bump puts the first sample out 5-7 sigma clear of a quiet baseline, then the load
#   creeps: the short hinge reached 2 samples back (8.7 ms early); the contact is within 1.5
#   samples of that sample.
GRADUAL_RISES = [
    pytest.param(seed, 0.0068, (1.5, 0.03, 60.0, 0.08, 40.0), 0.002,
                 id=f'soft-rise-inside-its-first-sample-{seed}') for seed in (0, 1, 4)] + [
    pytest.param(seed, 0.005, (0.6, 0.015, 40.0, 0.05, 20.0), 0.005,
                 id=f'step-out-of-the-noise-not-two-samples-back-{seed}') for seed in (0, 1)]


@pytest.mark.parametrize('seed, delay, shape, tolerance', GRADUAL_RISES)
def test_a_gradual_rise_is_placed_within_its_first_samples(seed, delay, shape, tolerance):
    peak, width, slope, lag, top = shape
    t, force, torque = _wrench(_bump_then(peak=peak, width=width, slope=slope, lag=lag, top=top,
                                          delay=delay), seed=seed)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert abs(p.onset_t - ONSET - delay) <= tolerance, (p.onset_t - ONSET - delay) * 1e3


@pytest.mark.parametrize('seed', [2, 6])
def test_in_band_bumps_before_an_impact_do_not_move_it_early(seed):
    # a stiff contact (1000 N/s) jumps from the noise to over 7 sigma in one sample; the
    # second to fourth samples before it carry 2.5 sigma of vibration each, inside the
    # 3.5-sigma band. The CUSUM took their start for a creeping rise's and put the onset
    # 39 ms early; after a jump the contact is in that sample's period or the one before
    # (with other seeds the noise takes a bump out of the band, which is then the onset)
    t, force, torque = _wrench(lambda tau: np.minimum(1000.0 * tau, 8.0), seed=seed,
                               outliers=((0.038, 2.5), (0.028, 2.5), (0.018, 2.5)))
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert p.source == 'ft'
    assert abs(p.onset_t - ONSET) <= 0.005, (p.onset_t - ONSET) * 1e3


def test_the_whitened_direction_cancels_an_interference_outside_the_change():
    # an oscillation along v (not along the change u) of 20 noise units: its projection on u
    # has a standard deviation of 6, on the whitened direction about the noise's; the change
    # keeps its size
    rng = np.random.default_rng(0)
    u = np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0]) / np.sqrt(2.0)
    v = np.array([0.8, 0.0, 0.6, 0.0, 0.0, 0.0])
    base = 20.0 * np.outer(np.sin(np.linspace(0.0, 6.0 * np.pi, 100)), v)
    base += rng.normal(0.0, 1.0, base.shape)
    u_w = whitened_direction(w=base, u=u)
    assert np.std(base @ u) > 5.0
    assert np.std(base @ u_w) < 1.5
    assert (30.0 * u) @ u_w == pytest.approx(30.0)


def _sloshing(load_fn, *, seed: int, amp: float) -> tuple:
    """``_wrench`` plus liquid slosh: ``amp`` N at 2.5 Hz, mostly sideways, damped slowly."""
    t, force, torque = _wrench(load_fn, seed=seed)
    phase = np.random.default_rng(100 + seed).uniform(0.0, 2.0 * np.pi)
    slosh = amp * np.sin(2.0 * np.pi * 2.5 * t + phase) * np.exp(-0.2 * t)
    force[:, 0] += 0.8 * slosh
    force[:, 2] += 0.6 * slosh
    torque[:, 1] += 0.08 * slosh
    return t, force, torque


@pytest.mark.parametrize('seed', [2, 3, 7])
def test_a_soft_rise_under_liquid_slosh_is_found_within_20_ms(seed):
    # 5 N of slosh (20 noise units along the load's direction) and a lagged soft rise: the
    # projection on the change direction took a slosh swing for the rise and put the onset
    # 120-200 ms early; the slosh lies mostly outside the change's direction, and the
    # whitened projection cancels it (the onset is then 1-12 ms late)
    t, force, torque = _sloshing(
        lambda tau: np.minimum(200.0 * tau * (1.0 - np.exp(-tau / 0.05)), 10.0),
        seed=seed, amp=5.0)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert abs(p.onset_t - ONSET) <= 0.020, (p.onset_t - ONSET) * 1e3


def test_a_rise_the_cusum_moved_back_is_not_extrapolated_two_more_samples():
    # an impact bump (0.3 N, 20 ms) and a lagged ramp: noise lifts the samples before the
    # band crossing, the CUSUM moves the onset back to them, and the rise climbs more than
    # its 2-sigma allowance per sample from there. The short hinge, allowed 2 samples before
    # the CUSUM's sample, put the onset 26 ms early; it passed the allowance within a sample
    # of the start, so one sample back at most (16 ms early, the noise's doing)
    delay = 0.002
    t, force, torque = _wrench(_bump_then(peak=0.3, width=0.02, slope=60.0, lag=0.1, top=20.0,
                                          delay=delay), seed=3)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert abs(p.onset_t - ONSET - delay) <= 0.020, (p.onset_t - ONSET - delay) * 1e3


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_a_sound_long_before_a_steep_rise_is_not_the_contact(seed):
    # an impact bump (5 sigma in its sample) and a lagged ramp (80 N/s, lag 30 ms) that then
    # climbs 5-10 sigma per sample: a slow rise by the fast-rise test, whose sound is looked
    # for from 80 ms before. A clatter of the kitchen 60 ms before the contact, which itself
    # makes no sound, was taken (60 ms early); a load that grows at most like the square of
    # the time since the touch cannot have started there, so the F/T onset stands
    t, force, torque = _wrench(_bump_then(peak=2.5, width=0.003, slope=80.0, lag=0.03,
                                          top=8.0), seed=seed)
    audio = _sounds(seed=seed, events=((ONSET - 0.06, 200.0, 0.005),))
    p = propose_onset(ft_t=t, force=force, torque=torque, audio=audio, audio_rate=AUDIO_RATE,
                      audio_t0=0.0)
    assert p.source == 'ft'
    assert abs(p.onset_t - ONSET) <= 0.020, (p.onset_t - ONSET) * 1e3


def test_rise_fits_start_rejects_a_start_too_early_for_the_growth():
    # y = 100 (s - 0.5)^2 from 0.5 s sampled at 100 Hz: a start at 0.5 s fits, one at 0.4 s
    # cannot (from 0.4 s, the later samples grow faster than the square of the time)
    t = np.arange(100) * DT
    y = 1000.0 * np.maximum(t - 0.5, 0.0) ** 2
    m = int(np.nonzero(y > 3.5)[0][0])
    assert rise_fits_start(t=t, y=y, sd=1.0, m=m, end=m + 10, start=0.5, power=2.0,
                           margin=2.0)
    assert not rise_fits_start(t=t, y=y, sd=1.0, m=m, end=m + 10, start=0.4, power=2.0,
                               margin=2.0)


def _begun_during_a_lift(force: np.ndarray, torque: np.ndarray, t: np.ndarray) -> None:
    """Add a 60 N load (lift inertia, a grasp settling) fading out over the first second."""
    fade = np.clip(1.0 - t, 0.0, None)
    force[:, 2] -= 60.0 * fade
    torque[:, 0] -= 3.0 * fade


@pytest.mark.parametrize('seed', [5, 6])
def test_a_larger_change_under_way_at_the_start_is_not_the_contact(seed):
    # a bag begun during a lift: the first second moves the load more than the contact does,
    # and there is nothing before it to measure from, so its onset would be the first sample
    t, force, torque = _wrench(_soft, seed=seed)
    _begun_during_a_lift(force, torque, t)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert abs(p.onset_t - ONSET) <= 0.020, (p.onset_t - ONSET) * 1e3
    # the larger change counts against the proposal: look at it before using it
    assert p.confidence == 0.0


def test_a_recording_whose_only_change_has_no_rest_before_it_gets_no_onset():
    t, force, torque = _wrench(lambda tau: 0.0 * tau, seed=5)
    _begun_during_a_lift(force, torque, t)
    p = propose_onset(ft_t=t, force=force, torque=torque)
    assert p.onset_t is None and p.confidence == 0.0
    assert p.reason == NO_REST
