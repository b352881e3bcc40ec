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

"""A small synthetic recording with one contact-like event, for the feature tools and benches."""

import numpy as np


def synthetic_recording(*, audio_rate: int, ft_rate: float, seconds: float = 5.0,
                        event_s: float = 3.0, seed: int = 0) -> dict:
    """
    Return a synthetic recording with one contact-like event.

    Returns
    -------
    dict
        ``audio`` (m,) int16, ``ft_t`` (n,) s, ``force`` and ``torque`` (n, 3), ``t0`` s.

    """
    rng = np.random.default_rng(seed)
    t0 = 1_700_000_000.0
    ta = np.arange(int(seconds * audio_rate)) / audio_rate
    audio = 0.003 * rng.normal(size=ta.size)
    after = np.clip(ta - event_s, 0, None)
    ring = (ta >= event_s) * np.exp(-after / 0.02) * np.sin(2 * np.pi * 2500 * after)
    audio += 0.3 * ring
    tf = np.arange(int(seconds * ft_rate)) / ft_rate
    load = np.where(tf < event_s, 4.0, 4.0 - 3.0 * (1 - np.exp(-(tf - event_s) / 0.08)))
    wobble = (tf >= event_s) * np.exp(-np.clip(tf - event_s, 0, None) / 0.3) * np.sin(
        2 * np.pi * 8 * (tf - event_s))
    force = np.stack([0.05 * rng.normal(size=tf.size), 0.05 * rng.normal(size=tf.size),
                      load + 0.5 * wobble], axis=1)
    torque = np.stack([0.01 * rng.normal(size=tf.size), 0.1 * load + 0.2 * wobble,
                       0.01 * rng.normal(size=tf.size)], axis=1)
    return {'audio': (np.clip(audio, -1, 1) * 32767).astype(np.int16), 'ft_t': t0 + tf,
            'force': force, 'torque': torque, 't0': t0}
