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
The live contact detector node.

It converts messages to arrays (:mod:`contact_detector.io.messages`), hands them to
:class:`~contact_detector.detection.detector.ContactDetector` (all the logic: features, forest,
confirmation, arming, warm-up, staleness, corrupt-input hold-off, time-jump reset) and turns the
returned decisions into messages. The offline tools run the same detector on the same arrays.

Interface (all names relative, remappable)::

    subscribes  wrist_wrench         geometry_msgs/msg/WrenchStamped   sensor-data QoS
                audio                audio.msg_type                    sensor-data QoS
                                     (not with an F/T-only model)
                audio_info           audio_common_msgs/msg/AudioInfo   transient local
                                     (ros-drivers audio_common types only)
    publishes   contact              std_msgs/msg/Bool      one per frame (audio frame, or
                                                            F/T frame with an F/T-only model)
                contact_probability  std_msgs/msg/Float32   one per frame
                release              std_msgs/msg/Bool      True once per event while armed
                /diagnostics         diagnostic_msgs/msg/DiagnosticArray
                gripper.topic        trajectory_msgs/msg/JointTrajectory (gripper.enabled)
    services    ~/arm                std_srvs/srv/SetBool
                ~/reset              std_srvs/srv/Trigger
                ~/zero_sensor        std_srvs/srv/Trigger   (sets wrench.bias)

The wiring (:class:`DetectorWiring`) is shared with the managed (lifecycle) variant,
:mod:`contact_detector.ros.lifecycle_node`. See ``docs/node.md``. Next to it: parameters in
:mod:`.params`, the audio-format negotiation in :mod:`.audio_format`, ``/diagnostics`` in
:mod:`.diagnostics`, the opt-in executor in :mod:`.executor`.

Why over 500 lines: this module is one job, the wiring of one object (set-up and tear-down in
lifecycle steps, the input callbacks, outputs, services, clock jumps and parameter updates),
whose methods share that object's state; split further, one object's methods would be spread
over several files.
"""

from collections import deque
from dataclasses import replace
import gc
import importlib
import re
import sys
import time
from typing import Any, Callable, Dict, Optional

from contact_detector.detection.detector import ContactDetector, Decisions, DetectorSettings
from contact_detector.detection.fallback import AudioFallback
from contact_detector.errors import ConfigError, InputError, ModelError
from contact_detector.features.carried import CarriedLoad
from contact_detector.features.resample import StampRate
from contact_detector.io.cdr import (BOOL_FALSE, BOOL_TRUE, FAST_DECODERS,
                                     read_wrench_stamped, write_float32)
from contact_detector.io.messages import (AUDIO_MSG_TYPES, audio_stamp, audio_to_samples,
                                          AudioFormat, AudioMsgType, check_stamp, wrench_sample)
from contact_detector.model.bundle import ModelBundle
from contact_detector.model.storage import load_bundle
from contact_detector.ros.audio_format import AudioFormatNegotiation
from contact_detector.ros.diagnostics import DiagnosticsMixin, InputStream
from contact_detector.ros.gripper import open_gripper_trajectory
from contact_detector.ros.model_search import default_ft_model_path, default_model_path
from contact_detector.ros.params import (config_from_values, current_values,
                                         declare_parameters, NodeConfig, PARAMS_BY_NAME)
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
import numpy as np
from rcl_interfaces.msg import SetParametersResult
import rclpy
from rclpy.clock import ClockChange, JumpThreshold
from rclpy.duration import Duration
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data, QoSProfile,
                       ReliabilityPolicy)
from rclpy.serialization import deserialize_message
from std_msgs.msg import Bool, Float32
from std_srvs.srv import SetBool, Trigger
from trajectory_msgs.msg import JointTrajectory

#: A backwards jump of the node clock larger than this resets the detector, s.
CLOCK_JUMP_RESET_S = 0.1
#: History depth of the output publishers (100 frames = 1 s).
OUTPUT_DEPTH = 100
#: Processing latencies kept for :meth:`DetectorWiring.latency_samples`.
LATENCY_HISTORY = 100_000

NODE_COUNTERS = ('audio_waiting_info', 'audio_refused', 'bad_stamps', 'clock_jumps',
                 'callback_errors', 'detector_rebuilds', 'contact_msgs', 'release_msgs')
_NUMBERS = re.compile(r'[-+]?\d+(\.\d+)?(e[-+]?\d+)?')


def import_audio_types(msg_type: str) -> tuple:
    """
    Import the message classes of an audio type of :data:`AUDIO_MSG_TYPES`.

    Returns
    -------
    spec : AudioMsgType
    msg_class : type
        The audio message class.
    info_class : type or None
        ``AudioInfo`` for types whose format comes from an ``audio_info`` topic.

    Raises
    ------
    ConfigError
        The package is not installed, or the installed one lacks the type (the two
        audio_common variants share the package name ``audio_common_msgs``).

    """
    spec: AudioMsgType = AUDIO_MSG_TYPES[msg_type]
    try:
        module = importlib.import_module(f'{spec.package}.msg')
    except ImportError as err:
        raise ConfigError(
            f'audio.msg_type={msg_type!r} needs the ROS message package {spec.package!r} '
            f'({spec.source}), which is not installed here ({err}). Install or build it in '
            'your workspace and source it, or publish audio as std_msgs/msg/Int16MultiArray'
        ) from err
    msg_class = getattr(module, spec.type_name, None)
    if msg_class is None:
        raise ConfigError(f'the installed {spec.package} has no {spec.type_name}: '
                          f'{msg_type} comes from {spec.source}, another package of the same '
                          'name is installed')
    info_class = None
    if spec.info_topic:
        info_class = getattr(module, 'AudioInfo', None)
        if info_class is None:
            raise ConfigError(f'the installed {spec.package} has no AudioInfo')
    return spec, msg_class, info_class


class _Throttle:
    """Rate-limit log lines per key; count what was suppressed."""

    def __init__(self) -> None:
        self._last: Dict[str, float] = {}
        self._suppressed: Dict[str, int] = {}

    def __call__(self, key: str, period_s: float) -> Optional[int]:
        """Return the number suppressed since the last line if one may be logged, else None."""
        now = time.monotonic()
        last = self._last.get(key)
        if last is not None and now - last < period_s:
            self._suppressed[key] = self._suppressed.get(key, 0) + 1
            return None
        self._last[key] = now
        return self._suppressed.pop(key, 0)


class DetectorWiring(DiagnosticsMixin):
    """
    The node's ROS wiring around :class:`ContactDetector`, shared by both node classes.

    A mixin for an rclpy :class:`~rclpy.node.Node` (:class:`ContactDetectorNode`) or
    :class:`~rclpy.lifecycle.LifecycleNode`
    (:class:`~contact_detector.ros.lifecycle_node.ContactDetectorLifecycleNode`). Its set-up
    comes in steps that the plain node runs at once and the managed node runs in its
    transitions:

    ``_load``
        config, model, detector, counters (no ROS entity; configure).
    ``_create_outputs`` / ``_destroy_outputs``
        publishers and the ``~/arm`` and ``~/reset`` services (configure / cleanup).
    ``_create_inputs`` / ``_destroy_inputs``
        subscriptions, the diagnostics timer and the clock-jump callback (activate /
        deactivate): without them nothing is decided, so nothing is released.
    """

    def _load(self, config: NodeConfig, bundle: Optional[ModelBundle]) -> None:
        """
        Take a validated config, load the model (unless given) and build the detector.

        Raises
        ------
        ConfigError
            The audio message package is missing, or the model cannot run with the config.
        ModelError
            The model cannot be loaded.

        """
        self.config: NodeConfig = config
        # rcl's clock itself: Clock.now() wraps it in a Time object (~2 us more per read).
        self._clock_handle = self.get_clock().handle
        cfg = self.config
        self.audio_spec, audio_class, info_class = import_audio_types(cfg.audio_msg_type)
        if bundle is None:
            path = cfg.model_path or str(default_model_path() if cfg.audio_enabled
                                         else default_ft_model_path())
            bundle = load_bundle(path=path)
            self.model_path = path
        else:
            self.model_path = '(given)'
        if not cfg.audio_enabled and not bundle.feature_config.ft_only:
            raise ConfigError(f'audio.enabled is false but model {bundle.model_id} '
                              f'({self.model_path}) uses audio features: give an F/T-only '
                              'model.path, or leave it empty for the shipped F/T-only model')
        self.bundle = bundle
        # An F/T-only model: no audio subscription, frames are clocked by the wrench stream.
        self.use_audio = not bundle.feature_config.ft_only
        # model.ft_also_decides: the F/T-only model decides beside the audio model;
        # audio.timeout_s: it stands in while the audio is silent.
        self.ft_bundle = (load_bundle(path=default_ft_model_path())
                          if self.use_audio and (cfg.model_ft_also_decides
                                                 or cfg.audio_timeout_s > 0) else None)
        self._audio_class, self._info_class = audio_class, info_class
        self.counts = dict.fromkeys(NODE_COUNTERS, 0)
        self._count_base: Dict[str, int] = {}
        self._throttle = _Throttle()
        self._pending: Optional[NodeConfig] = None
        self.audio = InputStream()
        self.wrench = InputStream()
        self.wrench_rate = StampRate()      # the rate the wrench really arrives at
        self._rate_warned = False
        self.negotiation = AudioFormatNegotiation(
            configured=AudioFormat(sample_rate=cfg.audio_sample_rate,
                                   channels=cfg.audio_channels),
            info_topic=self.audio_spec.info_topic, wait_for_info=cfg.audio_wait_for_info,
            channel=cfg.audio_channel)
        self.detector = self._build_detector(rate=cfg.audio_sample_rate,
                                             armed=cfg.release_armed_on_start)
        self._time_jumps_seen = 0
        self._carried_seen = None           # the last carried-load measurement logged
        self._zero_seen = None              # the last zero measurement applied
        self._placeholders_seen = 0         # F/T placeholders (exact zeros) warned about
        self._noise_bursts_seen = 0         # bursts of a noisy F/T reading warned about
        self._latency = {'audio': deque(maxlen=LATENCY_HISTORY),
                         'wrench': deque(maxlen=LATENCY_HISTORY)}
        self._window_latency: list = []
        self._window_age: list = []
        self._window_start = time.monotonic()
        self._window_counts: Dict[str, int] = {}
        self._started: set = set()
        self.diagnostics_timer = None

    def _create_outputs(self, make_publisher: Callable[..., Any]) -> None:
        """Create the publishers (with ``make_publisher``) and the services."""
        cfg = self.config
        # One second of frames: a reliable subscriber that stalls briefly loses nothing.
        output_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=OUTPUT_DEPTH,
                                reliability=ReliabilityPolicy.RELIABLE)
        # The gripper's topic first: the one name a user gives, refused before anything exists
        self.gripper_pub = None
        if cfg.gripper_enabled:
            try:
                self.gripper_pub = make_publisher(JointTrajectory, cfg.gripper_topic, output_qos)
            except NameValidationException as err:
                raise ConfigError(f'parameter gripper.topic={cfg.gripper_topic!r} is not a valid '
                                  f'topic name: {err}') from err
        self.contact_pub = make_publisher(Bool, 'contact', output_qos)
        self.probability_pub = make_publisher(Float32, 'contact_probability', output_qos)
        self.release_pub = make_publisher(Bool, 'release', output_qos)
        self.diagnostics_pub = make_publisher(DiagnosticArray, '/diagnostics', 10)
        self.arm_srv = self.create_service(SetBool, '~/arm', self._on_arm)
        self.reset_srv = self.create_service(Trigger, '~/reset', self._on_reset)
        self.zero_srv = self.create_service(Trigger, '~/zero_sensor', self._on_zero)

    def _destroy_outputs(self, destroy_publisher: Callable[[Any], Any]) -> None:
        """Destroy what :meth:`_create_outputs` made."""
        for pub in (self.contact_pub, self.probability_pub, self.release_pub,
                    self.diagnostics_pub, self.gripper_pub):
            if pub is not None:
                destroy_publisher(pub)
        self.destroy_service(self.arm_srv)
        self.destroy_service(self.reset_srv)
        self.destroy_service(self.zero_srv)

    def _create_inputs(self) -> None:
        """Subscribe to the inputs; start the diagnostics timer and the clock-jump callback."""
        cfg = self.config
        input_qos = QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=cfg.qos_depth,
            reliability=(ReliabilityPolicy.RELIABLE if cfg.qos_reliability == 'reliable'
                         else ReliabilityPolicy.BEST_EFFORT),
            durability=qos_profile_sensor_data.durability)
        # Serialised bytes, read by io.cdr (rclpy's deserialisation for anything it refuses):
        # no message object per input message.
        self._read_audio = FAST_DECODERS.get(cfg.audio_msg_type)
        self.wrench_sub = self.create_subscription(WrenchStamped, 'wrist_wrench',
                                                   self._on_wrench, input_qos, raw=True)
        self.audio_sub = (self.create_subscription(self._audio_class, 'audio', self._on_audio,
                                                   input_qos, raw=self._read_audio is not None)
                          if self.use_audio else None)
        self.info_sub = None
        if self._info_class is not None and self.use_audio:
            info_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                                  reliability=ReliabilityPolicy.RELIABLE,
                                  durability=DurabilityPolicy.TRANSIENT_LOCAL)
            self.info_sub = self.create_subscription(self._info_class, 'audio_info',
                                                     self._on_audio_info, info_qos)
        self.diagnostics_timer = self.create_timer(cfg.diagnostics_period_s,
                                                   self._publish_diagnostics)
        self._jump_handle = self.get_clock().create_jump_callback(
            JumpThreshold(min_forward=None, min_backward=Duration(
                nanoseconds=-int(CLOCK_JUMP_RESET_S * 1e9))),
            post_callback=self._on_clock_jump)
        # Said once; /diagnostics says it every period until an input arrives.
        inputs = [sub.topic_name for sub in (self.wrench_sub, self.audio_sub) if sub is not None]
        self.get_logger().info(f'waiting for input on {" and ".join(inputs)}')

    def _destroy_inputs(self) -> None:
        """Destroy what :meth:`_create_inputs` made."""
        self._jump_handle.unregister()
        self.destroy_timer(self.diagnostics_timer)
        self.diagnostics_timer = None
        for sub in (self.wrench_sub, self.audio_sub, self.info_sub):
            if sub is not None:
                self.destroy_subscription(sub)
        self.wrench_sub = self.audio_sub = self.info_sub = None

    def _log_loaded(self) -> None:
        cfg, rule = self.config, self.detector.rule
        both = ''
        if getattr(self.detector, 'both_decide', False):
            both = (f'; the F/T-only model {self.ft_bundle.model_id} decides too, the first '
                    'release of either (model.ft_also_decides)')
        self.get_logger().info(
            f'model {self.bundle.model_id} ({self.model_path}); rule {rule.describe()}; '
            f'audio {self._audio_text()}; wrench {cfg.wrench_rate:g} Hz; '
            f'release {"armed" if self.detector.armed else "disarmed"}{both}')

    def _settings(self, *, rate: float, armed: bool,
                  bundle: Optional[ModelBundle] = None) -> DetectorSettings:
        cfg = self.config
        return DetectorSettings(
            audio_rate=rate, wrench_rate=cfg.wrench_rate, max_ft_age_s=cfg.max_ft_age_s,
            max_ft_wait_s=cfg.max_ft_wait_s, max_input_delay_s=cfg.max_input_delay_s,
            warmup_s=cfg.warmup_s, corrupt_holdoff_s=cfg.corrupt_holdoff_s, armed_on_start=armed,
            rule=cfg.rule((bundle or self.bundle).decision_rule), wrench_bias=cfg.wrench_bias,
            noise_jump_n=cfg.wrench_noise_jump)

    def _build_detector(self, *, rate: float, armed: bool):
        try:
            detector = ContactDetector(bundle=self.bundle,
                                       settings=self._settings(rate=rate, armed=armed))
            if self.ft_bundle is None:
                return detector
            fallback = ContactDetector(bundle=self.ft_bundle, settings=self._settings(
                rate=rate, armed=False, bundle=self.ft_bundle))
            return AudioFallback(primary=detector, fallback=fallback,
                                 timeout_s=self.config.audio_timeout_s,
                                 both_decide=self.config.model_ft_also_decides)
        except ConfigError as err:
            raise ConfigError(f'cannot run model {self.bundle.model_id} with audio at {rate:g} '
                              f'Hz and wrench.rate={self.config.wrench_rate:g} Hz: {err}'
                              ) from err

    def _audio_text(self) -> str:
        if not self.use_audio:
            return 'off (F/T-only model: no audio subscription, one frame per F/T frame)'
        return f'{self.config.audio_msg_type} {self.negotiation.describe()}'

    @property
    def audio_format(self) -> AudioFormat:
        """Return the format audio chunks are decoded with (see :mod:`.audio_format`)."""
        return self.negotiation.format

    @property
    def audio_refused(self) -> Optional[str]:
        """Return why every audio chunk is dropped (unsupported format), else None."""
        return self.negotiation.refused

    # --- helpers ---------------------------------------------------------------------------------

    def _now(self) -> float:
        return self._clock_handle.get_now().nanoseconds * 1e-9

    def _warn(self, key: str, message: str) -> None:
        suppressed = self._throttle(key, self.config.log_throttle_s)
        if suppressed is not None:
            more = f' ({suppressed} more since the last report)' if suppressed else ''
            self.get_logger().warning(message + more)

    def _undecodable(self, kind: str, err: BaseException, now: float, entry: float) -> None:
        # A message whose bytes do not deserialise is dropped like any corrupt message:
        # counted, a hold-off, and for audio a restarted stream (the samples on either side
        # of it are not joined into one frame).
        stream = self.audio if kind == 'audio' else self.wrench
        stream.last_rx = now
        stream.received += 1
        reason = f'cannot deserialise it: {type(err).__name__}: {err}'
        self._handle(self.detector.drop(kind=kind, reason=reason, stamp=now), now, entry, kind)

    def _callback_failed(self, where: str, err: BaseException) -> None:
        self.counts['callback_errors'] += 1
        self._warn(f'error-{where}', f'{where} callback failed and dropped its message: '
                   f'{type(err).__name__}: {err}')

    def _set_audio_rate(self, rate: float) -> None:
        """Rebuild the detector for another audio rate (arming kept, counters carried)."""
        if rate == self.detector.settings.audio_rate:
            return
        old = self.detector
        try:
            self.detector = self._build_detector(rate=rate, armed=old.armed)
        except ConfigError as err:
            self.negotiation.refuse(str(err))
            self.get_logger().error(f'audio refused: {err}')
            return
        for name, value in old.counts.items():
            self._count_base[name] = self._count_base.get(name, 0) + value
        self.counts['detector_rebuilds'] += 1
        self._time_jumps_seen = 0
        self._placeholders_seen = 0
        self._noise_bursts_seen = 0
        self.get_logger().info(f'audio rate is now {rate:g} Hz: detector rebuilt, state reset')

    def detector_counts(self) -> Dict[str, int]:
        """Detector counters since start-up (summed over rebuilds) plus the node's own."""
        counts = {name: self._count_base.get(name, 0) + value
                  for name, value in self.detector.counts.items()}
        counts.update(self.counts)
        return counts

    def wrench_wanted(self) -> bool:
        """Whether an audio frame waits for F/T data (the executor then wakes for wrench)."""
        return not self.use_audio or self.detector.extractor.pending > 0

    def latency_samples(self, kind: str = 'audio') -> np.ndarray:
        """
        Return processing times (s) of recent callbacks that published frames, oldest first.

        From callback entry to the return of the last publish, for the ``kind`` ('audio' or
        'wrench') callbacks; the last :data:`LATENCY_HISTORY` are kept.
        """
        return np.array(self._latency[kind])

    # --- input callbacks -------------------------------------------------------------------------

    def _on_audio(self, msg: Any) -> None:
        entry = time.perf_counter()
        try:
            now = self._now()
            if isinstance(msg, bytes):
                try:
                    fast = self._read_audio(msg)
                    msg = (fast if fast is not None
                           else deserialize_message(msg, self._audio_class))
                except Exception as err:  # truncated or corrupt bytes: bad input, not a bug
                    self._undecodable('audio', err, now, entry)
                    return
            self._receive_audio(msg, now, entry)
        except Exception as err:  # a callback must never raise
            self._callback_failed('audio', err)

    def _receive_audio(self, msg: Any, now: float, entry: float) -> None:
        cfg = self.config
        stream = self.audio
        stream.last_rx = now
        stream.received += 1
        stream.window_msgs += 1
        negotiation = self.negotiation
        drop = negotiation.gate()
        if drop is not None:
            self.counts[drop.counter] += 1
            self._warn(drop.key, drop.message)
            return
        try:
            if self.audio_spec.embedded_info \
                    and negotiation.on_embedded(msg, cfg.audio_msg_type):
                self._set_audio_rate(negotiation.format.sample_rate)
                if negotiation.refused is not None:
                    return
            fmt = negotiation.format
            max_samples = int(cfg.audio_max_chunk_s * fmt.sample_rate)
            samples = audio_to_samples(msg, msg_type=cfg.audio_msg_type, channels=fmt.channels,
                                       channel=cfg.audio_channel, max_samples=max_samples)
            stamp = now
            if cfg.audio_stamp_source == 'header':
                stamp = audio_stamp(msg, cfg.audio_msg_type)
                try:
                    check_stamp(stamp=stamp, now=now, max_future_s=cfg.max_future_s,
                                previous=stream.last_stamp, what='audio stamp',
                                backjump_s=self.detector.extractor.audio.backjump_tolerance_s,
                                unset_hint=' (set audio.stamp_source: receive)')
                except InputError:
                    self.counts['bad_stamps'] += 1
                    raise
        except InputError as err:
            self._handle(self.detector.drop(kind='audio', reason=str(err), stamp=now), now,
                         entry, 'audio')
            return
        stream.last_stamp = stamp
        stream.window_samples += samples.shape[0]
        self._handle(self.detector.on_audio(samples, stamp=stamp, now=now), now, entry,
                     'audio')

    def _on_wrench(self, msg: Any) -> None:
        entry = time.perf_counter()
        try:
            now = self._now()
            if isinstance(msg, bytes):
                try:
                    fast = read_wrench_stamped(msg)
                    msg = fast if fast is not None else deserialize_message(msg, WrenchStamped)
                except Exception as err:  # truncated or corrupt bytes: bad input, not a bug
                    self._undecodable('wrench', err, now, entry)
                    return
            self._receive_wrench(msg, now, entry)
        except Exception as err:  # a callback must never raise
            self._callback_failed('wrench', err)

    def _receive_wrench(self, msg: Any, now: float, entry: float) -> None:
        stream = self.wrench
        stream.last_rx = now
        stream.received += 1
        stream.window_msgs += 1
        try:
            t, values = wrench_sample(msg)
            if self.config.wrench_stamp_source == 'receive':
                t = now
            else:
                try:
                    check_stamp(stamp=t, now=now, max_future_s=self.config.max_future_s,
                                what='wrench stamp',
                                unset_hint=' (set wrench.stamp_source: receive)')
                except InputError:
                    self.counts['bad_stamps'] += 1
                    raise
        except InputError as err:
            self._handle(self.detector.drop(kind='wrench', reason=str(err), stamp=None), now,
                         entry, 'wrench')
            return
        stream.last_stamp = t
        stream.window_samples += 1
        self.wrench_rate.add(t)
        self._handle(self.detector.on_wrench_one(t=t, values=values, now=now), now, entry,
                     'wrench')

    def _on_audio_info(self, msg: Any) -> None:
        try:
            outcome = self.negotiation.on_info(msg)
            if outcome.error is not None:
                self.get_logger().error(outcome.error)
            if outcome.info is not None:
                self.get_logger().info(outcome.info)
            if outcome.accepted is not None:
                self._set_audio_rate(outcome.accepted.sample_rate)
        except Exception as err:  # a callback must never raise
            self._callback_failed('audio_info', err)

    # --- output ----------------------------------------------------------------------------------

    def _handle(self, decisions: Decisions, now: float, entry: float, kind: str) -> None:
        """Publish a block of decisions and note what the detector reported."""
        if decisions.error is not None:
            # Throttled per kind of fault: the reason without its numbers.
            self._warn(f'drop-{kind}-' + _NUMBERS.sub('#', decisions.error), decisions.error)
        jumps = self.detector.counts.get('time_jumps', 0)
        if jumps != self._time_jumps_seen:
            self._time_jumps_seen = jumps
            self.get_logger().warning(f'{self.detector.last_error}; warming up again')
        carried = self.detector.carried_load
        if carried is not self._carried_seen:
            self._carried_seen = carried
            if carried is not None:
                self._log_carried(carried)
        # the counts restart with the stream (a reset), so each is followed down as well
        ft = self.detector.extractor.ft
        if ft.placeholders > self._placeholders_seen:
            self._warn('wrench-placeholder', 'F/T sample with a force or torque of exactly '
                       f'(0, 0, 0) after a load dropped ({ft.placeholders} so far): '
                       "the driver's placeholder for a missing reading, not a measurement")
        self._placeholders_seen = ft.placeholders
        if ft.noise_bursts > self._noise_bursts_seen:
            self._warn('wrench-noise', 'F/T reading noisy: the force jumps back and forth by '
                       f'{ft.noise_level:.1f} N per sample (median over 0.1 s; '
                       f'{ft.noisy} noisy samples so far): interference or a loose '
                       'connector, not a load; no release for '
                       f'{ft.noise_hold_s:.2f} s after it')
        self._noise_bursts_seen = ft.noise_bursts
        zero = self.detector.zero_measurement
        if zero is not self._zero_seen:
            self._zero_seen = zero
            if zero is not None:
                self._apply_zero(zero)
        switches = getattr(self.detector, 'switch_messages', None)
        if switches:
            for line in switches:
                self.get_logger().info(line)
            switches.clear()
        # A release can come with no frame: the F/T-only model's, deciding beside the audio
        # model (model.ft_also_decides), on a message that decided no audio frame.
        for t in decisions.releases:
            self._release(t)
        n = len(decisions)
        if n == 0:
            return
        # Serialised bytes: rclpy publishes them as they are (no message conversion per frame).
        contact_pub, probability_pub = self.contact_pub, self.probability_pub
        for contact, p in zip(decisions.contact.tolist(), decisions.p.tolist()):
            contact_pub.publish(BOOL_TRUE if contact else BOOL_FALSE)
            probability_pub.publish(write_float32(p))
        self.counts['contact_msgs'] += n
        done = time.perf_counter()
        latency = done - entry
        self._latency[kind].append(latency)
        self._window_latency.append(latency)
        self._window_age.append(now + latency - float(decisions.t[-1]))

    def _log_carried(self, carried: CarriedLoad) -> None:
        # One line per measurement (each start, reset and arming): the load the carried-load
        # features compare with, and a warning when it moved while it was measured.
        if carried.steady:
            self.get_logger().info(carried.describe())
        else:
            self.get_logger().warning(carried.describe() + ': arm again (~/arm) while the '
                                      'hand holds the object still')

    def _apply_zero(self, zero: CarriedLoad) -> None:
        # A completed ~/zero_sensor measurement: what the corrected signal read with the empty
        # hand is added to wrench.bias, through the parameter (so `ros2 param get` and a
        # parameter dump show it, and one code path applies every bias).
        if not zero.steady:
            self.get_logger().warning(
                f'F/T zero not changed: the F/T moved by {zero.moved[0]:.2f} N / '
                f'{zero.moved[1]:.3f} N m over the {zero.samples} samples measured; call '
                '~/zero_sensor again with the hand empty and still')
            return
        bias = [round(b + z, 6) for b, z in zip(self.detector.bias, zero.load.tolist())]
        result = self.set_parameters([Parameter('wrench.bias', Parameter.Type.DOUBLE_ARRAY,
                                                bias)])[0]
        if not result.successful:
            self.get_logger().warning(f'F/T zero not changed: {result.reason}')
            return
        self.get_logger().info(
            f'F/T sensor zeroed over {zero.samples} samples (it read |F| {zero.force_n:.2f} N, '
            f'|T| {zero.torque_nm:.3f} N m); stream state reset, warming up again. To keep '
            f'it after a restart: wrench.bias: [{", ".join(f"{b:g}" for b in bias)}]')

    def _release(self, t: float) -> None:
        self.release_pub.publish(Bool(data=True))
        self.counts['release_msgs'] += 1
        if self.gripper_pub is not None:
            cfg = self.config
            self.gripper_pub.publish(open_gripper_trajectory(
                joint=cfg.gripper_joint, position=cfg.gripper_position,
                duration_s=cfg.gripper_duration_s))
        by = getattr(self.detector, 'last_release_by', None)
        model = f' by the {by} model' if by else ''
        self.get_logger().info(f'contact at t={t:.3f} s: RELEASE{model} (disarmed until ~/arm)')

    # --- services, clock -------------------------------------------------------------------------

    def _on_arm(self, request: SetBool.Request, response: SetBool.Response) -> SetBool.Response:
        try:
            self.detector.arm(bool(request.data))
            response.success = True
            response.message = 'release armed' if request.data else 'release disarmed'
            self.get_logger().info(response.message)
        except Exception as err:  # a callback must never raise
            response.success, response.message = False, f'{type(err).__name__}: {err}'
        return response

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        try:
            self.detector.reset()
            self.audio.last_stamp = None
            self.wrench.last_stamp = None
            response.success = True
            response.message = ('stream state reset, warming up again; release '
                                f'{"armed" if self.detector.armed else "disarmed"}')
            self.get_logger().info(response.message)
        except Exception as err:  # a callback must never raise
            response.success, response.message = False, f'{type(err).__name__}: {err}'
        return response

    def _on_zero(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        try:
            self.detector.measure_zero()
            config = self.bundle.feature_config
            n = config.carried_window
            response.success = True
            response.message = (f'measuring the F/T zero over the next '
                                f'{n / config.ft_rate_hz:.2f} s ({n} samples at the '
                                f'{config.ft_rate_hz:g} Hz feature rate): keep the hand empty '
                                'and still')
            self.get_logger().info(response.message)
        except Exception as err:  # a callback must never raise
            response.success, response.message = False, f'{type(err).__name__}: {err}'
        return response

    def _on_clock_jump(self, jump: Any) -> None:
        try:
            self.counts['clock_jumps'] += 1
            self.detector.reset()
            self.audio.last_stamp = None
            self.wrench.last_stamp = None
            if jump.clock_change in (ClockChange.ROS_TIME_ACTIVATED,
                                     ClockChange.ROS_TIME_DEACTIVATED):
                what = f'time source changed ({jump.clock_change.name})'
            else:
                what = (f'node clock jumped by {jump.delta.nanoseconds * 1e-9:+.3f} s (bag loop '
                        'or seek?)')
            self.get_logger().warning(f'{what}: detector state reset, warming up again')
        except Exception as err:  # a callback must never raise
            self._callback_failed('clock jump', err)

    # --- parameters ------------------------------------------------------------------------------

    def _validate_parameters(self, params: list) -> SetParametersResult:
        mine = {p.name: p.value for p in params if p.name in PARAMS_BY_NAME}
        if not mine:
            return SetParametersResult(successful=True)
        values = current_values(self)
        values.update(mine)
        try:
            candidate = config_from_values(values)
            if self.detector is not None:       # None: a managed node not configured yet
                for det, bundle in self._rule_targets():
                    det.check_rule(candidate.rule(bundle.decision_rule))
        except ConfigError as err:
            self.get_logger().warning(f'parameter update refused: {err}')
            return SetParametersResult(successful=False, reason=str(err))
        self._pending = candidate
        return SetParametersResult(successful=True)

    def _rule_targets(self) -> list:
        """Return the (detector, bundle) pairs whose rules the release parameters set."""
        if isinstance(self.detector, AudioFallback):
            return [(self.detector.primary, self.bundle), (self.detector.fallback, self.ft_bundle)]
        return [(self.detector, self.bundle)]

    def _apply_parameters(self, params: list) -> None:
        new, self._pending = self._pending, None
        if new is None or not any(p.name in PARAMS_BY_NAME for p in params) \
                or self.bundle is None:         # configure reads the parameters
            return
        old, self.config = self.config, new
        if new.wrench_bias != old.wrench_bias:
            self.detector.set_bias(new.wrench_bias)     # checked: no ConfigError
        for det, bundle in self._rule_targets():
            det.settings = replace(det.settings, max_input_delay_s=new.max_input_delay_s,
                                   warmup_s=new.warmup_s,
                                   corrupt_holdoff_s=new.corrupt_holdoff_s,
                                   rule=new.rule(bundle.decision_rule))
            det.set_rule(det.settings.rule)
        if new.diagnostics_period_s != old.diagnostics_period_s \
                and self.diagnostics_timer is not None:
            self.destroy_timer(self.diagnostics_timer)
            self.diagnostics_timer = self.create_timer(new.diagnostics_period_s,
                                                       self._publish_diagnostics)
        changed = ', '.join(f'{p.name}={p.value!r}' for p in params if p.name in PARAMS_BY_NAME)
        self.get_logger().info(f'parameters updated: {changed}')


class ContactDetectorNode(DetectorWiring, Node):
    """
    ROS 2 node around :class:`ContactDetector`, running from construction.

    Parameters
    ----------
    node_name : str
        Node name (default ``contact_detector``).
    bundle : ModelBundle, optional
        A loaded model; default: load ``model.path`` (or the shipped model).
    **kwargs
        Passed to :class:`rclpy.node.Node` (``context``, ``parameter_overrides``, ...).

    Raises
    ------
    ConfigError
        A parameter is invalid, or the audio message package is missing.
    ModelError
        The model cannot be loaded.

    """

    def __init__(self, node_name: str = 'contact_detector', *,
                 bundle: Optional[ModelBundle] = None, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        try:
            self._load(declare_parameters(self), bundle)
            self._log_loaded()
            self._create_outputs(self.create_publisher)
            self._create_inputs()
            self.add_on_set_parameters_callback(self._validate_parameters)
            self.add_post_set_parameters_callback(self._apply_parameters)
        except BaseException:
            self.destroy_node()
            raise


def make_executor(node: ContactDetectorNode) -> Executor:
    """
    Return the executor ``executor.type`` asks for, with ``node`` added.

    ``single_threaded`` (the default) is rclpy's :class:`SingleThreadedExecutor`: public rclpy
    API only. ``hot_path`` (opt-in) is :class:`~contact_detector.ros.executor.HotPathExecutor`:
    less CPU per message, private rclpy API (a warning is logged on an rclpy version it was not
    checked with).

    With ``executor.lazy_wrench``, ``hot_path`` wakes up for audio chunks and for wrench
    messages only while an audio frame waits for F/T data: the wrench messages that arrived
    meanwhile are taken first at the next wake-up (fewer wake-ups, each costing a cold start;
    their processing adds to that chunk's latency). They are taken at least every half of the
    time the wrench queue (``qos.depth``) lasts at ``wrench.rate``. Wrench stamped on receipt
    (``wrench.stamp_source: receive``) wakes the node at once.
    """
    cfg = node.config
    if cfg.executor_type == 'hot_path':
        # Private rclpy API: imported only when asked for (see its module docstring).
        from contact_detector.ros.executor import (CHECKED_RCLPY_VERSIONS, HotPathExecutor,
                                                   rclpy_version)
        version = rclpy_version()
        if version not in CHECKED_RCLPY_VERSIONS:
            node.get_logger().warning(
                f'executor.type hot_path uses private rclpy API checked with rclpy '
                f'{", ".join(CHECKED_RCLPY_VERSIONS)}; this is rclpy {version or "(unknown)"}: '
                'run test/test_hot_path_executor.py, or use executor.type single_threaded')
        # Without audio the wrench stream clocks the frames: never lazy.
        lazy = ([node.wrench_sub] if cfg.executor_lazy_wrench and node.use_audio
                and cfg.wrench_stamp_source == 'header' else [])
        executor = HotPathExecutor(hot=list(node.subscriptions), poll_s=cfg.executor_poll_s,
                                   lazy=lazy, wanted=node.wrench_wanted,
                                   lazy_max_s=min(cfg.executor_poll_s,
                                                  0.5 * cfg.qos_depth / cfg.wrench_rate),
                                   context=node.context)
    else:
        executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    return executor


def spin_node(*, args: Optional[list], make_node: Callable[[], Node],
              make_exec: Callable[[Node], Executor]) -> int:
    """
    Start rclpy, build a node and spin it until shutdown; return the exit code.

    A wrong configuration, whether the node's checks or rclpy's own (arguments it cannot
    parse, a parameter of the wrong type for rclpy), is one FATAL line and exit code 1, never
    a traceback; SIGINT and an external shutdown are 0.

    Parameters
    ----------
    args : list or None
        Command-line arguments for ``rclpy.init`` (None: ``sys.argv``).
    make_node : callable
        Builds the node, in the initialised default context.
    make_exec : callable
        Builds the executor that spins it.

    Returns
    -------
    int

    """
    logger = rclpy.logging.get_logger('contact_detector')
    try:
        rclpy.init(args=args)
    except Exception as err:  # rclpy's own errors for bad arguments have no common base
        logger.fatal(f'cannot start: bad ROS arguments: {err}')
        return 1
    node = None
    code = 0
    try:
        node = make_node()
        executor = make_exec(node)
        # The model and the compiled forest live as long as the process: keep them out of
        # the garbage collector's full passes (shorter pauses in the callbacks).
        gc.freeze()
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ConfigError, ModelError) as err:
        logger.fatal(f'cannot start: {err}')
        code = 1
    except ParameterException as err:   # from rclpy, e.g. use_sim_time:=notabool
        logger.fatal(f'cannot start: parameter: {err}')
        code = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


def main(args: Optional[list] = None) -> int:
    """Run the node (``ros2 run contact_detector contact_detector_node``); return the exit code."""
    return spin_node(args=args, make_node=ContactDetectorNode, make_exec=make_executor)


if __name__ == '__main__':
    sys.exit(main())
