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
Damaged bags: what can be read is read, the loss is reported, nothing readable is an error.

The bags are written with rosbags' writers (through the simulator's bag writer) in tmp_path,
and the tests damage the bytes themselves, as a recorder killed mid-write or a bad disk does.
"""

import json
import logging
from pathlib import Path
import shutil
import sqlite3

from contact_detector.cli import detect as detect_cli
from contact_detector.errors import BagError
from contact_detector.io.bags import find_bags, iter_messages, topic_types
from contact_detector.io.cdr import FAST_DECODERS
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import numpy as np
import pytest

pytestmark = pytest.mark.slow   # writes and reads many bags, runs detect

TOPICS = {'/wrist_wrench': 'geometry_msgs/msg/WrenchStamped',
          '/audio': 'std_msgs/msg/Int16MultiArray', '/contact_truth': 'std_msgs/msg/Bool'}


@pytest.fixture(scope='module')
def trial():
    return simulate_trial(seed=5, index=0)


def _bag(trial, tmp_path: Path, storage: str) -> Path:
    return write_trial_bag(trial=trial, path=tmp_path / storage / trial.name, storage=storage)


def _storage_file(bag: Path) -> Path:
    if bag.is_file():
        return bag
    return next(p for p in bag.iterdir() if p.suffix in ('.db3', '.mcap'))


def _keys(bag: Path) -> list:
    """Topic and log time of every message read, checked equal with the offline tools' path."""
    keys = [(m.topic, m.log_time_ns) for m in iter_messages(bag)]
    fast = [(m.topic, m.log_time_ns) for m in iter_messages(bag, decoders=FAST_DECODERS)]
    assert fast == keys
    return keys


def _cut(file: Path, fraction: float) -> None:
    data = file.read_bytes()
    file.write_bytes(data[:int(len(data) * fraction)])


def _warnings(caplog, bag: Path) -> list:
    return [r.getMessage() for r in caplog.records
            if r.levelno == logging.WARNING and str(bag) in r.getMessage()]


@pytest.mark.parametrize('storage', ['ros1', 'sqlite3', 'mcap'])
def test_a_bag_cut_short_yields_the_messages_before_the_cut(trial, tmp_path, caplog, storage):
    bag = _bag(trial, tmp_path, storage)
    intact = _keys(bag)
    _cut(_storage_file(bag), 0.6)
    with caplog.at_level(logging.WARNING):
        got = _keys(bag)
        assert topic_types(bag) == TOPICS
    # the readable part, in log-time order, is what the intact bag has up to the cut
    assert 0.3 * len(intact) < len(got) < len(intact)
    if storage == 'sqlite3':
        # rows are cut in write order, which is log-time order within a few messages
        kept = set(got)
        assert got == [k for k in intact if k in kept]
        last = got[-1][1] - 50_000_000
        assert got[:len(got) - 20] == [k for k in intact if k[1] < last][:len(got) - 20]
    else:
        assert got == intact[:len(got)]
    [warning] = _warnings(caplog, bag)
    assert 'damaged bag' in warning and 'cut short' in warning
    assert f'read {len(got)} messages' in warning
    if storage != 'ros1':       # rosbag2 records its message count: the loss is counted
        assert f'{len(intact) - len(got)} of {len(intact)} messages lost' in warning


@pytest.mark.parametrize('storage', ['ros1', 'mcap'])
def test_a_bag_without_its_index_or_footer_reads_whole(trial, tmp_path, caplog, storage):
    """The recorder died while writing the index (ROS 1) or the summary and footer (mcap)."""
    bag = _bag(trial, tmp_path, storage)
    intact = _keys(bag)
    file = _storage_file(bag)
    file.write_bytes(file.read_bytes()[:-40])
    with caplog.at_level(logging.WARNING):
        assert _keys(bag) == intact
    assert len(_warnings(caplog, bag)) == 1


def test_a_damaged_sqlite3_page_loses_only_its_rows(trial, tmp_path, caplog):
    bag = _bag(trial, tmp_path, 'sqlite3')
    intact = _keys(bag)
    file = _storage_file(bag)
    data = bytearray(file.read_bytes())
    page = 4096
    middle = (len(data) // page // 2) * page
    data[middle:middle + 256] = b'\xff' * 256          # a page header overwritten
    file.write_bytes(bytes(data))
    with caplog.at_level(logging.WARNING):
        got = _keys(bag)
    assert 0.5 * len(intact) < len(got) < len(intact)
    assert set(got) <= set(intact) and got == sorted(got, key=lambda k: k[1])
    # the rows after the damaged page are read too, not only those before it
    assert got[-1] == intact[-1]
    [warning] = _warnings(caplog, bag)
    assert f'{len(intact) - len(got)} of {len(intact)} messages lost' in warning


def test_corrupt_payloads_are_skipped_and_counted(trial, tmp_path, caplog):
    bag = _bag(trial, tmp_path, 'sqlite3')
    intact = _keys(bag)
    with sqlite3.connect(_storage_file(bag)) as con:
        ids = [r[0] for r in con.execute(
            'SELECT messages.id FROM messages JOIN topics ON topic_id = topics.id '
            "WHERE topics.name = '/audio' ORDER BY messages.id LIMIT 3 OFFSET 20")]
        con.executemany("UPDATE messages SET data = X'0001020304' WHERE id = ?",
                        [(i,) for i in ids])
    with caplog.at_level(logging.WARNING):
        got = _keys(bag)
    assert len(got) == len(intact) - 3 and set(got) < set(intact)
    [warning] = _warnings(caplog, bag)
    assert 'skipped 3 messages whose bytes do not deserialise (3 on /audio)' in warning


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
@pytest.mark.parametrize('damage', ['missing', 'broken'])
def test_a_missing_or_broken_metadata_yaml(trial, tmp_path, caplog, storage, damage):
    bag = _bag(trial, tmp_path, storage)
    intact = _keys(bag)
    meta = bag / 'metadata.yaml'
    if damage == 'missing':
        meta.unlink()
    else:
        meta.write_text(meta.read_text()[:120])
    assert find_bags([bag.parent]) == [bag]     # still a bag: it has its storage file
    # a folder of bags with a stray storage file stays a folder of bags
    (bag.parent / 'stray.mcap').write_bytes(b'')
    assert find_bags([bag.parent]) == [bag]
    with caplog.at_level(logging.WARNING):
        assert topic_types(bag) == TOPICS
        assert _keys(bag) == intact
    [warning] = _warnings(caplog, bag)
    assert 'does not open' in warning and f'read {len(intact)} messages' in warning


def test_nothing_readable_is_a_bag_error_naming_the_bag(trial, tmp_path):
    ros1 = _bag(trial, tmp_path, 'ros1')
    ros1.write_bytes(ros1.read_bytes()[:20])
    mcap = _bag(trial, tmp_path, 'mcap')
    _storage_file(mcap).write_bytes(b'not an mcap file at all' * 10)
    db3 = _bag(trial, tmp_path, 'sqlite3')
    _storage_file(db3).write_bytes(bytes(range(256)) * 40)
    for bag in (ros1, mcap, db3):
        with pytest.raises(BagError, match='cannot read bag') as err:
            list(iter_messages(bag))
        assert str(bag) in str(err.value) and 'no readable topic or message' in str(err.value)
    with pytest.raises(BagError, match=str(ros1)):
        topic_types(ros1)


@pytest.mark.parametrize('storage', ['ros1', 'sqlite3', 'mcap'])
def test_any_cut_or_flipped_bytes_give_messages_or_a_bag_error(trial, tmp_path, storage):
    """Never a crash: cut anywhere or with bytes flipped, a bag reads or raises BagError."""
    bag = _bag(trial, tmp_path, storage)
    intact = set(_keys(bag))
    file = _storage_file(bag)
    data = file.read_bytes()
    rng = np.random.default_rng(0)
    for k in range(12):
        damaged = bytearray(data[:int(rng.integers(0, len(data)))] if k % 2 else data)
        if not k % 2:
            at = rng.integers(0, len(data), size=8)
            damaged[at[0]:at[0] + 64] = rng.integers(0, 256, 64, dtype=np.uint8).tobytes()
            for i in at[1:]:
                damaged[i] ^= 0xFF
        file.write_bytes(bytes(damaged))
        try:
            # (the fast readers and rosbags may judge a flipped payload differently)
            got = [(m.topic, m.log_time_ns) for m in iter_messages(bag)]
            fast = [(m.topic, m.log_time_ns)
                    for m in iter_messages(bag, decoders=FAST_DECODERS)]
        except BagError as err:
            assert str(bag) in str(err)
            continue
        # what is read was recorded; flipped bytes may alter a time but never add messages
        assert len(got) <= len(intact) and (k % 2 == 0 or set(got) <= intact)
        assert len(fast) <= len(intact) and (k % 2 == 0 or fast == got)


def _rows(path: Path) -> dict:
    out: dict = {}
    for line in path.read_text().splitlines():
        row = json.loads(line)
        out.setdefault(row['bag'].removesuffix('.bag'), []).append(row)
    return out


def test_detect_goes_on_over_a_damaged_bag(tmp_path, caplog):
    """The damaged bag's decisions are the intact bag's up to the damage: no invented release."""
    intact_dir, damaged_dir = tmp_path / 'intact', tmp_path / 'damaged'
    for index in range(2):
        write_trial_bag(trial=simulate_trial(seed=8, index=index),
                        path=intact_dir / f'place_{index}', storage='ros1')
    shutil.copytree(intact_dir, damaged_dir)
    cut = damaged_dir / 'place_1.bag'
    _cut(cut, 0.7)
    args = ['--audio-rate', '16000', '--wrench-rate', '100']
    assert detect_cli.main([str(intact_dir), *args, '--out', str(tmp_path / 'a.jsonl')]) == 0
    with caplog.at_level(logging.WARNING):
        assert detect_cli.main([str(damaged_dir), *args,
                                '--out', str(tmp_path / 'b.jsonl')]) == 0
    assert _warnings(caplog, cut)
    before, after = _rows(tmp_path / 'a.jsonl'), _rows(tmp_path / 'b.jsonl')
    assert after['place_0'] == before['place_0']
    kept = after['place_1']
    assert 0 < len(kept) < len(before['place_1'])
    assert kept == before['place_1'][:len(kept)]
