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
The simulator's trials are the reference ones, bit for bit, in every condition set.

A refactor of :mod:`contact_detector.sim` must not change a trial: training data, the held-out
trials and every figure quoted in the docs come from it. Each digest covers every array a bag
is written from (wrench, audio, chunking, log times) and the trial's manifest record (every
parameter, derived fact, phase and impact). The digests were recorded on x86_64 with numpy 2.4;
floating point of another numpy (or CPU) may differ in the last bit, so the test skips there.
A deliberate change of the simulator updates them: print the new ones with
``.venv/bin/python test/test_sim_reference.py`` and say why in the commit. To compare whole
data sets (bags and manifest) see ``tools/sim_digest.py``.
"""

import hashlib
import json
import os
import platform
import sys

from contact_detector.sim import simulate_trial, simulate_trials, sound_bank
from contact_detector.sim.bag_writer import manifest_entry
import numpy as np
import pytest

SEED = 3
#: numpy (major, minor) and machine the digests were recorded with.
RECORDED_WITH = ((2, 4), 'x86_64')
#: Fingerprint of the sound bank behind the 'real_sounds' digest.
RECORDED_BANK = 'f46bfe88083a7d2d'

#: name -> SHA-256 of :func:`trial_digest`: one trial of each 'wide' set (trial i of
#: ``simulate_trials(n=12, seed=3, conditions=['wide'])``), 'paper' with a 1 kHz sensor and
#: 44.1 kHz audio, and one 'real_sounds' trial.
EXPECTED = {
    'paper_0': 'c48d2f3f0331edf91218cfecd9641aeac968ff17a341c70ea8ba68635278fa1b',
    'heavy_1': '6677cf4e5ff7fc6ced9662449834e1302956e7cea603aab69bb0da679d2d2928',
    'soft_2': '3ff71fb77b05708e02978b56f92b21729ff14ffd17c519c8071f756329af2e72',
    'noisy_3': 'b7b7701d2019d54243e5157086064c58c6f4659f6d6f55f5ebbc15a43fd89ee3',
    'gain_4': '143617b05056b900d116d25a426d7fe6a3251fdf9c814453510c79ffc32ffb4a',
    'odd_chunking_5': '80b91e3904a07943a54cbb601ab8807e626448f87a915f0e36483719aee06fbd',
    'geometry_6': '26709d0a63a9c163f1a8d48eb290354ed20a64a7b2c2b1a62ae36b47a2009aeb',
    'spring_7': '40604474b73672bedd23b9e1415489d53d302539b1d0735e3cc2d0c753e5c5f4',
    'compliant_8': 'd6128a3fb3432b79cde2363346c478d4e2ac1190c03917dcc2ca362eca38cb81',
    'approach_9': 'b22f51a2cf93cb7800dbc98f3a817c7c9679977e72359c9ddfc0ed6a9d804776',
    'exogenous_10': 'cfdc2ea9fb378c44e45c7e2443e49e0dc40af2ec0edd69e56a8e90f1bdb18f63',
    'quiet_contact_11': '6081a7e8cf88d3de29de379cd34a74d43de1345d356a4fc4ca16ec78163e6be6',
    'paper_1khz_44k': '66e9ff2a74f3d2cf22ebe8582e7b05d52cfec40ce8a935f78972ba6a02b02995',
    'real_sounds_13': '47b08a18bd789666d7558d021cd70c120ddbddb26f7ad799e439c987d6bb4cd7',
}


def trial_digest(trial) -> str:
    """Return the SHA-256 of a trial's arrays (dtype, shape, bytes) and manifest record."""
    sha = hashlib.sha256()
    for name in ('wrench_t', 'force', 'torque', 'audio', 'chunk_ends', 'chunk_log_t',
                 'wrench_log_t'):
        array = np.ascontiguousarray(getattr(trial, name))
        sha.update(f'{name}:{array.dtype.str}:{array.shape}'.encode())
        sha.update(array.tobytes())
    sha.update(json.dumps(manifest_entry(trial), allow_nan=False).encode())
    return sha.hexdigest()


def reference_trials(*, real: bool):
    """Yield ``(name, trial)`` of the reference trials (with 'real_sounds' if ``real``)."""
    for trial in simulate_trials(n=12, seed=SEED, conditions=['wide']):
        yield f'{trial.condition}_{trial.index}', trial
    yield 'paper_1khz_44k', simulate_trial(seed=SEED, index=12, condition='paper',
                                           ft_rate=1000.0, audio_rate=44100)
    if real:
        yield 'real_sounds_13', simulate_trial(seed=SEED, index=13, condition='real_sounds')


def _skip_unless_recorded_here() -> None:
    numpy_version = tuple(int(v) for v in np.__version__.split('.')[:2])
    if (numpy_version, platform.machine()) != RECORDED_WITH:
        pytest.skip(f'digests recorded with numpy {RECORDED_WITH[0]} on {RECORDED_WITH[1]}, '
                    f'this is numpy {np.__version__} on {platform.machine()}')


def test_simulated_trials_are_bit_identical_to_the_reference():
    _skip_unless_recorded_here()
    got = dict(reference_trials(real=False))
    assert sorted(got) == sorted(k for k in EXPECTED if not k.startswith('real_sounds'))
    changed = [name for name, trial in got.items() if trial_digest(trial) != EXPECTED[name]]
    assert not changed, f'simulated trials changed: {changed}'


def test_real_sounds_trial_is_bit_identical_to_the_reference():
    _skip_unless_recorded_here()
    if not sound_bank.bank_available():
        why = f'the real sound bank is not in {sound_bank.bank_dir()} ({sound_bank.FETCH_COMMAND})'
        if os.environ.get('CI'):
            pytest.fail(why + ' -- CI must have it')    # tools/setup.sh fetches it
        pytest.skip(why)
    if sound_bank.load_bank().fingerprint != RECORDED_BANK:
        pytest.skip('another sound bank than the one the digest was recorded with')
    trial = simulate_trial(seed=SEED, index=13, condition='real_sounds')
    assert trial_digest(trial) == EXPECTED['real_sounds_13']


if __name__ == '__main__':
    bank = sound_bank.load_bank().fingerprint if sound_bank.bank_available() else None
    print(f'RECORDED_BANK = {bank!r}')
    for key, value in reference_trials(real=bank is not None):
        print(f'    {key!r}: {trial_digest(value)!r},')
    sys.exit(0)
