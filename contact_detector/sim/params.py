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
Typed values of one simulated trial: the drawn parameters and the family parameters.

:class:`TrialParams` holds one value per parameter of
:data:`contact_detector.sim.conditions.PAPER_RANGES` (their meaning and ranges are documented
there and in docs/simulator.md); :class:`FamilyParams` one per family parameter, its defaults
being what the six original condition sets use. Both are frozen: a trial's synthesis reads them
and never changes them. ``as_dict()`` gives the JSON form stored in the manifest
(``Trial.params`` and its ``'family'`` entry).
"""

from dataclasses import dataclass, fields
from typing import Mapping

from contact_detector.errors import ConfigError


def _as_dict(values: object, names: list[str]) -> dict:
    # tuples become lists, as JSON stores them
    out = {}
    for name in names:
        value = getattr(values, name)
        out[name] = list(value) if isinstance(value, tuple) else value
    return out


@dataclass(frozen=True)
class TrialParams:
    """
    The randomised parameters of one trial, drawn by a condition set.

    Units are in the names' suffixes (``_s`` seconds, ``_hz``, ``_m``, ``_mps`` m/s, ``_kg``,
    ``_n`` newton, ``_nm`` newton metre, ``_npm`` N/m, ``_fs`` fraction of int16 full scale,
    ``_deg``, ``_db``, ``_lsb`` int16 steps).
    """

    # --- timeline (durations of the phases) ---
    rest_start_s: float
    lift_s: float
    lift_dist_m: float
    hold_s: float
    accel_s: float
    descent_speed_mps: float
    descend_s: float
    stop_latency_s: float
    stop_decel_s: float
    settle_s: float
    retreat_s: float
    retreat_ramp_s: float
    rest_end_s: float
    # --- object and hand ---
    object_mass_kg: float
    liquid_mass_kg: float
    hand_mass_kg: float
    lever_arm_m: float
    contact_lever_offset_m: float
    com_offset_m: float
    object_height_m: float
    hand_lever_m: float
    tilt_deg: float
    slosh_hz: float
    slosh_zeta: float
    # --- arm ---
    mode_hz: float
    mode_zeta: float
    jerk_gain: float
    arm_stiffness_npm: float
    ripple_hz: float
    ripple_n: float
    impact_transmission: float
    # --- F/T sensor ---
    force_noise_n: float
    torque_noise_nm: float
    force_quant_n: float
    torque_quant_nm: float
    force_bias_n: float
    torque_bias_nm: float
    force_drift_n: float
    torque_drift_nm: float
    ft_latency_s: float
    # --- surface ---
    surface: str
    surface_stiffness_npm: float
    contact_tau_s: float
    impact_duration_s: float
    friction: float
    creep: float
    hardness: float
    brightness: float
    table_modes_hz: tuple[float, float]
    table_decay_s: float
    # --- audio ---
    contact_amp_fs: float
    glass_decay_s: float
    bounce: bool
    mic_distance_m: float
    bg_rms_fs: float
    hum_hz: float
    hum_rms_fs: float
    fan_rms_fs: float
    babble_rms_fs: float
    clatter_per_s: float
    whine_hz: float
    whine_rms_fs: float
    ego_broad_rms_fs: float
    mic_gain: float
    agc_depth_db: float
    agc_hz: float
    mic_dc_lsb: float
    # --- chunking ---
    chunking: str
    jitter_max_s: float
    # --- exogenous impacts ---
    hit_count: int
    hand_hit_amp_fs: float
    hand_hit_force_n: float
    table_hit_amp_fs: float
    table_hit_vib_n: float

    @classmethod
    def from_mapping(cls, values: Mapping[str, object]) -> 'TrialParams':
        """
        Build the parameters from ``{name: value}`` (every parameter, no other name).

        Raises
        ------
        ConfigError
            A parameter is missing or unknown.

        """
        names = {f.name for f in fields(cls)}
        missing, unknown = names - set(values), set(values) - names
        if missing or unknown:
            raise ConfigError(f'trial parameters: missing {sorted(missing)}, '
                              f'unknown {sorted(unknown)}')
        return cls(**{name: tuple(v) if isinstance(v, list) else v
                      for name, v in values.items()})

    def as_dict(self) -> dict:
        """Return ``{name: value}`` in sorted name order (tuples as lists)."""
        return _as_dict(self, sorted(f.name for f in fields(self)))


@dataclass(frozen=True)
class FamilyParams:
    """
    The family parameters of one trial: the structure of the robot, the sensor and the room.

    A condition set draws some of them (:attr:`ConditionSet.family
    <contact_detector.sim.conditions.ConditionSet.family>`); the others keep these defaults,
    which reproduce the recorded robot.
    """

    frame: str = 'hsr'  # 'hsr' (hand along +z, up ~ -x), 'axis', 'random'
    contact_lever_m: float = 0.0  # |sensor -> contact point| (frames 'axis' / 'random')
    tared: bool = False  # bias = -(load measured at rest before the lift)
    tool_compensated: bool = False  # the driver removes the hand's static weight
    stop_rule: str = 'torque_y'  # 'torque_y', 'force', 'wrench' (force or torque), 'load'
    stop_force_n: float = 0.0  # |F - F_base| threshold ('force', 'wrench')
    stop_torque_nm: float = 3.0  # |T - T_base| threshold ('wrench')
    stop_load_frac: float = 1.0  # 'load': |F - F_base| >= frac * object weight
    contact_model: str = 'lag'  # 'lag' (first-order), 'spring' (N = k depth), 'compliant'
    transfer_s: float = 0.0  # 'compliant': time for the weight to move to the table
    decel: bool = False  # the approach slows down towards the table
    decel_ratio: float = 1.0  # contact speed / descent speed when decelerating
    decel_s: float = 0.0  # duration of the slow-down ramp
    # the events below happen only with hits 'touch', 'brush', 'setdown' or 'mixed'
    touch_force_n: float = 4.0  # a person touching / pushing the object or the arm
    touch_s: float = 0.3
    brush_force_n: float = 2.0  # the arm brushing something while it moves
    brush_s: float = 0.4
    brush_amp_fs: float = 0.02
    setdown_amp_fs: float = 0.1  # another object set down on the table
    setdown_vib_n: float = 0.02
    mic_mode: str = 'normal'  # 'normal' or 'noise_only' (the mic hears only the room)
    contact_sound_db: float = 0.0  # contact sound level change
    ego_family: str = 'motor'  # 'motor' (whine + broadband), 'fan', 'gear', 'servo'
    ego_extra_rms_fs: float = 0.0  # level of the extra ego-noise family
    push_horizon_s: float = 6.0  # longest push searched for the stop
    # 'real': contact, knocks, room and ego noise are recordings (contact_detector.sim.sound_bank)
    sound_source: str = 'synthetic'
    real_room_rms_fs: float = 0.0  # level of the recorded room background
    real_ego_rms_fs: float = 0.0  # level of the recorded drive noise at full speed

    def as_dict(self) -> dict:
        """Return ``{name: value}`` in the order of the fields above."""
        return _as_dict(self, [f.name for f in fields(self)])
