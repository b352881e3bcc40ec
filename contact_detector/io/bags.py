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
Shared bag helpers: finding bags, reading messages, ground truth and manifests.

One reader for every recording a user has: rosbag2 directories (sqlite3 or mcap) and ROS 1
``.bag`` files, through rosbags (no ROS install needed). rosbag2 messages are deserialised
with rosbags' ROS 2 Jazzy typestore, extended with every message definition embedded in the
bag (rosbag2 since Iron stores them; rosbags' AnyReader reads them), so non-standard types
such as ``audio_common_msgs/msg/AudioData`` decode without their package. Deserialised
messages have the same field names as rclpy messages (``header.stamp.sec``,
``wrench.force.x``, array fields as numpy arrays), so one set of message -> array adapters
serves recorded bags and the live node. ROS 1 messages are deserialised with the definitions
every ROS 1 bag stores; their field names are the same (ROS 1's ``Header.seq`` is never read),
see :mod:`contact_detector.io.ros1`.

A damaged bag still yields what can be read (:mod:`contact_detector.io.salvage`): a bag the
readers cannot open (a ROS 1 bag cut short before its index, an mcap file without its footer,
a rosbag2 directory whose ``metadata.yaml`` is missing or broken, a sqlite3 database with
unreadable pages) is scanned for its messages, and one warning per bag (logger
``contact_detector.io.bags``) names the bag, the damage and the messages read and lost. A
message whose bytes do not deserialise is skipped and counted in the same way. Only a bag with
nothing readable raises :class:`~contact_detector.errors.BagError`.

Length: over 500 lines because it is the one reader every command shares (finding bags,
opening each storage, falling back to :mod:`.salvage` message by message, truth and
manifests); splitting it would put the fallback's bookkeeping in two places.
"""

from collections import Counter
from contextlib import contextmanager, ExitStack
import json
import logging
import math
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, NamedTuple, Sequence

from contact_detector.errors import BagError, InputError
from contact_detector.io import ros1, salvage
from contact_detector.io.messages import wrench_sample
import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Reader as Ros1Reader
from rosbags.rosbag2 import Reader
from rosbags.typesys import get_typestore, Stores

#: Topic and type names written by the simulator and read by the tools.
WRENCH_TOPIC = '/wrist_wrench'
AUDIO_TOPIC = '/audio'
TRUTH_TOPIC = '/contact_truth'
WRENCH_TYPE = 'geometry_msgs/msg/WrenchStamped'
AUDIO_TYPE = 'std_msgs/msg/Int16MultiArray'
TRUTH_TYPE = 'std_msgs/msg/Bool'
MANIFEST_NAME = 'manifest.json'

_TYPESTORE = None
_LOG = logging.getLogger(__name__)
_WARNED: set = set()


def jazzy_typestore():
    """Return the (cached) rosbags typestore with ROS 2 Jazzy's standard message types."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


class BagMessage(NamedTuple):
    """One deserialised message: topic, type name, bag log time (ns) and the message."""

    topic: str
    msgtype: str
    log_time_ns: int
    msg: Any


def is_bag_dir(path: Path) -> bool:
    """
    Return True if ``path`` is a rosbag2 directory.

    That is a directory holding ``metadata.yaml``, or (its ``metadata.yaml`` lost) storage
    files (``*.db3``, ``*.mcap``) and no subdirectory (a folder of bags is not a bag).
    """
    if not path.is_dir():
        return False
    if (path / 'metadata.yaml').is_file():
        return True
    entries = list(path.iterdir())
    return not any(p.is_dir() for p in entries) and any(
        p.suffix in ('.db3', '.mcap') and p.is_file() for p in entries)


def is_ros1_bag(path: Path) -> bool:
    """Return True if ``path`` is a ROS 1 bag file (``*.bag``)."""
    return path.is_file() and path.suffix == '.bag'


def is_bag(path: Path) -> bool:
    """Return True if ``path`` is a rosbag2 directory or a ROS 1 ``.bag`` file."""
    return is_bag_dir(path) or is_ros1_bag(path)


def find_bags(paths: Sequence[str | Path]) -> list[Path]:
    """
    Resolve bag paths.

    Parameters
    ----------
    paths : sequence of str or Path
        Each is a rosbag2 directory (has ``metadata.yaml``), a ROS 1 ``.bag`` file, a
        directory whose direct entries are bags of either kind, or a rosbag2 storage file
        (``.db3`` / ``.mcap``, meaning its directory).

    Returns
    -------
    list of Path
        Bag directories and ``.bag`` files; a directory of bags contributes its bags sorted by
        name. Argument order is kept; duplicates are dropped.

    Raises
    ------
    BagError
        A path does not exist or holds no bag, or no bag was found at all.

    """
    out: list[Path] = []
    for item in paths:
        path = Path(item)
        if not path.exists():
            raise BagError(f'no such bag or directory: {path}')
        if path.is_file() and path.suffix in ('.db3', '.mcap'):
            found = [path.parent]
        elif is_bag(path):
            found = [path]
        elif path.is_dir():
            found = sorted(p for p in path.iterdir() if is_bag(p))
            if not found:
                raise BagError(f'{path} is neither a bag (a rosbag2 directory with '
                               'metadata.yaml, or a ROS 1 .bag file) nor a directory of bags')
        else:
            raise BagError(f'{path} is not a bag (a rosbag2 directory with metadata.yaml, or '
                           'a ROS 1 .bag file)')
        for bag in found:
            if bag not in out:
                out.append(bag)
    if not out:
        raise BagError('no bag given')
    return out


def recording_names(bags: Sequence[Path]) -> dict[Path, str]:
    """
    Name each bag by the shortest end of its path that no other bag's path ends with.

    Bags from different folders often share a file name (``day1/trial_0000``,
    ``day2/trial_0000``); reports keyed by the name alone would merge them.

    Parameters
    ----------
    bags : sequence of Path
        Bags, e.g. from :func:`find_bags`.

    Returns
    -------
    dict
        Bag -> its name (``trial_0000``) when that is unique, else the fewest trailing path
        parts that are (``day1/trial_0000``).

    """
    parts = {bag: Path(bag).resolve().parts for bag in bags}
    out: dict[Path, str] = {}
    k = 1
    while len(out) < len(parts):
        # how many bags end with each k-part tail: one is a name no other bag shares
        tails = Counter(mine[-k:] for mine in parts.values())
        for bag, mine in parts.items():
            if bag not in out and (tails[mine[-k:]] == 1 or k >= len(mine)):
                out[bag] = '/'.join(mine[-k:])
        k += 1
    return out


def _complete_typestore(reader: AnyReader) -> None:
    """Add Jazzy's types that the bag did not embed (AnyReader uses only the embedded ones)."""
    jazzy = jazzy_typestore()
    have = set(reader.typestore.fielddefs)
    missing = {name: defs for name, defs in jazzy.fielddefs.items() if name not in have}
    if missing and any(c.msgtype not in have for c in reader.connections):
        reader.typestore.register(missing)


@contextmanager
def open_reader(path: str | Path) -> Iterator[AnyReader]:
    """
    Open a rosbag2 directory or a ROS 1 bag with rosbags' :class:`AnyReader`.

    Use as ``with open_reader(path) as reader: ...``. For rosbag2 the reader's typestore holds
    the bag's embedded definitions plus the Jazzy standard types; for ROS 1 the definitions
    the bag stores (every ROS 1 bag stores all of them).

    Raises
    ------
    BagError
        The bag is missing, unreadable or corrupt.

    """
    path = Path(path)
    _check_bag(path)
    try:
        reader = AnyReader([path], default_typestore=jazzy_typestore())
        reader.open()
    except Exception as err:  # rosbags raises several unrelated types for bad bags
        raise BagError(f'cannot open bag {path}: {err}') from err
    try:
        if reader.is2:
            _complete_typestore(reader)
        yield reader
    finally:
        reader.close()


def iter_messages(path: Path, *, topics: Sequence[str] | None = None,
                  decoders: Mapping[str, Callable[[bytes], Any]] | None = None,
                  raw: bool = False) -> Iterator[BagMessage]:
    """
    Yield the messages of a bag in log-time order.

    A damaged bag yields what can be read (see the module docstring): the messages before the
    damage (and, for sqlite3, after it where the table reads again), with one warning naming
    the bag and what was lost. A message whose bytes do not deserialise is skipped, counted and
    reported in one warning when the iteration ends.

    Parameters
    ----------
    path : Path
        rosbag2 directory or ROS 1 ``.bag`` file.
    topics : sequence of str or None
        Only these topics (all if None). Topics missing from the bag are ignored.
    decoders : mapping or None
        Faster readers of rosbag2 messages by type (``pkg/msg/Type`` -> function of the CDR
        bytes, see :mod:`contact_detector.io.cdr`); a reader that returns None hands the
        message to rosbags. ROS 1 bags use :data:`contact_detector.io.ros1.FAST_DECODERS`
        when ``decoders`` is given.
    raw : bool
        Yield each message's bytes as stored (CDR for rosbag2, the ROS 1 serialisation for a
        ``.bag``) instead of a deserialised message; ``decoders`` is then ignored. What
        ``replay`` publishes (:func:`iter_cdr`).

    Yields
    ------
    BagMessage

    Raises
    ------
    BagError
        Nothing in the bag can be read, or a message's type is neither embedded in the bag nor
        a Jazzy standard type.

    """
    path = Path(path)
    _check_bag(path)
    is1 = is_ros1_bag(path)
    if raw:
        decoders = _RAW
    else:
        decoders = (ros1.FAST_DECODERS if is1 else decoders) if decoders else {}
    seen = _Seen()
    bad: dict[str, int] = {}
    problem = None
    with ExitStack() as stack:
        try:
            # The plain reader: AnyReader's typestore set-up costs ~30 ms per bag, and the
            # fast decoders do not need it. It is opened only if a message needs rosbags.
            reader = stack.enter_context(_plain_reader(path, fast=bool(decoders)))
        except Exception as err:  # rosbags raises several unrelated types for bad bags
            problem = f'it does not open ({_first_line(err)})'
        if problem is None:
            conns = [c for c in reader.connections if topics is None or c.topic in topics]
            if not conns:
                return
            typed = []

            def slow(raw: bytes, msgtype: str) -> Any:
                if not typed:
                    typed.append(stack.enter_context(open_reader(path)))
                return typed[0].deserialize(raw, msgtype)

            def known(msgtype: str) -> bool:
                return msgtype in typed[0].typestore.fielddefs if typed else False

            try:
                for conn, log_ns, raw in reader.messages(connections=conns):
                    decode = decoders.get(conn.msgtype)     # inline: the per-message path
                    try:
                        msg = None if decode is None else decode(raw)
                    except Exception:  # a fast reader tripped on damaged bytes: rosbags judges
                        msg = None
                    if msg is None:
                        msg = _decode(path, raw, conn.topic, conn.msgtype, decoders={},
                                      slow=slow, known=known, bad=bad)
                        if msg is None:
                            continue
                    log_ns = int(log_ns)
                    seen.add(conn.topic, log_ns)
                    yield BagMessage(conn.topic, conn.msgtype, log_ns, msg)
            except BagError:
                raise
            except Exception as err:  # the bag is damaged past the messages read so far
                problem = f'it is damaged after {seen.count} messages ({_first_line(err)})'
    if problem is not None:
        saved = _salvaged(path, problem)
        wanted = {k for k, c in saved.conns.items() if topics is None or c.topic in topics}
        for key, log_ns, raw in saved.messages:
            if key not in wanted or seen.has(saved.conns[key].topic, log_ns):
                continue
            conn = saved.conns[key]
            msg = _decode(path, raw, conn.topic, conn.msgtype, decoders=decoders,
                          slow=saved.deserialize, known=saved.knows, bad=bad)
            if msg is not None:
                yield BagMessage(conn.topic, conn.msgtype, log_ns, msg)
    if bad:
        counts = ', '.join(f'{n} on {topic}' for topic, n in sorted(bad.items()))
        _warn_once(f'damaged bag {path}: skipped {sum(bad.values())} messages whose bytes do '
                   f'not deserialise ({counts})')


class _AsStored(dict):
    """Decoders that keep every message's bytes as stored (``iter_messages(raw=True)``)."""

    def get(self, key: str, default: Any = None) -> Callable[[bytes], bytes]:
        return bytes

    def __bool__(self) -> bool:
        return True


_RAW = _AsStored()


def _metadata(path: Path) -> dict | None:
    """Read a rosbag2 directory's ``metadata.yaml`` with libyaml (None if it does not read)."""
    try:
        import yaml
        loader = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)
        return yaml.load((path / 'metadata.yaml').read_text(encoding='utf-8'),
                         Loader=loader)['rosbag2_bagfile_information']
    except Exception:  # missing or broken: the callers let rosbags (or salvage) read the bag
        return None


def _plain_reader(path: Path, *, fast: bool) -> Any:
    """
    Return the storage reader of ``iter_messages``: rosbags' ROS 1 or rosbag2 reader.

    With ``fast`` (the offline tools' decoders), a single uncompressed sqlite3 file is read by
    :class:`contact_detector.io.salvage.Sqlite3Reader`, which skips rosbags' counting scans.
    """
    if is_ros1_bag(path):
        return Ros1Reader(path)
    info = _metadata(path) if fast else None
    if info is not None and info.get('storage_identifier') == 'sqlite3' \
            and not info.get('compression_format') \
            and len(info.get('relative_file_paths') or ()) == 1:
        file = path / info['relative_file_paths'][0]
        if file.is_file():
            return salvage.Sqlite3Reader(file)
    return Reader(path)


class _Seen:
    """Messages yielded so far, to skip them when a bag read falls back to salvage."""

    def __init__(self) -> None:
        self.count = 0
        self.last_ns = -1
        self.at_last: dict = {}

    def add(self, topic: str, log_ns: int) -> None:
        self.count += 1
        if log_ns != self.last_ns:
            self.last_ns, self.at_last = log_ns, {}
        self.at_last[topic] = self.at_last.get(topic, 0) + 1

    def has(self, topic: str, log_ns: int) -> bool:
        # both reads are in log-time order: all before the last time yielded was yielded
        if log_ns != self.last_ns:
            return log_ns < self.last_ns
        left = self.at_last.get(topic, 0)
        self.at_last[topic] = left - 1
        return left > 0


def _decode(path: Path, raw: bytes, topic: str, msgtype: str, *,
            decoders: Mapping[str, Callable[[bytes], Any]], slow: Callable[[bytes, str], Any],
            known: Callable[[str], bool], bad: dict) -> Any:
    """Deserialise one message; None (counted in ``bad``) if its bytes are damaged."""
    decode = decoders.get(msgtype)
    if decode is not None:
        try:
            msg = decode(raw)
        except Exception:  # a fast reader that trips on damaged bytes: let rosbags judge
            msg = None
        if msg is not None:
            return msg
    try:
        return slow(raw, msgtype)
    except Exception as err:
        if not known(msgtype):
            raise BagError(f'{path}: cannot deserialise {topic} ({msgtype}): {err}') from err
        bad[topic] = bad.get(topic, 0) + 1
        return None


def _expected_count(path: Path) -> int | None:
    """Message count that ``metadata.yaml`` gives, if it reads."""
    try:
        return int(_metadata(path)['message_count'])
    except Exception:  # missing or broken: unknown
        return None


_SALVAGED: dict = {}


def _salvaged(path: Path, problem: str) -> salvage.Salvaged:
    """Salvage a bag once per process state of the file; warn once."""
    files = sorted(path.iterdir()) if path.is_dir() else [path]
    key = (str(path.resolve()), tuple((f.name, f.stat().st_size, f.stat().st_mtime_ns)
                                      for f in files if f.is_file()))
    if key not in _SALVAGED:
        expected = _expected_count(path) if path.is_dir() else None
        if len(_SALVAGED) > 8:
            _SALVAGED.clear()
        _SALVAGED[key] = salvage.salvage(path, problem=problem, expected=expected)
    saved = _SALVAGED[key]
    _warn_once(f'damaged bag {path}: {saved.summary()}')
    return saved


def _first_line(err: Exception) -> str:
    return (str(err).strip().splitlines() or [type(err).__name__])[0]


def _warn_once(text: str) -> None:
    if text not in _WARNED:
        _WARNED.add(text)
        _LOG.warning('warning: %s', text)


def iter_cdr(path: Path, *, topics: Sequence[str] | None = None
             ) -> Iterator[tuple[str, str, int, bytes]]:
    """
    Yield ``(topic, msgtype, log time ns, ROS 2 CDR bytes)`` of every message, in log order.

    rosbag2 messages are yielded as recorded. ROS 1 messages are deserialised with the bag's
    definitions and serialised again as ROS 2 CDR with the Jazzy definitions (types Jazzy
    lacks, e.g. ``audio_common_msgs``, keep the bag's definitions; ``Header.seq`` is dropped),
    so ``replay`` can publish an old recording into a ROS 2 graph. The messages are read by
    :func:`iter_messages`, so a damaged bag gives what can be read, with the same warning.

    Raises
    ------
    BagError
        Nothing in the bag can be read, or a ROS 1 message does not map onto its ROS 2 type.

    """
    path = Path(path)
    if not is_ros1_bag(path):
        for m in iter_messages(path, topics=topics, raw=True):
            yield m.topic, m.msgtype, m.log_time_ns, m.msg
        return
    store = None
    for m in iter_messages(path, topics=topics):
        if store is None:
            store = _ros2_typestore(path)
        try:
            cdr = bytes(store.serialize_cdr(ros1.to_ros2(m.msg, msgtype=m.msgtype,
                                                         typestore=store), m.msgtype))
        except Exception as err:
            raise BagError(f'{path}: cannot convert {m.topic} ({m.msgtype}) to ROS 2: '
                           f'{err}') from err
        yield m.topic, m.msgtype, m.log_time_ns, cdr


def _ros2_typestore(path: Path) -> Any:
    """Jazzy's types plus the types of a ROS 1 bag that Jazzy lacks (its own definitions)."""
    try:
        with open_reader(path) as reader:
            defs = reader.typestore.fielddefs
    except BagError as err:     # a damaged bag: the definitions the salvage found
        saved = _salvaged(path, f'it does not open ({_first_line(err)})')
        defs = saved.definitions()
    store = get_typestore(Stores.ROS2_JAZZY)
    have = set(store.fielddefs)
    store.register({name: d for name, d in defs.items() if name not in have})
    return store


def _check_bag(path: Path) -> None:
    if not is_bag(path):
        raise BagError(f'{path} is not a bag (a rosbag2 directory with metadata.yaml, or a '
                       'ROS 1 .bag file)')


def topic_types(path: Path) -> dict[str, str]:
    """
    Topic name -> message type of a bag (from its index: no message is read).

    A damaged bag gives the topics that can be read (see :func:`iter_messages`).

    Raises
    ------
    BagError
        Not a bag, or nothing in it can be read.

    """
    path = Path(path)
    _check_bag(path)
    if is_bag_dir(path):
        # metadata.yaml with libyaml: rosbags' reader parses it with ruamel (~50 ms a bag)
        try:
            return {t['topic_metadata']['name']: t['topic_metadata']['type']
                    for t in _metadata(path)['topics_with_message_count']}
        except Exception:  # anything unusual: let rosbags read it (and report the problem)
            pass
    try:
        with (Ros1Reader(path) if is_ros1_bag(path) else Reader(path)) as reader:
            return {c.topic: c.msgtype for c in reader.connections}
    except Exception as err:  # rosbags raises several unrelated types for bad bags
        return _salvaged(path, f'it does not open ({_first_line(err)})').topic_types()


def read_truth(path: Path, *, topic: str = TRUTH_TOPIC) -> list[tuple[float, bool]]:
    """
    Ground-truth edges from ``/contact_truth`` (std_msgs/Bool).

    Returns
    -------
    list of (float, bool)
        ``(log time in s, value)`` in time order: True at each true contact onset, False where
        the labelled onset window ends. Empty if the bag has no such topic (recorded bags).

    """
    return [(m.log_time_ns * 1e-9, bool(m.msg.data)) for m in iter_messages(path, topics=[topic])]


class WrenchSeries(NamedTuple):
    """
    Wrench samples of one topic, in increasing stamp order, and the messages left out.

    Attributes
    ----------
    t : np.ndarray, shape (n,)
        Header stamps, s, strictly increasing.
    force : np.ndarray, shape (n, 3)
        Force, N.
    torque : np.ndarray, shape (n, 3)
        Torque, N m.
    frame_id : str
        ``header.frame_id`` of the last message read.
    bad_messages : int
        Messages the adapter refused (:func:`~contact_detector.io.messages.wrench_sample`:
        an invalid stamp such as ``nanosec >= 1e9``, missing or non-numeric fields).
    non_finite : int
        Messages with a NaN or infinite value.
    out_of_order : int
        Messages whose stamp repeats or precedes the last one kept.
    first_problem : str
        Why the first refused message was refused ('' if none was).

    """

    t: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    frame_id: str
    bad_messages: int = 0
    non_finite: int = 0
    out_of_order: int = 0
    first_problem: str = ''

    @property
    def dropped(self) -> int:
        """Messages left out, for every reason."""
        return self.bad_messages + self.non_finite + self.out_of_order

    def describe_drops(self) -> str:
        """
        Say how many messages were left out and why ('' if none).

        E.g. ``dropped 12 of 1100 F/T messages: 12 with NaN/Inf values``.
        """
        if not self.dropped:
            return ''
        parts = [f'{n} {what}' for n, what in (
            (self.bad_messages, f'refused (first: {self.first_problem})'),
            (self.non_finite, 'with NaN/Inf values'),
            (self.out_of_order, 'with a stamp that repeats or precedes the previous one'))
            if n]
        return (f'dropped {self.dropped} of {self.dropped + self.t.size} F/T messages: '
                + ', '.join(parts))


#: A stamp this far (s) ahead of the next one, which follows the one before it, is a lone
#: jump forward; :func:`read_wrench` drops it (the node's ``check_stamp`` takes a jump back
#: of more than this for a time jump, not a reordering).
LONE_JUMP_S = 0.5


def read_wrench(path: Path, *, topic: str = WRENCH_TOPIC) -> WrenchSeries:
    """
    Read a ``geometry_msgs/WrenchStamped`` topic into arrays (stamps from the headers).

    Each message goes through the node's adapter
    (:func:`~contact_detector.io.messages.wrench_sample`), and the messages the detector would
    not use are left out and counted (:class:`WrenchSeries`; the caller reports them): refused
    ones (an invalid stamp, missing fields), NaN/Inf values, and stamps that repeat or go back
    (kept: strictly increasing stamps, in the order the bag holds them). A lone stamp more than
    :data:`LONE_JUMP_S` ahead of the next one, which follows the one before it, is the one
    left out, not every sample after it.

    Raises
    ------
    BagError
        The topic holds another type than WrenchStamped, or has no message that can be used.

    """
    t, values = [], []
    bad = non_finite = out_of_order = 0
    first_problem = ''
    frame = ''
    last = -math.inf
    for m in iter_messages(path, topics=[topic]):
        if m.msgtype != WRENCH_TYPE:
            raise BagError(f'{path}: {topic} holds {m.msgtype}, not {WRENCH_TYPE}')
        try:
            stamp, six = wrench_sample(m.msg)
        except InputError as err:
            bad += 1
            first_problem = first_problem or str(err)
            continue
        if not all(math.isfinite(v) for v in six):
            non_finite += 1
            continue
        if not stamp > last:
            if len(t) >= 2 and t[-2] < stamp < last - LONE_JUMP_S:
                # the sample before this one was a lone stamp far ahead of its neighbours:
                # drop it, not every later sample (the detector resets on the jump back)
                t.pop()
                values.pop()
            else:
                # a sorted copy would hide a reordering the detector sees (and refuses) live
                out_of_order += 1
                continue
            out_of_order += 1
        last = stamp
        t.append(stamp)
        values.append(six)
        frame = str(getattr(getattr(m.msg, 'header', None), 'frame_id', frame))
    series = WrenchSeries(np.asarray(t, dtype=float),
                          np.asarray(values, dtype=float).reshape(-1, 6)[:, :3],
                          np.asarray(values, dtype=float).reshape(-1, 6)[:, 3:], frame,
                          bad_messages=bad, non_finite=non_finite, out_of_order=out_of_order,
                          first_problem=first_problem)
    if not t:
        raise BagError(f'{path}: no usable messages on {topic} ({series.describe_drops()})'
                       if series.dropped else f'{path}: no messages on {topic}')
    return series


class AudioSeries(NamedTuple):
    """Concatenated audio chunks: samples, chunk end indices (exclusive), chunk log times (s)."""

    samples: np.ndarray
    chunk_ends: np.ndarray
    log_t: np.ndarray

    def t0(self, rate: float) -> float:
        """
        Time of sample 0, estimated from the log times: ``min_k(log_t[k] - (end_k - 1)/rate)``.

        Log time = time of a chunk's last sample + transport delay (>= 0), so the lower envelope
        is the best estimate without stamps.
        """
        return float(np.min(self.log_t - (self.chunk_ends - 1) / rate))


def read_audio(path: Path, *, topic: str = AUDIO_TOPIC) -> AudioSeries:
    """Read an Int16MultiArray (or any message with an int ``data`` array) audio topic."""
    chunks, log_t = [], []
    for m in iter_messages(path, topics=[topic]):
        chunks.append(np.asarray(m.msg.data).astype(np.int16, copy=False).ravel())
        log_t.append(m.log_time_ns * 1e-9)
    if not chunks:
        raise BagError(f'{path}: no messages on {topic}')
    ends = np.cumsum([len(c) for c in chunks]).astype(np.int64)
    return AudioSeries(np.concatenate(chunks), ends, np.asarray(log_t))


def read_manifest(path: str | Path) -> dict:
    """
    Load a simulator manifest.

    Parameters
    ----------
    path : str or Path
        The directory holding ``manifest.json`` or the file itself.

    Raises
    ------
    BagError
        Missing, not JSON, or not a manifest (no 'trials' list).

    """
    path = Path(path)
    file = path / MANIFEST_NAME if path.is_dir() else path
    try:
        data = json.loads(file.read_text(encoding='utf-8'))
    except (OSError, ValueError) as err:
        raise BagError(f'cannot read manifest {file}: {err}') from err
    if not isinstance(data, dict) or not isinstance(data.get('trials'), list):
        raise BagError(f'{file} is not a simulator manifest (no "trials" list)')
    return data


def manifest_index(path: str | Path) -> dict[str, tuple[int, dict]]:
    """
    Index a manifest's trial entries by their ``bag`` and their ``name``.

    Parameters
    ----------
    path : str or Path
        The directory holding ``manifest.json`` or the file itself.

    Returns
    -------
    dict
        Name -> the position and entry of the first trial with that ``bag`` or ``name``.
        Entries with neither (or that are no JSON object) name no bag and are left out.

    Raises
    ------
    BagError
        As :func:`read_manifest`.

    """
    out: dict[str, tuple[int, dict]] = {}
    for position, trial in enumerate(read_manifest(path)['trials']):
        if isinstance(trial, dict):
            for key in (trial.get('bag'), trial.get('name')):
                if isinstance(key, str):
                    out.setdefault(key, (position, trial))
    return out


def manifest_entry(bag: str | Path, *,
                   index: dict[str, tuple[int, dict]] | None = None) -> dict | None:
    """
    Return the entry of ``bag`` in the ``manifest.json`` beside it, or None.

    The entry is the first whose ``bag`` or ``name`` is the bag's name (or, for a ROS 1
    ``.bag`` file, its stem). ``index`` is the folder's :func:`manifest_index`, for a caller
    that looks up many bags of one folder; None reads the manifest.
    """
    bag = Path(bag)
    if index is None:
        file = bag.parent / MANIFEST_NAME
        if not file.is_file():
            return None
        index = manifest_index(file)
    names = {bag.name, bag.stem} if bag.suffix == '.bag' else {bag.name}
    hits = [index[n] for n in names if n in index]
    return min(hits, key=lambda hit: hit[0])[1] if hits else None
