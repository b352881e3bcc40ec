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
Hypothesis fuzzing of the detector core and of every message adapter.

What is asserted
----------------
* ``ContactDetector``: no exception escapes ``on_audio`` / ``on_wrench`` / ``drop`` /
  ``flush`` / ``reset`` for any sequence of audio chunks (dtype int16, float16/32/64, int32,
  int64, uint8, bool, complex, object; 0-D, 1-D, 2-D; 0..200000 elements; NaN, Inf, huge,
  clipped) and wrench messages (any shapes and dtypes, NaN/Inf, stamps random, repeating,
  backwards, bag loops, far in the future, non-numeric), with any ``now``; every returned
  block is consistent (a release only at a valid contact frame).
* No release on corrupt or stale input. *Corrupt*: a message the core refuses (wrong shape or
  dtype, NaN/Inf, non-finite or non-numeric stamp, wrench stamps repeating, reordered or not
  increasing) or one an adapter refused (``drop()``). *Stale*: a well-formed message whose
  every sample is older than ``now - max_input_delay_s`` (single late messages, and whole
  stretches of good audio and wrench that arrive late together). After a warm-up on good input the
  detector is flushed and armed with the most permissive rule (threshold 0, one frame: every
  valid frame that is not blocked would release) and then gets only corrupt, stale and empty
  messages: no frame decided in that phase may be valid and none may release. Then good input
  returns on a later time line, and a release must follow within 2 s (recovery by itself).
* Hold-off: in a good stream with random faults injected, no release happens at a frame time
  before ``t + corrupt_holdoff_s`` of any corrupt message received at stream time ``t``.
* Message adapters (:mod:`contact_detector.io.messages`): for random duck-typed messages only
  InputError or ConfigError comes out, and what comes out is well-formed.
"""

from dataclasses import replace
from datetime import datetime
import os
from types import SimpleNamespace as NS

from contact_detector.detection.detector import ContactDetector, Decisions, DetectorSettings
from contact_detector.errors import ConfigError, InputError
from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.io.messages import (AUDIO_MSG_TYPES, audio_stamp, audio_to_samples,
                                          check_audio_info, check_stamp, embedded_audio_format,
                                          normalise_msg_type, stamp_to_seconds,
                                          wrench_to_arrays)
from contact_detector.model.bundle import ModelBundle, runtime_versions
from contact_detector.model.rule import DecisionRule
from contact_detector.model.storage import load_bundle, save_bundle
from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
import pytest
from sklearn.ensemble import RandomForestClassifier

pytestmark = pytest.mark.slow   # hypothesis: thousands of examples per test

RATE = 16000
FT_RATE = 100.0
CHUNK = 160
T0 = 1_700_000_000.0
#: Every valid frame that is not blocked is a contact and releases (the worst case).
PERMISSIVE = DecisionRule(threshold=0.0, confirm_frames=1, refractory_s=0.0)
SETTINGS = DetectorSettings(audio_rate=RATE, wrench_rate=FT_RATE, rule=PERMISSIVE)
#: FUZZ_SCALE=10 runs ten times as many examples (a longer, non-CI fuzzing session).
SCALE = float(os.environ.get('FUZZ_SCALE', '1'))


def fuzz(examples: int):
    return settings(max_examples=max(1, int(examples * SCALE)), deadline=None,
                    derandomize=SCALE == 1,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


ALLOWED = (InputError, ConfigError)


@pytest.fixture(scope='module')
def bundle(tmp_path_factory):
    """Return a real (tiny) forest on random features, saved and loaded by model/storage.py."""
    config = FeatureConfig()
    rng = np.random.default_rng(0)
    x = rng.normal(0.0, 1.0, (400, config.n_features))
    y = (x[:, 0] + 0.3 * rng.normal(size=400) > 0).astype(int)
    forest = RandomForestClassifier(n_estimators=3, max_depth=6, random_state=0).fit(x, y)
    made = ModelBundle(forest=forest, feature_config=config,
                       feature_names=config.feature_names,
                       feature_schema_version=FEATURE_SCHEMA_VERSION,
                       label_window={'start_s': 0.0, 'end_s': 0.1},
                       decision_rule=DecisionRule(threshold=0.5, confirm_frames=2),
                       versions=runtime_versions(), training={'source': 'test_fuzz'},
                       created=datetime(2026, 1, 1).isoformat())
    path = save_bundle(bundle=made, path=tmp_path_factory.mktemp('fuzz') / 'tiny.npz')
    return load_bundle(path=path)


def new_detector(bundle, **overrides) -> ContactDetector:
    return ContactDetector(bundle=bundle, settings=replace(SETTINGS, **overrides))


def check_block(d: Decisions) -> None:
    """Shapes agree, p in [0, 1], contact only on valid frames, releases only on contacts."""
    assert isinstance(d, Decisions)
    n = len(d)
    for arr in (d.t, d.p, d.contact, d.valid):
        assert isinstance(arr, np.ndarray) and arr.shape == (n,)
    assert np.all((d.p >= 0.0) & (d.p <= 1.0))
    assert not np.any(d.contact & ~d.valid)
    assert set(d.releases) <= set(d.t[d.contact].tolist())


# --- good input ------------------------------------------------------------------------------

def good_audio(rng: np.random.Generator) -> np.ndarray:
    return np.clip(rng.normal(0.0, 400.0, CHUNK), -32768, 32767).astype(np.int16)


def good_wrench(rng: np.random.Generator, t: float) -> dict:
    force = np.array([[6.0, 0.2, 0.1]]) + rng.normal(0.0, 0.05, (1, 3))
    torque = np.array([[0.1, 0.9, 0.0]]) + rng.normal(0.0, 0.01, (1, 3))
    return {'t': np.array([t]), 'force': force, 'torque': torque}


def feed_good(det: ContactDetector, rng: np.random.Generator, *, t0: float,
              seconds: float) -> list:
    """Feed 10 ms of wrench then audio per step from ``t0``; return the decision blocks."""
    blocks = []
    for k in range(int(round(seconds * 100))):
        t = t0 + (k + 1) * 0.01
        blocks.append(det.on_wrench(**good_wrench(rng, t), now=t))
        blocks.append(det.on_audio(good_audio(rng), stamp=t, now=t))
    return blocks


# --- random arrays (built from a drawn seed: hypothesis stays fast at 200 000 elements) -------

DTYPES = ('int16', 'float32', 'float64', 'int32', 'int64', 'uint8', 'bool', 'complex64',
          'float16', 'object')
FILLS = ('noise', 'zeros', 'clipped', 'nan', 'inf', 'huge', 'tiny')


def make_array(*, dtype: str, shape: tuple, fill: str, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    base = np.asarray(rng.normal(0.0, 0.3, shape))
    size = base.size
    with np.errstate(all='ignore'):
        if fill == 'zeros':
            base = np.zeros(shape)
        elif fill == 'clipped':
            base = np.clip(base * 20.0, -1.0, 1.0)
        elif fill == 'huge':
            base = base * 1e300
        elif fill == 'tiny':
            base = base * 1e-300
        elif fill in ('nan', 'inf') and size:
            flat = base.reshape(-1)
            flat[rng.integers(size)] = np.nan if fill == 'nan' else -np.inf
        base = np.asarray(base)        # arithmetic on 0-D arrays gives numpy scalars
        if dtype == 'object':
            arr = base.astype(object)
            if size and rng.random() < 0.5:
                arr.reshape(-1)[rng.integers(size)] = rng.choice(['x', None, 3])
            return arr
        if dtype == 'complex64':
            return (base + 1j * base).astype(np.complex64)
        if dtype == 'bool':
            return base > 0
        info = np.iinfo(dtype) if np.dtype(dtype).kind in 'iu' else None
        if info is not None:
            scaled = np.nan_to_num(base * info.max, nan=0.0, posinf=info.max, neginf=info.min)
            return np.clip(scaled, info.min, info.max).astype(dtype)
        return base.astype(dtype)


@st.composite
def arrays(draw, *, ndims=(0, 1, 2), dtypes=DTYPES, fills=FILLS, min_size=0,
           max_size=200_000) -> np.ndarray:
    ndim = draw(st.sampled_from(ndims))
    size = draw(st.one_of(st.integers(min_size, 400), st.integers(min_size, max_size)))
    if ndim == 0:
        shape = ()
    elif ndim == 1:
        shape = (size,)
    else:
        cols = draw(st.integers(1, 4))
        shape = (max(size // cols, 1 if min_size else 0), cols)
    return make_array(dtype=draw(st.sampled_from(dtypes)), shape=shape,
                      fill=draw(st.sampled_from(fills)), seed=draw(st.integers(0, 2 ** 32 - 1)))


# --- property 1: nothing escapes ---------------------------------------------------------------

STAMP_KINDS = ('next', 'next', 'next', 'repeat', 'back_small', 'back_big', 'future', 'nan',
               'inf', 'random', 'none', 'text')


def pick_stamp(kind: str, clock: float, rng: np.random.Generator):
    return {'next': clock, 'repeat': clock - 0.01, 'back_small': clock - 0.2,
            'back_big': clock - 30.0, 'future': clock + 1e6, 'nan': float('nan'),
            'inf': float('inf'), 'random': float(rng.normal(0.0, 1e9)), 'none': None,
            'text': 'soon'}[kind]


@st.composite
def audio_ops(draw):
    return ('audio', draw(arrays()), draw(st.sampled_from(STAMP_KINDS)))


@st.composite
def wrench_ops(draw):
    n = draw(st.integers(0, 60))
    t_shape = draw(st.sampled_from(['n', 'n', 'n1', 'scalar', 'n+1', 'list', 'none', 'text',
                                    'bigint']))
    f_shape = draw(st.sampled_from([(n, 3), (n, 3), (n, 3), (n, 2), (3,), (n, 3, 1)]))
    fill = draw(st.sampled_from(('noise', 'noise', 'nan', 'inf', 'huge')))
    dtype = draw(st.sampled_from(('float64', 'float64', 'float32', 'int32', 'object')))
    order = draw(st.sampled_from(('up', 'up', 'up', 'flat', 'down', 'shuffle')))
    return ('wrench', n, t_shape, f_shape, fill, dtype, order,
            draw(st.sampled_from(STAMP_KINDS)), draw(st.integers(0, 2 ** 32 - 1)))


def build_wrench(op, clock: float) -> dict:
    _, n, t_shape, f_shape, fill, dtype, order, kind, seed = op
    rng = np.random.default_rng(seed)
    start = pick_stamp(kind, clock, rng)
    start = clock if start is None or isinstance(start, str) else start
    with np.errstate(all='ignore'):
        t = start - 0.01 * n + 0.01 * np.arange(1, n + 1)
    if order == 'flat':
        t = np.full(n, start)
    elif order == 'down':
        t = t[::-1]
    elif order == 'shuffle':
        t = rng.permutation(t)
    t_value = {'n': t, 'n1': t[:, None], 'scalar': np.float64(start),
               'n+1': np.append(t, start), 'list': t.tolist(), 'none': None,
               'text': ['a'] * n, 'bigint': [10 ** 400] * max(n, 1)}[t_shape]
    force = make_array(dtype=dtype, shape=f_shape, fill=fill, seed=seed)
    torque = make_array(dtype=dtype, shape=f_shape, fill='noise', seed=seed + 1)
    return {'t': t_value, 'force': force, 'torque': torque}


@st.composite
def control_ops(draw):
    what = draw(st.sampled_from(('drop', 'drop', 'reset', 'flush', 'arm', 'advance')))
    if what == 'drop':
        stamp = draw(st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True),
                               st.just('offset')))
        return ('drop', draw(st.sampled_from(('audio', 'wrench'))), stamp)
    if what == 'advance':
        return ('advance', draw(st.sampled_from((0.05, 0.3, 1.0, 30.0, -30.0, 1e5))))
    return (what,)


ANY_OP = st.one_of(audio_ops(), wrench_ops(), control_ops())


@fuzz(100)
@given(ops=st.lists(ANY_OP, max_size=25), now_kind=st.sampled_from(('clock', 'late', 'none')),
       seed=st.integers(0, 2 ** 32 - 1))
def test_no_exception_escapes_the_detector(bundle, ops, now_kind, seed):
    rng = np.random.default_rng(seed)
    det = new_detector(bundle)
    clock = T0
    blocks = feed_good(det, rng, t0=clock, seconds=0.3)
    clock += 0.3
    for op in ops:
        clock += 0.01
        now = {'clock': clock, 'late': clock + 2.0, 'none': None}[now_kind]
        if op[0] == 'audio':
            stamp = pick_stamp(op[2], clock, rng)
            blocks.append(det.on_audio(op[1], stamp=stamp, now=now))
        elif op[0] == 'wrench':
            blocks.append(det.on_wrench(**build_wrench(op, clock), now=now))
        elif op[0] == 'drop':
            stamp = clock if op[2] == 'offset' else op[2]
            blocks.append(det.drop(kind=op[1], reason='fuzz', stamp=stamp))
        elif op[0] == 'reset':
            det.reset()
        elif op[0] == 'flush':
            blocks.append(det.flush())
        elif op[0] == 'arm':
            det.arm(True)
        else:
            clock += op[1]
    blocks.append(det.flush())
    for d in blocks:
        check_block(d)
    assert det.counts['releases'] == sum(len(d.releases) for d in blocks)
    assert all(isinstance(v, int) and v >= 0 for v in det.counts.values())
    # And the detector still works: good input on a new time line is decided (valid frames).
    later = feed_good(det, rng, t0=clock + 100.0, seconds=1.0)
    assert any(d.valid.any() for d in later)


# --- property 2: corrupt or stale input never releases; good input recovers ------------------

GOOD_AUDIO_DTYPES = ('int16', 'float32', 'float64', 'float16')
BAD_AUDIO_DTYPES = ('int32', 'int64', 'uint8', 'bool', 'complex64', 'object')


@st.composite
def corrupt_audio(draw):
    how = draw(st.sampled_from(('dtype', 'ndim', 'nonfinite', 'stamp', 'empty', 'stale')))
    stamp_kind = 'ok'
    if how == 'dtype':
        arr = draw(arrays(ndims=(1,), dtypes=BAD_AUDIO_DTYPES, min_size=1))
    elif how == 'ndim':
        arr = draw(arrays(ndims=(0, 2), min_size=1))
    elif how == 'nonfinite':
        arr = draw(arrays(ndims=(1,), dtypes=('float32', 'float64'), fills=('nan', 'inf'),
                          min_size=1))
    elif how == 'stamp':
        arr = draw(arrays(ndims=(1,), dtypes=GOOD_AUDIO_DTYPES, fills=('noise', 'clipped'),
                          min_size=1))
        stamp_kind = draw(st.sampled_from(('nan', 'inf', 'text')))
    elif how == 'empty':
        arr = np.zeros(0, dtype=draw(st.sampled_from(GOOD_AUDIO_DTYPES)))
    else:
        arr = draw(arrays(ndims=(1,), dtypes=GOOD_AUDIO_DTYPES,
                          fills=('noise', 'zeros', 'clipped', 'huge', 'tiny'), min_size=1))
        stamp_kind = 'stale'
    return ('audio', arr, stamp_kind, draw(st.floats(0.001, 100.0)))


@st.composite
def corrupt_wrench(draw):
    how = draw(st.sampled_from(('nonfinite', 'shape', 'dtype', 'order', 'repeat', 'stale')))
    return ('wrench', how, draw(st.integers(1, 40)), draw(st.floats(0.02, 100.0)),
            draw(st.integers(0, 2 ** 32 - 1)))


def build_corrupt_wrench(op, *, now: float, last_t, max_delay: float) -> dict:
    _, how, n, age, seed = op
    rng = np.random.default_rng(seed)
    stale_end = now - max_delay - age
    t = stale_end - 0.01 * (n - 1) + 0.01 * np.arange(n)
    force = np.array([[6.0, 0.2, 0.1]]).repeat(n, axis=0) + rng.normal(0.0, 0.05, (n, 3))
    torque = np.zeros((n, 3))
    if how == 'nonfinite':
        force[rng.integers(n), rng.integers(3)] = rng.choice([np.nan, np.inf, -np.inf])
        t = t + (max_delay + age)            # fresh stamps: only the NaN/Inf makes it corrupt
    elif how == 'shape':
        force = force[:, :2] if rng.random() < 0.5 else np.append(t, 0.0)
        t = t + (max_delay + age)
    elif how == 'dtype':
        force = np.full((n, 3), 'x')
        t = t + (max_delay + age)
    elif how == 'order':
        t = np.full(2, now) if n == 1 else np.sort(t)[::-1] + (max_delay + age)
        force, torque = np.zeros((t.size, 3)), np.zeros((t.size, 3))
    elif how == 'repeat' and last_t is not None:
        t = np.array([last_t - 0.2 * rng.random()])
        force, torque = force[:1], torque[:1]
    return {'t': t, 'force': force, 'torque': torque}


@st.composite
def corrupt_drops(draw):
    return ('drop', draw(st.sampled_from(('audio', 'wrench'))),
            draw(st.one_of(st.none(), st.just('now'),
                           st.floats(allow_nan=True, allow_infinity=True))))


@st.composite
def lagged_streams(draw):
    """Good audio and wrench, but all of it ``lag`` s late: a delayed link or a stalled node."""
    return ('lagged', draw(st.floats(0.1, 1.0)), draw(st.floats(0.51, 5.0)))


CORRUPT_OP = st.one_of(corrupt_audio(), corrupt_wrench(), corrupt_drops(), lagged_streams())


@fuzz(50)
@given(ops=st.lists(CORRUPT_OP, min_size=1, max_size=25),
       steps=st.lists(st.floats(0.0, 0.5), min_size=25, max_size=25),
       seed=st.integers(0, 2 ** 32 - 1))
def test_corrupt_or_stale_input_never_releases_and_good_input_recovers(bundle, ops, steps,
                                                                       seed):
    rng = np.random.default_rng(seed)
    det = new_detector(bundle, armed_on_start=False)
    delay = det.settings.max_input_delay_s
    now = T0
    feed_good(det, rng, t0=now, seconds=1.0)
    now += 1.0
    det.flush()                           # nothing decided later comes from good input
    det.arm(True)
    blocks = []
    for op, step in zip(ops, steps):
        now += step
        if op[0] == 'audio':
            _, arr, kind, age = op
            stamp = {'ok': now, 'nan': float('nan'), 'inf': float('inf'), 'text': 'later',
                     'stale': now - delay - age}[kind]
            blocks.append(det.on_audio(arr, stamp=stamp, now=now))
        elif op[0] == 'wrench':
            msg = build_corrupt_wrench(op, now=now, last_t=det.extractor.ft.last_input_t,
                                       max_delay=delay)
            blocks.append(det.on_wrench(**msg, now=now))
        elif op[0] == 'lagged':
            for _ in range(int(op[1] * 100)):
                now += 0.01
                blocks.append(det.on_wrench(**good_wrench(rng, now - op[2]), now=now))
                blocks.append(det.on_audio(good_audio(rng), stamp=now - op[2], now=now))
        else:
            stamp = now if op[2] == 'now' else op[2]
            blocks.append(det.drop(kind=op[1], reason='refused by an adapter', stamp=stamp))
    for d in blocks:
        check_block(d)
    assert not any(d.valid.any() for d in blocks), 'a frame of corrupt/stale input was valid'
    assert not any(d.releases for d in blocks) and det.counts['releases'] == 0
    assert det.armed
    # Good input again, later than anything accepted (stale, so <= now): a release within 2 s.
    start = now + 5.0
    later = feed_good(det, rng, t0=start, seconds=2.0)
    releases = [r for d in later for r in d.releases]
    assert len(releases) == 1 and start < releases[0] <= start + 2.0, (releases, det.counts)


# --- property 3: the hold-off after a corrupt message ----------------------------------------

FAULTS = ('audio_nan', 'audio_2d', 'audio_dtype', 'wrench_nan', 'wrench_shape',
          'wrench_repeat', 'adapter_audio', 'adapter_wrench')


@fuzz(40)
@given(faults=st.lists(st.tuples(st.integers(0, 199), st.sampled_from(FAULTS)), max_size=8),
       seed=st.integers(0, 2 ** 32 - 1))
def test_no_release_within_the_holdoff_after_a_corrupt_message(bundle, faults, seed):
    rng = np.random.default_rng(seed)
    det = new_detector(bundle)
    hold, warm = det.settings.corrupt_holdoff_s, det.settings.warmup_s
    plan = dict(faults)
    fault_t, releases, first_frame = [], [], None
    for k in range(200):
        t = T0 + (k + 1) * 0.01
        blocks = [det.on_wrench(**good_wrench(rng, t), now=t),
                  det.on_audio(good_audio(rng), stamp=t, now=t)]
        fault = plan.get(k)
        if fault == 'audio_nan':
            blocks.append(det.on_audio(np.full(CHUNK, np.nan), stamp=t, now=t))
        elif fault == 'audio_2d':
            blocks.append(det.on_audio(np.zeros((CHUNK, 2), np.int16), stamp=t, now=t))
        elif fault == 'audio_dtype':
            blocks.append(det.on_audio(np.zeros(CHUNK, np.int32), stamp=t, now=t))
        elif fault == 'wrench_nan':
            msg = good_wrench(rng, t + 0.005)
            msg['torque'][0, 2] = np.nan
            blocks.append(det.on_wrench(**msg, now=t))
        elif fault == 'wrench_shape':
            blocks.append(det.on_wrench(t=[t + 0.005], force=[[1.0, 2.0]], torque=[[0.0] * 3],
                                        now=t))
        elif fault == 'wrench_repeat':
            blocks.append(det.on_wrench(**good_wrench(rng, t), now=t))
        elif fault is not None:
            kind = 'audio' if fault == 'adapter_audio' else 'wrench'
            blocks.append(det.drop(kind=kind, reason='refused by an adapter', stamp=t))
        if fault is not None:
            fault_t.append(t)
        for d in blocks:
            check_block(d)
            if first_frame is None and len(d):
                first_frame = float(d.t[0])
            for r in d.releases:
                releases.append(r)
                det.arm(True)
    for r in releases:
        assert r >= first_frame + warm
        assert not any(f <= r < f + hold for f in fault_t), (r, fault_t)
    # With no fault at all the permissive rule releases right after the warm-up.
    if not faults:
        assert releases and releases[0] < first_frame + warm + 0.05


# --- message adapters ------------------------------------------------------------------------

MISSING = object()


def junk():
    """Any value a field might hold in a malformed message."""
    scalars = st.one_of(st.none(), st.booleans(), st.integers(-2 ** 70, 2 ** 70),
                        st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5),
                        st.binary(max_size=9),
                        st.sampled_from([np.float32('inf'), np.float64('nan'), np.int64(-1),
                                         np.uint64(2 ** 63), np.float32(1e30)]))
    arrays_ = arrays(max_size=2000)
    lists = st.lists(st.one_of(st.integers(-2 ** 40, 2 ** 40), st.floats(), st.text(max_size=2),
                               st.none()), max_size=8)
    return st.one_of(scalars, arrays_, lists, st.builds(NS), st.builds(dict))


def field(plausible):
    """Return a field's value: usually plausible, sometimes junk, sometimes missing."""
    return st.one_of(plausible, plausible, junk(), st.just(MISSING))


def ns(**fields) -> NS:
    return NS(**{k: v for k, v in fields.items() if v is not MISSING})


@st.composite
def stamps(draw):
    return ns(sec=draw(field(st.integers(-2 ** 31, 2 ** 31))),
              nanosec=draw(field(st.integers(-10, 2 * 10 ** 9))))


@st.composite
def headers(draw):
    return ns(stamp=draw(field(stamps())), frame_id=draw(field(st.text(max_size=3))))


@st.composite
def vectors(draw):
    number = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10))
    return ns(x=draw(field(number)), y=draw(field(number)), z=draw(field(number)))


@st.composite
def wrench_msgs(draw):
    return ns(header=draw(field(headers())),
              wrench=draw(field(st.builds(lambda f, m: ns(force=f, torque=m),
                                          field(vectors()), field(vectors())))))


def sample_values():
    """Plausible sample arrays in every container a message may use."""
    ints = st.lists(st.integers(-40000, 40000), max_size=64)
    return st.one_of(
        ints, st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=64),
        arrays(ndims=(1,), max_size=5000), arrays(max_size=500), st.binary(max_size=64),
        ints.map(lambda v: np.asarray(v).astype(np.int16)))


@st.composite
def multiarrays(draw):
    layout = draw(field(st.builds(lambda off: ns(data_offset=off, dim=[]),
                                  field(st.integers(-5, 100)))))
    return ns(layout=layout, data=draw(field(sample_values())))


@st.composite
def ros_drivers_audio(draw):
    payload = draw(field(st.one_of(st.binary(max_size=65), sample_values())))
    audio = ns(data=payload)
    return ns(header=draw(field(headers())), audio=draw(field(st.just(audio))), data=payload)


TYPED = ('float32_data', 'int32_data', 'int24_data', 'int16_data', 'int8_data', 'uint8_data')


@st.composite
def mgonzs13_audio(draw):
    info = ns(format=draw(field(st.sampled_from([1, 2, 4, 8, 16, 32, 0, 3, 64]))),
              channels=draw(field(st.integers(-1, 4))),
              rate=draw(field(st.sampled_from([16000, 44100, 0, 10 ** 7]))),
              chunk=draw(field(st.integers(0, 1024))))
    chosen = draw(st.sets(st.sampled_from(TYPED), max_size=3))
    data = ns(**{name: draw(field(sample_values())) if name in chosen else [] for name in TYPED})
    name = draw(st.sampled_from(('audio_data', 'audio')))
    audio = ns(info=draw(field(st.just(info))), **{name: draw(field(st.just(data)))})
    return ns(header=draw(field(headers())), audio=draw(field(st.just(audio))))


def assert_only_allowed(call):
    """Run ``call``; any exception other than InputError/ConfigError fails the test."""
    try:
        return call()
    except ALLOWED:
        return None


@fuzz(150)
@given(msg=wrench_msgs())
def test_wrench_adapter(msg):
    out = assert_only_allowed(lambda: wrench_to_arrays(msg))
    if out is not None:
        t, force, torque = out
        assert t.shape == (1,) and np.isfinite(t).all()
        assert force.shape == torque.shape == (1, 3)
        assert force.dtype == torque.dtype == np.float64


@fuzz(150)
@given(stamp=st.one_of(stamps(), junk()))
def test_stamp_adapter(stamp):
    out = assert_only_allowed(lambda: stamp_to_seconds(stamp))
    assert out is None or (isinstance(out, float) and np.isfinite(out))


@fuzz(200)
@given(stamp=st.floats(allow_nan=True, allow_infinity=True), now=st.floats(-1e12, 1e12),
       previous=st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True)),
       max_future=st.floats(0.0, 1e6))
def test_check_stamp(stamp, now, previous, max_future):
    try:
        check_stamp(stamp=stamp, now=now, max_future_s=max_future, previous=previous)
    except InputError:
        return
    assert np.isfinite(stamp) and stamp - now <= max_future


@fuzz(100)
@given(msg_type=st.one_of(st.sampled_from(sorted(AUDIO_MSG_TYPES)), st.text(max_size=30),
                          st.sampled_from(['std_msgs/Int16MultiArray', 'audio_common_msgs/x'])))
def test_msg_type_names(msg_type):
    assert_only_allowed(lambda: normalise_msg_type(msg_type))


@st.composite
def any_audio_msg(draw):
    msg_type = draw(st.sampled_from(sorted(AUDIO_MSG_TYPES)))
    if 'MultiArray' in msg_type:
        msg = draw(multiarrays())
    elif msg_type == 'audio_common_msgs/msg/AudioStamped':
        msg = draw(mgonzs13_audio())
    else:
        msg = draw(ros_drivers_audio())
    # Sometimes the wrong kind of message for the configured type.
    if draw(st.integers(0, 9)) == 0:
        msg = draw(st.one_of(multiarrays(), mgonzs13_audio(), ros_drivers_audio(), junk()))
    return msg_type, msg


@fuzz(100)
@given(typed=any_audio_msg(), channels=st.integers(1, 4),
       channel=st.one_of(st.none(), st.integers(-1, 5)),
       max_samples=st.one_of(st.none(), st.integers(1, 3000)))
def test_audio_adapters(typed, channels, channel, max_samples):
    msg_type, msg = typed
    out = assert_only_allowed(lambda: audio_to_samples(
        msg, msg_type=msg_type, channels=channels, channel=channel, max_samples=max_samples))
    if out is not None:
        assert isinstance(out, np.ndarray) and out.ndim == 1 and out.size > 0
        assert out.dtype in (np.int16, np.float32)
        assert np.isfinite(out).all()
        assert max_samples is None or out.size <= max_samples
    stamp = assert_only_allowed(lambda: audio_stamp(msg, msg_type))
    assert stamp is None or np.isfinite(stamp)
    fmt = assert_only_allowed(lambda: embedded_audio_format(msg, msg_type))
    assert fmt is None or (fmt.channels >= 1 and 1000 <= fmt.sample_rate <= 384000)


@st.composite
def audio_infos(draw):
    if draw(st.booleans()):
        return ns(channels=draw(field(st.integers(-1, 300))),
                  sample_rate=draw(field(st.sampled_from([16000, 0, 10 ** 9]))),
                  sample_format=draw(field(st.sampled_from(['S16LE', 's16le', 'F32LE']))),
                  bitrate=draw(field(st.integers(0, 10 ** 6))),
                  coding_format=draw(field(st.sampled_from(['wave', 'mp3', 'raw', 'flac']))))
    return ns(format=draw(field(st.sampled_from([1, 8, 3]))),
              channels=draw(field(st.integers(-1, 3))),
              rate=draw(field(st.sampled_from([16000, 0, 10 ** 9]))),
              chunk=draw(field(st.integers(0, 10))))


@fuzz(150)
@given(info=st.one_of(audio_infos(), junk()))
def test_audio_info_adapter(info):
    fmt = assert_only_allowed(lambda: check_audio_info(info))
    assert fmt is None or (fmt.channels >= 1 and 1000 <= fmt.sample_rate <= 384000)
