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
F/T samples reading exactly zero: a driver's placeholder after a load, a reading near zero.

A driver that loses a reading often publishes a zero wrench (or a zeroed force or torque)
instead. After a load, the jump to nothing and back is the shape of a contact taking the load
off, so :class:`ForceTorqueStream` leaves such samples out: the features are those of the
recording without them, on every path (one sample per call, any batch). Exact zeros among
readings near zero (a quantised sensor zeroed while idle) are readings and stay.
"""

from contact_detector.features.config import CARRIED_FEATURES, FeatureConfig, SHIFT_FEATURES
from contact_detector.features.force_torque import ForceTorqueStream
import numpy as np
import pytest

CONFIG = FeatureConfig(audio=False, ft_window=64, ft_detrend='mean', delta_window=1,
                       extra_features=SHIFT_FEATURES + CARRIED_FEATURES)
RATE = 100.0
T0 = 1_700_000_000.0


def _held(*, n: int = 400, load_n: float = 5.0, seed: int = 3) -> tuple:
    """Return stamps (n,) and samples (n, 6) of a hand holding ``load_n`` N along -z."""
    rng = np.random.default_rng(seed)
    values = np.hstack([rng.normal(scale=0.02, size=(n, 3)),
                        rng.normal(scale=0.002, size=(n, 3))])
    values[:, 2] -= load_n
    return T0 + np.arange(n) / RATE, values


def _push(stream: ForceTorqueStream, t, values, *, chunk: int):
    out_t, out_x = [], []
    for lo in range(0, t.size, chunk):
        ft_t, ft_x = stream.push(t=t[lo:lo + chunk], force=values[lo:lo + chunk, :3],
                                 torque=values[lo:lo + chunk, 3:])
        out_t.append(ft_t)
        out_x.append(ft_x)
    return np.concatenate(out_t), np.concatenate(out_x)


@pytest.mark.parametrize('chunk', [1, 7, 400])
def test_zeros_after_a_load_are_left_out_on_every_path(chunk):
    t, values = _held()
    dropout = np.zeros(values.shape[0], dtype=bool)
    dropout[150:153] = True         # 30 ms: interpolated over
    dropout[250:262] = True         # 120 ms: the window restarts
    broken = values.copy()
    broken[dropout] = 0.0
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    got_t, got_x = _push(stream, t, broken, chunk=chunk)
    assert stream.placeholders == 15
    clean = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    want_t, want_x = _push(clean, t[~dropout], values[~dropout], chunk=1)
    assert got_t.size == want_t.size > 0
    np.testing.assert_array_equal(got_t, want_t)
    np.testing.assert_array_equal(got_x, want_x)
    assert stream.restarts == clean.restarts == 1


def test_exact_zeros_among_readings_near_zero_are_readings():
    # a sensor zeroed with the empty hand and quantised to 0.1 N, idle: zeros are its readings
    t, values = _held(load_n=0.0)
    quantised = np.round(values / 0.1) * 0.1
    assert (~quantised.any(axis=1)).sum() > 100
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    _push(stream, t, quantised, chunk=1)
    assert stream.placeholders == 0
    # then a load: zeros from now on are placeholders
    stream.push(t=np.array([t[-1] + 0.01]), force=np.array([[0.0, 0.0, -5.0]]),
                torque=np.zeros((1, 3)))
    stream.push(t=np.array([t[-1] + 0.02]), force=np.zeros((1, 3)), torque=np.zeros((1, 3)))
    assert stream.placeholders == 1


@pytest.mark.parametrize('half', [slice(0, 3), slice(3, 6)])
def test_a_zeroed_force_or_torque_after_a_load_is_a_placeholder(half):
    t, values = _held()
    values[:, 3] += 0.4                 # a torque above its floor too (0.05 N m)
    broken = values.copy()
    broken[200:210, half] = 0.0
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    got = _push(stream, t, broken, chunk=1)
    assert stream.placeholders == 10
    keep = np.ones(t.size, dtype=bool)
    keep[200:210] = False
    want = _push(ForceTorqueStream(config=CONFIG, input_rate=RATE), t[keep], values[keep],
                 chunk=400)
    np.testing.assert_array_equal(got[1], want[1])


def test_a_torque_that_was_always_zero_is_a_reading():
    # a driver without torque: its torque is (0, 0, 0) from the start, never after a load
    t, values = _held()
    values[:, 3:] = 0.0
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    _push(stream, t, values, chunk=1)
    assert stream.placeholders == 0


def test_a_torque_alone_counts_as_a_load():
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    rows = np.array([[0.0, 0.0, 0.1, 0.0, 0.3, 0.0], [0.0] * 6, [0.0] * 6])
    stream.push(t=T0 + np.arange(3) / RATE, force=rows[:, :3], torque=rows[:, 3:])
    assert stream.placeholders == 2


def test_a_zero_at_the_start_is_a_reading_and_a_reset_keeps_what_came_before():
    # nothing before it: a reading (a sensor zeroed while idle starts so); a stream reset (a
    # time jump, a new zero) does not change what the sensor last read
    stream = ForceTorqueStream(config=CONFIG, input_rate=RATE)
    stream.push(t=np.array([T0]), force=np.zeros((1, 3)), torque=np.zeros((1, 3)))
    assert stream.placeholders == 0
    stream.push(t=np.array([T0 + 0.01]), force=np.array([[0.0, 0.0, -5.0]]),
                torque=np.zeros((1, 3)))
    stream.reset()
    frames = stream.push(t=np.array([T0 + 0.02]), force=np.zeros((1, 3)),
                         torque=np.zeros((1, 3)))
    assert stream.placeholders == 1 and frames[0].size == 0
    assert stream.last_input_t is None         # the left-out sample is not a stamp either
