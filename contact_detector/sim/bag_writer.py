"""
Write simulated trials as rosbag2 (sqlite3 or mcap) with rosbags, plus the JSON manifest.

Every bag holds three topics (message definitions embedded, so ``ros2 bag info`` and rosbags'
AnyReader both open it):

``/wrist_wrench`` geometry_msgs/msg/WrenchStamped
    ``header.stamp`` = sample time, ``frame_id`` ``wrist_ft_sensor_frame``; log time = stamp
    + sensor transport latency.
``/audio`` std_msgs/msg/Int16MultiArray
    mono S16 chunks, ``layout.dim = [('samples', n, n)]``; log time = time of the chunk's last
    sample + transport jitter.
``/contact_truth`` std_msgs/msg/Bool
    True logged at the true contact onset, False where the labelled onset window ends.
"""

import json
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

from contact_detector.errors import BagError, ConfigError
from contact_detector.io.bags import (AUDIO_TOPIC, AUDIO_TYPE, jazzy_typestore, MANIFEST_NAME,
                                      TRUTH_TOPIC, TRUTH_TYPE, WRENCH_TOPIC, WRENCH_TYPE)
from contact_detector.sim.trial import Trial

FRAME_ID = 'wrist_ft_sensor_frame'
STORAGES = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}
#: Manifest format version; bump when a field changes meaning.
MANIFEST_VERSION = 1


def _ns(trial: Trial, t: np.ndarray) -> np.ndarray:
    """Absolute seconds -> int64 ns, exact for the (integer) start time."""
    start_ns = int(round(trial.start_time * 1e9))
    return start_ns + np.round((np.asarray(t, dtype=float) - trial.start_time) * 1e9).astype(
        np.int64)


def write_trial_bag(*, trial: Trial, path: Path, storage: str = 'sqlite3') -> Path:
    """
    Write one trial as a rosbag2 directory.

    Parameters
    ----------
    trial : Trial
        From :func:`contact_detector.sim.trial.simulate_trial`.
    path : Path
        The bag directory to create; it must not exist.
    storage : str
        'sqlite3' or 'mcap'.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ConfigError
        Unknown storage.
    BagError
        ``path`` exists or writing failed.

    """
    if storage not in STORAGES:
        raise ConfigError(f'storage must be one of {sorted(STORAGES)}, got {storage!r}')
    path = Path(path)
    if path.exists():
        raise BagError(f'{path} already exists')
    ts = jazzy_typestore()
    types = ts.types
    Time = types['builtin_interfaces/msg/Time']
    Header = types['std_msgs/msg/Header']
    Vector3 = types['geometry_msgs/msg/Vector3']
    Wrench = types['geometry_msgs/msg/Wrench']
    WrenchStamped = types[WRENCH_TYPE]
    Int16MultiArray = types[AUDIO_TYPE]
    Layout = types['std_msgs/msg/MultiArrayLayout']
    Dim = types['std_msgs/msg/MultiArrayDimension']
    Bool = types[TRUTH_TYPE]

    stamp_ns = _ns(trial, trial.wrench_t)
    wrench_log = trial.wrench_log_t if trial.wrench_log_t is not None else trial.wrench_t
    wrench_log_ns = np.maximum(_ns(trial, wrench_log), stamp_ns)
    audio_log_ns = _ns(trial, trial.chunk_log_t)
    truth_ns = _ns(trial, np.array([trial.onset_t, trial.onset_end_t]))
    # one global log-time order (stable: wrench, audio, truth on ties)
    times = np.concatenate([wrench_log_ns, audio_log_ns, truth_ns])
    kinds = np.concatenate([np.zeros(len(wrench_log_ns), np.int8),
                            np.ones(len(audio_log_ns), np.int8), np.full(2, 2, np.int8)])
    idx = np.concatenate([np.arange(len(wrench_log_ns)), np.arange(len(audio_log_ns)),
                          np.arange(2)])
    order = np.lexsort((idx, kinds, times))
    starts = np.concatenate(([0], trial.chunk_ends[:-1]))
    force = trial.force.tolist()
    torque = trial.torque.tolist()
    audio = trial.audio
    try:
        writer = Writer(path, version=9, storage_plugin=STORAGES[storage])
        with writer:
            c_w = writer.add_connection(WRENCH_TOPIC, WRENCH_TYPE, typestore=ts)
            c_a = writer.add_connection(AUDIO_TOPIC, AUDIO_TYPE, typestore=ts)
            c_t = writer.add_connection(TRUTH_TOPIC, TRUTH_TYPE, typestore=ts)
            for k in order:
                kind, i, t = kinds[k], int(idx[k]), int(times[k])
                if kind == 0:
                    sec, nsec = divmod(int(stamp_ns[i]), 1_000_000_000)
                    fx, fy, fz = force[i]
                    tx, ty, tz = torque[i]
                    msg = WrenchStamped(
                        header=Header(stamp=Time(sec=sec, nanosec=nsec), frame_id=FRAME_ID),
                        wrench=Wrench(force=Vector3(x=fx, y=fy, z=fz),
                                      torque=Vector3(x=tx, y=ty, z=tz)))
                    writer.write(c_w, t, ts.serialize_cdr(msg, WRENCH_TYPE))
                elif kind == 1:
                    data = audio[starts[i]:trial.chunk_ends[i]]
                    n = len(data)
                    msg = Int16MultiArray(
                        layout=Layout(dim=[Dim(label='samples', size=n, stride=n)],
                                      data_offset=0),
                        data=data)
                    writer.write(c_a, t, ts.serialize_cdr(msg, AUDIO_TYPE))
                else:
                    writer.write(c_t, t, ts.serialize_cdr(Bool(data=(i == 0)), TRUTH_TYPE))
    except Exception as err:  # rosbags raises its own and OS errors
        raise BagError(f'cannot write bag {path}: {err}') from err
    return path


def manifest_entry(trial: Trial, *, bag: str | None = None) -> dict:
    """
    Return the manifest record of one trial (plain JSON types).

    Keys: name, bag (directory name relative to the manifest), condition, seed, index,
    start_time, end_time, ft_rate, audio_rate, onset_t, onset_end_t, contact_end_t, stop_t,
    phases (list of [name, t_start, t_end]), impacts (list of {t, kind, in_air, amplitude}),
    params (every randomised parameter plus 'derived' facts). Times are absolute seconds.
    """
    return {
        'name': trial.name,
        'bag': bag if bag is not None else trial.name,
        'condition': trial.condition,
        'seed': int(trial.seed),
        'index': int(trial.index),
        'start_time': float(trial.start_time),
        'end_time': float(trial.end_time),
        'ft_rate': float(trial.ft_rate),
        'audio_rate': int(trial.audio_rate),
        'onset_t': float(trial.onset_t),
        'onset_end_t': float(trial.onset_end_t),
        'contact_end_t': float(trial.contact_end_t),
        'stop_t': float(trial.stop_t),
        'phases': [[name, float(a), float(b)] for name, a, b in trial.phases],
        'impacts': [{'t': float(i.t), 'kind': i.kind, 'in_air': bool(i.in_air),
                     'amplitude': float(i.amplitude)} for i in trial.impacts],
        'params': trial.params,
    }


def write_manifest(*, trials: Iterable[Trial | Mapping], out_dir: Path,
                   settings: Mapping | None = None) -> Path:
    """
    Write ``out_dir/manifest.json``.

    Parameters
    ----------
    trials : iterable of Trial or dict
        Trials, or records already made by :func:`manifest_entry` (so a long run need not keep
        every trial's arrays in memory).
    out_dir : Path
        Directory holding the trial bags.
    settings : mapping or None
        Generator settings stored under 'settings' (seed, conditions, rates, storage, ...).

    Returns
    -------
    Path
        The manifest file.

    """
    out_dir = Path(out_dir)
    records = [manifest_entry(t) if isinstance(t, Trial) else dict(t) for t in trials]
    data = {
        'format': 'contact_detector.sim.manifest',
        'version': MANIFEST_VERSION,
        'settings': dict(settings or {}),
        'trials': records,
    }
    file = out_dir / MANIFEST_NAME
    tmp = file.with_suffix('.json.tmp')
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        tmp.write_text(json.dumps(data, indent=1, allow_nan=False) + '\n', encoding='utf-8')
        tmp.replace(file)
    except (OSError, ValueError) as err:
        raise BagError(f'cannot write manifest {file}: {err}') from err
    return file
