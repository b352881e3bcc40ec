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

"""The contact sound in ``label``: a loud impact just after an early F/T step is the contact."""

from contact_detector.evaluation.labelling import propose_onset
import numpy as np
import pytest

FT_RATE, AUDIO_RATE = 100.0, 16000.0
STEP_T = 1.503          # the F/T leaves its baseline here (a push on the held object)


def _recording(*, click_t: float | None, click_gain: float) -> dict:
    rng = np.random.default_rng(4)
    t = 0.5 + np.arange(int(3.0 * FT_RATE)) / FT_RATE
    force = rng.normal(0.0, 0.05, (len(t), 3))
    torque = rng.normal(0.0, 0.005, (len(t), 3))
    held = (t > STEP_T) & (t < STEP_T + 0.8)                # a fast, lasting load change
    force[:, 2] += np.where(held, 8.0, 0.0)
    torque[:, 0] += np.where(held, 0.4, 0.0)
    audio = rng.normal(0.0, 100.0, int(3.5 * AUDIO_RATE))
    if click_t is not None:
        k = int(round(click_t * AUDIO_RATE))
        n = int(0.02 * AUDIO_RATE)
        audio[k:k + n] += click_gain * np.exp(-np.arange(n) / (0.004 * AUDIO_RATE)) * \
            np.sin(2 * np.pi * 3000.0 * np.arange(n) / AUDIO_RATE)
    return {'ft_t': t, 'force': force, 'torque': torque, 'audio': audio,
            'audio_rate': AUDIO_RATE, 'audio_t0': 0.0}


@pytest.mark.parametrize('delay', [0.045, 0.07])
def test_a_loud_impact_after_an_early_step_sets_the_onset(delay):
    p = propose_onset(**_recording(click_t=STEP_T + delay, click_gain=20000.0))
    assert p.source == 'audio'
    assert p.onset_t == pytest.approx(STEP_T + delay, abs=0.001)
    assert p.ft_onset_t == pytest.approx(STEP_T, abs=0.010)


def test_a_faint_sound_after_the_step_does_not_move_it():
    # +10 dB over the floor: a sound, but not the loud impact that would outweigh the F/T
    p = propose_onset(**_recording(click_t=STEP_T + 0.05, click_gain=300.0))
    assert p.source == 'ft' and p.onset_t == pytest.approx(STEP_T, abs=0.010)


def test_a_loud_impact_long_after_the_step_is_something_else():
    p = propose_onset(**_recording(click_t=STEP_T + 0.15, click_gain=20000.0))
    assert p.source == 'ft' and p.onset_t == pytest.approx(STEP_T, abs=0.010)
