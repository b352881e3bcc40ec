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
The node's parameters without ROS: their table, their checks and the frozen config.

:data:`PARAMS` is the one table of the node's parameters (name, default and type, range,
choices). The node declares them with rclpy (:mod:`contact_detector.ros.params`, which adds
the descriptors); the offline tools read the same names from a parameter file
(:func:`read_param_file`). Both validate with :func:`config_from_values`, so a value the node
refuses at start-up is refused offline with the same message.
"""

import array
import dataclasses
from dataclasses import dataclass
import fnmatch
import math
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence

from contact_detector.detection.release import rule_overrides
from contact_detector.errors import ConfigError
from contact_detector.features.noise import NOISE_JUMP_N
from contact_detector.io.messages import (AUDIO_MSG_TYPES, MAX_SAMPLE_RATE, MIN_SAMPLE_RATE,
                                          normalise_msg_type)
from contact_detector.io.node_params import read_node_params
from contact_detector.model.rule import DecisionRule

STAMP_SOURCES = ('receive', 'header')
RELIABILITIES = ('best_effort', 'reliable')
EXECUTORS = ('hot_path', 'single_threaded')


@dataclass(frozen=True)
class ParamSpec:
    """
    One node parameter.

    Attributes
    ----------
    name : str
        Dotted parameter name (``audio.sample_rate``).
    default : bool, int, float, str or tuple of float
        Default value; its type is the parameter's type (a tuple: a double array of that
        length).
    description : str
        Shown by ``ros2 param describe``.
    low, high : float or None
        Inclusive range for numbers (each element of an array).
    read_only : bool
        Refuse changes after start-up.
    choices : tuple of str
        Allowed values of a string parameter (empty = any).

    """

    name: str
    default: Any
    description: str
    low: Optional[float] = None
    high: Optional[float] = None
    read_only: bool = True
    choices: tuple = ()


#: Every parameter of the node, in the order of params/contact_detector.yaml.
PARAMS: Sequence[ParamSpec] = (
    ParamSpec('model.path', '', 'Model file (.npz; legacy .joblib or .skops need scikit-learn), '
              'with its .card.json beside it; empty = the shipped models/contact_forest.npz.'),
    ParamSpec('model.ft_also_decides', False, 'With a model that uses audio: true = the shipped '
              'F/T-only model models/contact_forest_ft.npz decides beside it, and the first '
              'release of either is the release (more slow, quiet load transfers caught: soft '
              'surfaces, fixtures, partial stops; a few more early releases after brushes).'),
    ParamSpec('audio.enabled', True, 'false: no audio subscription (a robot without a '
              'microphone); with model.path empty the shipped F/T-only model '
              'models/contact_forest_ft.npz is loaded. An F/T-only model.path also turns the '
              'audio subscription off.'),
    ParamSpec('audio.timeout_s', 0.0, 'With a model that uses audio: after this long without '
              'audio (s of stream time) while F/T keeps coming, the shipped F/T-only model takes '
              'over until the audio has been back for warmup_s; 0 = off.', 0.0, 60.0),
    ParamSpec('audio.msg_type', 'std_msgs/msg/Int16MultiArray',
              'Message type of the audio topic.', choices=tuple(AUDIO_MSG_TYPES)),
    ParamSpec('audio.sample_rate', 16000.0,
              'Audio sample rate in Hz (for audio_common types taken from the stream info).',
              MIN_SAMPLE_RATE, MAX_SAMPLE_RATE),
    ParamSpec('audio.channels', 1, 'Interleaved channels per audio message (for audio_common '
              'types taken from the stream info).', 1, 64),
    ParamSpec('audio.channel', -1, 'Channel to use, 0-based; -1 = average all channels.',
              -1, 63),
    ParamSpec('audio.stamp_source', 'receive', "Time of an audio chunk's last sample: "
              "'receive' = the node clock when the message arrives, 'header' = the header "
              'stamp (stamped types only).', choices=STAMP_SOURCES),
    ParamSpec('audio.max_chunk_s', 1.0, 'Largest accepted audio chunk, seconds; longer chunks '
              'are dropped as corrupt.', 0.001, 60.0),
    ParamSpec('audio.wait_for_info', True, 'ros-drivers audio_common types: drop audio until '
              'audio_info has confirmed raw S16LE; false = trust the audio.* parameters.'),
    ParamSpec('wrench.rate', 100.0, 'Wrench rate in Hz, 50 to 10000: resampled onto the F/T '
              'feature rate of the model (block means for integer multiples). The node '
              'measures the real rate and warns when it differs by more than 10 %.',
              1.0, 100000.0),
    ParamSpec('wrench.bias', (0.0,) * 6, "The F/T sensor's zero, subtracted from every "
              'wrench sample: [fx, fy, fz] N then [tx, ty, tz] N m, what the sensor reads with '
              'an empty hand. ~/zero_sensor measures and sets it; a change restarts the stream '
              'state (warm-up). Zero the sensor with the empty hand, never while it holds the '
              'object.', -10000.0, 10000.0, read_only=False),
    ParamSpec('wrench.noise_jump', NOISE_JUMP_N, 'A force reading whose median jump over 0.1 s is '
              'at least this, N, while it reverses direction from sample to sample '
              '(interference, a loose connector) is noise: no frame whose F/T features saw it '
              'releases (0.64 s after it with the shipped models; 0 = off).', 0.0, 1000.0),
    ParamSpec('wrench.stamp_source', 'header', "Time of a wrench sample: 'header' = its stamp, "
              "'receive' = the node clock on arrival.", choices=STAMP_SOURCES),
    ParamSpec('qos.reliability', 'best_effort', 'Reliability of the input subscriptions '
              '(sensor-data QoS otherwise). A reliable subscription does not match a '
              'best-effort publisher.', choices=RELIABILITIES),
    ParamSpec('qos.depth', 10, 'History depth of the input subscriptions.', 1, 10000),
    ParamSpec('max_input_delay_s', 0.5, 'A frame older than this (receive time minus frame '
              'time) when processed is stale: decided false, never releases.', 0.001, 60.0,
              read_only=False),
    ParamSpec('max_ft_age_s', 0.0, 'Largest age of the F/T features given to an audio frame, '
              's; 0 = the default of the feature core (F/T hop + 50 ms).', 0.0, 60.0),
    ParamSpec('max_ft_wait_s', 0.25, 'Longest an audio frame waits for F/T before it is '
              'decided without (invalid), s.', 0.0, 60.0),
    ParamSpec('max_future_s', 1.0, 'A stamp further than this ahead of the node clock is '
              'refused as corrupt (unsynchronised clocks show up here), s.', 0.0, 1.0e6,
              read_only=False),
    ParamSpec('warmup_s', 0.5, 'No release during this long after the first audio frame '
              'following a start or reset, s.', 0.0, 3600.0, read_only=False),
    ParamSpec('corrupt_holdoff_s', 0.2, 'No release during this long after a dropped '
              '(corrupt) message, s.', 0.0, 3600.0, read_only=False),
    ParamSpec('release.armed_on_start', True, 'Whether the release may fire before the first '
              '~/arm call.'),
    ParamSpec('release.threshold', -1.0, 'Contact when P(contact) >= this; negative = the '
              'decision rule of the model.', -1.0, 1.0, read_only=False),
    ParamSpec('release.confirm_frames', 0, 'Consecutive contact frames that make an event; 0 = '
              'the decision rule of the model.', 0, 1000, read_only=False),
    ParamSpec('release.refractory_s', -1.0, 'Minimum time between contact events, s; negative '
              '= the decision rule of the model.', -1.0, 3600.0, read_only=False),
    ParamSpec('release.average_frames', 0, 'Compare the mean P(contact) of this many frames '
              'with the threshold; 0 = the decision rule of the model.', 0, 1000,
              read_only=False),
    ParamSpec('release.sustain_frames', -1, 'Slow path: a frame is also contact when the mean '
              'P(contact) of this many frames >= release.sustain_threshold (0 = off); negative '
              '= the decision rule of the model.', -1, 1000, read_only=False),
    ParamSpec('release.sustain_threshold', -1.0, 'Threshold of the slow path; negative = the '
              'decision rule of the model.', -1.0, 1.0, read_only=False),
    ParamSpec('release.evidence_threshold', -1.0, 'Evidence path: a frame is also contact when '
              'the sum of P(contact) - release.evidence_drift over consecutive frames (never '
              'below 0) reaches this (0 = off); negative = the decision rule of the model.',
              -1.0, 1000.0, read_only=False),
    ParamSpec('release.evidence_drift', -1.0, 'What each frame subtracts from the evidence; '
              'negative = the decision rule of the model.', -1.0, 1.0, read_only=False),
    ParamSpec('release.load_threshold', -1.0, 'Load path: a frame is also contact when the '
              'force has stayed this far from the load carried at the start or arming for '
              'release.load_frames frames and the mean P(contact) of '
              'release.load_support_frames frames >= release.load_support, N (0 = off; needs '
              'a model with carried-load features); negative = the decision rule of the model.',
              -1.0, 1000.0, read_only=False),
    ParamSpec('release.load_frames', 0, 'Frames the load path needs the force away from the '
              'carried load; 0 = the decision rule of the model.', 0, 1000, read_only=False),
    ParamSpec('release.load_support', -1.0, 'Mean P(contact) the load path needs; negative = '
              'the decision rule of the model.', -1.0, 1.0, read_only=False),
    ParamSpec('release.load_support_frames', 0, 'Frames of that mean; 0 = the decision rule '
              'of the model.', 0, 1000, read_only=False),
    ParamSpec('release.load_direction', -2.0, 'Direction gate of the load path: it also needs '
              "the cosine between the force's distance from the carried load and the carried "
              'load <= this, or exactly 0 (a tared sensor) (1 = off); below -1 = the decision '
              'rule of the model.', -2.0, 1.0, read_only=False),
    ParamSpec('release.load2_threshold', -1.0, "Second load path: the load path's test with "
              'its own distance, frames, backing and direction gate, N (0 = off; needs a model '
              'with carried-load features); negative = the decision rule of the model.',
              -1.0, 1000.0, read_only=False),
    ParamSpec('release.load2_frames', 0, 'Frames the second load path needs the force away '
              'from the carried load; 0 = the decision rule of the model.', 0, 1000,
              read_only=False),
    ParamSpec('release.load2_support', -1.0, 'Mean P(contact) the second load path needs; '
              'negative = the decision rule of the model.', -1.0, 1.0, read_only=False),
    ParamSpec('release.load2_support_frames', 0, 'Frames of that mean; 0 = the decision '
              'rule of the model.', 0, 1000, read_only=False),
    ParamSpec('release.load2_direction', -2.0, 'Direction gate of the second load path, as '
              'release.load_direction; below -1 = the decision rule of the model.', -2.0, 1.0,
              read_only=False),
    ParamSpec('release.load2_steady', -1.0, 'The second load path also needs a steady load: '
              'the distances of the newest 10 frames within max - min <= this x their median '
              '(0 = off); negative = the decision rule of the model.', -1.0, 100.0,
              read_only=False),
    ParamSpec('gripper.enabled', False, 'On release also publish a JointTrajectory that opens '
              'the gripper.'),
    ParamSpec('gripper.topic', '/gripper_controller/joint_trajectory',
              'JointTrajectory topic of the gripper controller (HSR on the ROS 1 bridge: '
              '/hsrb/gripper_controller/command).'),
    ParamSpec('gripper.joint', 'hand_motor_joint', 'Gripper joint to command.',
              read_only=False),
    ParamSpec('gripper.position', 1.2, 'Open position of the gripper joint, rad (HSR: 1.2).',
              -100.0, 100.0, read_only=False),
    ParamSpec('gripper.duration_s', 0.5, 'time_from_start of the trajectory point, s.',
              0.0, 60.0, read_only=False),
    ParamSpec('executor.type', 'single_threaded', 'Executor run by main(): '
              "'single_threaded' is rclpy's SingleThreadedExecutor (public rclpy API only); "
              "'hot_path' (opt-in) serves the input subscriptions from a small wait set, "
              'less CPU per message, built on private rclpy API checked with the rclpy '
              'versions in contact_detector.ros.executor.CHECKED_RCLPY_VERSIONS.',
              choices=EXECUTORS),
    ParamSpec('executor.poll_s', 0.05, 'hot_path: longest delay of service, parameter and '
              'timer callbacks, s.', 0.001, 1.0),
    ParamSpec('executor.lazy_wrench', False, 'hot_path: wrench messages wake the node only '
              'while an audio frame waits for F/T data; the others are taken with the next '
              'audio chunk (fewer wake-ups, less CPU; their processing then adds to the '
              'latency of that chunk). Needs wrench.stamp_source header.'),
    ParamSpec('diagnostics.period_s', 1.0, 'Period of /diagnostics, s.', 0.05, 3600.0,
              read_only=False),
    ParamSpec('log_throttle_s', 2.0, 'Minimum time between two warnings about bad input of '
              'one kind, s.', 0.0, 3600.0, read_only=False),
)

PARAMS_BY_NAME: Dict[str, ParamSpec] = {spec.name: spec for spec in PARAMS}


@dataclass(frozen=True)
class NodeConfig:
    """
    The node's parameters, validated (see :data:`PARAMS` for meanings and units).

    ``audio_channel`` is None for "mix all channels"; ``max_ft_age_s`` None for the core's
    default; ``release_overrides`` holds the decision-rule fields that parameters set (the model
    bundle's rule applies to the others).
    """

    model_path: str
    model_ft_also_decides: bool
    audio_enabled: bool
    audio_timeout_s: float
    audio_msg_type: str
    audio_sample_rate: float
    audio_channels: int
    audio_channel: Optional[int]
    audio_stamp_source: str
    audio_max_chunk_s: float
    audio_wait_for_info: bool
    wrench_rate: float
    wrench_bias: tuple
    wrench_noise_jump: float
    wrench_stamp_source: str
    qos_reliability: str
    qos_depth: int
    max_input_delay_s: float
    max_ft_age_s: Optional[float]
    max_ft_wait_s: float
    max_future_s: float
    warmup_s: float
    corrupt_holdoff_s: float
    release_armed_on_start: bool
    release_overrides: Mapping[str, Any]
    gripper_enabled: bool
    gripper_topic: str
    gripper_joint: str
    gripper_position: float
    gripper_duration_s: float
    executor_type: str
    executor_poll_s: float
    executor_lazy_wrench: bool
    diagnostics_period_s: float
    log_throttle_s: float

    def rule(self, base: DecisionRule) -> DecisionRule:
        """Return ``base`` (the model's rule) with the parameters that are set overriding it."""
        return dataclasses.replace(base, **self.release_overrides)


def check_value(name: str, value: Any) -> Any:
    """Check type, range and choices of one value; raise ConfigError naming the parameter."""
    spec = PARAMS_BY_NAME.get(name)
    if spec is None:
        raise ConfigError(f'unknown parameter {name!r}')
    if isinstance(spec.default, tuple):
        # a double array (list, tuple, rclpy's array): each element checked as a float
        size = len(spec.default)
        if not isinstance(value, (list, tuple, array.array)) or len(value) != size:
            raise ConfigError(f'parameter {name} must be a list of {size} numbers, '
                              f'got {value!r}')
        return tuple(_check_one(spec, v, float) for v in value)
    return _check_one(spec, value, type(spec.default))


def _check_one(spec: ParamSpec, value: Any, want: type) -> Any:
    # type (floats take integers too: dynamically typed, see ParamSpec), finite, range, choices
    name = spec.name
    if want is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if type(value) is not want:
        raise ConfigError(f'parameter {name} must be a {want.__name__}, got {value!r}')
    if want is float and not math.isfinite(value):
        raise ConfigError(f'parameter {name} must be finite, got {value!r}')
    if spec.low is not None and not spec.low <= value <= spec.high:
        raise ConfigError(f'parameter {name}={value!r} is outside [{spec.low}, {spec.high}]')
    if spec.choices and value not in spec.choices:
        raise ConfigError(f'parameter {name}={value!r} must be one of {list(spec.choices)}')
    return value


def config_from_values(values: Mapping[str, Any]) -> NodeConfig:
    """
    Validate parameter values (missing ones take their defaults) and freeze them.

    Raises
    ------
    ConfigError
        Wrong type, out of range, not one of the choices, or inconsistent with another
        parameter; the message names the parameter.

    """
    unknown = sorted(set(values) - set(PARAMS_BY_NAME))
    if unknown:
        raise ConfigError(f'unknown parameters {unknown}')
    v = {spec.name: check_value(spec.name, values.get(spec.name, spec.default)) for spec in PARAMS}
    try:
        msg_type = normalise_msg_type(v['audio.msg_type'])
    except ConfigError as err:
        raise ConfigError(f'parameter audio.msg_type: {err}') from err
    channel = v['audio.channel']
    if channel >= v['audio.channels'] and not AUDIO_MSG_TYPES[msg_type].info_topic \
            and not AUDIO_MSG_TYPES[msg_type].embedded_info:
        raise ConfigError(f'parameter audio.channel={channel} does not exist with '
                          f'audio.channels={v["audio.channels"]} (use -1 to mix)')
    if v['audio.stamp_source'] == 'header' and not AUDIO_MSG_TYPES[msg_type].stamped:
        raise ConfigError(f"parameter audio.stamp_source='header' needs a stamped audio type; "
                          f'{msg_type} has no header (use receive)')
    if v['gripper.enabled'] and not v['gripper.topic'].strip():
        raise ConfigError('parameter gripper.topic must not be empty when gripper.enabled')
    if not v['gripper.joint'].strip():
        raise ConfigError('parameter gripper.joint must not be empty')
    return NodeConfig(
        model_path=v['model.path'], model_ft_also_decides=v['model.ft_also_decides'],
        audio_enabled=v['audio.enabled'],
        audio_timeout_s=v['audio.timeout_s'], audio_msg_type=msg_type,
        audio_sample_rate=v['audio.sample_rate'], audio_channels=v['audio.channels'],
        audio_channel=None if channel < 0 else channel,
        audio_stamp_source=v['audio.stamp_source'], audio_max_chunk_s=v['audio.max_chunk_s'],
        audio_wait_for_info=v['audio.wait_for_info'], wrench_rate=v['wrench.rate'],
        wrench_bias=v['wrench.bias'], wrench_noise_jump=v['wrench.noise_jump'],
        wrench_stamp_source=v['wrench.stamp_source'], qos_reliability=v['qos.reliability'],
        qos_depth=v['qos.depth'], max_input_delay_s=v['max_input_delay_s'],
        max_ft_age_s=v['max_ft_age_s'] or None, max_ft_wait_s=v['max_ft_wait_s'],
        max_future_s=v['max_future_s'], warmup_s=v['warmup_s'],
        corrupt_holdoff_s=v['corrupt_holdoff_s'],
        release_armed_on_start=v['release.armed_on_start'],
        release_overrides=rule_overrides(v),
        gripper_enabled=v['gripper.enabled'], gripper_topic=v['gripper.topic'].strip(),
        gripper_joint=v['gripper.joint'].strip(), gripper_position=v['gripper.position'],
        gripper_duration_s=v['gripper.duration_s'], executor_type=v['executor.type'],
        executor_poll_s=v['executor.poll_s'], executor_lazy_wrench=v['executor.lazy_wrench'],
        diagnostics_period_s=v['diagnostics.period_s'], log_throttle_s=v['log_throttle_s'])


#: Parameters every rclpy node has; a parameter file may set them for the node, and the
#: offline tools have no use for them.
RCLPY_PARAMS = ('use_sim_time', 'start_type_description_service', 'qos_overrides.*')


def read_param_file(path: Path) -> Dict[str, Any]:
    """
    Read the node's parameters from a ROS 2 parameter file and check them as the node does.

    Parameters
    ----------
    path : Path
        YAML file with a ``<node>: ros__parameters:`` section (see
        :func:`~contact_detector.io.node_params.read_node_params` for which sections count).

    Returns
    -------
    dict
        The parameters the file sets, flat (``'release.threshold'`` -> value), each checked
        (floats given as integers become floats); rclpy's own parameters are left out.

    Raises
    ------
    ConfigError
        The file cannot be read, names a parameter the node does not have (a typo), or a
        value the node would refuse at start-up (type, range, choices, or two parameters that
        contradict each other); the message names the file and the parameter.

    """
    given = {name: value for name, value in read_node_params(path).items()
             if not any(fnmatch.fnmatchcase(name, p) for p in RCLPY_PARAMS)}
    unknown = sorted(set(given) - set(PARAMS_BY_NAME))
    if unknown:
        raise ConfigError(f'{path}: {", ".join(unknown)}: not a parameter of the contact '
                          'detector node (a typo?)')
    try:
        config_from_values(given)
        return {name: check_value(name, value) for name, value in given.items()}
    except ConfigError as err:
        raise ConfigError(f'{path}: {err}') from err
