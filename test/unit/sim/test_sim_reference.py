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
parameter, derived fact, phase and impact). OpenBLAS and numpy pick their kernels by the CPU
at run time, and the kernels differ in the last bit (an AVX-512 machine and an AVX2 one gave
different trials), so the trials are simulated in a child process pinned to OpenBLAS's
generic x86-64 kernels on one thread and numpy's baseline loops. The digests were recorded so
on x86_64 with numpy 2.4; another numpy (with its own OpenBLAS) or machine may differ in the
last bit, so the test skips there. A deliberate change of the simulator updates them: print
the new ones with ``.venv/bin/python test/unit/sim/test_sim_reference.py`` and say why in the
commit. To compare whole data sets (bags and manifest) see ``tools/sim_digest.py``.
"""

import hashlib
import json
import os
import platform
import subprocess
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
    'paper_0': '766bdb4b469dd0b729288df11f81f4545705a3938664dfe6c690a0be45a83aeb',
    'heavy_1': 'fa697e4797af92e826bbe5c9ff22f3f794d758e10ef0b71a04c13029e2aed0b2',
    'soft_2': 'ca3b4020f8a6c0ccda4c1b5cd447ab0e62fd2ed3b9069dc22208adf9cb11b0a6',
    'noisy_3': '5668acb854684e2f3663c1bb498f5b7984d32a42dd00d03aa35208084d186adc',
    'gain_4': '143617b05056b900d116d25a426d7fe6a3251fdf9c814453510c79ffc32ffb4a',
    'odd_chunking_5': '35dd823b77d35b7c73c01361f7037cc13cc0685a619b25deaf563ae26d9cc6e9',
    'geometry_6': 'd2b4ad0ccf746789203da56f5e7797ac9b47c1d8895607b282c1f69f107dedbe',
    'spring_7': 'b788928e51b1e76635ff9534fe9da613e49dd2133b7dadb280ef389cf2d601a7',
    'compliant_8': 'cab226cff27e4621fc9aea85075460e802e348d65f482c291f5bf5fd5d61d584',
    'approach_9': 'b22f51a2cf93cb7800dbc98f3a817c7c9679977e72359c9ddfc0ed6a9d804776',
    'exogenous_10': 'cfdc2ea9fb378c44e45c7e2443e49e0dc40af2ec0edd69e56a8e90f1bdb18f63',
    'quiet_contact_11': '7e4f8882e1bfe212f414fef7b1e010a154d94e5ad57985628ffe6167fc064e60',
    'paper_1khz_44k': 'f29f0f46dd6c2bbf0cfab8455feb7746da7d242f7fddabeb9230960bc7a3aee7',
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


def reference_trials(*, simulated: bool = True, real: bool):
    """Yield ``(name, trial)`` of the reference trials: the synthetic ones, 'real_sounds'."""
    if simulated:
        for trial in simulate_trials(n=12, seed=SEED, conditions=['wide']):
            yield f'{trial.condition}_{trial.index}', trial
        yield 'paper_1khz_44k', simulate_trial(seed=SEED, index=12, condition='paper',
                                               ft_rate=1000.0, audio_rate=44100)
    if real:
        yield 'real_sounds_13', simulate_trial(seed=SEED, index=13, condition='real_sounds')


def pinned_environment() -> dict:
    """Return the environment of a child whose arithmetic does not depend on the CPU."""
    env = dict(os.environ)
    # Every SIMD target numpy may dispatch to beyond its baseline, found here or not.
    simd = np.show_config(mode='dicts').get('SIMD Extensions', {})
    targets = list(simd.get('found', [])) + list(simd.get('not found', []))
    env.update(OPENBLAS_CORETYPE='Prescott', OPENBLAS_NUM_THREADS='1',
               NPY_DISABLE_CPU_FEATURES=' '.join(targets))
    return env


def pinned_digests(*, simulated: bool = True, real: bool) -> dict:
    """Return name -> digest of the reference trials, simulated with the arithmetic pinned."""
    argv = ([sys.executable, __file__, '--child'] + (['--simulated'] if simulated else [])
            + (['--real'] if real else []))
    done = subprocess.run(argv, env=pinned_environment(), capture_output=True, text=True,
                          timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _skip_unless_recorded_here() -> None:
    numpy_version = tuple(int(v) for v in np.__version__.split('.')[:2])
    if (numpy_version, platform.machine()) != RECORDED_WITH:
        pytest.skip(f'digests recorded with numpy {RECORDED_WITH[0]} on {RECORDED_WITH[1]}, '
                    f'this is numpy {np.__version__} on {platform.machine()}')


def test_simulated_trials_are_bit_identical_to_the_reference():
    _skip_unless_recorded_here()
    got = pinned_digests(real=False)
    assert sorted(got) == sorted(k for k in EXPECTED if not k.startswith('real_sounds'))
    changed = [name for name, digest in got.items() if digest != EXPECTED[name]]
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
    got = pinned_digests(simulated=False, real=True)
    assert got == {'real_sounds_13': EXPECTED['real_sounds_13']}


if __name__ == '__main__':
    if '--child' in sys.argv:     # the pinned child of pinned_digests
        trials = reference_trials(simulated='--simulated' in sys.argv, real='--real' in sys.argv)
        print(json.dumps({key: trial_digest(trial) for key, trial in trials}))
        sys.exit(0)
    bank = sound_bank.load_bank().fingerprint if sound_bank.bank_available() else None
    print(f'RECORDED_BANK = {bank!r}')
    for key, value in pinned_digests(real=bank is not None).items():
        print(f'    {key!r}: {value!r},')
    sys.exit(0)
