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
The carried load: what the hand holds when the release is armed, and whether it held still.

The carried-load features (``*_shift_rel``, ``*_carried_cos``,
:func:`~contact_detector.features.deltas.relative_to_carried`) compare every later load change
with the per-axis median of the first ``carried_window`` F/T samples after a start or an
arming. That median is only the object's load if the hand held the object still meanwhile;
:func:`measure_carried_load` also says how far the load moved during the measurement, so the
node and ``detect`` can warn about an arming during a grasp, a lift or a knock.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CarriedLoad:
    """
    One measurement of the carried load.

    Attributes
    ----------
    load : np.ndarray, shape (6,)
        Per-axis median of the samples: force x, y, z in N, torque x, y, z in N m.
    moved : np.ndarray, shape (2,)
        ``|median(second half) - median(first half)|`` of the force (N) and of the torque
        (N m) vectors: how far the load moved while it was measured.
    floor : np.ndarray, shape (2,)
        The smallest |F| (N) and |T| (N m) that counts as a load.
    samples : int
        How many F/T samples (at the feature rate) the median is over.

    """

    load: np.ndarray
    moved: np.ndarray
    floor: np.ndarray
    samples: int

    @property
    def force_n(self) -> float:
        """Length of the carried force, N."""
        return float(np.linalg.norm(self.load[:3]))

    @property
    def torque_nm(self) -> float:
        """Length of the carried torque, N m."""
        return float(np.linalg.norm(self.load[3:]))

    @property
    def below_floor(self) -> bool:
        """Whether the carried force is below its floor: a tared sensor, or an empty hand."""
        return self.force_n < float(self.floor[0])

    @property
    def steady(self) -> bool:
        """Whether the load moved by less than the floors while it was measured."""
        return bool(np.all(self.moved <= self.floor))

    @property
    def status(self) -> str:
        """One word for /diagnostics: ``moved``, ``below-floor`` or ``steady``."""
        return 'moved' if not self.steady else 'below-floor' if self.below_floor else 'steady'

    def describe(self) -> str:
        """
        Return one log line: the load, and why it cannot be trusted if it cannot.

        The caller adds the remedy: the node's is to arm again (``~/arm``) while the hand holds
        the object still; a recording's, to start with the object held still.
        """
        text = (f'carried load measured over {self.samples} F/T samples: '
                f'|F| {self.force_n:.2f} N, |T| {self.torque_nm:.3f} N m')
        if not self.steady:
            return (text + f'; it moved by {self.moved[0]:.2f} N / {self.moved[1]:.3f} N m '
                    'while it was measured, so the carried-load features compare load '
                    'changes with the wrong load')
        if self.below_floor:
            # the cost and the remedy: with the load tared away a slow contact looks like a
            # push from nothing (docs/node.md has the figures)
            return (text + f'; below {self.floor[0]:g} N, read as a tared sensor (the '
                    'carried-load cosines are 0; an untared sensor reads this with an empty '
                    'hand). A sensor tared while the hand holds the object costs slow '
                    'contacts: they are released later or not at all; zero it with the '
                    'empty hand instead if the robot can')
        return text


def measure_carried_load(*, rows: np.ndarray, floor: np.ndarray) -> CarriedLoad:
    """
    Measure the carried load from F/T samples.

    ``load = median(rows, axis=0)``; ``moved = |median(second half) - median(first half)|``
    over the force and the torque vectors (the halves split at ``n // 2``).

    Parameters
    ----------
    rows : np.ndarray, shape (n, 6)
        F/T samples at the feature rate, n >= 1: force x, y, z in N, torque in N m.
    floor : np.ndarray, shape (2,)
        The smallest |F| (N) and |T| (N m) that counts as a load.

    Returns
    -------
    CarriedLoad

    """
    rows = np.asarray(rows, dtype=np.float64)
    half = rows.shape[0] // 2
    if half:
        step = np.median(rows[half:], axis=0) - np.median(rows[:half], axis=0)
        moved = np.array([np.linalg.norm(step[:3]), np.linalg.norm(step[3:])])
    else:
        moved = np.zeros(2)
    return CarriedLoad(load=np.median(rows, axis=0), moved=moved,
                       floor=np.asarray(floor, dtype=np.float64), samples=int(rows.shape[0]))
