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
Real recorded sounds for the simulator's ``'real_sounds'`` family: fetch, cache and load.

The recordings are not part of the repository. :func:`fetch` takes them from Debian's package
``minetest-data`` (the Minetest game's media: Foley recordings from freesound.org and
opengameart.org under CC0, CC BY 3.0 and CC BY-SA 3.0, see ``docs/simulator.md``): it runs
``apt-get download minetest-data`` (no root needed when the package lists are there; as root it
runs ``apt-get update`` once if the download fails), unpacks the ``.deb`` with ``dpkg-deb -x``,
decodes the Ogg Vorbis files of :data:`BANK` with ``soundfile`` (a dependency) and
writes each as a mono float32 WAV file plus ``bank.json`` into the cache folder
(:func:`bank_dir`: ``$CONTACT_DETECTOR_SOUNDS`` or ``~/.cache/contact_detector/sounds``).
It is idempotent: a complete cache is left as it is. ``tools/fetch_sounds.sh`` (called by
``tools/setup.sh``) runs it through :func:`main`.

:func:`load_bank` reads the cache with scipy alone and raises :class:`ConfigError` naming the
fetch command when it is missing. Roles of the clips (:data:`ROLES`):

``contact``
    a hard object set down on a hard surface (a block or a glass/ice/wood/metal step).
``hand``
    a knock with a hard object or knuckle on metal (knocks on the robot's hand).
``table``
    a knock or chop on wood or stone (knocks on the table).
``room``
    continuous room background (running water, a stove's crackle).
``ego``
    continuous mechanical rolling/drive noise (the arm's motors and gears while it moves).
"""

from dataclasses import dataclass
import functools
import hashlib
import json
import math
import os
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile
from typing import Sequence

from contact_detector.errors import ConfigError
import numpy as np

#: Environment variable naming the cache folder.
SOUNDS_ENV = 'CONTACT_DETECTOR_SOUNDS'
#: Debian package the recordings come from, and the folder of its media inside the package.
PACKAGE = 'minetest-data'
PACKAGE_ROOT = 'usr/share/games/minetest/games/minetest_game/mods'
#: The command that fills the cache (named in errors and skips).
FETCH_COMMAND = 'tools/fetch_sounds.sh'
#: Version of the cache layout (a cache with another version is rebuilt).
BANK_VERSION = 1

#: role -> files under :data:`PACKAGE_ROOT` (see the module doc and docs/simulator.md).
BANK: dict[str, tuple[str, ...]] = {
    'contact': (
        'default/sounds/default_place_node_hard.1.ogg',
        'default/sounds/default_place_node_hard.2.ogg',
        'default/sounds/default_glass_footstep.ogg',
        'default/sounds/default_hard_footstep.1.ogg',
        'default/sounds/default_hard_footstep.2.ogg',
        'default/sounds/default_hard_footstep.3.ogg',
        'default/sounds/default_wood_footstep.1.ogg',
        'default/sounds/default_wood_footstep.2.ogg',
        'default/sounds/default_ice_footstep.1.ogg',
        'default/sounds/default_ice_footstep.2.ogg',
        'default/sounds/default_place_node_metal.1.ogg',
        'default/sounds/default_place_node_metal.2.ogg',
    ),
    'hand': (
        'default/sounds/default_dug_metal.1.ogg',
        'default/sounds/default_dug_metal.2.ogg',
        'default/sounds/default_dig_metal.ogg',
        'default/sounds/default_metal_footstep.1.ogg',
        'default/sounds/default_metal_footstep.2.ogg',
        'default/sounds/default_metal_footstep.3.ogg',
    ),
    'table': (
        'default/sounds/default_dig_choppy.1.ogg',
        'default/sounds/default_dig_choppy.2.ogg',
        'default/sounds/default_dig_choppy.3.ogg',
        'default/sounds/default_dig_cracky.1.ogg',
        'default/sounds/default_dig_cracky.2.ogg',
        'default/sounds/default_dig_cracky.3.ogg',
        'default/sounds/default_dig_oddly_breakable_by_hand.ogg',
        'default/sounds/default_dug_node.1.ogg',
        'default/sounds/default_dug_node.2.ogg',
    ),
    'room': (
        'env_sounds/sounds/env_sounds_water.1.ogg',
        'env_sounds/sounds/env_sounds_water.2.ogg',
        'env_sounds/sounds/env_sounds_water.3.ogg',
        'env_sounds/sounds/env_sounds_water.4.ogg',
        'default/sounds/default_furnace_active.ogg',
    ),
    'ego': (
        'carts/sounds/carts_cart_moving.1.ogg',
        'carts/sounds/carts_cart_moving.2.ogg',
        'carts/sounds/carts_cart_moving.3.ogg',
    ),
}
#: Roles of impulsive clips (aligned on their onset) and of continuous clips (looped).
IMPULSE_ROLES = ('contact', 'hand', 'table')
LOOP_ROLES = ('room', 'ego')
ROLES = IMPULSE_ROLES + LOOP_ROLES

#: An impulsive clip's onset is its first sample with ``|x| >= ONSET_FRACTION * max|x|``.
ONSET_FRACTION = 0.2
#: Kept before the onset (faded in) and longest part kept after it, s.
PRE_ROLL_S = 0.001
MAX_IMPULSE_S = 0.6
#: A loop keeps the span from its first to its last 0.25 s frame whose RMS reaches 0.7 times
#: the median frame RMS (the recordings fade in and out).
LOOP_FRAME_S = 0.25
LOOP_STEADY_FRACTION = 0.7
#: Fade at the end of an impulsive clip and cross-fade between loop repetitions, s.
FADE_S = 0.02


def bank_dir() -> Path:
    """Return the cache folder: ``$CONTACT_DETECTOR_SOUNDS`` or ``~/.cache/.../sounds``."""
    env = os.environ.get(SOUNDS_ENV, '').strip()
    if env:
        return Path(env).expanduser()
    return Path.home() / '.cache' / 'contact_detector' / 'sounds'


def _wav_name(role: str, source: str) -> str:
    return f'{role}__{Path(source).stem}.wav'


def _manifest_ok(folder: Path) -> bool:
    try:
        meta = json.loads((folder / 'bank.json').read_text())
    except (OSError, ValueError):
        return False
    want = {_wav_name(r, s) for r in BANK for s in BANK[r]}
    files = meta.get('files', {})
    return meta.get('version') == BANK_VERSION and set(files) == want \
        and all((folder / name).is_file() for name in want)


def _run(cmd: Sequence[str], *, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(list(cmd), cwd=cwd, capture_output=True, text=True, check=False)


def _download_deb(work: Path) -> Path:
    """``apt-get download PACKAGE`` into ``work`` (``apt-get update`` once as root if needed)."""
    if shutil.which('apt-get') is None or shutil.which('dpkg-deb') is None:
        raise ConfigError(f'fetching the real sound bank needs apt-get and dpkg-deb (Debian or '
                          f'Ubuntu); then run {FETCH_COMMAND}')
    res = _run(['apt-get', 'download', PACKAGE], cwd=work)
    if res.returncode != 0 and hasattr(os, 'geteuid') and os.geteuid() == 0:
        _run(['apt-get', 'update', '-q'], cwd=work)
        res = _run(['apt-get', 'download', PACKAGE], cwd=work)
    debs = sorted(work.glob(f'{PACKAGE}_*.deb'))
    if res.returncode != 0 or not debs:
        raise ConfigError(f'apt-get download {PACKAGE} failed ({res.stderr.strip()[-300:]}); '
                          f'run "sudo apt-get update" and then {FETCH_COMMAND}')
    return debs[0]


def fetch(*, dest: Path | None = None, quiet: bool = False) -> Path:
    """
    Fill the cache folder with the bank's clips (idempotent).

    Parameters
    ----------
    dest : Path or None
        Cache folder; None: :func:`bank_dir`.
    quiet : bool
        Print nothing.

    Returns
    -------
    Path
        The cache folder, holding one mono float32 WAV per clip and ``bank.json``.

    Raises
    ------
    ConfigError
        apt-get, dpkg-deb or the ``soundfile`` package is missing, the download fails or a
        file of :data:`BANK` is not in the package.

    """
    folder = Path(dest) if dest is not None else bank_dir()
    if _manifest_ok(folder):
        if not quiet:
            print(f'sound bank: {folder} is complete')
        return folder
    try:
        import soundfile
    except ImportError as err:
        raise ConfigError('decoding the real sound bank needs the soundfile package '
                          f'(pip install soundfile), then run {FETCH_COMMAND}') from err
    from scipy.io import wavfile
    folder.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix='contact_detector_sounds_') as tmp:
        work = Path(tmp)
        deb = _download_deb(work)
        res = _run(['dpkg-deb', '-x', str(deb), str(work / 'x')], cwd=work)
        if res.returncode != 0:
            raise ConfigError(f'dpkg-deb -x {deb.name} failed: {res.stderr.strip()[-300:]}')
        version = _run(['dpkg-deb', '-f', str(deb), 'Version'], cwd=work).stdout.strip()
        stage = Path(tempfile.mkdtemp(prefix='.sounds_', dir=folder.parent))
        files = {}
        try:
            for role, sources in BANK.items():
                for source in sources:
                    path = work / 'x' / PACKAGE_ROOT / source
                    if not path.is_file():
                        raise ConfigError(f'{PACKAGE} {version} has no {source}')
                    data, rate = soundfile.read(str(path), dtype='float32', always_2d=True)
                    mono = data.mean(axis=1).astype(np.float32)
                    name = _wav_name(role, source)
                    wavfile.write(str(stage / name), int(rate), mono)
                    files[name] = {'role': role, 'source': f'{PACKAGE_ROOT}/{source}',
                                   'rate_hz': int(rate), 'samples': int(len(mono)),
                                   'sha256': hashlib.sha256(
                                       (stage / name).read_bytes()).hexdigest()}
            meta = {'version': BANK_VERSION, 'package': PACKAGE, 'package_version': version,
                    'files': files}
            (stage / 'bank.json').write_text(json.dumps(meta, indent=1, sort_keys=True) + '\n')
            if folder.exists():
                shutil.rmtree(folder)
            stage.rename(folder)
        finally:
            if stage.exists():
                shutil.rmtree(stage, ignore_errors=True)
    if not quiet:
        print(f'sound bank: {len(files)} clips from {PACKAGE} {version} in {folder}')
    return folder


@dataclass(frozen=True)
class Clip:
    """
    One recording, mono, peak-normalised (impulses) or RMS-normalised (loops).

    Attributes
    ----------
    name : str
        File name in the cache (``role__stem.wav``).
    role : str
        One of :data:`ROLES`.
    rate : int
        Sample rate in Hz of ``data``.
    data : numpy.ndarray
        float64 samples: an impulse has ``max|data| = 1`` and starts :data:`PRE_ROLL_S`
        before its onset; a loop is the recording's steady middle with RMS 1.
    onset : int
        Index of the onset in ``data`` (0 for loops).

    """

    name: str
    role: str
    rate: int
    data: np.ndarray
    onset: int


@dataclass(frozen=True)
class SoundBank:
    """The loaded bank: clips per role and a fingerprint of the cache (``bank.json`` hash)."""

    folder: str
    clips: dict
    fingerprint: str
    package_version: str

    def at_rate(self, clip: Clip, rate: int) -> tuple[np.ndarray, int]:
        """``clip`` resampled to ``rate`` Hz (polyphase) and its onset index at that rate."""
        return _resampled(self.fingerprint, clip.name, clip.rate, rate, clip.data, clip.onset)


#: Resampled clips: (fingerprint, name, source rate, rate) -> (samples, onset index).
_RESAMPLED: dict = {}


def _resampled(fingerprint: str, name: str, src: int, rate: int, data: np.ndarray,
               onset: int) -> tuple[np.ndarray, int]:
    key = (fingerprint, name, src, rate)
    hit = _RESAMPLED.get(key)
    if hit is None:
        from scipy.signal import resample_poly
        g = math.gcd(int(src), int(rate))
        up, down = int(rate) // g, int(src) // g
        y = data if up == down else resample_poly(data, up, down)
        hit = (np.ascontiguousarray(y, dtype=np.float64),
               int(round(onset * rate / src)))
        _RESAMPLED[key] = hit
    return hit


def _prepare(name: str, role: str, rate: int, x: np.ndarray) -> Clip:
    x = np.asarray(x, dtype=np.float64)
    x = x - x.mean()
    if role in IMPULSE_ROLES:
        peak = float(np.max(np.abs(x)))
        i_on = int(np.argmax(np.abs(x) >= ONSET_FRACTION * peak))
        pre = int(round(PRE_ROLL_S * rate))
        i0 = max(0, i_on - pre)
        i1 = min(len(x), i_on + int(round(MAX_IMPULSE_S * rate)))
        y = x[i0:i1].copy()
        if i_on - i0 > 0:
            k = np.arange(i_on - i0)
            y[:i_on - i0] *= 0.5 * (1 - np.cos(np.pi * k / (i_on - i0)))
        nf = min(len(y) // 4, int(round(FADE_S * rate)))
        if nf > 0:
            y[-nf:] *= 0.5 * (1 + np.cos(np.pi * np.arange(nf) / nf))
        y /= float(np.max(np.abs(y)))
        return Clip(name=name, role=role, rate=rate, data=y, onset=i_on - i0)
    # a loop keeps its steady middle: the game's fade-ins and fade-outs are cut off
    w = max(1, int(round(LOOP_FRAME_S * rate)))
    frames = np.sqrt(np.mean(x[:len(x) // w * w].reshape(-1, w) ** 2, axis=1))
    steady = np.nonzero(frames >= LOOP_STEADY_FRACTION * np.median(frames))[0]
    x = x[steady[0] * w:(steady[-1] + 1) * w]
    rms = float(np.sqrt(np.mean(x ** 2)))
    return Clip(name=name, role=role, rate=rate, data=x / max(rms, 1e-12), onset=0)


@functools.lru_cache(maxsize=4)
def _load(folder: str) -> SoundBank:
    from scipy.io import wavfile
    path = Path(folder)
    raw = (path / 'bank.json').read_bytes()
    meta = json.loads(raw)
    clips: dict = {role: [] for role in ROLES}
    for name in sorted(meta['files']):
        info = meta['files'][name]
        rate, x = wavfile.read(str(path / name))
        clips[info['role']].append(_prepare(name, info['role'], int(rate), x))
    return SoundBank(folder=str(path), clips={r: tuple(c) for r, c in clips.items()},
                     fingerprint=hashlib.sha256(raw).hexdigest()[:16],
                     package_version=str(meta.get('package_version', '')))


def load_bank(*, folder: Path | None = None) -> SoundBank:
    """
    Load the cached bank (cached in memory per folder).

    Parameters
    ----------
    folder : Path or None
        Cache folder; None: :func:`bank_dir`.

    Raises
    ------
    ConfigError
        The cache is missing or incomplete (the message names :data:`FETCH_COMMAND`).

    """
    path = Path(folder) if folder is not None else bank_dir()
    if not _manifest_ok(path):
        raise ConfigError(f'the real sound bank is not in {path} (condition set '
                          f"'real_sounds'); run {FETCH_COMMAND} (needs apt-get and soundfile) or "
                          f'set {SOUNDS_ENV} to a fetched bank')
    return _load(str(path.resolve()))


def bank_available(*, folder: Path | None = None) -> bool:
    """Return True if :func:`load_bank` would find a complete cache."""
    return _manifest_ok(Path(folder) if folder is not None else bank_dir())


def main(argv: Sequence[str] | None = None) -> int:
    """``tools/fetch_sounds.sh [DEST]``: fetch the bank into DEST or :func:`bank_dir`; 0 if ok."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) > 1 or any(a.startswith('-') for a in args):
        print(f'usage: {FETCH_COMMAND} [DEST]', file=sys.stderr)
        return 2
    try:
        fetch(dest=Path(args[0]) if args else None)
    except ConfigError as err:
        print(f'sound bank: {err}', file=sys.stderr)
        return 1
    return 0
