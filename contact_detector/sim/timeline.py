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
When the arm moves in a simulated trial: the phases' times and the velocity ramps between them.

Times are seconds relative to the trial start. :func:`approach_timeline` plans everything up to
the first contact; :func:`stop_timeline` adds the stop, settle and retreat once the robot's stop
rule has fired.
"""

from dataclasses import dataclass, replace

from contact_detector.sim.params import FamilyParams, TrialParams
from contact_detector.sim.signals import ramp_pos

#: The stop rule's baseline is the mean T_y over this many seconds before the descent starts.
BASELINE_WINDOW_S = 0.3
#: Fastest retreat to the start position, m/s.
MAX_RETREAT_SPEED = 0.1


@dataclass(frozen=True)
class Timeline:
    """
    The times of a trial's motion, seconds from its start.

    Attributes
    ----------
    t_lift0, t_hold0, t_acc0, t_desc0 : float
        Start of the lift, the hold at the start position, the acceleration and the
        constant-speed descent.
    onset : float
        First contact of the object with the table.
    z_contact : float
        Height of the hand at the onset relative to its rest height, m.
    descent_dist : float
        Distance from the start position down to the contact, m.
    v_c : float
        Speed at contact, m/s.
    t_s, t_r0, t_r1, end : float or None
        The arm stops, the retreat starts and ends, the trial ends (None before the stop is
        known).
    v_r, push_depth, retreat_s : float or None
        Retreat speed in m/s, depth pushed after the contact in m, retreat duration in s.

    """

    t_lift0: float
    t_hold0: float
    t_acc0: float
    t_desc0: float
    onset: float
    z_contact: float
    descent_dist: float
    v_c: float
    t_s: float | None = None
    t_r0: float | None = None
    t_r1: float | None = None
    v_r: float | None = None
    push_depth: float | None = None
    end: float | None = None
    retreat_s: float | None = None


def approach_timeline(*, p: TrialParams, q: FamilyParams) -> tuple[Timeline, list]:
    """
    Timeline and velocity ramps up to the first contact.

    Returns
    -------
    (Timeline, list of (dv, t0, d))
        The times before the stop, and the ramps of the lift, the hold and the descent (with
        the slow-down of a decelerating approach).

    """
    v_d = p.descent_speed_mps
    t_lift0 = p.rest_start_s
    ra = 0.25 * p.lift_s
    v_l = p.lift_dist_m / (p.lift_s - ra)
    t_hold0 = t_lift0 + p.lift_s
    t_acc0 = t_hold0 + p.hold_s
    t_desc0 = t_acc0 + p.accel_s
    onset = t_desc0 + p.descend_s
    base_ramps = [(v_l, t_lift0, ra), (-v_l, t_hold0 - ra, ra), (-v_d, t_acc0, p.accel_s)]
    v_c = v_d
    if q.decel:
        # a careful controller slows down to v_c before the expected table height
        v_c = min(v_d, max(0.005, v_d * q.decel_ratio))
        dec_s = min(q.decel_s, p.descend_s - 0.2)
        base_ramps.append((v_d - v_c, onset - 0.05 - dec_s, dec_s))
    z_contact = ramp_pos(base_ramps, onset)
    descent_dist = v_d * (0.5 * p.accel_s + p.descend_s)
    if q.decel:
        descent_dist = p.lift_dist_m - z_contact
    tl = Timeline(t_lift0=t_lift0, t_hold0=t_hold0, t_acc0=t_acc0, t_desc0=t_desc0,
                  onset=onset, z_contact=z_contact, descent_dist=descent_dist, v_c=v_c)
    return tl, base_ramps


def stop_timeline(*, p: TrialParams, tl: Timeline, base_ramps: list,
                  stop_rel: float) -> tuple[list, Timeline]:
    """Ramps and timeline after the stop rule fired at ``stop_rel`` (relative seconds)."""
    v_d = tl.v_c
    t_s = stop_rel + p.stop_latency_s
    t_r0 = t_s + p.stop_decel_s + p.settle_s
    push_depth = v_d * (t_s - tl.onset) + 0.5 * v_d * p.stop_decel_s
    dist = tl.descent_dist + push_depth
    rr = p.retreat_ramp_s
    # retreat no faster than MAX_RETREAT_SPEED: a long descent takes longer to undo
    retreat_s = max(p.retreat_s, dist / MAX_RETREAT_SPEED + rr)
    v_r = dist / (retreat_s - rr)
    ramps = base_ramps + [(v_d, t_s, p.stop_decel_s),
                          (v_r, t_r0, rr), (-v_r, t_r0 + retreat_s - rr, rr)]
    return ramps, replace(tl, t_s=t_s, t_r0=t_r0, t_r1=t_r0 + retreat_s, v_r=v_r,
                          push_depth=push_depth, end=t_r0 + retreat_s + p.rest_end_s,
                          retreat_s=retreat_s)
