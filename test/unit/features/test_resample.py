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

"""Any F/T rate from 50 Hz to 10 kHz: resampling onto the feature grid, offline and streaming."""

import dataclasses

from contact_detector.detection import factory
from contact_detector.errors import ConfigError
from contact_detector.features.config import FeatureConfig
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.features.frames import FeatureFrames
from contact_detector.features.resample import integer_ratio, WrenchResampler
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.discovery import discover_streams
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest

RATES = [50.0, 51.0, 100.0, 125.0, 200.0, 333.0, 500.0, 1000.0, 10000.0]
T0 = 1_700_000_000.0


def _step(rate: float, *, seconds: float = 2.0, t_step: float = 1.0, jitter: float = 0.0,
          seed: int = 0):
    """Stamps at ``rate`` (optional jitter); force z = 10 N until ``T0 + t_step``, then 20 N."""
    n = int(seconds * rate)
    t = T0 + np.arange(n) / rate
    if jitter:
        t = t + np.random.default_rng(seed).uniform(-jitter, jitter, n) / rate
    values = np.zeros((n, 6))
    values[:, 2] = np.where(t < T0 + t_step, 10.0, 20.0)
    values[:, 5] = 0.1
    return t, values


def _old_block_means(t, values, m):
    # The decimation ForceTorqueStream did before the resampler existed.
    n_blocks = t.size // m
    used = n_blocks * m
    dec_v = values[:used].reshape(n_blocks, m, 6).mean(axis=1) if m > 1 else values[:used]
    return t[m - 1:used:m], dec_v


@pytest.mark.parametrize('rate, m', [(100.0, 1), (1000.0, 10), (500.0, 5), (10000.0, 100)])
def test_integer_ratios_keep_the_block_means_bit_for_bit(rate, m):
    t, values = _step(rate)
    values[:, :3] += np.random.default_rng(1).normal(0, 0.3, (t.size, 3))
    resampler = WrenchResampler(input_rate=rate, output_rate=100.0)
    assert resampler.block == m
    want_t, want_v = _old_block_means(t, values, m)
    # in chunks of odd sizes, as messages arrive
    got_t, got_v, lo = [], [], 0
    for size in np.random.default_rng(2).integers(1, 3 * m + 2, size=10 * t.size):
        if lo >= t.size:
            break
        a, b = resampler.push(t=t[lo:lo + size], values=values[lo:lo + size])
        got_t.append(a)
        got_v.append(b)
        lo += size
    assert np.array_equal(np.concatenate(got_t), want_t)
    assert np.array_equal(np.concatenate(got_v), want_v)


def test_integer_ratio_tolerates_a_measured_rate():
    assert integer_ratio(input_rate=999.7, output_rate=100.0) == 10
    assert integer_ratio(input_rate=100.4, output_rate=100.0) == 1
    assert integer_ratio(input_rate=125.0, output_rate=100.0) == 0
    assert integer_ratio(input_rate=51.0, output_rate=100.0) == 0
    for bad in (49.0, 10200.0, float('nan')):
        with pytest.raises(ConfigError, match='outside'):
            WrenchResampler(input_rate=bad, output_rate=100.0)


@pytest.mark.parametrize('rate', RATES)
def test_a_force_step_reaches_the_grid_at_its_time(rate):
    """The half-way crossing of a 10 N step is within one feature period (10 ms) of the step."""
    t, values = _step(rate, jitter=0.05)
    resampler = WrenchResampler(input_rate=rate, output_rate=100.0)
    out_t, out_v = resampler.push(t=t, values=values)
    # the grid: 100 Hz, uniform (block paths: the block ends), covering the recording
    steps = np.diff(out_t)
    assert np.allclose(np.median(steps), 0.01, rtol=0.02)
    assert out_t[-1] <= t[-1] and t[-1] - out_t[-1] < 0.01 + 1.0 / rate
    assert np.allclose(out_v[:, 5], 0.1)                # a constant stays constant
    crossing = out_t[np.argmax(out_v[:, 2] >= 15.0)]
    assert T0 + 1.0 - 1.0 / rate <= crossing <= T0 + 1.0 + 0.01 + 1.0 / rate, crossing - T0
    # the same samples one by one (a live node) give the same grid to rounding
    one = WrenchResampler(input_rate=rate, output_rate=100.0)
    pieces = [one.push(t=t[i:i + 1], values=values[i:i + 1]) for i in range(t.size)]
    assert np.allclose(np.concatenate([p[0] for p in pieces]), out_t, rtol=0, atol=1e-9)
    assert np.allclose(np.concatenate([p[1] for p in pieces]), out_v, rtol=0, atol=1e-9)


@pytest.mark.parametrize('rate', [51.0, 125.0, 333.0])
def test_the_grid_uses_nothing_later_than_one_input_period(rate):
    t, values = _step(rate)
    resampler = WrenchResampler(input_rate=rate, output_rate=100.0)
    emitted = []
    for i in range(t.size):
        out_t, _ = resampler.push(t=t[i:i + 1], values=values[i:i + 1])
        emitted.extend((g, t[i]) for g in out_t)
        # every grid point up to the newest stamp is out, none after it
        assert not emitted or emitted[-1][0] <= t[i]
        assert resampler._t.size <= int(np.ceil(rate / 100.0)) + 3      # bounded memory
    delay = np.array([arrived - g for g, arrived in emitted])
    assert np.all(delay >= -1e-6) and np.all(delay <= 1.0 / rate + 1e-6)   # stamps ~1e-7 s


@pytest.mark.parametrize('rate', [51.0, 125.0, 200.0, 333.0, 1000.0])
def test_feature_frames_of_a_step_come_at_the_right_time(rate):
    """force_change rises within one feature period of where it rises at 100 Hz."""
    config = FeatureConfig(ft_window=16, extra_features=('force_change',))

    def rise(r):
        t, values = _step(r)
        stream = ForceTorqueStream(config=config, input_rate=r)
        ft_t, x = stream.push(t=t, force=values[:, :3], torque=values[:, 3:])
        col = stream.columns.index('force_change')
        return ft_t[np.argmax(x[:, col] >= 5.0)]
    assert abs(rise(rate) - rise(100.0)) <= 0.01 + 1.0 / rate


#: An F/T-only configuration (frames clocked by the F/T stream) with a feature over samples.
FT_ONLY = FeatureConfig(audio=False, ft_window=16, extra_features=('force_change',))
OFF_GRID, ON_GRID = [51.0, 125.0, 333.0], [100.0, 200.0, 1000.0]


def _noisy(rate: float, *, jitter: float, seconds: float = 1.0, seed: int = 0):
    """Return stamps and a held load with noise on every axis at ``rate`` (jitter in steps)."""
    rng = np.random.default_rng(seed)
    n = int(seconds * rate)
    t = T0 + np.arange(n) / rate
    if jitter:
        t = t + rng.uniform(-jitter / 2, jitter / 2, n) / rate
    return t, np.array([0.5, 0.2, -5.0, 0.01, 0.02, 0.0]) + rng.normal(0, 0.3, (n, 6))


def _ft_only_rows(t, values, rate):
    frames = StreamingFeatureExtractor(config=FT_ONLY, audio_rate=16000.0,
                                       ft_input_rate=rate).push_wrench(
        t=t, force=values[:, :3], torque=values[:, 3:])
    return frames.t, frames.x


@pytest.mark.parametrize('jitter', [0.0, 0.1])
@pytest.mark.parametrize('rate', OFF_GRID + ON_GRID)
def test_an_ft_only_row_is_timed_at_the_newest_sample_it_depends_on(rate, jitter):
    """
    A row's time is the stamp of the newest wrench sample its values depend on.

    Changing the samples from ``k`` on leaves every row timed before ``t_k`` as it was, bit for
    bit (no row depends on a sample after its time), and every row time is a stamp (so before
    the next sample's). Where the wrench is resampled (51, 125, 333 Hz) a row's grid point lies
    before that stamp; the detector must not count latency from there. The rows timed at
    ``t_k`` change too (the time is not later than needed), but for stamps exactly on the
    125 Hz lattice: every 4th falls on a grid point, and the resampler's "at or after
    ``g_j``" (``floor((t - g_0) f_out + 1e-9)`` on stamps of 1.7e9 s) counts about half of
    those as before it, so the next sample completes that grid point and times its row.
    """
    first = ForceTorqueStream(config=FT_ONLY, input_rate=100.0).first_end / 100.0
    t, values = _noisy(rate, jitter=jitter, seconds=first + 70 / rate + 0.1)
    times, x = _ft_only_rows(t, values, rate)
    at = np.searchsorted(t, times)
    assert np.array_equal(t[at], times)                    # a stamp, so < the next one
    # sample by sample (a live node) gives the same times and values
    live = StreamingFeatureExtractor(config=FT_ONLY, audio_rate=16000.0, ft_input_rate=rate)
    rows = [live.push_wrench_one(t=t[i], values=values[i]) for i in range(t.size)]
    assert np.array_equal(np.concatenate([r.t for r in rows]), times)
    np.testing.assert_allclose(np.concatenate([r.x for r in rows]), x, rtol=0, atol=1e-9)
    rng = np.random.default_rng(1)
    checked = 0
    for k in range(at[0], min(at[0] + 60, t.size)):
        changed = values.copy()
        changed[k:] += rng.normal(0, 3.0, (t.size - k, 6))
        times_k, x_k = _ft_only_rows(t, changed, rate)
        assert np.array_equal(times_k, times)
        before = times < t[k]
        assert np.array_equal(x_k[before], x[before]), k
        on = times == t[k]
        if jitter or rate in ON_GRID:
            assert np.all(np.any(x_k[on] != x[on], axis=1)), k
        checked += int(np.any(x_k[on] != x[on], axis=1).sum())
    assert checked >= 5


@pytest.mark.parametrize('rate', OFF_GRID + ON_GRID)
def test_ft_only_frames_move_only_their_time_and_only_off_the_grid(rate):
    """The features of an F/T-only frame are the grid's; its time moves by < 1 input step."""
    t, values = _noisy(rate, jitter=0.1, seconds=2.0)
    kw = {'t': t, 'force': values[:, :3], 'torque': values[:, 3:]}
    own_t, own_x = ForceTorqueStream(config=FT_ONLY, input_rate=rate).push(**kw)
    grid_t, grid_x = ForceTorqueStream(config=dataclasses.replace(FT_ONLY, audio=True),
                                       input_rate=rate).push(**kw)
    assert own_t.size == grid_t.size > 50
    assert np.array_equal(own_x, grid_x)
    if rate in ON_GRID:
        assert np.array_equal(own_t, grid_t)            # block means: the block's last stamp
        return
    late = own_t - grid_t
    assert np.all(late >= 0) and late.max() > 0.2 / rate
    assert np.all(late < np.diff(t).max())


# every rate issue #15 names, and the ends of the range the node takes
@pytest.mark.parametrize('rate', [50.0, 51.0, 125.0, 200.0, 333.0, 500.0, 1000.0, 10000.0])
def test_the_live_path_keeps_every_ft_frame_a_sample_completes(rate):
    """
    One wrench message per sample (the node): the rows of ``push_wrench``, bit for bit.

    At 51 Hz one sample completes two grid points (two F/T frames) now and then; an audio
    frame takes the newest, so losing one makes it use F/T 10 ms older than offline.
    """
    config = FeatureConfig(ft_window=16, extra_features=('force_change',))
    t, values = _noisy(rate, jitter=0.1, seconds=1.5)
    audio = np.random.default_rng(2).normal(0, 0.05, int(1.5 * 16000) + 160)
    out = {}
    for one in (False, True):
        ex = StreamingFeatureExtractor(config=config, audio_rate=16000.0, ft_input_rate=rate)
        rows = []
        for k in range(150):
            stamp = T0 + (160 * (k + 1) - 1) / 16000.0
            rows.append(ex.push_audio(audio[160 * k:160 * (k + 1)], stamp=stamp))
            for i in np.flatnonzero((t > stamp - 0.01) & (t <= stamp)):
                rows.append(ex.push_wrench_one(t=t[i], values=values[i]) if one else
                            ex.push_wrench(t=t[i:i + 1], force=values[i:i + 1, :3],
                                           torque=values[i:i + 1, 3:]))
        out[one] = FeatureFrames.concat(rows, ex.names)
    assert len(out[True]) > 100 and out[True].valid.sum() > 50
    for field in ('t', 'x', 'valid'):
        assert np.array_equal(getattr(out[True], field), getattr(out[False], field)), field


def _upsampled(trial, rate):
    # A 10 kHz sensor: the simulator's 5 kHz wrench, interpolated (the simulator stops there).
    t = trial.wrench_t[0] + np.arange(int((trial.wrench_t[-1] - trial.wrench_t[0]) * rate)) / rate
    force = np.stack([np.interp(t, trial.wrench_t, trial.force[:, k]) for k in range(3)], 1)
    torque = np.stack([np.interp(t, trial.wrench_t, trial.torque[:, k]) for k in range(3)], 1)
    return dataclasses.replace(trial, ft_rate=rate, wrench_t=t, force=force, torque=torque,
                               wrench_log_t=None)


@pytest.mark.slow
@pytest.mark.parametrize('index', [0, 1])
def test_simulated_trials_at_every_rate_are_detected_like_at_100_hz(tmp_path, index):
    make, stream = factory.build_detector_factory(model=None, params_file=None,
                                                  audio_rate=None)
    latency = {}
    for rate in [100.0, 50.0, 51.0, 125.0, 200.0, 333.0, 500.0, 1000.0, 10000.0]:
        if rate > 5000:
            trial = _upsampled(simulate_trial(seed=21, index=index, ft_rate=5000.0), rate)
        else:
            trial = simulate_trial(seed=21, index=index, ft_rate=rate)
        bag = write_trial_bag(trial=trial, path=tmp_path / f'{rate:g}')
        found = discover_streams(bag, param_audio_rate=trial.audio_rate)
        assert found.wrench_rate == pytest.approx(rate, rel=0.01)     # measured from stamps
        run = factory.detect_bag(bag=bag, make_detector=make,
                                 spec=factory.stream_spec(found, stream), streams=found)
        assert len(run.releases) == 1, (rate, run.releases)
        latency[rate] = run.releases[0] - trial.onset_t
    # every rate: released after the onset and soon, as at 100 Hz
    assert 0.0 <= latency[100.0] <= 0.1
    assert all(0.0 <= value <= 0.1 for value in latency.values()), latency
