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
Shared helpers of the node tests: a small test model and simulated-trial message streams.

Used by the node tests. The model is the shipped
``models/contact_forest.npz`` when it exists, otherwise a small forest (8 trees) trained here
on features of simulated trials, saved with ``save_bundle``.
"""

from datetime import datetime
import json
import os
from pathlib import Path
import signal
import subprocess
import sys
import time
from typing import Callable, List, Optional

from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.sim.messages import Event, message_events
from contact_detector.sim.trial import simulate_trial, Trial
import numpy as np

REPO = Path(__file__).resolve().parents[1]
SHIPPED_MODEL = REPO / 'models' / 'contact_forest.npz'
#: Simulator seed of the test model's training trials; test trials use other seeds.
TRAIN_SEED = 7
TRAIN_TRIALS = 12
LABEL_WINDOW_S = 0.1
TEST_RULE = {'threshold': 0.5, 'confirm_frames': 2, 'refractory_s': 1.0}

_cache: dict = {}


def trial_events(trial: Trial, *, t_from: float = -np.inf,
                 t_to: float = np.inf) -> List[Event]:
    """Return the trial's messages in log-time order within a span (see ``message_events``)."""
    return message_events(trial=trial, t_from=t_from, t_to=t_to)


def sensor_event(trial: Trial, event: Event):
    """Return one of :func:`trial_events` as the offline tools read it, received at its time."""
    from contact_detector.io.sensor_stream import AudioEvent, WrenchEvent

    if event.kind == 'audio':
        return AudioEvent(samples=trial.audio[event.lo:event.hi], stamp=event.t, now=event.t)
    span = slice(event.lo, event.hi)
    return WrenchEvent(t=trial.wrench_t[span], force=trial.force[span],
                       torque=trial.torque[span], now=event.t)


def trial_features(trial: Trial, config: FeatureConfig) -> tuple:
    """Feature frames of a trial fed as the node would (audio stamped with its log time)."""
    extractor = StreamingFeatureExtractor(config=config, audio_rate=trial.audio_rate,
                                          ft_input_rate=trial.ft_rate)
    blocks = []
    for e in trial_events(trial):
        if e.kind == 'audio':
            blocks.append(extractor.push_audio(trial.audio[e.lo:e.hi], stamp=e.t))
        else:
            blocks.append(extractor.push_wrench(t=trial.wrench_t[e.lo:e.hi],
                                                force=trial.force[e.lo:e.hi],
                                                torque=trial.torque[e.lo:e.hi]))
    blocks.append(extractor.flush())
    blocks = [b for b in blocks if len(b)]
    return (np.concatenate([b.t for b in blocks]), np.concatenate([b.x for b in blocks]),
            np.concatenate([b.valid for b in blocks]))


def trial_features_fast(trial: Trial, config: FeatureConfig) -> tuple:
    """Feature frames of a trial from two big pushes (the whole wrench, then the audio)."""
    extractor = StreamingFeatureExtractor(config=config, audio_rate=trial.audio_rate,
                                          ft_input_rate=trial.ft_rate, history_s=60.0)
    extractor.push_wrench(t=trial.wrench_t, force=trial.force, torque=trial.torque)
    frames = extractor.push_audio(trial.audio,
                                  stamp=float(trial.audio_time(trial.audio.size - 1)))
    return frames.t, frames.x, frames.valid


def train_test_model(path: Path, *, n_trials: int = TRAIN_TRIALS,
                     audio_rate: int = 16000) -> Path:
    """Fit an 8-tree forest on simulated trials and save it (with its card) at ``path``."""
    # scikit-learn and the bundle are imported here: the e2e publisher does not need them.
    from sklearn.ensemble import RandomForestClassifier

    from contact_detector.model.bundle import ModelBundle, runtime_versions
    from contact_detector.model.rule import DecisionRule
    from contact_detector.model.storage import save_bundle
    config = FeatureConfig()
    xs, ys = [], []
    for i in range(n_trials):
        trial = simulate_trial(seed=TRAIN_SEED, index=i, audio_rate=audio_rate,
                               hits=('hand', 'table', 'none')[i % 3])
        t, x, valid = trial_features_fast(trial, config)
        y = (t >= trial.onset_t) & (t < trial.onset_t + LABEL_WINDOW_S)
        xs.append(x[valid])
        ys.append(y[valid])
    forest = RandomForestClassifier(n_estimators=8, max_features='sqrt', min_samples_leaf=2,
                                    random_state=0)
    forest.fit(np.concatenate(xs), np.concatenate(ys).astype(int))
    bundle = ModelBundle(forest=forest, feature_config=config,
                         feature_names=config.feature_names,
                         feature_schema_version=FEATURE_SCHEMA_VERSION,
                         label_window={'start_s': 0.0, 'end_s': LABEL_WINDOW_S},
                         decision_rule=DecisionRule(**TEST_RULE), versions=runtime_versions(),
                         training={'source': 'test fixture', 'trials': n_trials},
                         created=datetime(2026, 1, 1).isoformat())
    return save_bundle(bundle=bundle, path=Path(path))


def model_path(directory: Path, *, allow_shipped: bool = True) -> Path:
    """Return the shipped model if there is one, else a test model (trained once per process)."""
    if allow_shipped and SHIPPED_MODEL.is_file():
        return SHIPPED_MODEL
    if 'model' not in _cache or not _cache['model'].is_file():
        _cache['model'] = train_test_model(Path(directory) / 'test_forest.npz')
    return _cache['model']


def load_test_model(directory: Path):
    """Load the small test model (never the shipped one), trained once per process."""
    from contact_detector.model.storage import load_bundle

    return load_bundle(path=model_path(directory, allow_shipped=False))


def uses_shipped(path: Optional[Path]) -> bool:
    """Whether ``path`` is the shipped model."""
    return path is not None and Path(path).resolve() == SHIPPED_MODEL.resolve()


def start_process(args, log: Path) -> subprocess.Popen:
    """Start ``python ARGS`` in the repository with this test run's environment (DDS on lo)."""
    return subprocess.Popen([sys.executable, *args], cwd=Path(__file__).resolve().parents[1],
                            env=dict(os.environ), stdout=open(log, 'w'),
                            stderr=subprocess.STDOUT)


def stop_process(proc: subprocess.Popen, timeout: float = 10.0) -> int:
    """SIGINT (as Ctrl-C would), then kill after ``timeout``; return the exit code."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            return proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            return proc.wait()
    return proc.returncode


def run_live_trial(*, start: Callable[[list, Path], subprocess.Popen], node_args: list,
                   tmp_path: Path) -> dict:
    """
    Run the node, a listener and a live trial publisher as three processes; return the results.

    ``start(args, log)`` starts ``python ARGS`` (:func:`start_process`, or another Python's);
    ``node_args`` are the node's (``['-m', 'contact_detector.ros.node', ...]``). The publisher
    plays a simulated trial at the real rate once the listener is up
    (``contact_detector.ros.live_trial``), 1.5 s past the onset; the node is stopped with
    SIGINT after the listener. Returns ``pub`` and ``got`` (the publisher's and the listener's
    JSON), ``logs`` (``node``, ``listen``, ``pub``) and the exit codes ``node_code``,
    ``pub_code`` and ``listen_code``.
    """
    pub_json, listen_json, stop = (tmp_path / 'pub.json', tmp_path / 'listen.json',
                                   tmp_path / 'stop')
    node = start(node_args, tmp_path / 'node.log')
    ready = tmp_path / 'listener_ready'
    listener = start(['-m', 'contact_detector.ros.live_trial', 'listen',
                      '--out', str(listen_json), '--stop-file', str(stop), '--max-s', '90',
                      '--ready-file', str(ready)], tmp_path / 'listen.log')
    publisher = start(['-m', 'contact_detector.ros.live_trial', 'publish', '--out', str(pub_json),
                       '--after-onset', '1.5', '--wait-file', str(ready)], tmp_path / 'pub.log')
    try:
        publisher.wait(timeout=75)
        time.sleep(0.5)
        stop.touch()
        listener.wait(timeout=15)
    finally:
        stop.touch()
        for proc in (publisher, listener):
            if proc.poll() is None:
                proc.kill()
        node_code = stop_process(node)
    logs = {name: (tmp_path / f'{name}.log').read_text() for name in ('node', 'listen', 'pub')}
    out = {'logs': logs, 'node_code': node_code, 'pub_code': publisher.returncode,
           'listen_code': listener.returncode}
    for key, path in (('pub', pub_json), ('got', listen_json)):
        out[key] = json.loads(path.read_text()) if path.exists() else None
    return out


def stamp(t: float):
    """Return ``t`` seconds as a ``builtin_interfaces/Time`` (nanoseconds rounded, capped)."""
    from builtin_interfaces.msg import Time
    sec = int(np.floor(t))
    return Time(sec=sec, nanosec=min(999_999_999, int(round((t - sec) * 1e9))))


def spin_until(executor, predicate: Callable[[], bool], *, timeout: float = 10.0) -> None:
    """Spin ``executor`` in 10 ms steps until ``predicate()``; fail after ``timeout`` s."""
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError('timed out waiting for the node')
        executor.spin_once(timeout_sec=0.01)
