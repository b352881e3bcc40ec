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
The detector pipeline: feature core + compiled forest + release logic + input health.

:class:`ContactDetector` is everything the node does between "a message arrived, here are its
arrays" and "publish these decisions". The live node, ``detect``, ``evaluate`` and the demo all
drive this one class, so what is measured offline is what runs on the robot. It has no ROS
import and reads no clock: every call passes the stream times (and, optionally, ``now``, the
time the message was received, for the staleness check).
"""

import dataclasses
from dataclasses import dataclass, field
import math
from typing import Optional, Sequence, Union

from contact_detector.detection.release import ReleaseLogic
from contact_detector.errors import ConfigError, InputError
from contact_detector.features.audio import to_unit_audio
from contact_detector.features.carried import CarriedLoad
from contact_detector.features.config import LOAD_DIRECTION_FEATURE, LOAD_FEATURE
from contact_detector.features.force_torque import bias_vector
from contact_detector.features.frames import FeatureFrames, TimeJumpError
from contact_detector.features.noise import NOISE_JUMP_N
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.rule import DecisionRule
import numpy as np

#: A dropped message's stamp is trusted at most this far ahead of the newest accepted input, s
#: (a corrupt message may carry any stamp; its hold-off must not block releases for ever).
MAX_DROP_AHEAD_S = 1.0
_FLOAT32_MAX = float(np.finfo(np.float32).max)
#: A chunk with a sample at or beyond this (full scale = 1) counts as clipped.
CLIP_LEVEL = 32767.0 / 32768.0


@dataclass(frozen=True)
class DetectorSettings:
    """
    Runtime settings of :class:`ContactDetector` (the node's parameters map onto these).

    Attributes
    ----------
    audio_rate : float
        Audio sample rate, Hz (any rate: frames are defined in seconds).
    wrench_rate : float
        Wrench rate, Hz; an integer multiple of the model's F/T feature rate.
    max_ft_age_s : float or None
        Largest age of the F/T features given to an audio frame; None = the core's default.
    max_ft_wait_s : float
        Longest an audio frame waits for F/T before it is decided without (invalid).
    max_input_delay_s : float
        A frame older than this when its message is processed (``now - t``) is stale.
    warmup_s : float
        No release during this long after the first audio frame following a reset.
    corrupt_holdoff_s : float
        No release during this long after a corrupt (dropped) message.
    armed_on_start : bool
        Whether a release may fire before the first ``arm`` call.
    rule : DecisionRule or None
        Overrides the model bundle's decision rule.
    audio_rate_tolerance : float or None
        Largest accepted relative difference between the rate at which audio samples arrive
        (per second of stamps) and ``audio_rate``; beyond it every chunk is dropped (see
        :class:`AudioRateCheck`). None turns the check off.
    wrench_bias : tuple of 6 float
        The F/T sensor's zero, subtracted from every wrench sample: force x, y, z in N, then
        torque x, y, z in N m (what the sensor reads with an empty hand).
    noise_jump_n : float
        A force reading whose median jump over 0.1 s is at least this (N) while it reverses
        direction from sample to sample is noise: no frame whose features saw it releases
        (:mod:`contact_detector.features.noise`); 0 = off.

    """

    audio_rate: float = 16000.0
    wrench_rate: float = 100.0
    max_ft_age_s: Optional[float] = None
    max_ft_wait_s: float = 0.25
    max_input_delay_s: float = 0.5
    warmup_s: float = 0.5
    corrupt_holdoff_s: float = 0.2
    armed_on_start: bool = True
    rule: Optional[DecisionRule] = None
    audio_rate_tolerance: Optional[float] = 0.2
    wrench_bias: tuple = (0.0,) * 6
    noise_jump_n: float = NOISE_JUMP_N

    def __post_init__(self) -> None:
        """Validate ranges; raise ConfigError naming the field."""
        bias = self.wrench_bias
        try:
            if not isinstance(bias, tuple):
                raise InputError(f'not a tuple: {bias!r}')
            bias_vector(bias)
        except InputError as err:
            raise ConfigError(f'wrench_bias must be a tuple of 6 finite numbers: {err}'
                              ) from err
        tol = self.audio_rate_tolerance
        if tol is not None and not (isinstance(tol, (int, float)) and math.isfinite(tol)
                                    and 0 < tol < 1):
            raise ConfigError(f'audio_rate_tolerance must be None or in (0, 1), got {tol!r}')
        for name in ('max_ft_wait_s', 'max_input_delay_s', 'warmup_s', 'corrupt_holdoff_s',
                     'noise_jump_n'):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ConfigError(f'{name} must be a finite number >= 0, got {value!r}')
        if self.max_ft_age_s is not None and not self.max_ft_age_s > 0:
            raise ConfigError(f'max_ft_age_s must be > 0, got {self.max_ft_age_s!r}')


@dataclass
class Decisions:
    """
    Decisions for a block of audio frames.

    Attributes
    ----------
    t : np.ndarray, shape (n,)
        Frame times (last audio sample used), seconds.
    p : np.ndarray, shape (n,)
        P(contact); 0 for invalid frames.
    contact : np.ndarray, shape (n,), bool
        The per-frame decision.
    valid : np.ndarray, shape (n,), bool
        Whether the frame had fresh, sound input.
    releases : list of float
        Times at which a release fired.
    events : list of float
        Times at which a contact event was confirmed, armed or not.
    error : str or None
        Why the message was dropped, if it was.

    """

    t: np.ndarray
    p: np.ndarray
    contact: np.ndarray
    valid: np.ndarray
    releases: list = field(default_factory=list)
    events: list = field(default_factory=list)
    error: Optional[str] = None

    def __len__(self) -> int:
        """Return the number of frames."""
        return int(self.t.shape[0])

    @classmethod
    def empty(cls, error: Optional[str] = None) -> 'Decisions':
        """Return a block with no frames (its arrays are shared and read-only)."""
        return cls(t=_NO_FLOATS, p=_NO_FLOATS, contact=_NO_BOOLS, valid=_NO_BOOLS, error=error)

    @classmethod
    def concat(cls, blocks: Sequence['Decisions']) -> 'Decisions':
        """Concatenate blocks in order: frames, releases, events, and the first error."""
        error = next((b.error for b in blocks if b.error), None)
        kept = [b for b in blocks if len(b)]
        releases = [r for b in blocks for r in b.releases]
        events = [e for b in blocks for e in b.events]
        if not kept:
            return dataclasses.replace(cls.empty(error), releases=releases, events=events)
        return cls(t=np.concatenate([b.t for b in kept]), p=np.concatenate([b.p for b in kept]),
                   contact=np.concatenate([b.contact for b in kept]),
                   valid=np.concatenate([b.valid for b in kept]), releases=releases,
                   events=events, error=error)


_NO_FLOATS = np.zeros(0)
_NO_BOOLS = np.zeros(0, dtype=bool)
_NO_FLOATS.flags.writeable = _NO_BOOLS.flags.writeable = False


class AudioRateCheck:
    """
    Notice audio whose sample count does not follow its stamps: a wrong rate or channel count.

    Stereo audio read as mono, or 32 kHz audio configured as 16 kHz, is otherwise accepted
    silently (frame times just follow the stamps) and gives features on a wrong time scale.
    Each chunk of ``n`` samples stamped ``s`` gives the offset ``o = s - S / rate``, ``S`` the
    samples counted since the check (re)started. Transport delay only adds to ``o``, so the
    minimum of ``o`` over blocks of ``block_s`` of stamps follows the stream's true start; with
    ``r_true`` samples per second it drifts by ``1 - r_true / rate`` seconds per second. Once the
    block minima span ``min_span_s``, ``ratio = 1 - drift`` (between the oldest kept block and
    the newest, at most ``window_s`` apart) estimates ``r_true / rate``. A stamp going backwards,
    or a chunk more than ``gap_s`` later than its samples allow (a dropout, a stall), restarts the
    check, so jitter, bursts and dropouts are not mistaken for a wrong rate.

    Parameters
    ----------
    rate : float
        Configured audio rate, Hz.
    tolerance : float
        A mismatch is ``|ratio - 1| > tolerance``.

    """

    def __init__(self, *, rate: float, tolerance: float, block_s: float = 0.5,
                 window_s: float = 2.0, min_span_s: float = 1.0, gap_s: float = 0.2) -> None:
        self.rate = float(rate)
        self.tolerance = tolerance
        self.block_s, self.window_s = block_s, window_s
        self.min_span_s, self.gap_s = min_span_s, gap_s
        self.reset()

    def reset(self) -> None:
        """Start measuring afresh."""
        self._last: Optional[float] = None
        self._samples = 0
        self._blocks: list = []         # [first stamp, min offset, stamp of the min]
        self.ratio: Optional[float] = None

    def update(self, *, n: int, stamp: float) -> Optional[float]:
        """Add a chunk of ``n`` samples ending at ``stamp`` (s); return the ratio if off."""
        if self._last is not None and (stamp < self._last
                                       or stamp - self._last - n / self.rate > self.gap_s):
            self.reset()
        self._samples += n
        offset = stamp - self._samples / self.rate
        blocks = self._blocks
        if not blocks or stamp - blocks[-1][0] >= self.block_s:
            blocks.append([stamp, offset, stamp])
            while len(blocks) > 2 and blocks[-1][0] - blocks[1][0] >= self.window_s:
                del blocks[0]
        elif offset < blocks[-1][1]:
            blocks[-1][1], blocks[-1][2] = offset, stamp
        self._last = stamp
        span = blocks[-1][2] - blocks[0][2]
        if span < self.min_span_s:
            self.ratio = None
            return None
        self.ratio = 1.0 - (blocks[-1][1] - blocks[0][1]) / span
        return self.ratio if abs(self.ratio - 1.0) > self.tolerance else None


class ContactDetector:
    """
    Contact decisions and releases from audio chunks and wrench samples.

    With an F/T-only model (``bundle.feature_config.ft_only``) every F/T feature frame is
    decided (frames are clocked by the wrench stream at the model's feature rate), with the
    same release logic, warm-up, staleness, hold-off and time-jump handling; audio chunks,
    sound or corrupt, are then ignored and counted in ``audio_ignored``, never an error.

    Parameters
    ----------
    bundle : ModelBundle
        A loaded model (its feature configuration defines the features).
    settings : DetectorSettings
        Runtime settings.

    """

    COUNTERS = ('audio_msgs', 'wrench_msgs', 'audio_dropped', 'wrench_dropped', 'time_jumps',
                'frames', 'invalid_frames', 'stale_frames', 'events', 'releases',
                'audio_restarts', 'wrench_restarts', 'audio_rate_mismatch', 'nonfinite_frames',
                'audio_clipped', 'audio_ignored', 'wrench_placeholders', 'wrench_noise')

    def __init__(self, *, bundle: ModelBundle, settings: DetectorSettings) -> None:
        self.bundle = bundle
        self.settings = settings
        config = bundle.feature_config
        self.ft_only = config.ft_only
        # A model that measures the carried load also gets the distance of the force from it
        # (force_carried_shift) and the direction of that distance (force_carried_shift_cos),
        # the load paths' inputs, computed by the same feature core; the forest reads only the
        # model's own columns, the first n_model.
        self._n_model = config.n_features
        config = config.with_rule_columns()
        names = config.feature_names
        self._load_col: Optional[int] = (names.index(LOAD_FEATURE) if LOAD_FEATURE in names
                                         else None)
        self._cos_col: Optional[int] = (names.index(LOAD_DIRECTION_FEATURE)
                                        if LOAD_DIRECTION_FEATURE in names else None)
        self.rule = self.check_rule(settings.rule or bundle.decision_rule)
        try:
            self.forest = bundle.compile()
            self.extractor = StreamingFeatureExtractor(
                config=config, audio_rate=settings.audio_rate,
                ft_input_rate=settings.wrench_rate, max_ft_age_s=settings.max_ft_age_s,
                max_ft_wait_s=settings.max_ft_wait_s, noise_jump_n=settings.noise_jump_n)
        except InputError as err:
            raise ConfigError(f'cannot build the detector: {err}') from err
        self.extractor.ft.set_bias(settings.wrench_bias)    # checked by the settings
        self.logic = ReleaseLogic(rule=self.rule, armed=settings.armed_on_start)
        self.rate_check = (None if settings.audio_rate_tolerance is None else AudioRateCheck(
            rate=settings.audio_rate, tolerance=settings.audio_rate_tolerance))
        self.counts = dict.fromkeys(self.COUNTERS, 0)
        self.last_error: Optional[str] = None
        self.reset()

    # --- control ---------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget all stream state (buffers, anchors, confirmation run); keep arming."""
        self.extractor.reset()
        self.logic.reset()
        if self.rate_check is not None:
            self.rate_check.reset()
        self._warm_until: Optional[float] = None
        self._holdoff_until = -math.inf
        self.latest_audio_t: Optional[float] = None
        self.latest_wrench_t: Optional[float] = None

    def arm(self, armed: bool) -> None:
        """
        Arm or disarm the release; arming measures the carried load again.

        The carried-load features (``*_shift_rel``, ``*_carried_cos``) compare the load change
        with the load the hand carries when the release is armed, before the approach: the
        median of the next ``carried_window`` F/T samples (the previous measurement holds
        until then).
        """
        self.logic.arm(armed)
        if armed:
            self.measure_carried()

    def measure_carried(self) -> None:
        """Measure the carried load again over the next ``carried_window`` F/T samples."""
        self.extractor.ft.measure_carried()

    @property
    def carried_load(self) -> Optional[CarriedLoad]:
        """
        Return the last completed carried-load measurement, or None.

        None before the first ``carried_window`` F/T samples after a start, a reset or an
        arming, and always when the model has no carried-load feature. A new object per
        measurement: compare identities to notice a new one.
        """
        return self.extractor.ft.carried_load

    @property
    def armed(self) -> bool:
        """Whether the next contact event releases."""
        return self.logic.armed

    @property
    def bias(self) -> tuple:
        """Return the F/T sensor's zero subtracted from every sample: 6 floats, N then N m."""
        return tuple(self.extractor.ft.bias.tolist())

    def set_bias(self, bias: Sequence[float]) -> None:
        """
        Subtract ``bias`` from every later wrench sample; forget the stream state if it changed.

        A new zero is a step in every F/T sample: the windows, the carried load and the
        confirmation run start again (:meth:`reset`: warm-up, no release from the step); the
        arming is kept.

        Raises
        ------
        ConfigError
            Not 6 finite numbers.

        """
        old = self.extractor.ft.bias
        try:
            self.extractor.ft.set_bias(bias)
        except InputError as err:
            raise ConfigError(str(err)) from err
        if not np.array_equal(old, self.extractor.ft.bias):
            self.settings = dataclasses.replace(self.settings, wrench_bias=self.bias)
            self.reset()

    def measure_zero(self) -> None:
        """
        Measure the sensor's reading over the next ``carried_window`` F/T samples (an empty hand).

        The result is :attr:`zero_measurement`; the caller adds its load to :attr:`bias`
        (:meth:`set_bias`) if it is steady. Nothing else changes meanwhile.
        """
        self.extractor.ft.measure_zero()

    @property
    def zero_measurement(self) -> Optional[CarriedLoad]:
        """Return the last completed zero measurement (a new object each), or None."""
        return self.extractor.ft.zero_measurement

    def set_rule(self, rule: DecisionRule) -> None:
        """
        Apply another decision rule from the next frame on (stream state and arming kept).

        Raises
        ------
        ConfigError
            The rule's load path is on and the model does not measure the carried load.

        """
        self.rule = self.check_rule(rule)
        self.logic.rule = self.rule

    def check_rule(self, rule: DecisionRule) -> DecisionRule:
        """Return ``rule``; raise ConfigError if it needs a load the model cannot give."""
        if rule.uses_load and self._load_col is None:
            raise ConfigError(
                f'the load paths (load_threshold {rule.load_threshold:g} N, '
                f'load2_threshold {rule.load2_threshold:g} N) need the carried load, '
                f'which model {self.bundle.model_id} does not measure (it has no carried-load '
                'feature); set release.load_threshold and release.load2_threshold to 0')
        return rule

    # --- input -----------------------------------------------------------------------------

    def on_audio(self, samples: np.ndarray, *, stamp: float,
                 now: Optional[float] = None) -> Decisions:
        """
        Process a mono audio chunk whose last sample is at ``stamp``.

        Corrupt chunks are dropped and counted (the audio stream restarts, so a lost chunk never
        glues two pieces of sound together), and so is every chunk while the samples arrive at
        a rate that does not match ``audio_rate`` (:class:`AudioRateCheck`); a backwards time
        jump resets everything first.
        """
        self.counts['audio_msgs'] += 1
        if self.ft_only:
            self.counts['audio_ignored'] += 1
            return Decisions.empty()
        try:
            unit = to_unit_audio(samples)
            self._check_rate(unit.shape[0], stamp)
            push = self.extractor.push_unit_audio       # unit is checked: not again
            frames = self._with_jump_reset(lambda: push(unit, stamp=stamp))
        except InputError as err:
            return self.drop(kind='audio', reason=str(err), stamp=stamp)
        if unit.size and float(np.max(np.abs(unit))) >= CLIP_LEVEL:
            # Real sound, decided as usual; counted so that diagnostics can say "gain too high".
            self.counts['audio_clipped'] += 1
        if self.extractor.audio.latest_time is not None:
            self.latest_audio_t = self.extractor.audio.latest_time
        return self.decide(frames, now=now)

    def on_wrench(self, *, t: np.ndarray, force: np.ndarray, torque: np.ndarray,
                  now: Optional[float] = None) -> Decisions:
        """Process wrench samples (stamps ``t`` s, force N, torque N m, shapes (n,), (n, 3))."""
        self.counts['wrench_msgs'] += 1
        try:
            frames = self._with_jump_reset(lambda: self.extractor.push_wrench(
                t=t, force=force, torque=torque))
        except InputError as err:
            stamp = None
            try:
                stamp = float(np.max(t))
            except (TypeError, ValueError, OverflowError):
                pass
            return self.drop(kind='wrench', reason=str(err), stamp=stamp)
        self.latest_wrench_t = self.extractor.ft.last_input_t
        return self.decide(frames, now=now)

    def on_wrench_one(self, *, t: float, values: Sequence[float],
                      now: Optional[float] = None) -> Decisions:
        """
        :meth:`on_wrench` for one sample (a live message): the same decisions, fewer calls.

        Parameters
        ----------
        t : float
            Header stamp, s.
        values : sequence of 6 float
            Force x, y, z (N) then torque x, y, z (N m).
        now : float or None
            Receive time, s.

        """
        self.counts['wrench_msgs'] += 1
        try:
            frames = self._with_jump_reset(
                lambda: self.extractor.push_wrench_one(t=t, values=values))
        except InputError as err:
            stamp = t if isinstance(t, (int, float)) else None
            return self.drop(kind='wrench', reason=str(err), stamp=stamp)
        self.latest_wrench_t = self.extractor.ft.last_input_t
        return self.decide(frames, now=now)

    def flush(self) -> Decisions:
        """Decide every frame still waiting for F/T (end of a recording)."""
        return self.decide(self.extractor.flush(), now=None)

    # --- internals ---------------------------------------------------------------------------

    def _check_rate(self, n: int, stamp: Optional[float]) -> None:
        """Raise InputError while the audio rate does not match (see AudioRateCheck)."""
        if self.rate_check is None or n == 0 or not isinstance(stamp, (int, float)) \
                or not math.isfinite(stamp):
            return                      # an empty chunk or a bad stamp: push_audio decides
        ratio = self.rate_check.update(n=n, stamp=float(stamp))
        if ratio is not None:
            self.counts['audio_rate_mismatch'] += 1
            rate = self.settings.audio_rate
            raise InputError(
                f'audio arrives at {ratio * rate:.0f} samples per second of stamps, but the '
                f'configured rate is {rate:.0f} Hz (x{ratio:.2f}): wrong sample rate or channel '
                'count configured (stereo read as mono?), or heavy message loss')

    def _with_jump_reset(self, push):
        try:
            return push()
        except TimeJumpError as err:
            self.counts['time_jumps'] += 1
            self.last_error = f'time jumped backwards, state reset: {err}'
            self.reset()
            return push()

    def drop(self, *, kind: str, reason: str, stamp: Optional[float] = None) -> Decisions:
        """
        Count a corrupt message of ``kind`` ('audio' or 'wrench') and hold off releases.

        Callers that reject a message before it reaches the detector (a message adapter) call
        this too, so every drop is counted and blocks releases for ``corrupt_holdoff_s``. A
        dropped audio chunk restarts the audio stream, so the samples on either side of the hole
        are never joined into one frame. An F/T-only detector ignores audio, corrupt or not: it
        only counts it in ``audio_ignored``.
        """
        if kind == 'audio' and self.ft_only:
            self.counts['audio_ignored'] += 1
            return Decisions.empty()
        self.counts[f'{kind}_dropped'] += 1
        if kind == 'audio':
            self.extractor.audio.reset()
        message = f'{kind} message dropped: {reason}'
        self.last_error = message
        # The hold-off runs from the newest accepted input time, or from the message's own stamp
        # if later but not more than MAX_DROP_AHEAD_S later (its stamp may be garbage too).
        # Before any input was accepted the warm-up blocks releases anyway.
        latest = [v for v in (self.latest_audio_t, self.latest_wrench_t) if v is not None]
        if latest:
            start = max(latest)
            if isinstance(stamp, (int, float)) and math.isfinite(stamp):
                start = max(start, min(float(stamp), start + MAX_DROP_AHEAD_S))
            self.hold_off_until(start + self.settings.corrupt_holdoff_s)
        return Decisions.empty(error=message)

    @property
    def holdoff_until(self) -> float:
        """Return the stream time before which no frame releases (a corrupt input), s."""
        return self._holdoff_until

    def hold_off_until(self, t: float) -> None:
        """
        Let no frame before stream time ``t`` (s) release; a later hold-off stands.

        :meth:`drop` calls it; so does :class:`~.fallback.AudioFallback`, which gives the
        F/T-only model deciding beside the audio model the audio model's hold-off.
        """
        self._holdoff_until = max(self._holdoff_until, t)

    def decide(self, frames: FeatureFrames, *,
               now: Union[None, float, np.ndarray]) -> Decisions:
        """
        Decide feature frames the extractor has emitted: validity, forest, release logic.

        Parameters
        ----------
        frames : FeatureFrames
            In time order.
        now : float, np.ndarray of shape (n,), or None
            Receive time (s) of the message that emitted the frames (per frame when they
            come from several messages; NaN or None: no staleness check, as at a flush).

        """
        n = len(frames)
        self.counts['audio_restarts'] = self.extractor.audio.restarts
        self.counts['wrench_restarts'] = self.extractor.ft.restarts
        self.counts['wrench_placeholders'] = self.extractor.ft.placeholders
        self.counts['wrench_noise'] = self.extractor.ft.noisy
        # a frame whose F/T features may hold a noisy sample is held off like one after a
        # dropped message
        self.hold_off_until(self.extractor.ft.noise_until)
        if n == 0:
            return Decisions.empty()
        if n == 1 and not isinstance(now, np.ndarray):
            return self._decide_one(frames, now=now)
        valid = frames.valid.copy()
        # Finite input can still overflow (e.g. float audio of 1e200): such rows are invalid.
        finite = np.all(np.abs(frames.x) <= _FLOAT32_MAX, axis=1)
        if not finite.all():
            self.counts['nonfinite_frames'] += int((valid & ~finite).sum())
            valid &= finite
        if now is not None:
            stale = (now - frames.t) > self.settings.max_input_delay_s     # NaN: not stale
            self.counts['stale_frames'] += int(stale.sum())
            valid &= ~stale
        p = np.zeros(n)
        if valid.any():
            rows = frames.x[valid, :self._n_model]
            p[valid] = (self.forest.predict_proba(rows) if rows.shape[0] > 1
                        else self.forest.predict_one(rows[0]))
        if self._warm_until is None:
            self._warm_until = float(frames.t[0]) + self.settings.warmup_s
        blocked = (frames.t < self._warm_until) | (frames.t < self._holdoff_until)
        load = cos = None
        if self._load_col is not None:
            load, cos = frames.x[:, self._load_col], frames.x[:, self._cos_col]
        contact, releases = self.logic.step(t=frames.t, p=p, valid=valid, blocked=blocked,
                                            load=load, load_cos=cos)
        self.counts['frames'] += n
        self.counts['invalid_frames'] += int(n - valid.sum())
        self.counts['events'] = self.logic.events
        self.counts['releases'] = self.logic.releases
        return Decisions(t=frames.t, p=p, contact=contact, valid=valid, releases=releases,
                         events=list(self.logic.last_events))

    def _decide_one(self, frames: FeatureFrames, *, now: Optional[float]) -> Decisions:
        """:meth:`decide` for one frame (the live case) in scalars: the same numbers."""
        t = float(frames.t[0])
        x = frames.x[0]
        valid = bool(frames.valid[0])
        # not <=: NaN is not finite either.
        if not float(np.max(np.abs(x))) <= _FLOAT32_MAX:
            self.counts['nonfinite_frames'] += int(valid)
            valid = False
        if now is not None and (now - t) > self.settings.max_input_delay_s:
            self.counts['stale_frames'] += 1
            valid = False
        p = self.forest.predict_one(x[:self._n_model]) if valid else 0.0
        if self._warm_until is None:
            self._warm_until = t + self.settings.warmup_s
        blocked = t < self._warm_until or t < self._holdoff_until
        load, cos = 0.0, math.nan
        if self._load_col is not None:
            load, cos = float(x[self._load_col]), float(x[self._cos_col])
        contact, releases = self.logic.step_one(t=t, p=p, ok=valid and not blocked, load=load,
                                                load_cos=cos)
        self.counts['frames'] += 1
        self.counts['invalid_frames'] += int(not valid)
        self.counts['events'] = self.logic.events
        self.counts['releases'] = self.logic.releases
        return Decisions(t=frames.t, p=np.array([p]), contact=np.array([contact]),
                         valid=np.array([valid]), releases=releases,
                         events=list(self.logic.last_events))
