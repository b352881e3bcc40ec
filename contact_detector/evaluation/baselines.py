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
Baseline detectors, streamed through the same interface as ContactDetector.

So that every detector is measured on the same trials by the same scorer, each baseline takes
the same calls (``on_audio``, ``on_wrench``, ``drop``, ``flush``) and returns the same
:class:`~contact_detector.detection.detector.Decisions`. Thresholds that depend on the sensor
are calibrated on the first ``calibration_s`` seconds after a reset (the robot at rest), as a
careful engineer would set them by hand; the fixed torque threshold is the recorded robot's.

* ``threshold``: |T_y - T_y(rest)| >= 3 N m, the stop rule of the recorded robot (paper 4.1).
* ``highpass``: a first-order high-pass (5 Hz) on |T|; contact when its magnitude exceeds
  ``k`` times its rest standard deviation (after Cho et al. 2012).
* ``lowpass-bandpass``: a low-pass (2 Hz) observer of |F| flags a contact when it leaves its
  rest level by ``k`` rest deviations, unless a band-pass (5-20 Hz) observer says the change
  is a collision (after Li et al. 2019).
* ``audio-onset``: audio power (eq. 1) ``db`` dB above the tracked noise floor.
* ``guard``: ``|F - F_rest| >= 2 N``, the distance of the force vector from its per-axis rest
  median, the plain guard the issues compare the forests with (the statistic of the load path,
  ``force_carried_shift``, without the forest behind it).
"""

import math
from typing import Optional

from contact_detector.detection.detector import Decisions
from contact_detector.detection.release import ReleaseLogic
from contact_detector.errors import ConfigError, InputError
from contact_detector.features.audio import AudioFramer, NoiseFloor, to_unit_audio
from contact_detector.features.config import FeatureConfig
from contact_detector.model.rule import DecisionRule
import numpy as np
from scipy import signal

BASELINES = ('threshold', 'highpass', 'lowpass-bandpass', 'audio-onset', 'guard')


class _Baseline:
    """Shared plumbing: counters, release logic, decisions at the wrench or audio rate."""

    #: The baselines compare with no carried load (the detector interface's attribute).
    carried_load = None

    def __init__(self, *, wrench_rate: float, audio_rate: float, armed: bool = True,
                 calibration_s: float = 1.0) -> None:
        self.wrench_rate = wrench_rate
        self.audio_rate = audio_rate
        self.calibration_s = calibration_s
        self.logic = ReleaseLogic(rule=DecisionRule(threshold=0.5, confirm_frames=1,
                                                    refractory_s=1.0), armed=armed)
        self.counts = {'audio_dropped': 0, 'wrench_dropped': 0, 'time_jumps': 0}
        self._last_t: Optional[float] = None
        self.reset()

    def reset(self) -> None:
        self.logic.reset()
        self._t0: Optional[float] = None
        self._last_t = None

    def drop(self, *, kind: str, reason: str, stamp: Optional[float] = None) -> Decisions:
        self.counts[f'{kind}_dropped'] += 1
        return Decisions.empty(error=reason)

    def flush(self) -> Decisions:
        return Decisions.empty()

    def on_audio(self, samples, *, stamp: float, now: Optional[float] = None) -> Decisions:
        return Decisions.empty()

    def on_wrench(self, *, t, force, torque, now: Optional[float] = None) -> Decisions:
        return Decisions.empty()

    def _decide(self, t: np.ndarray, flag: np.ndarray, calibrating: np.ndarray) -> Decisions:
        p = flag.astype(float)
        valid = ~calibrating
        contact, releases = self.logic.step(t=t, p=p, valid=valid)
        return Decisions(t=t, p=p, contact=contact, valid=valid, releases=releases,
                         events=list(self.logic.last_events))

    def _wrench_arrays(self, t, force, torque):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        force = np.atleast_2d(np.asarray(force, dtype=float))
        torque = np.atleast_2d(np.asarray(torque, dtype=float))
        if not (np.all(np.isfinite(force)) and np.all(np.isfinite(torque))):
            raise InputError('wrench contains NaN or Inf')
        if self._last_t is not None and t[0] <= self._last_t:
            if self._last_t - t[0] > 0.5:
                self.counts['time_jumps'] += 1
                self.reset()
            else:
                raise InputError('repeated or out-of-order wrench stamp')
        self._last_t = float(t[-1])
        if self._t0 is None:
            self._t0 = float(t[0])
        return t, force, torque


class _RestStats:
    """Mean and standard deviation of a signal over the calibration period."""

    def __init__(self) -> None:
        self.values: list = []
        self.mean = 0.0
        self.sd = 0.0
        self.done = False

    def add(self, values: np.ndarray) -> None:
        self.values.extend(values.tolist())

    def finish(self) -> None:
        data = np.asarray(self.values) if self.values else np.zeros(1)
        self.mean, self.sd, self.done = float(data.mean()), float(data.std()) + 1e-9, True
        self.values = []


class ThresholdBaseline(_Baseline):
    """The recorded robot's rule: |T_y - rest T_y| >= ``threshold_nm``."""

    def __init__(self, *, threshold_nm: float = 3.0, **kw) -> None:
        self.threshold_nm = threshold_nm
        super().__init__(**kw)

    def reset(self) -> None:
        super().reset()
        self.rest = _RestStats()

    def on_wrench(self, *, t, force, torque, now: Optional[float] = None) -> Decisions:
        try:
            t, force, torque = self._wrench_arrays(t, force, torque)
        except InputError as err:
            return self.drop(kind='wrench', reason=str(err))
        calibrating = t < self._t0 + self.calibration_s
        if not self.rest.done:
            self.rest.add(torque[calibrating, 1])
            if not calibrating.all():
                self.rest.finish()
        flag = np.abs(torque[:, 1] - self.rest.mean) >= self.threshold_nm
        return self._decide(t, flag & ~calibrating, calibrating)


class _FilterBaseline(_Baseline):
    """A streaming IIR filter bank on |F| or |T| with rest calibration."""

    def _filter(self, b, a, x, key):
        zi = self._zi.get(key)
        if zi is None:
            zi = signal.lfilter_zi(b, a) * x[0]
        y, self._zi[key] = signal.lfilter(b, a, x, zi=zi)
        return y

    def reset(self) -> None:
        super().reset()
        self._zi: dict = {}
        self.rest = {}


class HighPassBaseline(_FilterBaseline):
    """High-pass (``cutoff_hz``) on |T|; contact when ``|hp| > k * sd_rest`` (Cho et al.)."""

    def __init__(self, *, cutoff_hz: float = 5.0, k: float = 8.0, **kw) -> None:
        self.k = k
        super().__init__(**kw)
        self.b, self.a = signal.butter(1, cutoff_hz, btype='highpass', fs=self.wrench_rate)

    def on_wrench(self, *, t, force, torque, now: Optional[float] = None) -> Decisions:
        try:
            t, force, torque = self._wrench_arrays(t, force, torque)
        except InputError as err:
            return self.drop(kind='wrench', reason=str(err))
        hp = self._filter(self.b, self.a, np.linalg.norm(torque, axis=1), 'hp')
        calibrating = t < self._t0 + self.calibration_s
        rest = self.rest.setdefault('hp', _RestStats())
        if not rest.done:
            rest.add(hp[calibrating])
            if not calibrating.all():
                rest.finish()
        flag = np.abs(hp) > self.k * rest.sd if rest.done else np.zeros(t.size, bool)
        return self._decide(t, flag & ~calibrating, calibrating)


class LowPassBandPassBaseline(_FilterBaseline):
    """Low-pass observer of |F| for contacts, band-pass observer vetoes collisions (Li)."""

    def __init__(self, *, lowpass_hz: float = 2.0, band_hz: tuple = (5.0, 20.0),
                 k: float = 8.0, k_collision: float = 8.0, **kw) -> None:
        self.k, self.k_collision = k, k_collision
        super().__init__(**kw)
        nyquist = self.wrench_rate / 2
        self.lp = signal.butter(2, lowpass_hz, btype='lowpass', fs=self.wrench_rate)
        self.bp = signal.butter(2, [band_hz[0], min(band_hz[1], 0.9 * nyquist)],
                                btype='bandpass', fs=self.wrench_rate)

    def on_wrench(self, *, t, force, torque, now: Optional[float] = None) -> Decisions:
        try:
            t, force, torque = self._wrench_arrays(t, force, torque)
        except InputError as err:
            return self.drop(kind='wrench', reason=str(err))
        magnitude = np.linalg.norm(force, axis=1)
        lp = self._filter(*self.lp, magnitude, 'lp')
        bp = np.abs(self._filter(*self.bp, magnitude, 'bp'))
        calibrating = t < self._t0 + self.calibration_s
        for key, values in (('lp', lp), ('bp', bp)):
            rest = self.rest.setdefault(key, _RestStats())
            if not rest.done:
                rest.add(values[calibrating])
                if not calibrating.all():
                    rest.finish()
        if not self.rest['lp'].done:
            return self._decide(t, np.zeros(t.size, bool), calibrating)
        contact = np.abs(lp - self.rest['lp'].mean) > self.k * self.rest['lp'].sd
        collision = bp > self.rest['bp'].mean + self.k_collision * self.rest['bp'].sd
        return self._decide(t, contact & ~collision & ~calibrating, calibrating)


class AudioOnsetBaseline(_Baseline):
    """Audio power (eq. 1) at least ``db`` dB above the tracked noise floor."""

    def __init__(self, *, db: float = 20.0, **kw) -> None:
        self.db = db
        self.config = FeatureConfig.paper()  # the paper's audio frames and noise floor
        super().__init__(**kw)

    def reset(self) -> None:
        super().reset()
        self.framer = AudioFramer(config=self.config, sample_rate=self.audio_rate)
        self.floor = NoiseFloor(config=self.config)
        self._audio_t0: Optional[float] = None
        self._prev_floor: Optional[float] = None

    def on_audio(self, samples, *, stamp: float, now: Optional[float] = None) -> Decisions:
        try:
            t, power = self.framer.push(to_unit_audio(samples), stamp=stamp)
        except InputError as err:
            return self.drop(kind='audio', reason=str(err))
        if t.size == 0:
            return Decisions.empty()
        if self._audio_t0 is None:
            self._audio_t0 = float(t[0])
        # Compare with the floor before this frame, so the onset does not raise its own floor.
        floor = self.floor.update(power)
        first = floor[0] if self._prev_floor is None else self._prev_floor
        previous = np.concatenate([[first], floor[:-1]])
        self._prev_floor = float(floor[-1])
        ratio_db = 10 * np.log10((power + 1e-10) / (previous + 1e-10))
        calibrating = t < self._audio_t0 + self.calibration_s
        return self._decide(t, (ratio_db >= self.db) & ~calibrating, calibrating)


class GuardBaseline(_Baseline):
    """
    The plain guard: contact when ``|F - F_rest| >= threshold_n``.

    ``F_rest`` is the per-axis median of the force over the calibration period (the hand at
    rest with its load); the distance is the length of the vector change, so neither the
    sensor's mounting nor a constant bias matters. A knock or a push over the threshold fires
    it as surely as the table does: the point of the comparison.
    """

    def __init__(self, *, threshold_n: float = 2.0, **kw) -> None:
        self.threshold_n = threshold_n
        super().__init__(**kw)

    def reset(self) -> None:
        super().reset()
        self._rest_rows: list = []
        self._rest: Optional[np.ndarray] = None

    def on_wrench(self, *, t, force, torque, now: Optional[float] = None) -> Decisions:
        try:
            t, force, torque = self._wrench_arrays(t, force, torque)
        except InputError as err:
            return self.drop(kind='wrench', reason=str(err))
        calibrating = t < self._t0 + self.calibration_s
        if self._rest is None:
            self._rest_rows.extend(force[calibrating].tolist())
            if not calibrating.all():
                self._rest = np.median(np.asarray(self._rest_rows).reshape(-1, 3), axis=0)
        if self._rest is None:
            return self._decide(t, np.zeros(t.size, bool), calibrating)
        flag = np.linalg.norm(force - self._rest, axis=1) >= self.threshold_n
        return self._decide(t, flag & ~calibrating, calibrating)


def make_baseline(name: str, *, wrench_rate: float, audio_rate: float) -> _Baseline:
    """
    Build a baseline detector by name.

    Raises
    ------
    ConfigError
        For an unknown name.

    """
    classes = {'threshold': ThresholdBaseline, 'highpass': HighPassBaseline,
               'lowpass-bandpass': LowPassBandPassBaseline, 'audio-onset': AudioOnsetBaseline,
               'guard': GuardBaseline}
    if name not in classes:
        raise ConfigError(f'unknown detector {name!r}; choose forest or one of {BASELINES}')
    if not (math.isfinite(wrench_rate) and wrench_rate > 0):
        raise ConfigError(f'wrench rate must be > 0, got {wrench_rate}')
    return classes[name](wrench_rate=wrench_rate, audio_rate=audio_rate)
