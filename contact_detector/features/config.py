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
Feature configuration: the contract between the feature core, the model file and the node.

A :class:`FeatureConfig` fully determines the feature vector computed for every audio frame.
It is stored inside every model bundle; loading a model refuses a configuration that differs
from the one the running code would use (see :mod:`contact_detector.model.storage`).
"""

from dataclasses import asdict, dataclass, fields, replace
import math
from typing import Any, Mapping, Sequence

from contact_detector.errors import ConfigError

#: Bump when the meaning of any feature changes (formula, bins, normalisation, alignment).
FEATURE_SCHEMA_VERSION = 1

#: The paper's seven features, in the order they appear in every feature vector.
PAPER_FEATURES = (
    'audio_power',
    'force_centroid',
    'force_spread',
    'force_flux',
    'torque_centroid',
    'torque_spread',
    'torque_flux',
)

#: Extra features beyond the paper, enabled by :attr:`FeatureConfig.extra_features`.
#: ``*_delta`` is the change of the F/T magnitude (mean of the newest ``delta_window`` samples
#: minus the mean of the ``delta_window`` samples ending ``delta_lag`` F/T samples earlier),
#: in N or N m; ``audio_power_rel_db`` is the audio power in dB above the tracked noise floor;
#: ``audio_peak_rel_db`` its maximum over the newest ``peak_frames`` audio frames (a recent
#: impact sound, while the F/T evidence of load transfer builds up); ``ft_delta_angle`` is
#: ``atan2(torque_delta, force_delta)`` in rad, whose tangent is the lever arm in m of the
#: change: the table pushes at the object's bottom, inertia and slosh act at its centre of mass
#: and knocks on the hand near the sensor. ``*_change`` and ``ft_change_angle`` are the same
#: against a robust baseline: the median of the ``baseline_window`` samples ending ``delta_lag``
#: samples earlier, so that a short knock does not come back 0.1 s later as an opposite change.
#: ``audio_rise_db`` is ``audio_power_rel_db`` minus its value ``rise_frames`` audio frames
#: earlier (dB; > 0 while a sound starts, < 0 while it decays) and ``audio_peak_gap_db`` is
#: ``audio_peak_rel_db - audio_power_rel_db`` (dB below the recent peak): together they tell a
#: sound that starts with the F/T change (the touch) from the tail of an earlier one (a knock
#: shortly before an F/T change that only looks like unloading). ``audio_hold_db`` is the
#: *minimum* of ``audio_power_rel_db`` over the newest ``audio_hold_frames`` audio frames
#: (fewer right after a start; dB): high only while a sound has lasted that long, as a
#: sustained scrape of a brush does and an impact click, which decays within tens of ms, does
#: not. ``force_change_max`` and
#: ``torque_change_max`` are the largest ``force_change`` / ``torque_change`` (N, N m) over the
#: newest ``change_max_frames`` F/T feature frames (fewer right after a start or gap): in the
#: early releases we looked at, a knock on the hand first pushed the load up and the rebound
#: that followed looked like unloading; a touch unloads without that push before it.
#: ``force_shift`` and ``torque_shift`` are the length of the change of the force (torque)
#: *vector*: ``|mean of the newest delta_window vectors - per-axis median of the
#: shift_window vectors ending shift_lag samples earlier|`` (N, N m). A length does not
#: depend on the sensor's orientation, on where gravity points in its frame, on its tare or on
#: the sign convention of the robot, and it grows whether the table takes the load or the arm
#: presses beyond it. ``*_shift_min`` is its minimum over the newest ``shift_min_frames`` F/T
#: feature frames (a *lasting* change: a knock's pulse and the ringing after it pass through
#: small values, a load transfer does not) and ``*_shift_max`` its maximum over the newest
#: ``change_max_frames`` frames. ``*_change_hold`` is the signed change that *held* over the
#: newest ``hold_frames`` F/T feature frames: their smallest ``*_change`` if all are > 0, their
#: largest if all are < 0, else 0 (N, N m); ``*_shift_hold`` the smallest ``*_shift`` over the
#: same frames. A knock's pulse falls back within a few frames, a step of the load does not.
#: ``*_shift_rel`` is ``*_shift`` divided by the length of the *carried* load, the per-axis
#: median of the first ``carried_window`` F/T samples after a start or an arming (floored at
#: ``carried_floor_force`` N / ``carried_floor_torque`` N m, so a tared sensor gives the plain
#: shift in those units); ``*_carried_cos`` is the cosine between the vector change and the
#: carried load (-1: the change takes the carried load off, as a table does on an untared
#: sensor; 0 for a change across it, and 0 when the carried load is below the floor).
#: ``ft_carried_lever`` is ``ln((torque_shift_rel + 0.02) / (force_shift_rel + 0.02))``: 0 when
#: the torque changed by the same fraction of the carried torque as the force of the carried
#: force, as when the table takes the weight off under the object's centre of mass; a push
#: nearer the sensor than the weight, or one with a sideways part, gives another value.
#: ``*_carried_shift`` is ``|mean of the newest delta_window vectors - carried load|`` (N, N m):
#: the whole change since the arming, which a slow transfer (a soft layer over 0.5 s) builds up
#: and the sliding ``*_shift`` baseline forgets; ``*_carried_shift_min`` its minimum over the
#: newest ``shift_min_frames`` F/T feature frames. Like the shifts, a length that does not
#: depend on how the sensor is mounted; a constant bias cancels, as the carried load is read by
#: the same sensor.
#: ``*_carried_shift_cos`` is the direction of that distance: the cosine between ``mean of the
#: newest delta_window vectors - carried load`` and the carried load (-1: the load came off,
#: as the table takes it off an untared sensor; 0 for a push across it, and 0 when the carried
#: load is below the floor or the distance is 0). Unlike ``*_carried_cos`` it describes the
#: whole change since the arming, not the newest one, so it does not turn with the noise once
#: a change has settled.
#: ``force_roughness`` is the root mean square of the force vector's second difference over
#: the newest ``rough_window`` F/T samples, ``sqrt(mean_k |F_k - 2 F_(k-1) + F_(k-2)|^2)`` (N):
#: 0 for a constant or a linearly changing force, the sensor noise at rest, more while
#: something rubs (stick-slip) or rings. ``force_roughness_rel`` divides it by the same value
#: ``shift_lag`` samples earlier (floored at 0.05 N): how much rougher the force has become,
#: whatever the sensor's noise and gain. A table that takes the load off changes it smoothly
#: once the first ring-down has passed; the arm brushing something changes it by a force that
#: fluctuates as it slips.
EXTRA_FEATURES = (
    'audio_power_rel_db',
    'audio_peak_rel_db',
    'audio_rise_db',
    'audio_peak_gap_db',
    'audio_hold_db',
    'force_delta',
    'torque_delta',
    'ft_delta_angle',
    'force_change',
    'torque_change',
    'ft_change_angle',
    'force_change_max',
    'torque_change_max',
    'force_shift',
    'torque_shift',
    'force_shift_min',
    'torque_shift_min',
    'force_shift_max',
    'torque_shift_max',
    'force_change_hold',
    'torque_change_hold',
    'force_shift_hold',
    'torque_shift_hold',
    'force_shift_rel',
    'torque_shift_rel',
    'force_carried_cos',
    'torque_carried_cos',
    'ft_carried_lever',
    'force_carried_shift',
    'torque_carried_shift',
    'force_carried_shift_min',
    'torque_carried_shift_min',
    'force_carried_shift_cos',
    'torque_carried_shift_cos',
    'force_roughness',
    'force_roughness_rel',
)

#: Features computed from the audio alone, in the order a pending frame stores them.
AUDIO_FEATURES = ('audio_power', 'audio_power_rel_db', 'audio_peak_rel_db', 'audio_rise_db',
                  'audio_peak_gap_db', 'audio_hold_db')

#: Extra features computed from changes of |F| and |T| (they need ``delta_lag`` of history).
DELTA_FEATURES = ('force_delta', 'torque_delta', 'ft_delta_angle', 'force_change',
                  'torque_change', 'ft_change_angle', 'force_change_max', 'torque_change_max',
                  'force_shift', 'torque_shift', 'force_shift_min', 'torque_shift_min',
                  'force_shift_max', 'torque_shift_max', 'force_change_hold',
                  'torque_change_hold', 'force_shift_hold', 'torque_shift_hold',
                  'force_shift_rel', 'torque_shift_rel', 'force_carried_cos',
                  'torque_carried_cos', 'ft_carried_lever', 'force_carried_shift',
                  'torque_carried_shift', 'force_carried_shift_min', 'torque_carried_shift_min',
                  'force_carried_shift_cos', 'torque_carried_shift_cos', 'force_roughness',
                  'force_roughness_rel')

#: The features that need the ``*_change`` values (against the baseline median).
CHANGE_FEATURES = ('force_change', 'torque_change', 'ft_change_angle', 'force_change_max',
                   'torque_change_max')

#: The features computed from the force and torque *vectors* (not their magnitudes): they do not
#: depend on how the sensor is oriented, on gravity's direction in its frame or on its tare.
SHIFT_FEATURES = ('force_shift', 'torque_shift', 'force_shift_min', 'torque_shift_min',
                  'force_shift_max', 'torque_shift_max')

#: The features that hold a change over the newest ``hold_frames`` F/T feature frames (they
#: need both the ``*_change`` and the ``*_shift`` values).
HOLD_FEATURES = ('force_change_hold', 'torque_change_hold', 'force_shift_hold',
                 'torque_shift_hold')

#: The features that compare the vector change with the load carried after a start or an
#: arming (they need the ``*_shift`` vector change and the carried load).
CARRIED_FEATURES = ('force_shift_rel', 'torque_shift_rel', 'force_carried_cos',
                    'torque_carried_cos')

#: The features computed from :data:`CARRIED_FEATURES` (they need the same carried load).
CARRIED_DERIVED = ('ft_carried_lever',)

#: The distance of the force (torque) vector from the load carried after a start or an arming,
#: and its smallest value over the newest ``shift_min_frames`` F/T feature frames: the whole
#: load transfer since the arming, however slowly it came (a guard's ``|F - F_rest|``).
CARRIED_SHIFT_FEATURES = ('force_carried_shift', 'torque_carried_shift',
                          'force_carried_shift_min', 'torque_carried_shift_min')

#: The direction of the distance from the carried load: the cosine between it and the carried
#: load (-1 when the load came off, 0 across it).
CARRIED_SHIFT_COS_FEATURES = ('force_carried_shift_cos', 'torque_carried_shift_cos')

#: The roughness of the force over the newest ``rough_window`` F/T samples, and against its
#: roughness ``shift_lag`` samples earlier (computed with the vector shifts).
ROUGH_FEATURES = ('force_roughness', 'force_roughness_rel')

#: Every feature that reads the torque: the paper's three torque columns, every extra
#: ``torque_*`` feature and the angles and lever arm that compare the torque with the force.
#: A configuration with ``torque=False`` has none of them.
TORQUE_FEATURES = (tuple(n for n in PAPER_FEATURES if n.startswith('torque_'))
                   + tuple(n for n in EXTRA_FEATURES if n.startswith('torque_'))
                   + ('ft_delta_angle', 'ft_change_angle', 'ft_carried_lever'))

#: Every feature that needs the carried load (measured after a start or an arming).
NEEDS_CARRIED = (CARRIED_FEATURES + CARRIED_DERIVED + CARRIED_SHIFT_FEATURES
                 + CARRIED_SHIFT_COS_FEATURES)

#: The column the load path of a decision rule reads: the distance of the force from the
#: carried load, N.
LOAD_FEATURE = 'force_carried_shift'

#: The column the load paths' direction gate reads: the cosine between the force's distance
#: from the carried load and the carried load.
LOAD_DIRECTION_FEATURE = 'force_carried_shift_cos'

#: The columns a decision rule reads beside P(contact), in :func:`ReleaseLogic.step`'s order
#: (``load``, ``load_cos``); a configuration that measures the carried load computes both.
RULE_FEATURES = (LOAD_FEATURE, LOAD_DIRECTION_FEATURE)

#: :attr:`FeatureConfig.carried_window`, ``carried_floor_force`` and ``carried_floor_torque``
#: when not given: left out of :meth:`FeatureConfig.to_dict` like ``hold_frames``. 50 samples
#: are the detector's 0.5 s warm-up at 100 Hz. The floors (0.5 N, 0.05 N m) are 2.5 and 3 times
#: the largest per-sample noise the simulator gives a sensor (0.2 N, 0.015 N m; a median of 50
#: samples of a tared sensor stays far below them) and under the weight of the lightest object
#: it carries (0.1 kg, ~1 N; its torque at 5 cm, ~0.05 N m): below them the carried load is
#: noise, not a load whose direction means something.
DEFAULT_CARRIED = {'carried_window': 50, 'carried_floor_force': 0.5,
                   'carried_floor_torque': 0.05}

#: :attr:`FeatureConfig.hold_frames` when not given: left out of :meth:`FeatureConfig.to_dict`
#: so configurations written before the field existed, and their model hashes, stay the same.
DEFAULT_HOLD_FRAMES = 4

#: :attr:`FeatureConfig.audio_hold_frames` when not given: 8 frames, 80 ms at the 10 ms hop.
#: A 32 ms frame holds a click for up to 4 hops, so a shorter hold can still see a click in
#: every frame; 8 frames see a click's decay too. Left out of :meth:`FeatureConfig.to_dict`
#: like ``hold_frames``, so older model hashes stay the same.
DEFAULT_AUDIO_HOLD_FRAMES = 8

#: :attr:`FeatureConfig.rough_window` when not given: 20 samples, 0.2 s at 100 Hz (a brush
#: lasts 0.15-0.6 s). Left out of :meth:`FeatureConfig.to_dict` like ``hold_frames``.
DEFAULT_ROUGH_WINDOW = 20

WINDOW_FUNCTIONS = ('rect', 'hann')
DETREND_MODES = ('none', 'mean')


@dataclass(frozen=True)
class FeatureConfig:
    """
    Everything that defines the per-audio-frame feature vector.

    Attributes
    ----------
    audio_frame_s : float
        Audio frame length in seconds. HARK's default 512 samples at 16 kHz = 0.032 s.
    audio_hop_s : float
        Audio hop in seconds. HARK's default 160 samples at 16 kHz = 0.010 s (100 frames/s).
    ft_rate_hz : float
        Rate in Hz at which F/T features are computed. Input at an integer multiple of it is
        block-averaged down (e.g. 1 kHz -> 100 Hz) so the features keep their meaning.
    ft_window : int
        DFT window length W_fL in F/T samples (at ``ft_rate_hz``). The paper uses 160.
    ft_hop : int
        F/T feature hop in samples. The paper uses 128; 1 updates at every F/T sample.
    ft_window_fn : str
        'rect' (no window, as pyAudioAnalysis and the paper) or 'hann'.
    ft_detrend : str
        'none' (the paper) or 'mean': subtract each window's mean before the DFT, so that the
        features do not depend on the static load (the object's weight).
    extra_features : tuple of str
        Names from :data:`EXTRA_FEATURES` appended after the paper's seven, in this order.
    delta_window : int
        F/T samples averaged on each side of a ``*_delta`` feature (and of the two changes
        behind ``ft_delta_angle``).
    delta_lag : int
        Distance in F/T samples between the two averages of a ``*_delta`` feature (and between
        the newest samples and the end of the baseline of a ``*_change`` feature).
    baseline_window : int
        F/T samples whose median is the baseline of a ``*_change`` feature.
    noise_floor_tau_s : float
        Time constant in seconds with which the audio noise floor rises (it falls at once).
    peak_frames : int
        Audio frames over which ``audio_peak_rel_db`` takes its maximum.
    rise_frames : int
        Distance in audio frames between the two values of ``audio_rise_db``.
    change_max_frames : int
        F/T feature frames (``ft_hop`` samples apart) over which ``force_change_max``,
        ``torque_change_max`` and ``*_shift_max`` take their maximum.
    shift_min_frames : int
        F/T feature frames over which ``force_shift_min`` and ``torque_shift_min`` take their
        minimum.
    shift_lag, shift_window : int
        The baseline of ``*_shift``: the per-axis median of ``shift_window`` F/T samples
        ending ``shift_lag`` samples before the newest. Longer than the ``*_change`` baseline,
        so that a load transfer of up to about ``(shift_lag + shift_window) / ft_rate_hz`` s is
        seen whole.
    audio : bool
        Whether the vector has audio columns. False: no ``audio_power`` column and no audio
        extra feature (refused); rows are then clocked by the F/T feature frames, one row per
        F/T feature frame, for robots without a microphone.
    torque : bool
        Whether the vector has torque columns. False: none of :data:`TORQUE_FEATURES` (the
        paper's three torque columns leave the vector, a torque extra feature is refused); the
        forest reads the force alone, whose changes do not depend on the lever arm of the
        contact (written by :meth:`to_dict` only when false).
    hold_frames : int
        F/T feature frames over which ``*_change_hold`` and ``*_shift_hold`` see whether a
        change held (default 4, 40 ms at 100 Hz; written by :meth:`to_dict` only when it
        differs).
    carried_window : int
        F/T samples (at ``ft_rate_hz``) after a start, a reset or an arming whose per-axis
        median is the carried load of ``*_shift_rel`` and ``*_carried_cos`` (default 50,
        0.5 s at 100 Hz: the warm-up).
    carried_floor_force, carried_floor_torque : float
        Smallest carried |F| in N and |T| in N m that counts as a load: ``*_shift_rel``
        divides by ``max(|carried|, floor)`` and ``*_carried_cos`` is 0 below it (defaults 0.5
        and 0.05; :data:`DEFAULT_CARRIED` says why). These three are written by
        :meth:`to_dict` only when they differ from their defaults.
    audio_hold_frames : int
        Audio frames over which ``audio_hold_db`` takes its minimum (default 8, 80 ms at the
        10 ms hop; written by :meth:`to_dict` only when it differs).
    rough_window : int
        F/T samples (at ``ft_rate_hz``) of second differences in ``force_roughness`` (default
        20, 0.2 s at 100 Hz; written by :meth:`to_dict` only when it differs).

    Notes
    -----
    Two named presets say where a configuration comes from: :meth:`paper` (the paper's
    160-sample F/T window every 128 samples, its seven features) and :meth:`shipped` (what the
    shipped model ``models/contact_forest.npz`` was trained with, the ``train`` command's
    defaults). The bare ``FeatureConfig()`` is neither: its field defaults are the base that
    the presets and :meth:`from_dict` fill in, the paper's seven features on a 0.32 s F/T
    window updated at every sample, and serve unit tests of the feature core. At run time the
    configuration comes from the model's card (``bundle.feature_config``), never from here.

    """

    audio_frame_s: float = 0.032
    audio_hop_s: float = 0.010
    ft_rate_hz: float = 100.0
    ft_window: int = 32
    ft_hop: int = 1
    ft_window_fn: str = 'rect'
    ft_detrend: str = 'none'
    extra_features: tuple = ()
    delta_window: int = 3
    delta_lag: int = 10
    baseline_window: int = 15
    noise_floor_tau_s: float = 2.0
    peak_frames: int = 10
    rise_frames: int = 2
    change_max_frames: int = 15
    shift_min_frames: int = 10
    shift_lag: int = 20
    shift_window: int = 40
    audio: bool = True
    torque: bool = True
    hold_frames: int = DEFAULT_HOLD_FRAMES
    carried_window: int = DEFAULT_CARRIED['carried_window']
    carried_floor_force: float = DEFAULT_CARRIED['carried_floor_force']
    carried_floor_torque: float = DEFAULT_CARRIED['carried_floor_torque']
    audio_hold_frames: int = DEFAULT_AUDIO_HOLD_FRAMES
    rough_window: int = DEFAULT_ROUGH_WINDOW

    def __post_init__(self) -> None:
        """Validate every field; raise :class:`ConfigError` naming the bad one."""
        object.__setattr__(self, 'extra_features', tuple(self.extra_features))
        positive = ('audio_frame_s', 'audio_hop_s', 'ft_rate_hz', 'noise_floor_tau_s',
                    'carried_floor_force', 'carried_floor_torque')
        for name in positive:
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ConfigError(f'FeatureConfig.{name} must be a finite number > 0, '
                                  f'got {value!r}')
        for name, low in (('ft_window', 4), ('ft_hop', 1), ('delta_window', 1),
                          ('delta_lag', 1), ('baseline_window', 1), ('peak_frames', 1),
                          ('rise_frames', 1), ('change_max_frames', 1),
                          ('shift_min_frames', 1), ('shift_lag', 1), ('shift_window', 1),
                          ('hold_frames', 1), ('carried_window', 1),
                          ('audio_hold_frames', 1), ('rough_window', 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ConfigError(f'FeatureConfig.{name} must be an int >= {low}, got {value!r}')
        if self.audio_hop_s > self.audio_frame_s:
            raise ConfigError('FeatureConfig.audio_hop_s must not exceed audio_frame_s '
                              f'({self.audio_hop_s} > {self.audio_frame_s})')
        if self.ft_window_fn not in WINDOW_FUNCTIONS:
            raise ConfigError(f'FeatureConfig.ft_window_fn must be one of {WINDOW_FUNCTIONS}, '
                              f'got {self.ft_window_fn!r}')
        if self.ft_detrend not in DETREND_MODES:
            raise ConfigError(f'FeatureConfig.ft_detrend must be one of {DETREND_MODES}, '
                              f'got {self.ft_detrend!r}')
        unknown = [n for n in self.extra_features if n not in EXTRA_FEATURES]
        if unknown or len(set(self.extra_features)) != len(self.extra_features):
            raise ConfigError(f'FeatureConfig.extra_features must be distinct names from '
                              f'{EXTRA_FEATURES}, got {self.extra_features!r}')
        if not isinstance(self.audio, bool):
            raise ConfigError(f'FeatureConfig.audio must be true or false, got {self.audio!r}')
        if not isinstance(self.torque, bool):
            raise ConfigError(f'FeatureConfig.torque must be true or false, got {self.torque!r}')
        torque_extra = [n for n in self.extra_features if n in TORQUE_FEATURES]
        if not self.torque and torque_extra:
            raise ConfigError(f'FeatureConfig.torque is false (a force-only model) but '
                              f'extra_features has the torque features {torque_extra}')
        audio_extra = [n for n in self.extra_features if n in AUDIO_FEATURES]
        if not self.audio and audio_extra:
            raise ConfigError(f'FeatureConfig.audio is false (an F/T-only model) but '
                              f'extra_features has the audio features {audio_extra}')

    @classmethod
    def paper(cls) -> 'FeatureConfig':
        """
        Return the paper's configuration (arXiv 2012.01583, section 4.2).

        Audio frames of 512 samples every 160 at 16 kHz (0.032 s / 0.010 s); the F/T DFT over
        ``ft_window = 160`` samples every ``ft_hop = 128``, rectangular window, no detrending;
        the seven features of :data:`PAPER_FEATURES` and no extra ones.
        """
        return cls(audio_frame_s=0.032, audio_hop_s=0.010, ft_window=160, ft_hop=128,
                   ft_window_fn='rect', ft_detrend='none', extra_features=())

    @classmethod
    def shipped(cls) -> 'FeatureConfig':
        """
        Return the configuration of the shipped model, the defaults of ``contact-detector train``.

        Chosen by leave-one-family-out (docs/generalisation.md): a 0.64 s F/T window updated
        at every sample with its mean removed; audio loudness relative to the room (dB above
        the noise floor, its recent peak, rise and gap); the change of |F| and |T| against a
        median baseline and its recent maximum; the orientation- and tare-free length of the
        force and torque vector change with its 0.1 s minimum and 0.5 s maximum; that change
        against the load carried at the start or arming (its size as a fraction of that load,
        and the cosine between the two). The shipped
        model's card holds the same configuration (a test checks it).
        """
        return cls(ft_window=64, ft_hop=1, ft_detrend='mean', delta_window=1, delta_lag=5,
                   rise_frames=2, change_max_frames=50, shift_min_frames=10, shift_lag=20,
                   shift_window=40,
                   extra_features=('audio_power_rel_db', 'audio_peak_rel_db', 'audio_rise_db',
                                   'audio_peak_gap_db', 'force_change', 'torque_change',
                                   'force_change_max', 'torque_change_max', 'force_shift',
                                   'torque_shift', 'force_shift_min', 'torque_shift_min',
                                   'force_shift_max', 'torque_shift_max', 'force_shift_rel',
                                   'torque_shift_rel', 'force_carried_cos',
                                   'torque_carried_cos'))

    @property
    def feature_names(self) -> tuple:
        """
        Names of the feature vector's columns, in order.

        The paper's seven, without ``audio_power`` if F/T-only and without the torque columns
        if ``torque`` is false, then the extra features.
        """
        paper = tuple(n for n in PAPER_FEATURES
                      if (self.audio or n != 'audio_power')
                      and (self.torque or n not in TORQUE_FEATURES))
        return paper + self.extra_features

    @property
    def measures_carried(self) -> bool:
        """Return True when a column needs the carried load (:data:`NEEDS_CARRIED`)."""
        return any(name in NEEDS_CARRIED for name in self.extra_features)

    def with_extra(self, names: Sequence[str]) -> 'FeatureConfig':
        """
        Return this configuration with the extra features ``names`` appended where missing.

        The columns of ``self`` keep their places, first; the added ones follow in the order
        given. The detector computes a column the release rule reads (``force_carried_shift``,
        the load path of :class:`~contact_detector.model.rule.DecisionRule`) this way, without
        handing it to a forest that was not trained with it.
        """
        added = tuple(name for name in names if name not in self.extra_features)
        return replace(self, extra_features=self.extra_features + added) if added else self

    def with_rule_columns(self) -> 'FeatureConfig':
        """
        Return this configuration with the columns a decision rule reads, where it can have them.

        A configuration that measures the carried load gets :data:`RULE_FEATURES` appended
        (:meth:`with_extra`): the load paths' distance from the carried load and its direction.
        One without the carried load is returned as it is; a rule with a load path is refused
        for it where the rule is checked.
        """
        return self.with_extra(RULE_FEATURES) if self.measures_carried else self

    @property
    def n_features(self) -> int:
        """Length of the feature vector."""
        return len(self.feature_names)

    @property
    def ft_only(self) -> bool:
        """Return True when no column comes from the audio (frames clocked by the F/T stream)."""
        return not self.audio

    def audio_frame_samples(self, sample_rate: float) -> int:
        """
        Audio frame length W_L in samples at ``sample_rate``: ``round(audio_frame_s * rate)``.

        16 kHz -> 512, 44.1 kHz -> 1411, 48 kHz -> 1536 with the default 32 ms.
        """
        return max(1, int(math.floor(self.audio_frame_s * sample_rate + 0.5)))

    def to_dict(self) -> dict:
        """Plain-JSON form, stored in model bundles and cards."""
        data = asdict(self)
        data['extra_features'] = list(self.extra_features)
        if self.audio:
            # Configs written before the field existed, and their model hashes, stay the same.
            del data['audio']
        if self.torque:
            del data['torque']
        if self.hold_frames == DEFAULT_HOLD_FRAMES:
            del data['hold_frames']
        if self.audio_hold_frames == DEFAULT_AUDIO_HOLD_FRAMES:
            del data['audio_hold_frames']
        if self.rough_window == DEFAULT_ROUGH_WINDOW:
            del data['rough_window']
        for name, default in DEFAULT_CARRIED.items():
            if data[name] == default:
                del data[name]
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> 'FeatureConfig':
        """Inverse of :meth:`to_dict`; unknown keys are a :class:`ConfigError`."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ConfigError(f'unknown FeatureConfig keys: {unknown}')
        try:
            return cls(**dict(data))
        except TypeError as err:
            raise ConfigError(f'invalid FeatureConfig: {err}') from err
