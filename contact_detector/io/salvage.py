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
Read what can be read from a damaged bag.

rosbags' readers need an intact bag: a ROS 1 bag's index (written last, so missing when the
recorder died), an mcap file's footer and summary, a rosbag2 directory's ``metadata.yaml``, a
sqlite3 database whose every page reads. A recording cut short or damaged on disk still holds
most of its messages, and this module scans the bytes for them:

* ROS 1 ``.bag``: the records in file order (connection records precede their messages in
  each chunk); a truncated chunk gives the complete records it holds (uncompressed or bz2;
  a cut lz4 chunk is lost).
* mcap: the records in file order, inside uncompressed or compressed chunks; a truncated
  chunk gives its complete records if it is uncompressed.
* sqlite3: the ``messages`` table in row order; past a page that does not read, the scan
  probes further rows (``id > last + 2**k``) and goes on where the table reads again.
* rosbag2 directories without a readable ``metadata.yaml``: the storage files (``*.db3``,
  ``*.mcap``) describe their own topics and types.

:class:`Sqlite3Reader` reads an intact sqlite3 file the same way (the same topic query), in
log-time order: the offline tools' fast path.

:func:`salvage` returns the messages found, in log-time order, what was lost (counted where the
bag says how many messages it had), and deserialisers built from the definitions the bag
stores. :func:`contact_detector.io.bags.iter_messages` falls back to it when a bag does not
read, and logs one warning per bag.

Length: over 500 lines because it holds one byte-level scanner per storage format (ROS 1,
mcap, sqlite3), each small, behind one interface; they share the record bookkeeping.
"""

import bz2
from dataclasses import dataclass, field
from pathlib import Path
import shutil
import sqlite3
import struct
import tempfile
from typing import Any, Iterator, NamedTuple, Optional
from urllib.parse import quote

from contact_detector.errors import BagError

ROS1_MAGIC = b'#ROSBAG V2.0\n'
MCAP_MAGIC = b'\x89MCAP0\r\n'
MAX_PROBES = 64

_U16 = struct.Struct('<H')
_U32 = struct.Struct('<I')
_U64 = struct.Struct('<Q')


@dataclass(frozen=True)
class Conn:
    """
    A topic found in a damaged bag.

    Attributes
    ----------
    topic, msgtype : str
        Topic name and ``pkg/msg/Type``.
    msgdef : str
        Message definition stored in the bag ('' if none).
    fmt : str
        ``msg`` (ROS 1 / ros2msg text), ``idl`` or '' (none stored).

    """

    topic: str
    msgtype: str
    msgdef: str = ''
    fmt: str = ''


@dataclass
class Salvaged:
    """
    The readable part of a damaged bag.

    Attributes
    ----------
    path : Path
        The bag.
    is2 : bool
        rosbag2 (CDR payloads) rather than ROS 1.
    conns : dict
        Connection key -> :class:`Conn`.
    messages : list of (key, log time ns, bytes)
        In log-time order.
    problems : list of str
        What is damaged, one line per storage file.
    expected : int or None
        Messages the bag says it holds (``metadata.yaml``), if it says.

    """

    path: Path
    is2: bool
    conns: dict = field(default_factory=dict)
    messages: list = field(default_factory=list)
    problems: list = field(default_factory=list)
    expected: Optional[int] = None
    _store: Any = None

    def topic_types(self) -> dict[str, str]:
        """Topic -> message type of every connection found."""
        return {c.topic: c.msgtype for c in self.conns.values()}

    def summary(self) -> str:
        """One line: what is damaged and how many messages were read and lost."""
        read = len(self.messages)
        if self.expected is not None:
            lost = f', {max(self.expected - read, 0)} of {self.expected} messages lost'
        else:
            lost = ' (the bag does not record how many it had)'
        return f'{"; ".join(self.problems)}: read {read} messages{lost}'

    def deserialize(self, raw: bytes, msgtype: str) -> Any:
        """Deserialise one message with the definitions the bag stores (else Jazzy's)."""
        from rosbags.typesys import get_types_from_idl, get_types_from_msg, get_typestore
        from rosbags.typesys import Stores

        if self._store is None:
            store = get_typestore(Stores.ROS2_JAZZY if self.is2 else Stores.EMPTY)
            types: dict = {}
            for conn in self.conns.values():
                try:
                    if conn.fmt == 'msg':
                        types.update(get_types_from_msg(conn.msgdef, conn.msgtype))
                    elif conn.fmt == 'idl':
                        types.update(get_types_from_idl(conn.msgdef))
                except Exception:  # noqa: B902 - a bad definition: that type stays unknown
                    continue
            if self.is2:
                types = {k: v for k, v in types.items() if k not in store.fielddefs}
            store.register(types)
            self._store = store
        if self.is2:
            return self._store.deserialize_cdr(raw, msgtype)
        return self._store.deserialize_ros1(raw, msgtype)

    def definitions(self) -> dict:
        """Type name -> field definitions the deserialiser knows (rosbags ``fielddefs``)."""
        self.knows('')
        return dict(self._store.fielddefs) if self._store is not None else {}

    def knows(self, msgtype: str) -> bool:
        """Return True if ``msgtype`` has a definition (so a failure means bad bytes)."""
        if self._store is None:
            try:
                self.deserialize(b'', msgtype)
            except Exception:  # noqa: B902 - only builds the typestore
                pass
        return self._store is not None and msgtype in self._store.fielddefs


def salvage(path: Path, *, problem: str, expected: Optional[int] = None) -> Salvaged:
    """
    Scan a damaged bag for its readable messages.

    Parameters
    ----------
    path : Path
        ROS 1 ``.bag`` file or rosbag2 directory.
    problem : str
        Why the normal reader failed (the first line of the report).
    expected : int or None
        Message count from ``metadata.yaml`` if it reads.

    Returns
    -------
    Salvaged
        Messages sorted by log time.

    Raises
    ------
    BagError
        Nothing readable: no topic and no message found; names the bag and the problem.

    """
    path = Path(path)
    out = Salvaged(path=path, is2=path.is_dir(), problems=[problem], expected=expected)
    try:
        if path.is_dir():
            files = sorted(p for p in path.iterdir() if p.suffix in ('.db3', '.mcap'))
            if not files:
                raise BagError(f'cannot read bag {path}: {problem}; it holds no storage '
                               'file (*.db3 or *.mcap)')
            for file in files:
                (_sqlite if file.suffix == '.db3' else _mcap)(file, out)
        else:
            _ros1(path, out)
    except OSError as err:
        raise BagError(f'cannot read bag {path}: {problem}; {err}') from err
    except BagError:
        raise
    except Exception as err:  # noqa: B902 - damage the scanners did not foresee: keep the rest
        out.problems.append(f'the scan stopped at unexpected damage ({err!r})')
    if not out.conns and not out.messages:
        raise BagError(f'cannot read bag {path}: {"; ".join(out.problems)}; no readable '
                       'topic or message in it')
    out.messages.sort(key=lambda m: m[1])
    return out


# --- ROS 1 ------------------------------------------------------------------------------------

def _ros1_fields(buf: bytes) -> dict[str, bytes]:
    fields, pos = {}, 0
    while pos + 4 <= len(buf):
        (size,) = _U32.unpack_from(buf, pos)
        item = buf[pos + 4:pos + 4 + size]
        pos += 4 + size
        name, _, value = item.partition(b'=')
        fields[name.decode('latin-1')] = value
    return fields


def _ros1_records(buf: bytes, start: int):
    """Yield ``(header fields, data)`` of the complete records, then ``(None, bytes short)``."""
    pos = start
    while pos < len(buf):
        if pos + 4 > len(buf):
            break
        (hlen,) = _U32.unpack_from(buf, pos)
        if pos + 8 + hlen > len(buf):
            break
        header = _ros1_fields(buf[pos + 4:pos + 4 + hlen])
        (dlen,) = _U32.unpack_from(buf, pos + 4 + hlen)
        data_at = pos + 8 + hlen
        if data_at + dlen > len(buf):
            yield header, buf[data_at:], data_at + dlen - len(buf)
            return
        yield header, buf[data_at:data_at + dlen], 0
        pos = data_at + dlen
    if pos < len(buf):
        yield None, b'', len(buf) - pos


def _ros1_record(header: dict, data: bytes, out: Salvaged) -> None:
    """Take in one connection or message record."""
    from rosbags.rosbag1.reader import normalize
    from rosbags.typesys.msg import normalize_msgtype

    op = header.get('op', b'\0')[:1]
    if op == b'\x07':
        info = _ros1_fields(data)
        cid = _U32.unpack(header['conn'])[0]
        out.conns[cid] = Conn(topic=normalize(header['topic'].decode()),
                              msgtype=normalize_msgtype(info['type'].decode()),
                              msgdef=info.get('message_definition', b'').decode(), fmt='msg')
    elif op == b'\x02':
        cid = _U32.unpack(header['conn'])[0]
        sec, nsec = struct.unpack('<II', header['time'])
        if cid in out.conns:
            out.messages.append((cid, sec * 1_000_000_000 + nsec, bytes(data)))


def _ros1_inner(buf: bytes, out: Salvaged) -> bool:
    """Read the records of one chunk's content; return True if it ends in a partial record."""
    for header, data, short in _ros1_records(buf, 0):
        if header is None or short:
            return True
        _ros1_record(header, data, out)
    return False


def _decompress_partial(data: bytes, compression: str) -> bytes:
    if compression == 'none':
        return data
    if compression == 'bz2':
        try:
            return bz2.BZ2Decompressor().decompress(data)
        except (OSError, EOFError):
            return b''
    if compression == 'lz4':
        from rosbags.rosbag1.reader import decompressors
        try:
            return decompressors['lz4'](data)     # a whole chunk; a cut one is lost
        except Exception:  # noqa: B902 - lz4 raises RuntimeError and others for bad frames
            return b''
    raise ValueError(f'unknown chunk compression {compression!r}')


def _ros1(path: Path, out: Salvaged) -> None:
    buf = path.read_bytes()
    if not buf.startswith(ROS1_MAGIC):
        raise BagError(f'cannot read bag {path}: {out.problems[0]}; it does not start as a '
                       'ROS 1 bag (#ROSBAG V2.0)')
    chunks = 0
    for header, data, short in _ros1_records(buf, len(ROS1_MAGIC)):
        if header is None:
            out.problems.append(f'the file ends inside a record header ({short} bytes)')
            break
        op = header.get('op', b'\0')[:1]
        if op == b'\x05':
            chunks += 1
            try:
                compression = header.get('compression', b'none').decode()
                size = _U32.unpack(header['size'])[0]
                content = _decompress_partial(data, compression)
                partial = _ros1_inner(content, out)
            except (KeyError, ValueError, struct.error) as err:
                out.problems.append(f'chunk {chunks} is damaged ({err!r})')
                break
            if short or partial or len(content) < size:
                out.problems.append(f'chunk {chunks} is cut short or damaged ('
                                    f'{size - len(content)} of {size} bytes missing)')
        elif not short:
            try:
                _ros1_record(header, data, out)     # records outside chunks (unchunked bags)
            except (KeyError, ValueError, struct.error):
                out.problems.append('a damaged record outside the chunks')
                break
        if short and op != b'\x05':
            out.problems.append(f'the file ends {short} bytes short of a record')
            break


# --- mcap -------------------------------------------------------------------------------------

def _mcap_string(buf: bytes, pos: int) -> tuple[str, int]:
    (size,) = _U32.unpack_from(buf, pos)
    return buf[pos + 4:pos + 4 + size].decode(), pos + 4 + size


def _mcap_records(buf: bytes, pos: int, out: Salvaged, state: dict, where: str) -> None:
    """Read records from ``pos``; note in ``out.problems`` where they stop short."""
    while pos < len(buf):
        if pos + 9 > len(buf):
            out.problems.append(f'{where} ends inside a record header')
            return
        op = buf[pos]
        (size,) = _U64.unpack_from(buf, pos + 1)
        body_at, end = pos + 9, pos + 9 + size
        if op in (0x02, 0x0F):              # footer, data end: the rest is the summary
            return
        complete = end <= len(buf)
        body = buf[body_at:end]
        try:
            if op == 0x03 and complete:
                (sid,) = _U16.unpack_from(body, 0)
                name, at = _mcap_string(body, 2)
                encoding, at = _mcap_string(body, at)
                (dlen,) = _U32.unpack_from(body, at)
                state['schemas'][sid] = (name, encoding, body[at + 4:at + 4 + dlen].decode())
            elif op == 0x04 and complete:
                cid, sid = struct.unpack_from('<HH', body, 0)
                topic, at = _mcap_string(body, 4)
                name, encoding, text = state['schemas'].get(sid, ('', '', ''))
                key = (state['file'], cid)
                fmt = {'ros2msg': 'msg', 'ros2idl': 'idl'}.get(encoding, '')
                out.conns[key] = Conn(topic=topic, msgtype=name, msgdef=text, fmt=fmt)
            elif op == 0x05 and complete:
                cid, _, log_ns, _ = struct.unpack_from('<HIQQ', body, 0)
                key = (state['file'], cid)
                if key in out.conns:
                    out.messages.append((key, log_ns, bytes(body[22:])))
            elif op == 0x06:
                _mcap_chunk(body, complete, out, state, where)
        except (ValueError, struct.error) as err:
            out.problems.append(f'{where}: a damaged record at byte {pos} ({err})')
            return
        if not complete:
            if op != 0x06:
                out.problems.append(f'{where} is cut short or damaged (a record ends '
                                    f'{end - len(buf)} bytes past its end)')
            return
        pos = end


def _mcap_chunk(body: bytes, complete: bool, out: Salvaged, state: dict, where: str) -> None:
    _, _, usize, _ = struct.unpack_from('<QQQI', body, 0)
    compression, at = _mcap_string(body, 28)
    (csize,) = _U64.unpack_from(body, at)
    data = body[at + 8:at + 8 + csize]
    state['chunks'] += 1
    name = f'{where}: chunk {state["chunks"]}'
    if not complete or len(data) < csize:
        if compression:
            out.problems.append(f'{name} ({compression}) is cut short: its messages are lost')
            return
        out.problems.append(f'{name} is cut short or damaged ({usize - len(data)} of '
                            f'{usize} bytes missing)')
    elif compression:
        from rosbags.rosbag2.storage_mcap import DECOMPRESSORS
        try:
            data = DECOMPRESSORS[compression](data, usize)
        except Exception as err:  # noqa: B902 - any decoder failure: the chunk is lost
            out.problems.append(f'{name} does not decompress ({err})')
            return
    before = len(out.problems)
    _mcap_records(data, 0, out, state, name)
    if not complete:
        del out.problems[before:]         # the cut was reported above


def _mcap(file: Path, out: Salvaged) -> None:
    buf = file.read_bytes()
    if not buf.startswith(MCAP_MAGIC):
        out.problems.append(f'{file.name} is not an mcap file')
        return
    state = {'schemas': {}, 'chunks': 0, 'file': file.name}
    _mcap_records(buf, len(MCAP_MAGIC), out, state, file.name)


# --- sqlite3 ----------------------------------------------------------------------------------

def _sqlite(file: Path, out: Salvaged) -> None:
    with open(file, 'rb') as stream:
        head = stream.read(100)
    if not head.startswith(b'SQLite format 3\0'):
        out.problems.append(f'{file.name} is not an SQLite database')
        return
    page = int.from_bytes(head[16:18], 'big') if len(head) == 100 else 0
    page = 65536 if page == 1 else page
    declared = page * int.from_bytes(head[28:32], 'big') if page else 0
    size = file.stat().st_size
    if declared > size:
        # cut short: SQLite refuses a file shorter than its header says, even for the pages
        # that are there. A copy padded with zero pages reads up to the cut.
        with tempfile.TemporaryDirectory() as tmp:
            copy = Path(tmp) / file.name
            with open(file, 'rb') as src, open(copy, 'wb') as dst:
                shutil.copyfileobj(src, dst)
                dst.truncate(declared)              # zero pages (sparse: no memory, no disk)
            out.problems.append(f'{file.name} is cut short ({declared - size} of {declared} '
                                'bytes missing)')
            _sqlite_read(copy, file.name, out)
        return
    _sqlite_read(file, file.name, out)


def _sqlite_connect(file: Path) -> sqlite3.Connection:
    """Open a rosbag2 sqlite3 file read-only (immutable: no locks, no journal)."""
    return sqlite3.connect(f'file:{quote(str(file.resolve()))}?immutable=1', uri=True)


def _sqlite_conns(con: sqlite3.Connection, name: str) -> dict:
    """Topics of a rosbag2 sqlite3 file: ``(name, topic id)`` -> :class:`Conn`."""
    rows = con.execute('SELECT id, name, type FROM topics').fetchall()
    defs = {}
    try:
        for typ, enc, text in con.execute(
                'SELECT topic_type, encoding, encoded_message_definition '
                'FROM message_definitions'):
            defs[typ] = ({'ros2msg': 'msg', 'ros2idl': 'idl'}.get(enc, ''), text)
    except sqlite3.Error:
        pass                                # older schema (or damaged): Jazzy's types
    out = {}
    for tid, topic, typ in rows:
        fmt, text = defs.get(typ, ('', ''))
        out[(name, tid)] = Conn(topic=topic, msgtype=typ, msgdef=text, fmt=fmt)
    return out


def _sqlite_read(file: Path, name: str, out: Salvaged) -> None:
    try:
        con = _sqlite_connect(file)
    except sqlite3.Error as err:
        out.problems.append(f'{name} does not open ({err})')
        return
    try:
        try:
            out.conns.update(_sqlite_conns(con, name))
        except sqlite3.Error as err:
            out.problems.append(f'{name}: its topics table does not read ({err})')
            return
        _sqlite_messages(con, name, out)
    finally:
        con.close()


class SqliteConnection(NamedTuple):
    """A topic of :class:`Sqlite3Reader`: its id in the file, name and type."""

    tid: int
    topic: str
    msgtype: str


class Sqlite3Reader:
    """
    Reader of an intact single-file rosbag2 sqlite3 bag, for the offline tools' fast path.

    Use as ``with Sqlite3Reader(file) as reader``; ``reader.connections`` lists the topics and
    ``reader.messages(connections=...)`` yields ``(connection, log time ns, CDR bytes)`` in
    log-time order (``ORDER BY timestamp``, the query rosbags runs). Unlike rosbags' reader it
    does not count the messages per topic on opening (two scans of the whole table, a quarter
    of the time of decoding a 44.1 kHz bag). The connections come from the same query as
    :func:`salvage`'s; a file that does not read raises :class:`sqlite3.Error` (the caller
    falls back to :func:`salvage`).
    """

    def __init__(self, file: Path) -> None:
        self.file = Path(file)
        self.connections: list[SqliteConnection] = []
        self._con: Optional[sqlite3.Connection] = None

    def __enter__(self) -> 'Sqlite3Reader':
        """Open the file and read its topics."""
        self._con = _sqlite_connect(self.file)
        try:
            conns = _sqlite_conns(self._con, self.file.name)
        except BaseException:
            self._con.close()
            raise
        self.connections = [SqliteConnection(key[1], c.topic, c.msgtype)
                            for key, c in conns.items()]
        return self

    def __exit__(self, *exc: Any) -> None:
        """Close the file."""
        if self._con is not None:
            self._con.close()
            self._con = None

    def messages(self, *, connections: list) -> Iterator[tuple]:
        """Yield ``(connection, log time ns, bytes)`` of these connections in log-time order."""
        cmap = {c.tid: c for c in connections}
        marks = ','.join('?' * len(cmap))
        cur = self._con.execute(f'SELECT topic_id, timestamp, data FROM messages WHERE '
                                f'topic_id IN ({marks}) ORDER BY timestamp', list(cmap))
        for tid, log_ns, data in cur:
            yield cmap[tid], log_ns, data


def _sqlite_messages(con: sqlite3.Connection, name: str, out: Salvaged) -> None:
    last, gaps = 0, 0
    while True:
        try:
            cur = con.execute('SELECT id, topic_id, timestamp, data FROM messages '
                              'WHERE id > ? ORDER BY id', (last,))
            for rid, tid, log_ns, data in cur:
                if rid <= last:     # a damaged b-tree can loop back: ids must increase
                    raise sqlite3.DatabaseError(f'row {rid} after row {last}')
                last = rid
                if (name, tid) in out.conns and data is not None:
                    out.messages.append(((name, tid), log_ns, bytes(data)))
            break
        except sqlite3.Error as err:
            gaps += 1
            if gaps == 1:
                out.problems.append(f'{name} is damaged after row {last} ({err})')
            nxt = _sqlite_next_readable(con, last)
            if nxt is None or nxt <= last or gaps > MAX_PROBES:
                break
            last = nxt - 1


def _sqlite_next_readable(con: sqlite3.Connection, last: int) -> Optional[int]:
    """First row id past ``last + 2**k`` that the table reads, or None."""
    for k in range(MAX_PROBES):
        try:
            row = con.execute('SELECT id FROM messages WHERE id > ? ORDER BY id LIMIT 1',
                              (last + 2 ** k,)).fetchone()
        except (sqlite3.Error, OverflowError):
            continue
        if row is None:
            return None
        if row[0] > last + 2 ** k:          # else the damaged tree answered wrongly
            return row[0]
    return None
