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

"""Optional gripper adapter: the JointTrajectory that opens the gripper on a release."""

import math

from builtin_interfaces.msg import Duration
from contact_detector.errors import ConfigError
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

#: The HSR's gripper: joint ``hand_motor_joint`` opens at 1.2 rad.
HSR_GRIPPER_JOINT = 'hand_motor_joint'
HSR_GRIPPER_OPEN_RAD = 1.2


def open_gripper_trajectory(*, joint: str = HSR_GRIPPER_JOINT,
                            position: float = HSR_GRIPPER_OPEN_RAD,
                            duration_s: float = 0.5) -> JointTrajectory:
    """
    Build a one-point trajectory that moves ``joint`` to ``position``.

    Parameters
    ----------
    joint : str
        Joint name.
    position : float
        Target position, rad (or m for a prismatic joint).
    duration_s : float
        ``time_from_start`` of the point, s, >= 0.

    Returns
    -------
    trajectory_msgs.msg.JointTrajectory
        Header stamp left zero: controllers start a zero-stamped trajectory at once.

    """
    if not joint:
        raise ConfigError('gripper joint name must not be empty')
    if not (math.isfinite(position) and math.isfinite(duration_s) and duration_s >= 0):
        raise ConfigError(f'gripper position {position!r} and duration {duration_s!r} must be '
                          'finite, the duration >= 0')
    sec = int(math.floor(duration_s))
    nanosec = min(999_999_999, int(round((duration_s - sec) * 1e9)))
    point = JointTrajectoryPoint(positions=[float(position)],
                                 time_from_start=Duration(sec=sec, nanosec=nanosec))
    return JointTrajectory(joint_names=[joint], points=[point])
