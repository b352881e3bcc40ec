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

"""AudioFallback: the F/T-only model decides beside the audio model and stands in for it."""

from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.fallback import AudioFallback, FT_ONLY, MULTIMODAL
from contact_detector.detection.offline import run_detector
from contact_detector.errors import ConfigError
from contact_detector.io.sensor_stream import AudioEvent
from contact_detector.model.shipped import default_ft_model_path, default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim.messages import message_events
from contact_detector.sim.trial import simulate_trial
import node_support
import numpy as np
import pytest

TRIAL = {'seed': 3, 'index': 21, 'hits': 'hand'}  # in-air hand hits 1.5 s and 1.1 s before onset


@pytest.fixture(scope='module')
def bundles():
    return load_bundle(path=default_model_path()), load_bundle(path=default_ft_model_path())


@pytest.fixture(scope='module')
def trial():
    return simulate_trial(**TRIAL)


def _fallback(bundles, timeout_s=0.3) -> AudioFallback:
    primary, ft = bundles
    return AudioFallback(primary=ContactDetector(bundle=primary, settings=DetectorSettings()),
                         fallback=ContactDetector(bundle=ft, settings=DetectorSettings()),
                         timeout_s=timeout_s)


def _feed(fb: AudioFallback, trial, *, audio_until=np.inf, audio_from=np.inf) -> tuple:
    """Feed the trial in log-time order; audio only outside (audio_until, audio_from)."""
    events = []
    starts = np.concatenate([[0], trial.chunk_ends[:-1]])
    for lo, hi, t in zip(starts, trial.chunk_ends, trial.chunk_log_t):
        if t < audio_until or t >= audio_from:
            events.append((float(t), 1, lo, hi))
    for j, t in enumerate(trial.wrench_t):
        events.append((float(t), 0, j, j + 1))
    events.sort()
    frames, releases, active = 0, [], []
    for t, kind, lo, hi in events:
        if kind:
            d = fb.on_audio(trial.audio[lo:hi], stamp=t, now=t)
        else:
            values = [*trial.force[lo], *trial.torque[lo]]
            d = fb.on_wrench_one(t=trial.wrench_t[lo], values=values, now=t)
        frames += len(d)
        releases += d.releases
        active.append((t, fb.active_name))
    return frames, releases, active


@pytest.mark.slow
def test_audio_stops_halfway_ft_model_takes_over_and_releases_once(bundles, trial):
    fb = _fallback(bundles)
    stop = trial.onset_t - 1.2            # the audio dies between the two knocks on the hand
    frames, releases, active = _feed(fb, trial, audio_until=stop)
    assert fb.switches == 1 and fb.active_name == FT_ONLY
    switched = next(t for t, name in active if name == FT_ONLY)
    assert stop + 0.3 < switched < stop + 0.35          # the timeout, at a wrench message
    assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.5
    assert fb.counts['model_switches'] == 1 and fb.counts['releases'] == 1
    assert 'model switched to F/T-only' in fb.switch_messages[0]
    assert frames > 300


def test_audio_back_hands_over_after_the_warm_up(bundles, trial):
    fb = _fallback(bundles)
    gap = (trial.onset_t - 3.0, trial.onset_t - 1.5)
    _, releases, active = _feed(fb, trial, audio_until=gap[0], audio_from=gap[1])
    assert fb.switches == 2 and fb.active_name == MULTIMODAL
    back = [t for (t, name), (_, prev) in zip(active[1:], active) if name != prev][-1]
    assert gap[1] + fb.primary.settings.warmup_s - 0.02 <= back <= gap[1] + 0.6
    assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.3


def test_a_switch_never_releases_and_arming_follows(bundles, trial):
    fb = _fallback(bundles)
    fb.arm(False)
    _, releases, _ = _feed(fb, trial, audio_until=trial.onset_t - 1.2)
    assert releases == [] and not fb.armed and fb.switches == 1
    # no audio at all: the F/T-only model after the timeout, from the first wrench stamp
    fb = _fallback(bundles)
    _, releases, active = _feed(fb, trial, audio_until=-np.inf)
    assert active[0][1] == MULTIMODAL and fb.active_name == FT_ONLY and fb.switches == 1
    assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.5


def test_wrong_models_are_refused(bundles):
    primary, ft = bundles
    det = ContactDetector(bundle=primary, settings=DetectorSettings())
    with pytest.raises(ConfigError, match='F/T-only model as fallback'):
        AudioFallback(primary=det, fallback=det, timeout_s=0.3)
    with pytest.raises(ConfigError, match='timeout 0'):
        AudioFallback(primary=det, fallback=ContactDetector(
            bundle=ft, settings=DetectorSettings()), timeout_s=0.0)
    with pytest.raises(ConfigError, match='timeout'):
        AudioFallback(primary=det, fallback=ContactDetector(
            bundle=ft, settings=DetectorSettings()), timeout_s=-1.0, both_decide=True)


# --- both models decide (model.ft_also_decides) ------------------------------------------------

def _pair(bundles, timeout_s=0.0) -> AudioFallback:
    primary, ft = bundles
    return AudioFallback(primary=ContactDetector(bundle=primary, settings=DetectorSettings()),
                         fallback=ContactDetector(bundle=ft, settings=DetectorSettings()),
                         timeout_s=timeout_s, both_decide=True)


def _one_by_one(pair: AudioFallback, events: list) -> tuple:
    """Feed the pair message by message, as the node does; its releases and events."""
    releases, contact_events = [], []
    for e in events:
        if isinstance(e, AudioEvent):
            blocks = [pair.on_audio(e.samples, stamp=e.stamp, now=e.now)]
        else:
            blocks = [pair.on_wrench_one(t=float(t), values=[*f, *q], now=e.now)
                      for t, f, q in zip(e.t, e.force, e.torque)]
        for d in blocks:
            releases += d.releases
            contact_events += d.events
    d = pair.flush()
    return releases + d.releases, contact_events + d.events


def _first_trial_released_first_by(bundles, by: str) -> tuple:
    """Return the first paper trial of seed 5 whose first release alone is ``by``'s model's."""
    for index in range(20):
        trial = simulate_trial(seed=5, index=index, condition='paper')
        events = [node_support.sensor_event(trial, e) for e in message_events(trial=trial)]
        alone = [run_detector(events, detector=ContactDetector(bundle=b,
                                                               settings=DetectorSettings()))
                 for b in bundles]
        firsts = [r.releases[0] if r.releases else np.inf for r in alone]
        if np.isfinite(min(firsts)) and firsts[0] != firsts[1] and (
                (firsts[0] < firsts[1]) == (by == MULTIMODAL)):
            return trial, events, alone
    pytest.fail(f'no paper trial of seed 5 released first by the {by} model')


@pytest.mark.parametrize('by', [MULTIMODAL, FT_ONLY])
def test_both_decide_node_and_offline_release_once_within_one_audio_chunk(bundles, by):
    # one trial in which the audio model's release frame comes before the F/T-only model's, one
    # the other way round (which trials depends on the shipped models, so they are searched)
    trial, events, alone = _first_trial_released_first_by(bundles, by)
    offline = run_detector(events, detector=_pair(bundles))
    assert offline.released_by == by
    assert offline.releases == [min(r.releases[0] for r in alone)]
    assert trial.onset_t < offline.releases[0] < trial.onset_t + 0.1
    assert offline.counts['releases'] == 1 and offline.counts['ft_releases'] == (by == FT_ONLY)
    np.testing.assert_array_equal(offline.p, alone[0].p)      # the frames are the audio model's
    live = _pair(bundles)
    releases, contact_events = _one_by_one(live, events)
    live_by = live.last_release_by
    assert len(releases) == 1 and not live.armed
    # Offline the earlier frame is the release. On the node the first release decided is: an
    # F/T-only frame is decided when its wrench sample arrives, an audio frame only when the
    # audio chunk that completes it does, so an F/T-only release less than one audio chunk
    # after the audio model's comes first there (docs/node.md, "Two models decide").
    chunk_s = (max(len(e.samples) for e in events if isinstance(e, AudioEvent))
               / trial.audio_rate)
    assert offline.releases[0] <= releases[0] <= offline.releases[0] + chunk_s
    if live_by == by:
        assert releases == offline.releases and contact_events == offline.events
    else:       # only an audio release can be overtaken, and only by a later F/T-only frame
        assert (by, live_by) == (MULTIMODAL, FT_ONLY)
        assert releases == alone[1].releases[:1]
    assert not live.primary.armed and not live.fallback.armed     # one release per arming
    assert live.counts['releases'] == 1 and live.counts['ft_releases'] == (live_by == FT_ONLY)


def test_both_decide_rearms_both_and_offline_refuses_a_timeout(bundles):
    pair = _pair(bundles)
    assert pair.armed and pair.fallback.armed and len(pair.deciding) == 2
    pair.arm(False)
    assert not pair.primary.armed and not pair.fallback.armed
    pair.arm(True)
    assert pair.primary.armed and pair.fallback.armed
    with pytest.raises(ConfigError, match='timeout'):
        run_detector([], detector=_pair(bundles, timeout_s=0.3))
    with pytest.raises(ConfigError, match='without both_decide'):
        AudioFallback(primary=pair.primary, fallback=pair.fallback, timeout_s=0.0)


@pytest.mark.slow
def test_both_decide_audio_stops_the_ft_model_goes_on_and_releases_once(bundles, trial):
    fb = _pair(bundles, timeout_s=0.3)
    stop = trial.onset_t - 1.2            # the audio dies between the two knocks on the hand
    _, releases, _ = _feed(fb, trial, audio_until=stop)
    assert fb.switches == 1 and fb.active_name == FT_ONLY and fb.deciding == (fb.fallback,)
    assert len(releases) == 1 and trial.onset_t < releases[0] <= trial.onset_t + 0.5
    assert fb.counts['releases'] == 1 and fb.counts['ft_releases'] == 1
