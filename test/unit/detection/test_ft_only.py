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
F/T-only models (robots without a microphone): the core, on synthetic signals.

Frames are clocked by the F/T feature stream; the release logic, warm-up, staleness, hold-off,
gap restarts and time jumps are those of the multimodal path; audio is ignored, never an error.
"""

from typing import Optional

from bundle_support import lasting_change_bundle
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector, run_features
from contact_detector.errors import ConfigError
from contact_detector.features.batch import batch_features
from contact_detector.features.config import FeatureConfig, PAPER_FEATURES, SHIFT_FEATURES
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.sensor_stream import AudioEvent, BadEvent, WrenchEvent
from contact_detector.model.bundle import ModelBundle
import numpy as np
import pytest

CONFIG = FeatureConfig(audio=False, ft_window=64, ft_detrend='mean', delta_window=1,
                       extra_features=SHIFT_FEATURES)
RATE = 100.0
T0 = 1_700_000_000.0
#: Index of the first wrench sample that completes an F/T feature frame.
FIRST = ForceTorqueStream(config=CONFIG, input_rate=RATE).first_end
#: Where the table takes 3 N of the load in the synthetic trials, s after the start.
STEP_S = 4.0


def _bundle() -> ModelBundle:
    # A forest that says contact when force_shift_min > 1 N: a lasting change of the load.
    return lasting_change_bundle(config=CONFIG, n=3000, created='2026-11-23T00:00:00+00:00')


@pytest.fixture(scope='module')
def bundle() -> ModelBundle:
    return _bundle()


def _wrench(*, duration_s: float = 6.0, step_s: float = STEP_S, knock_s: Optional[float] = None,
            seed: int = 1, rate: float = RATE) -> tuple:
    """Stamps, force, torque: a held object (5 N), the table taking 3 N of it at ``step_s``."""
    rng = np.random.default_rng(seed)
    n = int(duration_s * rate)
    t = T0 + np.arange(n) / rate
    force = np.zeros((n, 3)) + rng.normal(scale=0.02, size=(n, 3))
    torque = np.zeros((n, 3)) + rng.normal(scale=0.002, size=(n, 3))
    force[:, 2] -= 5.0
    force[t - T0 >= step_s, 2] += 3.0
    if knock_s is not None:
        # a knock on the hand: a 30 ms pulse, then the load is what it was
        hit = (t - T0 >= knock_s) & (t - T0 < knock_s + 0.03)
        force[hit, 0] += 6.0
    return t, force, torque


def _events(t, force, torque, *, audio: bool = True, bad_audio_at: Optional[float] = None) -> list:
    """One wrench message per sample, a 10 ms audio chunk after each (as a bag replays it)."""
    events = []
    for i in range(t.size):
        events.append(WrenchEvent(t=t[i:i + 1], force=force[i:i + 1], torque=torque[i:i + 1],
                                  now=float(t[i]) + 0.002))
        if audio:
            events.append(AudioEvent(samples=np.zeros(160, np.int16), stamp=float(t[i]),
                                     now=float(t[i]) + 0.003))
        if bad_audio_at is not None and abs(t[i] - T0 - bad_audio_at) < 1e-6:
            events.append(BadEvent(kind='audio', reason='garbage', now=float(t[i])))
    return events


def _detector(bundle, **settings) -> ContactDetector:
    return ContactDetector(bundle=bundle, settings=DetectorSettings(**settings))


# --- configuration -----------------------------------------------------------------------------

def test_config_without_audio_has_no_audio_column_and_refuses_audio_features():
    assert CONFIG.ft_only
    assert CONFIG.feature_names == PAPER_FEATURES[1:] + SHIFT_FEATURES
    with pytest.raises(ConfigError, match='audio_power_rel_db'):
        FeatureConfig(audio=False, extra_features=('audio_power_rel_db',))
    with pytest.raises(ConfigError, match='audio'):
        FeatureConfig(audio='no')


def test_old_configs_load_and_write_unchanged():
    old = FeatureConfig(extra_features=('force_delta',))
    assert 'audio' not in old.to_dict()          # model files written before keep their hash
    assert FeatureConfig.from_dict(old.to_dict()) == old and not old.ft_only
    assert FeatureConfig.from_dict(CONFIG.to_dict()) == CONFIG
    assert CONFIG.to_dict()['audio'] is False


def test_model_id_says_ft_only(bundle):
    assert bundle.model_id.startswith('rf5-ft6+force_shift')


# --- frames clocked by the F/T stream -------------------------------------------------------

def test_one_row_per_ft_feature_frame_at_its_last_sample():
    t, force, torque = _wrench(duration_s=3.0)
    extractor = StreamingFeatureExtractor(config=CONFIG, audio_rate=16000.0)
    frames = extractor.push_wrench(t=t, force=force, torque=torque)
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    ft_t, ft_x = stream.push(t=t, force=force, torque=torque)
    assert len(frames) == ft_t.size > 200
    assert np.array_equal(frames.t, ft_t) and np.array_equal(frames.x, ft_x)
    assert frames.valid.all() and frames.names == CONFIG.feature_names
    assert frames.t[0] == t[FIRST]                  # from the first full window on


def test_streaming_rows_match_the_batch_reference():
    t, force, torque = _wrench(duration_s=3.0, knock_s=1.5)
    stream = StreamingFeatureExtractor(config=CONFIG, audio_rate=16000.0).push_wrench(
        t=t, force=force, torque=torque)
    batch = batch_features(config=CONFIG, audio=np.zeros(16000), audio_rate=16000.0,
                           audio_t0=T0, ft_t=t, force=force, torque=torque)
    assert np.array_equal(stream.t, batch.t) and batch.valid.all()
    np.testing.assert_allclose(stream.x, batch.x, rtol=1e-9, atol=1e-12)


def test_sample_by_sample_equals_one_push_and_audio_is_ignored():
    t, force, torque = _wrench(duration_s=3.0)
    whole = StreamingFeatureExtractor(config=CONFIG, audio_rate=16000.0).push_wrench(
        t=t, force=force, torque=torque)
    live = StreamingFeatureExtractor(config=CONFIG, audio_rate=16000.0)
    rows = []
    for i in range(t.size):
        rows.append(live.push_wrench_one(t=t[i], values=[*force[i], *torque[i]]))
        assert len(live.push_audio(np.ones(160, np.int16), stamp=t[i])) == 0
    got = [r for r in rows if len(r)]
    assert np.array_equal(np.concatenate([r.t for r in got]), whole.t)
    assert np.array_equal(np.concatenate([r.x for r in got]), whole.x)
    assert live.ignored_audio == t.size and len(live.flush()) == 0


# --- the detector ----------------------------------------------------------------------------

def test_releases_once_at_the_load_transfer_and_ignores_audio(bundle):
    events = _events(*_wrench(knock_s=2.5))
    run = run_detector(events, detector=_detector(bundle), in_blocks=False)
    assert len(run.releases) == 1
    assert T0 + STEP_S <= run.releases[0] <= T0 + STEP_S + 0.3
    assert run.counts['audio_ignored'] == run.counts['audio_msgs'] == 600
    assert run.counts['audio_dropped'] == 0 and run.valid.all()
    assert len(run.t) == 600 - FIRST
    assert not run.contact[run.t < T0 + STEP_S].any()    # the knock at 2.5 s is not contact


def test_blocks_give_the_per_message_decisions(bundle):
    events = _events(*_wrench(knock_s=2.5), bad_audio_at=3.0)
    blocks = run_detector(events, detector=_detector(bundle))
    single = run_detector(events, detector=_detector(bundle), in_blocks=False)
    for key in ('t', 'p', 'contact', 'valid'):
        assert np.array_equal(getattr(blocks, key), getattr(single, key)), key
    assert blocks.releases == single.releases and len(blocks.releases) == 1
    assert blocks.counts == single.counts
    assert single.counts['audio_ignored'] == 601       # a refused audio message is no error
    features = run_features(events, extractor=StreamingFeatureExtractor(
        config=CONFIG, audio_rate=16000.0))
    assert np.array_equal(features.t, single.t)         # train sees the frames detect decides


@pytest.mark.parametrize('rate', [51.0, 125.0])
def test_off_the_grid_rates_release_at_the_sample_that_decided(bundle, rate):
    # 51 and 125 Hz are resampled onto the 100 Hz grid: a frame is timed at the stamp of the
    # sample that completed it, in blocks and per message, and so is the release.
    t, force, torque = _wrench(knock_s=2.5, rate=rate)
    events = _events(t, force, torque)
    settings = {'wrench_rate': rate}
    blocks = run_detector(events, detector=_detector(bundle, **settings))
    single = run_detector(events, detector=_detector(bundle, **settings), in_blocks=False)
    for key in ('t', 'p', 'contact', 'valid'):
        assert np.array_equal(getattr(blocks, key), getattr(single, key)), key
    assert blocks.releases == single.releases and len(blocks.releases) == 1
    assert np.all(np.isin(single.t, t)) and single.releases[0] in t
    assert T0 + STEP_S <= single.releases[0] <= T0 + STEP_S + 0.3
    # the node's calls: one sample per on_wrench_one; its release log and age use these times
    node = _detector(bundle, **settings)
    decided = [node.on_wrench_one(t=float(e.t[0]), values=[*e.force[0], *e.torque[0]],
                                  now=e.now) if isinstance(e, WrenchEvent)
               else node.on_audio(e.samples, stamp=e.stamp, now=e.now) for e in events]
    assert np.array_equal(np.concatenate([d.t for d in decided]), single.t)
    assert [r for d in decided for r in d.releases] == single.releases


def test_warmup_applies_from_the_first_ft_frame(bundle):
    # The load moves as soon as the first window is full: no release during the warm-up.
    first = FIRST / RATE
    events = _events(*_wrench(step_s=first - 0.3), audio=False)
    run = run_detector(events, detector=_detector(bundle, warmup_s=1.0), in_blocks=False)
    assert run.releases == []
    run = run_detector(events, detector=_detector(bundle, warmup_s=0.0), in_blocks=False)
    assert len(run.releases) == 1


def test_bad_input_never_releases(bundle):
    t, force, torque = _wrench()
    # NaN at the step: dropped, counted, and the hold-off covers the step
    bad = (t - T0 >= STEP_S) & (t - T0 < STEP_S + 0.05)
    force[bad] = np.nan
    run = run_detector(_events(t, force, torque, audio=False),
                       detector=_detector(bundle, corrupt_holdoff_s=2.0), in_blocks=False)
    assert run.counts['wrench_dropped'] == bad.sum() > 0 and run.releases == []
    # everything stale: decided invalid, never released
    t, force, torque = _wrench()
    late = [WrenchEvent(t=e.t, force=e.force, torque=e.torque, now=e.now + 1.0)
            for e in _events(t, force, torque, audio=False)]
    for in_blocks in (True, False):
        run = run_detector(late, detector=_detector(bundle), in_blocks=in_blocks)
        assert run.releases == [] and not run.valid.any()
        assert run.counts['stale_frames'] == len(run.t) > 0


def test_gap_restarts_the_window_and_time_jump_resets(bundle):
    t, force, torque = _wrench()
    keep = (t - T0 < 2.0) | (t - T0 >= 2.5)               # 0.5 s without wrench
    run = run_detector(_events(t[keep], force[keep], torque[keep], audio=False),
                       detector=_detector(bundle))
    assert run.counts['wrench_restarts'] == 1 and len(run.releases) == 1
    # no frame from a window across the gap
    assert not np.any((run.t > T0 + 2.0) & (run.t < T0 + 2.5 + 0.59))
    # stamps jump back 10 s after the step: the state resets, nothing is released twice
    t2 = np.concatenate([t, t[-1] - 10.0 + np.arange(1, 301) / RATE])
    force2 = np.concatenate([force, force[-300:]])
    torque2 = np.concatenate([torque, torque[-300:]])
    run = run_detector(_events(t2, force2, torque2, audio=False), detector=_detector(bundle))
    assert run.counts['time_jumps'] == 1 and len(run.releases) == 1


def test_an_empty_or_audio_only_recording_decides_nothing(bundle):
    events = [AudioEvent(samples=np.zeros(160, np.int16), stamp=T0 + i / 100, now=T0 + i / 100)
              for i in range(100)]
    run = run_detector(events, detector=_detector(bundle))
    assert len(run.t) == 0 and run.releases == [] and run.counts['audio_ignored'] == 100
