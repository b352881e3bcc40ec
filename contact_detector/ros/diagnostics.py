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
The node's ``/diagnostics``: input rates and ages, latency, counters, and one status.

:class:`DiagnosticsMixin` is part of :class:`~contact_detector.ros.node.DetectorWiring`; every
``diagnostics.period_s`` it publishes one ``DiagnosticStatus`` (name ``<node>: contact
detector``) whose level says, in this order of precedence: ERROR while the audio is refused;
WARN while waiting for the first input, on a measured wrench rate far from ``wrench.rate``, on
a stale or missing input, on any increase of a :data:`WARN_COUNTERS` counter during the
period, while armed with a carried load that moved while it was measured
(:class:`~contact_detector.features.carried.CarriedLoad`), and while the F/T-only fallback
model stands in; OK otherwise. Each period is a new
measurement window (rates, latency percentiles, counter increases).
"""

import time
from typing import Dict, Optional

from contact_detector.detection.fallback import AudioFallback, FT_ONLY, MULTIMODAL
from contact_detector.features.resample import rate_mismatch
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import numpy as np

#: Counters whose increase during a diagnostics period turns the status to WARN.
WARN_COUNTERS = ('audio_dropped', 'wrench_dropped', 'time_jumps', 'clock_jumps',
                 'callback_errors', 'audio_waiting_info', 'bad_stamps', 'audio_rate_mismatch',
                 'nonfinite_frames', 'audio_restarts', 'wrench_restarts', 'stale_frames',
                 'audio_clipped', 'wrench_placeholders', 'wrench_noise')


class InputStream:
    """Arrival bookkeeping of one input topic (for rates and staleness in diagnostics)."""

    def __init__(self) -> None:
        self.last_rx: Optional[float] = None       # node clock, s
        self.last_stamp: Optional[float] = None    # stamp of the last accepted message, s
        self.received = 0                           # messages since start-up
        self.window_msgs = 0
        self.window_samples = 0


class DiagnosticsMixin:
    """
    Diagnostics of :class:`~contact_detector.ros.node.DetectorWiring` (which sets its state).

    Reads the wiring's ``config``, ``detector``, ``bundle``, ``ft_bundle``, ``negotiation``,
    ``audio`` and ``wrench`` (:class:`InputStream`), ``wrench_rate`` and the window state
    (``_window_latency``, ``_window_age``, ``_window_start``, ``_window_counts``,
    ``_started``, ``_rate_warned``) that :meth:`diagnostics` resets every period, and its
    ``_now``, ``_warn``, ``_callback_failed`` and ``detector_counts``.
    """

    def _publish_diagnostics(self) -> None:
        try:
            self.diagnostics_pub.publish(self.diagnostics())
        except Exception as err:  # a callback must never raise
            self._callback_failed('diagnostics', err)

    def diagnostics(self) -> DiagnosticArray:
        """Build the diagnostics message and start a new measurement window."""
        now = self._now()
        mono = time.monotonic()
        span = max(mono - self._window_start, 1e-9)
        cfg, det = self.config, self.detector
        counts = self.detector_counts()
        values: Dict[str, str] = {}

        def age(stream: InputStream) -> Optional[float]:
            return None if stream.last_rx is None else now - stream.last_rx

        def fmt_s(value: Optional[float]) -> str:
            return 'never' if value is None else f'{value:.3f}'

        def pct(samples: list, q: float) -> str:
            return f'{1e3 * float(np.percentile(samples, q)):.3f}' if samples else 'n/a'

        audio_age, wrench_age = age(self.audio), age(self.wrench)
        rule = det.rule
        values.update({
            'model_id': self.bundle.model_id,
            'model_path': self.model_path,
            'model_active': (det.active_name if isinstance(det, AudioFallback)
                             else 'audio + F/T' if self.use_audio else 'F/T-only'),
            'fallback_model_id': self.ft_bundle.model_id if self.ft_bundle else 'none',
            'models_deciding': (' and '.join(FT_ONLY if d.ft_only else MULTIMODAL
                                             for d in det.deciding)
                                if isinstance(det, AudioFallback) else
                                'audio + F/T' if self.use_audio else 'F/T-only'),
            'decision_rule': rule.describe(),
            'armed': str(det.armed),
            'audio_msg_type': cfg.audio_msg_type,
            'audio': 'on' if self.use_audio else 'off (F/T-only model)',
            'audio_format': self.negotiation.describe() if self.use_audio else 'n/a',
            'audio_info': self.negotiation.info_status(use_audio=self.use_audio),
            'audio_msg_rate_hz': f'{self.audio.window_msgs / span:.1f}',
            'audio_sample_rate_hz': f'{self.audio.window_samples / span:.0f}',
            'wrench_msg_rate_hz': f'{self.wrench.window_msgs / span:.1f}',
            'wrench_sample_rate_hz': f'{self.wrench.window_samples / span:.1f}',
            'audio_age_s': fmt_s(audio_age),
            'wrench_age_s': fmt_s(wrench_age),
            'wrench_stamp_lag_s': fmt_s(None if self.wrench.last_stamp is None
                                        else now - self.wrench.last_stamp),
            'latency_p50_ms': pct(self._window_latency, 50),
            'latency_p99_ms': pct(self._window_latency, 99),
            'latency_max_ms': pct(self._window_latency, 100),
            'frame_age_p50_ms': pct(self._window_age, 50),
            'frame_age_p99_ms': pct(self._window_age, 99),
            'last_error': det.last_error or '',
        })
        carried = det.carried_load
        if carried is None:
            values['carried_load'] = ('measuring' if det.extractor.ft.uses_carried
                                      else 'not used by the model')
        else:
            values.update({'carried_load': carried.status,
                           'carried_force_n': f'{carried.force_n:.3f}',
                           'carried_torque_nm': f'{carried.torque_nm:.4f}',
                           'carried_moved_n': f'{carried.moved[0]:.3f}'})
        # the sensor's zero (wrench.bias, ~/zero_sensor): N, N, N, N m, N m, N m
        values['wrench_bias'] = ' '.join(f'{b:g}' for b in det.bias)
        values.update({name: str(value) for name, value in sorted(counts.items())})
        values['audio_received'] = str(self.audio.received)
        values['wrench_received'] = str(self.wrench.received)
        inputs = (('audio', audio_age), ('wrench', wrench_age)) if self.use_audio else (
            ('wrench', wrench_age),)
        stale = [name for name, value in inputs
                 if value is None or value > cfg.max_input_delay_s]
        # Until the first input arrives the node is waiting, not faulty: no warning.
        waiting = all(value is None for _, value in inputs)
        for name, stream in (('audio', self.audio), ('wrench', self.wrench)):
            if stream.received and name not in self._started:
                self._started.add(name)
                self.get_logger().info(f'{name} input started')
        troubles = {name: counts.get(name, 0) - self._window_counts.get(name, 0)
                    for name in WARN_COUNTERS}
        troubles = {name: value for name, value in troubles.items() if value > 0}
        self._window_counts = counts
        measured = self.wrench_rate.rate()
        values['wrench_measured_rate_hz'] = 'n/a' if measured is None else f'{measured:.1f}'
        mismatch = rate_mismatch(measured=measured, configured=cfg.wrench_rate)
        if mismatch and not self._rate_warned:
            self.get_logger().warning(mismatch)      # once; /diagnostics says it every period
        self._rate_warned = mismatch is not None
        if self.audio_refused:
            level, message = DiagnosticStatus.ERROR, f'audio refused: {self.audio_refused}'
        elif waiting:
            level, message = DiagnosticStatus.WARN, (
                'waiting for input: ' + ', '.join(name for name, _ in inputs))
        elif mismatch:
            level, message = DiagnosticStatus.WARN, mismatch
        elif stale:
            level, message = DiagnosticStatus.WARN, f'stale or missing input: {", ".join(stale)}'
        elif troubles:
            level, message = DiagnosticStatus.WARN, 'bad input: ' + ', '.join(
                f'{name} +{value}' for name, value in troubles.items())
        elif det.armed and carried is not None and not carried.steady:
            level, message = DiagnosticStatus.WARN, (
                f'carried load moved by {carried.moved[0]:.2f} N while it was measured: arm '
                'again (~/arm) while the hand holds the object still')
        else:
            level, message = DiagnosticStatus.OK, (
                f'running, release {"armed" if det.armed else "disarmed"}')
        if isinstance(det, AudioFallback) and det.active is det.fallback:
            message += '; F/T-only model active (no audio for audio.timeout_s)'
            level = max(level, DiagnosticStatus.WARN)
        if level != DiagnosticStatus.OK and not waiting and message != mismatch:
            # Faults without a log line of their own (dropouts, stale input, clipping) show
            # up here, throttled like the others.
            self._warn(f'diagnostics-{message.split(":")[0]}', f'diagnostics: {message}')
        self.audio.window_msgs = self.audio.window_samples = 0
        self.wrench.window_msgs = self.wrench.window_samples = 0
        self._window_latency, self._window_age = [], []
        self._window_start = mono
        status = DiagnosticStatus(level=level, name=f'{self.get_name()}: contact detector',
                                  message=message, hardware_id=self.get_fully_qualified_name(),
                                  values=[KeyValue(key=k, value=v) for k, v in values.items()])
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        return array
