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

"""The carried-load measurement: the load, and whether it held still while it was measured."""

from contact_detector.features.carried import measure_carried_load
import numpy as np
import pytest

FLOOR = np.array([0.5, 0.05])


def _held(n: int = 50, *, weight_n: float = 6.0, seed: int = 0) -> np.ndarray:
    """``n`` samples of a hand holding ``weight_n`` still (gravity along -z, 10 cm lever)."""
    rng = np.random.default_rng(seed)
    rows = np.zeros((n, 6))
    rows[:, 2] = -weight_n
    rows[:, 3] = 0.1 * weight_n
    return rows + rng.normal(scale=[0.05] * 3 + [0.005] * 3, size=(n, 6))


def test_a_hand_holding_still_is_steady_whatever_the_sensor_frame():
    rows = _held()
    c, angle = np.cos(0.9), np.sin(0.9)
    rot = np.array([[c, -angle, 0], [angle, c, 0], [0, 0, 1]]) @ np.array(
        [[1, 0, 0], [0, c, -angle], [0, angle, c]])
    rotated = np.hstack([rows[:, :3] @ rot.T, rows[:, 3:] @ rot.T])
    for got in (measure_carried_load(rows=rows, floor=FLOOR),
                measure_carried_load(rows=rotated, floor=FLOOR)):
        assert got.force_n == pytest.approx(6.0, abs=0.05)
        assert got.torque_nm == pytest.approx(0.6, abs=0.005)
        assert got.steady and not got.below_floor and got.status == 'steady'
        assert 'moved' not in got.describe()


def test_a_knock_during_the_measurement_does_not_move_it():
    # a 30 ms knock of 15 N: the medians ignore it, the hand still holds the same load
    rows = _held()
    rows[20:23, :3] += [15.0, 0.0, 5.0]
    got = measure_carried_load(rows=rows, floor=FLOOR)
    assert got.steady and got.force_n == pytest.approx(6.0, abs=0.1)


def test_a_grasp_during_the_measurement_has_moved():
    # armed while the hand still closes on the object: 0 N, then the 6 N object
    rows = _held()
    rows[:25, :3] = _held(25, weight_n=0.0)[:, :3]
    rows[:25, 3:] = 0.0
    got = measure_carried_load(rows=rows, floor=FLOOR)
    assert not got.steady and got.status == 'moved'
    assert got.moved[0] == pytest.approx(6.0, abs=0.1)
    assert 'moved by 6.0' in got.describe()


def test_a_tared_sensor_or_an_empty_hand_is_below_the_floor():
    got = measure_carried_load(rows=_held(weight_n=0.0), floor=FLOOR)
    assert got.below_floor and got.steady and got.status == 'below-floor'
    # the line says what a tare costs and what to do about it
    assert 'read as a tared sensor' in got.describe()
    assert 'zero it with the empty hand' in got.describe()


def test_the_load_is_the_per_axis_median_the_features_use():
    rows = _held(seed=3)
    assert np.array_equal(measure_carried_load(rows=rows, floor=FLOOR).load,
                          np.median(rows, axis=0))
