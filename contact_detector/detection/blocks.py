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
A whole recording through the detector in a few array operations, bit-identical to live.

:func:`contact_detector.detection.offline.run_detector` feeds a recording to
:class:`~contact_detector.detection.detector.ContactDetector` one message at a time, as the node
does: ~260 us of Python and numpy per 10 ms of sensor data, i.e. 35-40x real time. This module
computes the same :class:`Decisions` for a *clean* recording in blocks:

1. one cheap scalar pass over the messages repeats every check and every piece of state the
   live path keeps per message (audio time anchor, audio rate check, wrench stamp order and
   gaps) and gives up (returns None) at anything that would make the live path drop, restart
   or reset: a refused message, a wrench gap, an audio dropout, a time jump, a rate mismatch;
2. all audio frames, all F/T feature frames and all forest probabilities are then computed in
   single calls: the feature functions give every row the same bits whatever the number of
   rows (``test_blocks.py``; that is why :func:`spectral.spectral_centroid_spread` uses
   ``einsum`` and not BLAS, and :class:`NoiseFloor` runs frame by frame);
3. for every audio frame, the message after which the live extractor would emit it (its F/T is
   there, or the wait timed out) follows from the per-message stamps by ``searchsorted``; that
   message fixes which F/T feature frame the audio frame gets and the receive time used for
   the staleness check, as live.

A recording that is not clean goes through the per-message path, so the result is always the
node's; only the speed differs.
"""

from dataclasses import dataclass
import math
from typing import List, Optional

from contact_detector.detection.detector import (AudioRateCheck, CLIP_LEVEL, ContactDetector,
                                                 Decisions)
from contact_detector.errors import InputError
from contact_detector.features import spectral
from contact_detector.features.audio import frame_ends, to_unit_audio
from contact_detector.features.config import AUDIO_FEATURES
from contact_detector.features.frames import FeatureFrames
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.sensor_stream import AudioEvent, BadEvent, Event, WrenchEvent
import numpy as np

#: Audio frames per power block (bounds the frame matrix: 4096 x 1536 x 8 B = 50 MB at 48 kHz)
#: where the frame starts have no short period (see :func:`_frame_powers`).
POWER_BLOCK = 4096
_INT16, _FLOAT64 = np.dtype(np.int16), np.dtype(np.float64)
#: Longest period of the frame starts' pattern looked for (4 covers 11.025 kHz: 110.25 samples).
PATTERN_PERIODS = 8


@dataclass
class BlockFeatures:
    """
    Every frame of a recording as the live extractor emits it, and when.

    Attributes
    ----------
    frames : FeatureFrames
        The rows in emission order (= time order), as the per-message path concatenates them.
    now : np.ndarray, shape (n,)
        Receive time (s) of the message after which each frame was emitted; NaN for frames
        emitted by the final flush.
    audio_msgs, wrench_msgs, clipped : int
        Messages pushed, and audio chunks at full scale.
    audio_ignored : int
        Audio messages (sound or refused) an F/T-only extractor ignored.

    """

    frames: FeatureFrames
    now: np.ndarray
    audio_msgs: int
    wrench_msgs: int
    clipped: int
    audio_ignored: int = 0


def run_blocks(events: List[Event], *, detector: ContactDetector) -> Optional[Decisions]:
    """
    Decide a clean recording in blocks; None if the per-message path is needed.

    Parameters
    ----------
    events : list of Event
        The recording, in log-time order (:func:`sensor_events`).
    detector : ContactDetector
        A fresh detector (nothing pushed yet); it is used up. Anything else (a baseline)
        returns None.

    Returns
    -------
    Decisions or None
        Every audio frame's decision in emission order, and the releases and events, exactly
        as the per-message path gives them (the detector's counters too); None when the
        recording is not clean (see the module docstring).

    """
    if not isinstance(detector, ContactDetector):
        return None                         # a baseline: it has its own path
    if detector.counts['audio_msgs'] or detector.counts['wrench_msgs']:
        return None
    settings = detector.settings
    rate = (None if settings.audio_rate_tolerance is None else AudioRateCheck(
        rate=settings.audio_rate, tolerance=settings.audio_rate_tolerance))
    got = block_features(events, extractor=detector.extractor, rate_check=rate,
                         skip_bad=False)
    if got is None:
        return None
    detector.counts['audio_msgs'] += got.audio_msgs
    detector.counts['wrench_msgs'] += got.wrench_msgs
    detector.counts['audio_clipped'] += got.clipped
    detector.counts['audio_ignored'] += got.audio_ignored
    return detector.decide(got.frames, now=got.now)


def block_features(events: List[Event], *, extractor: StreamingFeatureExtractor,
                   rate_check: Optional[AudioRateCheck] = None,
                   skip_bad: bool = True) -> Optional[BlockFeatures]:
    """
    Every feature frame of a clean recording, as a fresh ``extractor`` fed per message gives.

    Parameters
    ----------
    events : list of Event
        The recording, in log-time order.
    extractor : StreamingFeatureExtractor
        Fresh (nothing pushed yet); it is used up.
    rate_check : AudioRateCheck or None
        Give up where this check would refuse audio (the detector's path).
    skip_bad : bool
        Skip refused messages, as :func:`run_features` does (True), or give up at the first
        one, as the detector drops and holds off (False).

    Returns
    -------
    BlockFeatures or None
        None when the recording is not clean (see the module docstring).

    """
    ex = extractor
    if ex.pending or ex.audio.latest_time is not None or ex.ft.last_input_t is not None:
        return None
    scan = _scan(events, rate=None if ex.ft_only else rate_check, gap=ex.ft.gap_reset_s,
                 skip_bad=skip_bad, audio=not ex.ft_only)
    if scan is None:
        return None
    if ex.ft_only:
        return _ft_only_features(scan, extractor=ex)
    (nows, audio_idx, samples, sizes, stamps, wrench_idx, wt, wforce, wtorque, per_msg,
     _) = scan
    framer, fs = ex.audio, ex.audio.sample_rate
    n_events = nows.size

    # --- audio: anchors and frames, exactly as AudioFramer.push per chunk -------------------
    cum = np.cumsum(sizes)
    anchors = _anchors(sizes=sizes, stamps=stamps, framer=framer)
    if anchors is None:
        return None
    latest = anchors + (cum - 1) / fs
    w, hop = framer.frame_length, framer.hop
    total = int(cum[-1]) if cum.size else 0
    upper = int(math.floor((total - w + 0.5) / hop)) + 2 if total else 0
    ends = frame_ends(first=0, count=max(upper, 0), frame_length=w, hop=hop)
    ends = ends[ends <= total]
    chunk_of = np.searchsorted(cum, ends, side='left')
    t = anchors[chunk_of] + (ends - 1) / fs
    arrival = latest[chunk_of]
    if not (np.all(np.diff(t) > 0) and np.all(np.diff(latest) >= 0)):
        return None         # a time anchor that moved back by more than a hop: per message
    # Chunks are never empty (checked by the scan); a maximum is exact, grouped or not.
    clipped = (int(np.count_nonzero(np.maximum.reduceat(np.abs(samples), cum - sizes)
                                    >= CLIP_LEVEL)) if sizes.size else 0)
    power = _frame_powers(samples=samples, starts=ends - w, frame_length=w,
                          offsets=framer._offsets)
    per_frame = ex.levels.rows(power)
    audio = np.array(per_frame) if per_frame else np.zeros((0, len(AUDIO_FEATURES)))

    # --- F/T: one push of every sample (no gaps: checked by the scan) -----------------------
    if wt.size:
        ft_t, ft_x = ex.ft.push(t=wt, force=wforce, torque=wtorque)
    else:
        ft_t, ft_x = np.zeros(0), np.zeros((0, len(ex.ft.columns)))
    sample_event = np.repeat(wrench_idx, per_msg)
    ft_event = sample_event[np.searchsorted(wt, ft_t)] if ft_t.size else np.zeros(0, np.intp)
    ft_count = np.cumsum(np.bincount(ft_event, minlength=n_events)) if n_events else \
        np.zeros(0, np.int64)

    # --- when would the live extractor emit each frame? -------------------------------------
    last_ft = np.full(n_events, -np.inf)
    last_ft[wrench_idx] = wt[np.cumsum(per_msg) - 1]
    last_ft = np.maximum.accumulate(last_ft)
    newest_audio = np.full(n_events, -np.inf)
    newest_audio[audio_idx] = latest
    newest_audio = np.maximum.accumulate(newest_audio)
    ready_at = last_ft + ex.ready_margin_s               # frames with t < this are ready
    timeout_at = newest_audio - ex.max_ft_wait_s         # frames with arrival < this time out
    created = audio_idx[chunk_of]
    emitted = np.maximum(np.minimum(np.searchsorted(ready_at, t, side='right'),
                                    np.searchsorted(timeout_at, arrival, side='right')),
                         created)
    at_flush = emitted >= n_events

    # --- the F/T frame each audio frame gets at that moment ---------------------------------
    available = np.where(at_flush, ft_t.size,
                         ft_count[np.minimum(emitted, n_events - 1)] if n_events else 0)
    idx = np.minimum(np.searchsorted(ft_t, t, side='right') - 1, available - 1)
    oldest_kept = np.maximum(available - ex.history_frames, 0)
    valid = idx >= oldest_kept
    valid[valid] &= (t[valid] - ft_t[idx[valid]]) <= ex.max_ft_age_s
    x = np.zeros((t.size, len(ex.names)))
    for col, k in ex._audio_cols:
        x[:, col] = audio[:, k]
    if valid.any():
        rows = np.flatnonzero(valid)[:, None]
        x[rows, ex._ft_dst] = ft_x[idx[valid]][:, ex._ft_col]

    now = np.where(at_flush, np.nan, nows[np.minimum(emitted, n_events - 1)]
                   if n_events else np.nan)
    return BlockFeatures(frames=FeatureFrames(t=t, x=x, valid=valid, names=ex.names), now=now,
                         audio_msgs=int(audio_idx.size), wrench_msgs=int(wrench_idx.size),
                         clipped=clipped)


def _frame_powers(*, samples: np.ndarray, starts: np.ndarray, frame_length: int,
                  offsets: np.ndarray) -> np.ndarray:
    """
    :func:`spectral.audio_power` of the frames ``samples[s:s + frame_length]``, ``s`` in starts.

    Frame starts follow a pattern of period ``q`` (``floor(i * hop + 0.5)``; ``q = 1`` for a
    hop of a whole number of samples, 2 for 220.5 samples, ...): the frames of each phase
    ``r`` are then evenly spaced, a strided view of ``samples`` with contiguous rows, and
    ``audio_power`` runs on the view, without copying every frame. Each row's sum runs over
    the same contiguous samples as on the live path's copy, so the bits are the same
    (``test_blocks.py``). Starts without such a short period are gathered in blocks of
    :data:`POWER_BLOCK` frames.
    """
    n = starts.size
    power = np.empty(n)
    stride = samples.strides[0]
    for period in range(1, min(PATTERN_PERIODS, n) + 1):
        steps = [np.diff(starts[r::period]) for r in range(period)]
        if all(np.all(d == d[0]) for d in steps if d.size):
            for r in range(period):
                first = starts[r::period]
                step = int(steps[r][0]) if steps[r].size else 1
                view = np.lib.stride_tricks.as_strided(
                    samples[first[0]:], shape=(first.size, frame_length),
                    strides=(step * stride, stride), writeable=False)
                power[r::period] = spectral.audio_power(frames=view)
            return power
    for lo in range(0, n, POWER_BLOCK):
        block = starts[lo:lo + POWER_BLOCK]
        power[lo:lo + block.size] = spectral.audio_power(frames=samples[block[:, None] + offsets])
    return power


def _ft_only_features(scan: tuple, *, extractor: StreamingFeatureExtractor) -> BlockFeatures:
    """Every row of an F/T-only extractor: one per F/T feature frame, emitted by its sample."""
    (nows, audio_idx, _, _, _, wrench_idx, wt, wforce, wtorque, per_msg, ignored) = scan
    ex = extractor
    if wt.size:
        ft_t, ft_x = ex.ft.push(t=wt, force=wforce, torque=wtorque)
    else:
        ft_t, ft_x = np.zeros(0), np.zeros((0, len(ex.ft.columns)))
    frames = ex.ft_rows(ft_t, ft_x)
    if not len(frames):
        frames = FeatureFrames.empty(ex.names)
    sample_event = np.repeat(wrench_idx, per_msg)
    now = (nows[sample_event[np.searchsorted(wt, ft_t)]] if ft_t.size else np.zeros(0))
    return BlockFeatures(frames=frames, now=now, audio_msgs=int(audio_idx.size),
                         wrench_msgs=int(wrench_idx.size), clipped=0, audio_ignored=ignored)


def _scan(events: List[Event], *, rate: Optional[AudioRateCheck], gap: float,
          skip_bad: bool, audio: bool = True) -> Optional[tuple]:
    """
    Split the messages by kind, repeating the live per-message checks; None if not clean.

    The audio comes back as one array of unit samples and the size of each chunk: int16
    chunks (what bags hold) are scaled in one :func:`to_unit_audio` call over all of them,
    which is the same division per sample; any other chunk is checked and scaled on its own.
    ``audio`` False (an F/T-only extractor): audio messages, sound or refused, are not pushed
    and not checked; the last element of the tuple counts them.
    """
    nows = []
    audio_idx, chunks, sizes, stamps = [], [], [], []
    all_int16 = True
    wrench_idx, wt, wforce, wtorque, per_msg = [], [], [], [], []
    ignored = 0
    isfinite = math.isfinite
    for event in events:
        if not audio and (isinstance(event, AudioEvent)
                          or (isinstance(event, BadEvent) and event.kind == 'audio')):
            ignored += 1
            if isinstance(event, AudioEvent):
                audio_idx.append(-1)        # counted as a message, never pushed
            continue
        if isinstance(event, AudioEvent):
            stamp, samples = event.stamp, event.samples
            if type(samples) is np.ndarray and samples.dtype == _INT16 and samples.ndim == 1:
                unit = samples              # scaled with all the others below
            else:
                all_int16 = False
                try:
                    unit = to_unit_audio(samples)    # the live path's own check
                except InputError:
                    return None
            n = unit.shape[0]
            if not (n and isinstance(stamp, float) and isfinite(stamp)):
                return None
            if rate is not None and rate.update(n=n, stamp=stamp) is not None:
                return None
            audio_idx.append(len(nows))
            chunks.append(unit)
            sizes.append(n)
            stamps.append(stamp)
        elif isinstance(event, WrenchEvent):
            t, force, torque = event.t, event.force, event.torque
            if not (isinstance(t, np.ndarray) and t.ndim == 1 and t.size
                    and t.dtype == _FLOAT64 and force.shape == (t.size, 3)
                    and torque.shape == (t.size, 3) and force.dtype == _FLOAT64
                    and torque.dtype == _FLOAT64):
                return None
            wrench_idx.append(len(nows))
            wt.append(t)
            wforce.append(force)
            wtorque.append(torque)
            per_msg.append(t.size)
        elif isinstance(event, BadEvent) and not skip_bad:
            return None
        else:
            continue                        # truth (or a skipped refusal): never pushed
        nows.append(event.now)
    if not chunks:
        samples = np.zeros(0)
    elif all_int16:
        samples = to_unit_audio(np.concatenate(chunks))
    else:
        samples = np.concatenate([to_unit_audio(c) for c in chunks])
    if wt:
        t = np.concatenate(wt)
        force, torque = np.concatenate(wforce), np.concatenate(wtorque)
        steps = np.diff(t)
        # A repeated or older stamp is dropped live, a longer gap restarts the F/T window,
        # NaN/Inf is dropped: all for the per-message path.
        if not (np.all(steps > 0) and np.all(steps <= gap) and np.all(np.isfinite(t))
                and np.all(np.isfinite(force)) and np.all(np.isfinite(torque))):
            return None
    else:
        t, force, torque = np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3))
    return (np.array(nows, dtype=np.float64),
            np.array(audio_idx, dtype=np.intp), samples, np.array(sizes, dtype=np.int64),
            np.array(stamps, dtype=np.float64),
            np.array(wrench_idx, dtype=np.intp), t, force, torque,
            np.array(per_msg, dtype=np.intp), ignored)


def _anchors(*, sizes: np.ndarray, stamps: np.ndarray, framer) -> Optional[np.ndarray]:
    """Return the framer's time anchor after each chunk; None at a restart or a jump."""
    out = np.empty(sizes.size)
    anchor = last = None
    n_before = 0
    for i, (n, stamp) in enumerate(zip(sizes.tolist(), stamps.tolist())):
        anchor, verdict = framer.anchor_step(anchor=anchor, last_stamp=last, n_before=n_before,
                                             n=n, stamp=stamp)
        if verdict != 'ok':
            return None
        last = stamp
        n_before += n
        out[i] = anchor
    return out
