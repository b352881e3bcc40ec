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

"""Wrench streams for detector tests: an object held still, sent one sample per message."""

from typing import List, Tuple

from contact_detector.io.sensor_stream import WrenchEvent
import numpy as np


def held_load(*, seconds: float, rate: float, t0: float,
              seed: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return ``(t, force, torque)``: 5 N held along -z with sensor noise.

    ``t`` in s, shape (n,), ``n = int(seconds * rate)`` samples from ``t0``; ``force`` (N) and
    ``torque`` (N m), shape (n, 3), Gaussian noise of 0.02 N and 0.002 N m per axis (from
    ``seed``) plus the 5 N weight on z. The tests edit the arrays to add their event.
    """
    rng = np.random.default_rng(seed)
    n = int(seconds * rate)
    t = t0 + np.arange(n) / rate
    force = rng.normal(scale=0.02, size=(n, 3))
    torque = rng.normal(scale=0.002, size=(n, 3))
    force[:, 2] -= 5.0
    return t, force, torque


def sample_messages(*, t: np.ndarray, force: np.ndarray,
                    torque: np.ndarray) -> List[WrenchEvent]:
    """Return one wrench message per sample, each received 2 ms after its stamp."""
    return [WrenchEvent(t=t[i:i + 1], force=force[i:i + 1], torque=torque[i:i + 1],
                        now=float(t[i]) + 0.002) for i in range(t.size)]
