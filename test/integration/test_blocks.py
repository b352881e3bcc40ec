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
Offline decisions in blocks are the node's decisions, to the bit.

``detect``, ``evaluate`` and the benchmarks run a clean recording through
:mod:`contact_detector.detection.blocks`; anything unusual goes message by message, as the node
does. These tests compare both paths on simulated bags of several rates, chunkings and
storages, and on recordings damaged the ways the reliability page lists.
"""

from dataclasses import replace

from contact_detector.detection.blocks import run_blocks
from contact_detector.detection.detector import ContactDetector, DetectorSettings
from contact_detector.detection.offline import run_detector
from contact_detector.features import spectral
from contact_detector.features.audio import NoiseFloor
from contact_detector.features.force_torque import ForceTorqueStream
from contact_detector.io.sensor_stream import (AudioEvent, BadEvent, load_events, StreamSpec,
                                               WrenchEvent)
from contact_detector.model.shipped import default_model_path
from contact_detector.model.storage import load_bundle
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest

pytestmark = pytest.mark.slow   # simulates and decides whole recordings


@pytest.fixture(scope='module')
def bundle():
    return load_bundle(path=default_model_path())


def _detector(bundle, **settings) -> ContactDetector:
    return ContactDetector(bundle=bundle, settings=DetectorSettings(**settings))


def _same(a, b) -> None:
    for key in ('t', 'p', 'contact', 'valid'):
        x, y = getattr(a, key), getattr(b, key)
        assert x.dtype == y.dtype and np.array_equal(x, y), key
    assert a.releases == b.releases
    assert a.events == b.events
    assert a.counts == b.counts


def _both(events, bundle, **settings):
    blocks = run_detector(events, detector=_detector(bundle, **settings))
    single = run_detector(events, detector=_detector(bundle, **settings), in_blocks=False)
    _same(blocks, single)
    return blocks


# --- the feature functions give a row the same bits in any batch ----------------------------

def test_feature_rows_do_not_depend_on_the_batch():
    rng = np.random.default_rng(3)
    frames = rng.normal(size=(301, 64)) + 2.0
    spectra = spectral.magnitude_spectrum(frames=frames, detrend='mean')
    functions = {
        'spectrum': lambda x: spectral.magnitude_spectrum(frames=x, detrend='mean'),
        'centroid': lambda x: spectral.spectral_centroid_spread(spectra=x, window_length=64)[0],
        'spread': lambda x: spectral.spectral_centroid_spread(spectra=x, window_length=64)[1],
        'sum_normalised': lambda x: spectral.sum_normalised(spectra=x),
        'power': lambda x: spectral.audio_power(frames=x),
    }
    for name, fn in functions.items():
        data = frames if name in ('spectrum', 'power') else spectra
        whole = fn(data)
        one_by_one = np.concatenate([fn(data[i:i + 1]) for i in range(data.shape[0])])
        assert np.array_equal(whole, one_by_one), name


@pytest.mark.parametrize('rate', [100.0, 1000.0])
def test_force_torque_stream_one_push_equals_sample_by_sample(bundle, rate):
    rng = np.random.default_rng(4)
    n = 1500
    t = 1_700_000_000.0 + np.arange(n) / rate
    force, torque = rng.normal(size=(n, 3)) * 4 + 2, rng.normal(size=(n, 3))
    live = ForceTorqueStream(config=bundle.feature_config, input_rate=rate)
    pieces = [live.push(t=t[i:i + 1], force=force[i:i + 1], torque=torque[i:i + 1])
              for i in range(n)]
    whole = ForceTorqueStream(config=bundle.feature_config, input_rate=rate).push(
        t=t, force=force, torque=torque)
    assert np.array_equal(np.concatenate([p[0] for p in pieces]), whole[0])
    assert np.array_equal(np.concatenate([p[1] for p in pieces]), whole[1])


def test_noise_floor_does_not_depend_on_grouping(bundle):
    power = np.random.default_rng(5).uniform(1e-8, 1e-3, 1000)
    whole = NoiseFloor(config=bundle.feature_config).update(power)
    tracker = NoiseFloor(config=bundle.feature_config)
    cuts = [0, 1, 2, 5, 300, 301, 700, 1000]
    grouped = np.concatenate([tracker.update(power[a:b]) for a, b in zip(cuts, cuts[1:])])
    assert np.array_equal(whole, grouped)
    assert np.all(whole <= power)


def _synthetic(*, rate: float, audio_type: str, seconds: float = 4.0, chunk: int = 1024):
    """Audio chunks (int16, float32 or both in turn) and 100 Hz wrench; a knock at 1.5 s."""
    rng = np.random.default_rng(int(rate))
    n = int(seconds * rate)
    t0 = 1_700_000_000.0
    sound = 0.02 * rng.normal(size=n)
    knock = int(1.5 * rate)
    tail = np.arange(n - knock) / rate
    sound[knock:] += 0.5 * np.exp(-tail / 0.02) * np.sin(2 * np.pi * 900.0 * tail)
    sound = np.clip(sound, -1.0, 32767 / 32768)
    events = []
    for k, lo in enumerate(range(0, n, chunk)):
        piece = sound[lo:lo + chunk]
        as_int16 = audio_type == 'int16' or (audio_type == 'mixed' and k % 2 == 0)
        samples = (np.round(piece * 32767).astype(np.int16) if as_int16
                   else piece.astype(np.float32))
        stamp = t0 + (lo + piece.size - 1) / rate
        events.append(AudioEvent(samples=samples, stamp=stamp, now=stamp + 0.002))
    for k in range(int(seconds * 100)):
        t = t0 + k / 100.0
        load = -5.0 + (2.0 if t - t0 >= 1.5 else 0.0) + 0.01 * rng.normal(size=3)
        events.append(WrenchEvent(t=np.array([t]), force=np.array([[0.1, 0.2, 0.0]]) + load,
                                  torque=0.01 * rng.normal(size=(1, 3)), now=t + 0.001))
    return sorted(events, key=lambda e: e.now)


# A hop (10 ms) of a whole, half, quarter and an irregular number of samples: the block path
# computes the frame powers on one strided view per phase of the frame starts, or gathers them.
@pytest.mark.parametrize('rate', [44100.0, 22050.0, 11025.0, 15999.7])
@pytest.mark.parametrize('audio_type', ['int16', 'float32', 'mixed'])
def test_blocks_equal_message_by_message_at_any_rate_and_sample_type(bundle, rate, audio_type):
    from contact_detector.detection.blocks import block_features
    from contact_detector.detection.offline import run_features
    from contact_detector.features.streaming import StreamingFeatureExtractor

    events = _synthetic(rate=rate, audio_type=audio_type)

    def make():
        return StreamingFeatureExtractor(config=bundle.feature_config, audio_rate=rate)

    assert block_features(events, extractor=make()) is not None
    fast = run_features(events, extractor=make())
    slow = run_features(events, extractor=make(), in_blocks=False)
    for key in ('t', 'x', 'valid'):
        assert np.array_equal(getattr(fast, key), getattr(slow, key)), key
    assert run_blocks(events, detector=_detector(bundle, audio_rate=rate)) is not None
    run = _both(events, bundle, audio_rate=rate)
    assert run.t.size > 350 and run.valid.mean() > 0.8


# --- recordings: blocks and message by message agree ----------------------------------------

CASES = {
    '16k_sqlite': {'audio_rate': 16000, 'storage': 'sqlite3'},
    '44k1_mcap': {'audio_rate': 44100, 'storage': 'mcap'},
    'odd_chunks_48k': {'audio_rate': 48000, 'condition': 'odd_chunking'},
    '1kHz_ft': {'ft_rate': 1000.0, 'wrench_rate': 1000.0},
}


@pytest.fixture(scope='module')
def recordings(tmp_path_factory):
    root = tmp_path_factory.mktemp('blocks')
    out = {}
    for name, case in CASES.items():
        case = dict(case)
        storage = case.pop('storage', 'sqlite3')
        wrench_rate = case.pop('wrench_rate', 100.0)
        bags = []
        for index, (condition, hits) in enumerate([('paper', 'hand'), ('soft', 'table')]):
            trial = simulate_trial(seed=21, index=index, hits=hits,
                                   condition=case.get('condition', condition),
                                   audio_rate=case.get('audio_rate', 16000),
                                   ft_rate=case.get('ft_rate', 100.0))
            bags.append(write_trial_bag(trial=trial, path=root / name / trial.name,
                                        storage=storage))
        settings = {'audio_rate': float(case.get('audio_rate', 16000)), 'wrench_rate': wrench_rate}
        out[name] = ([load_events(b, spec=StreamSpec()) for b in bags], settings)
    return out


@pytest.mark.parametrize('case', sorted(CASES))
def test_blocks_equal_message_by_message(bundle, recordings, case):
    recs, settings = recordings[case]
    released = 0
    for events in recs:
        # The clean recording really takes the block path ...
        assert run_blocks(events, detector=_detector(bundle, **settings)) is not None
        run = _both(events, bundle, **settings)
        assert run.t.size > 500 and run.valid.mean() > 0.9
        released += len(run.releases)
    # ... and the comparison covers releases, not only quiet frames.
    assert released >= 1


def test_blocks_equal_with_other_rules_and_settings(bundle, recordings):
    recs, settings = recordings['16k_sqlite']
    rule = replace(bundle.decision_rule, threshold=0.3, confirm_frames=1, refractory_s=0.2)
    for events in recs:
        _both(events, bundle, rule=rule, **settings)
        _both(events, bundle, rule=replace(rule, threshold=0.85, average_frames=2,
                                           sustain_frames=10, sustain_threshold=0.3), **settings)
        _both(events, bundle, max_input_delay_s=0.005, **settings)     # log times make stale
        _both(events, bundle, max_ft_wait_s=0.0, armed_on_start=False, **settings)


def _damaged(events):
    """Yield (what, events) for each kind of damage the per-message path must handle."""
    wrench = [i for i, e in enumerate(events) if isinstance(e, WrenchEvent)]
    audio = [i for i, e in enumerate(events) if isinstance(e, AudioEvent)]
    mid_w, mid_a = wrench[len(wrench) // 2], audio[len(audio) // 2]
    e = events[mid_w]
    yield 'refused message', events[:mid_a] + [BadEvent(kind='audio', reason='odd byte count',
                                                        now=events[mid_a].now)] + events[mid_a:]
    yield 'duplicated wrench', events[:mid_w + 1] + [e] + events[mid_w + 1:]
    yield 'NaN wrench', events[:mid_w] + [replace(e, force=np.full((1, 3), np.nan))] + \
        events[mid_w + 1:]
    yield 'F/T dropout 0.3 s', [ev for i, ev in enumerate(events)
                                if not (i in wrench[len(wrench) // 2: len(wrench) // 2 + 30])]
    yield 'audio dropout', [ev for i, ev in enumerate(events)
                            if not (i in audio[len(audio) // 2: len(audio) // 2 + 40])]
    yield 'bag loop (time jumps back)', events + events
    yield 'empty audio chunk', events[:mid_a] + [replace(events[mid_a], samples=np.zeros(
        0, np.int16))] + events[mid_a + 1:]


def test_damaged_recordings_go_message_by_message(bundle, recordings):
    events = recordings['16k_sqlite'][0][0]
    seen = set()
    for what, damaged in _damaged(events):
        assert run_blocks(damaged, detector=_detector(bundle)) is None, what
        run = _both(damaged, bundle)
        seen.add(what)
        assert run.t.size > 0, what
    assert len(seen) == 7
    # A wrong configured rate (stereo read as mono looks like this) trips the rate check.
    assert run_blocks(events, detector=_detector(bundle, audio_rate=32000.0)) is None
    _both(events, bundle, audio_rate=32000.0)


def test_a_used_detector_is_not_taken_for_a_fresh_one(bundle, recordings):
    events = recordings['16k_sqlite'][0][0]
    detector = _detector(bundle)
    run_detector(events[:50], detector=detector, in_blocks=False)
    assert run_blocks(events[50:], detector=detector) is None


def test_cdr_readers_and_rosbags_give_the_same_run(bundle, tmp_path):
    # detect's decoding (CDR readers) against rosbags' deserialisation, message by message.
    from contact_detector.io import sensor_stream
    saved = dict(sensor_stream.FAST_DECODERS)
    try:
        trial = simulate_trial(seed=8, index=0, audio_rate=44100)
        path = write_trial_bag(trial=trial, path=tmp_path / 'b', storage='mcap')
        fast = load_events(path)
        sensor_stream.FAST_DECODERS.clear()
        slow = load_events(path)
    finally:
        sensor_stream.FAST_DECODERS.update(saved)
    settings = {'audio_rate': 44100.0}
    _same(run_detector(fast, detector=_detector(bundle, **settings)),
          run_detector(slow, detector=_detector(bundle, **settings), in_blocks=False))


def test_partial_recordings(bundle, recordings):
    events = recordings['16k_sqlite'][0][0]
    pieces = {'empty': [], 'first 30 messages': events[:30],
              'wrench only': [e for e in events if isinstance(e, WrenchEvent)],
              'audio only': [e for e in events if isinstance(e, AudioEvent)]}
    for name, piece in pieces.items():
        run = _both(piece, bundle)
        assert not run.releases, name
    # Audio without F/T: every frame is emitted after the wait, invalid, never a contact.
    run = _both(pieces['audio only'], bundle)
    assert run.t.size > 500 and not run.valid.any()


def test_training_features_in_blocks_equal_message_by_message(bundle, recordings):
    from contact_detector.detection.offline import run_features
    from contact_detector.features.streaming import StreamingFeatureExtractor

    for case in ('16k_sqlite', 'odd_chunks_48k', '1kHz_ft'):
        recs, settings = recordings[case]
        for events in recs:
            def make():
                return StreamingFeatureExtractor(config=bundle.feature_config,
                                                 audio_rate=settings['audio_rate'],
                                                 ft_input_rate=settings['wrench_rate'])
            fast = run_features(events, extractor=make())
            slow = run_features(events, extractor=make(), in_blocks=False)
            for key in ('t', 'x', 'valid'):
                assert np.array_equal(getattr(fast, key), getattr(slow, key)), (case, key)
            assert fast.names == slow.names
    # A refused message is skipped by both (no drop, no hold-off: features only).
    events = recordings['16k_sqlite'][0][0]
    damaged = events[:300] + [BadEvent(kind='audio', reason='x', now=events[300].now)] + \
        events[300:]
    fast = run_features(damaged, extractor=StreamingFeatureExtractor(
        config=bundle.feature_config, audio_rate=16000.0))
    slow = run_features(damaged, extractor=StreamingFeatureExtractor(
        config=bundle.feature_config, audio_rate=16000.0), in_blocks=False)
    assert np.array_equal(fast.x, slow.x) and np.array_equal(fast.valid, slow.valid)
