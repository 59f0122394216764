"""ROS 1 bags (format 2.0, what ``rosbag record`` writes): every connection whose type is a ros_acomms_msgs type is
checked against the suite's definitions (its MD5 against its own definition text, its definition text against each
edition: which edition recorded it, or none), and every message on it is decoded by the reference codec; other
types are counted and left alone.

The bag is read record by record from its start, chunk by chunk (each decompressed whole, at most CHUNK_LIMIT
bytes, and all of them together bounded against the bag's bytes as a compressed stream is: ``streams.BOMB_RATIO``
past ``streams.BOMB_FLOOR``), a connection record at most HEADER_LIMIT bytes inside a chunk as outside, a message
decoded only up to MESSAGE_LIMIT bytes; and its index is only checked, never needed: a bag whose recording was not closed has none, and one cut
short or damaged is read as far as it goes. That is why the reading is the suite's own and not rosbags' Reader
(which the tests hold it to): rosbags needs an intact index, holds every message's index entry in memory and
decompresses a chunk with no bound. A chunk compressed with lz4 needs the ``lz4`` package, which the ``ros``
extra installs with rosbags; without it such a chunk is said to be unreadable, in one line.
"""

from __future__ import annotations

import bz2
import struct
from collections.abc import Iterator
from pathlib import Path

from ...capture.findings import Frame, Finding
from ...capture.logs import Logged
from ...capture import streams
from ...capture.streams import Reader, Short
from ...core.verdicts import Verdict
from ...schemas import shorten
from ...kinds.scenario.passive import PassiveExchanges
from ...kinds.vector.errors import FrameError
from . import codec
from .definitions import DefinitionError
from .msgtext import expected_types, parse_full_text, text_differences, text_md5

MAGIC = b"#ROSBAG V2.0\n"
MESSAGE, BAG_HEADER, INDEX, CHUNK, CHUNK_INFO, CONNECTION = 2, 3, 4, 5, 6, 7
HEADER_LIMIT = 4 << 20  # bytes of a record's header (a connection's holds the full definition text)
CHUNK_LIMIT = 128 << 20  # bytes of a chunk held at once, compressed and decompressed (rosbag writes 768 KB ones)
MD5_CLAUSE = "ros-acomms#ros-1-md5-checksums"
UNKNOWN = "unknown-definition"  # messages of a connection whose definition no edition has: not judged
TOO_LARGE = "too-large-to-decode"  # a message beyond MESSAGE_LIMIT: not judged
MESSAGE_LIMIT = 4 << 20  # bytes of a message decoded whole (ros_acomms' are of a few kB)
DEFINITION_LIMIT = 1 << 20  # characters of a connection's definition text read (ros_acomms_msgs': a few kB each)
LISTED = 3  # differences named per edition
NAMED = 120  # characters of a topic or a type's name a report shows (the bag's text: it may be megabytes)


class Damage(Exception):
    """The bag cannot be read on from here (the message says where and why)."""


class BagRules:
    """What the capture judge needs of the suite for bags: the groups (types) in report order, and no exchanges
    (ros_acomms' exchanges are service calls, which a bag does not record). Frames are judged by their connection."""

    ports = frozenset()
    outside = "counted, left alone"

    def __init__(self, suite):
        self.wire = suite.wire
        self.keys = {g.name: g.key for g in suite.groups}

    def frame(self, payload: bytes):
        return None  # a bag's message is judged by its connection (Logged.channel)

    def exchanges(self, edition: str, scale: float) -> PassiveExchanges:
        return PassiveExchanges(self.wire, [], edition, scale)


class BagReader:
    """Reads ROS 1 bags for the ros_acomms suite: each connection judged against ``edition`` (None: against the
    edition that recorded it, the same for every connection of a type)."""

    format = "ROS 1 bag"
    addressed = False  # a message names no system (ros_acomms' addresses are fields of some types)
    gaps = False  # a bag is read up to damage in its stream, never on after it

    def __init__(self, suite, edition: str | None):
        self.suite, self.judged = suite, edition
        self.edition = edition or f"each connection's own ({', '.join(suite.editions)})"
        self.rules = BagRules(suite)
        self.clauses = {r["id"]: r["clause"] for r in suite.rules}
        self.notes: list[str] = []

    def recognises(self, head: bytes) -> bool:
        return head.startswith(MAGIC)

    def beside(self, path: Path, use: bool):
        return None, [], []  # a bag carries its definitions in its connections

    def units(self, pieces: Iterator[bytes], damage: list[str], name: str) -> Iterator[Logged | Finding]:
        bag = _Bag(self, Reader(pieces))
        try:
            yield from bag.read()
        except Damage as exc:
            damage.append(f"{name}: {exc}: the bag is read up to it")
        except Short as exc:
            where = f"at byte {bag.src.offset + exc.got:,}, inside the record that begins at byte {bag.record:,}"
            if not damage:  # else the stream stopped at damage it said: the bag does not end here
                damage.append(f"{name}: its index is cut short {where}: every chunk before it was read"
                              if bag.index_begins else f"{name}: the bag ends {where} (cut short): read up to it")
        else:
            damage += [] if damage else [f"{name}: {problem}" for problem in bag.index_problems()]
        self.notes += bag.summary(name)


class _Channel:
    """A connection's messages judged: decoded by ``view`` (an edition), or not judged (``why``), or of a type the
    suite does not cover (``group`` None)."""

    __slots__ = ("group", "full", "view", "why", "clauses")

    def __init__(self, group, full: str, view, why: str, clauses: dict):
        self.group, self.full, self.view, self.why, self.clauses = group, full, view, why, clauses

    def frame(self, payload: bytes) -> Frame:
        if self.group is None:
            return Frame(None, outside=self.full)
        if self.view is None:
            return Frame(self.group, UNKNOWN, 0, self.why, MD5_CLAUSE, undecided=True)
        if len(payload) > MESSAGE_LIMIT:  # decoded whole, its values would take ten to twenty times its size
            return Frame(self.group, TOO_LARGE, 0, f"{len(payload):,} bytes, more than the {MESSAGE_LIMIT >> 20} MB "
                         "a message is decoded whole up to: not judged", "", undecided=True)
        try:
            codec.decode(self.view, self.full, payload)
        except FrameError as exc:
            return Frame(self.group, exc.rule, exc.offset, exc.detail, self.clauses.get(exc.rule, ""))
        return Frame(self.group)


class _Bag:
    """One bag being read: its records in order, its connections, what its index says."""

    def __init__(self, reader: BagReader, src: Reader):
        self.reader, self.src = reader, src
        self.channels: dict[int, _Channel] = {}
        self.editions: dict[str, tuple[set[str], str]] = {}  # type -> (editions every connection so far has, the first)
        self.by_edition: dict[str, list[str]] = {}  # what recorded each connection -> its topics
        self.number = self.record = 0  # messages so far; where the record being read begins
        self.index_at = self.connections = self.chunks = None  # what the bag header says
        self.index_begins = False  # a record begins where the bag header says the index does
        self.index_found = [0, 0]  # connection and chunk info records outside the chunks (the index's)
        self.chunks_read = 0
        self.unpacked = 0  # bytes the chunks read so far hold decompressed

    def read(self) -> Iterator[Logged | Finding]:
        if self.src.take(len(MAGIC)) != MAGIC:
            raise Damage("no ROS 1 bag (V2.0) magic line")
        while not self.src.at_end():
            self.record = self.src.offset
            self.index_begins = self.index_begins or self.record == self.index_at
            op, fields, size = _record_head(self.src)
            if op == BAG_HEADER:
                self._bag_header(fields)
                self.src.skip(size)
            elif op == CHUNK:
                if size > CHUNK_LIMIT:
                    raise Damage(f"the chunk at byte {self.record:,} holds {size:,} bytes, more than the "
                                 f"{CHUNK_LIMIT >> 20} MB read at once")
                self.chunks_read += 1
                yield from self._chunk(fields, self.src.take(size))
            elif op == CONNECTION:  # outside a chunk: the index's copy of a connection
                if size > HEADER_LIMIT:
                    raise Damage(f"the connection record at byte {self.record:,} holds {size:,} bytes, more than the "
                                 f"{HEADER_LIMIT >> 20} MB read at once")
                self.index_found[0] += 1
                yield from self._connection(fields, self.src.take(size))
            elif op == CHUNK_INFO:
                self.index_found[1] += 1
                self.src.skip(size)
            elif op in (INDEX, MESSAGE):
                self.src.skip(size)
            else:
                raise Damage(f"the record at byte {self.record:,} is of no kind a bag has (op {op})")

    def _bag_header(self, fields: dict) -> None:
        self.index_at = _int(fields, "index_pos", 8, self.record) or None
        self.connections = _int(fields, "conn_count", 4, self.record)
        self.chunks = _int(fields, "chunk_count", 4, self.record)

    def _chunk(self, fields: dict, data: bytes) -> Iterator[Logged | Finding]:
        at = self.record
        size = _int(fields, "size", 4, at)
        if size > CHUNK_LIMIT:
            raise Damage(f"the chunk at byte {at:,} holds {size:,} bytes decompressed, more than the "
                         f"{CHUNK_LIMIT >> 20} MB read at once")
        self.unpacked += size  # the bag's chunks decompressed, against its bytes read: a bomb, as a stream's
        if self.unpacked > streams.BOMB_FLOOR and self.unpacked > streams.BOMB_RATIO * self.src.offset:
            raise Damage(f"its chunks up to the one at byte {at:,} ({self.chunks_read:,} of them) hold "
                         f"{self.unpacked >> 20} MB out of its first {self.src.offset:,} bytes, more than "
                         f"{streams.BOMB_RATIO} times their size (no bag compresses so well: a decompression bomb?): "
                         "refused from there")
        content = _decompressed(fields.get("compression", b""), data, size, at)
        inner = Reader([content] if content else [])
        while not inner.at_end():
            start = inner.offset
            try:
                op, record, length = _record_head(inner, at)
                if op == CONNECTION and length > HEADER_LIMIT:  # its definition: bounded as outside a chunk
                    raise Damage(f"the connection record in the chunk at byte {at:,} (byte {start:,} of its data) "
                                 f"holds {length:,} bytes, more than the {HEADER_LIMIT >> 20} MB read at once")
                body = inner.take(length)
            except Short:
                raise Damage(f"the record at byte {start:,} of the chunk at byte {at:,} runs past the chunk's "
                             "end") from None
            if op == CONNECTION:
                yield from self._connection(record, body)
            elif op == MESSAGE:
                conn = _int(record, "conn", 4, at)
                channel = self.channels.get(conn)
                if channel is None:
                    raise Damage(f"a message in the chunk at byte {at:,} (byte {start:,} of its data) is on "
                                 f"connection {conn}, which no connection record before it defines")
                secs, nsecs = struct.unpack("<II", _field(record, "time", 8, at))
                self.number += 1
                yield Logged(self.number, secs + nsecs * 1e-9, at, body, start, channel)
            else:
                raise Damage(f"a record in the chunk at byte {at:,} (byte {start:,} of its data) is of no kind a "
                             f"chunk holds (op {op})")

    def _connection(self, fields: dict, data: bytes) -> Iterator[Finding]:
        """A connection record (in a chunk, or in the index: the same connection again)."""
        conn = _int(fields, "conn", 4, self.record)
        if conn in self.channels:
            return
        topic = shorten(_text(fields.get("topic", b"")), NAMED)
        described = _fields(data, self.record)
        full, md5sum = _text(described.get("type", b"")), _text(described.get("md5sum", b""))
        definition = _text(described.get("message_definition", b""))
        known = self.reader.suite.defs.by_full.get(full)
        if known is None or known.auxiliary:
            self.channels[conn] = _Channel(None, shorten(full, NAMED), None, "", {})
            return
        findings, view, why = self._judged(known.name, full, md5sum, definition, f"connection {conn}", topic)
        self.channels[conn] = _Channel(known.name, full, view, why, self.reader.clauses)
        yield from findings

    def _judged(self, group: str, full: str, md5sum: str, definition: str, label: str, topic: str):
        """The findings on a connection's MD5 and definition; the edition view its messages decode by (None: not
        judged, and why)."""
        suite, judged = self.reader.suite, self.reader.judged
        clause = suite.defs.by_full[full].clause

        def finding(case: str, verdict: Verdict, detail: str = "", cited: str = clause) -> Finding:
            return Finding(group, f"connection/{case}", verdict, cited, detail, where=f"topic {topic}", label=label)
        if len(definition) > DEFINITION_LIMIT:  # read, its lines would take fifty times its size
            why = f"its definition text holds {len(definition):,} characters, more than the {DEFINITION_LIMIT >> 10} kB read"
            self._recorded("no edition (a definition too large to read)", topic)
            return [finding("definition", Verdict.INCONCLUSIVE, why)], None, f"{why}: not judged"
        try:
            parsed = parse_full_text(definition, full)
            own = text_md5(parsed, full)
        except DefinitionError as exc:
            why = shorten(str(exc))
            self._recorded("no edition (a definition that does not read)", topic)
            return [finding("definition", Verdict.FAIL, f"its definition text does not read: {why}")], None, \
                f"its connection's definition does not read ({why})"
        out = [finding("md5", Verdict.PASS if own == md5sum else Verdict.FAIL, "" if own == md5sum else
                       f"its header says md5sum {md5sum[:40]!r}, the MD5 of its own definition is {own}", MD5_CLAUSE)]
        differs = {}
        for edition in suite.editions:
            view = suite.defs.edition(edition)
            if full in view:
                differs[edition] = text_differences(expected_types(view, view[full]), parsed)
        matches = [e for e, d in differs.items() if not d]
        self._recorded(" and ".join(matches) or "no edition", topic)
        before, first = self.editions.get(full, (set(matches), f"{label} ({topic})"))
        common = before & set(matches)
        problem = None
        if not matches:
            problem = "its definition is that of no edition: " + "; ".join(
                f"edition {e}: {_first(d)}" for e, d in differs.items())
        elif judged is not None and judged not in matches:
            d = differs.get(judged)
            problem = (f"recorded with the definition of edition {' and '.join(matches)}, not {judged}'s" +
                       (f": {_first(d)}" if d else f" (edition {judged} has no {group})"))
        elif judged is None and not common:
            problem = (f"recorded with the definition of edition {' and '.join(matches)}, where {first} was "
                       f"recorded with {' and '.join(sorted(before)) or 'no edition'}'s: ROS 1 refuses to connect the "
                       "two (their MD5s differ)")
        else:
            self.editions[full] = (common, first)
        out.append(finding("definition", Verdict.FAIL if problem else Verdict.PASS, problem or ""))
        if not matches:
            return out, None, "recorded with a definition no edition has"
        edition = judged if judged in matches else next(e for e in suite.editions if e in (common or matches))
        return out, suite.defs.edition(edition), ""

    def _recorded(self, editions: str, topic: str) -> None:
        self.by_edition.setdefault(editions, []).append(topic)

    def index_problems(self) -> list[str]:
        """What is wrong with the bag's index, once the bag was read to its end."""
        if self.index_at is None:
            return ["it has no index (its recording was not closed: rosbag reindex would write one); read record "
                    "by record"]
        if not self.index_begins or self.index_found != [self.connections, self.chunks]:
            return [f"its index is damaged: its header says {self.connections} connections and {self.chunks} chunks "
                    f"at byte {self.index_at:,}; {'the records there' if self.index_begins else 'no record begins there'}"
                    f", {self.index_found[0]} connections and {self.index_found[1]} chunks are indexed (read record by "
                    f"record: {self.chunks_read} chunks)"]
        return []

    def summary(self, name: str) -> list[str]:
        if not self.by_edition:
            return []
        return [f"{name}: connections of ros_acomms_msgs types by the edition that recorded them: " + "; ".join(
            f"{editions}: {', '.join(labels[:6])}{' ...' if len(labels) > 6 else ''}"
            for editions, labels in self.by_edition.items())]


# ---------------------------------------------------------------- records

def _record_head(src: Reader, chunk: int | None = None) -> tuple[int, dict, int]:
    """(op, header fields, data length) of the record at ``src``; Damage for a header over HEADER_LIMIT."""
    at = src.offset
    (length,) = struct.unpack("<I", src.take(4))
    where = f"the record at byte {at:,}" if chunk is None else f"a record in the chunk at byte {chunk:,}"
    if length > HEADER_LIMIT:
        raise Damage(f"{where} claims a {length:,}-byte header, more than the {HEADER_LIMIT >> 20} MB read at once")
    fields = _fields(src.take(length), at)
    (size,) = struct.unpack("<I", src.take(4))
    op = fields.get("op", b"")
    if len(op) != 1:
        raise Damage(f"{where} has no op field")
    return op[0], fields, size


def _fields(data: bytes, at: int) -> dict[str, bytes]:
    """The ``name=value`` fields of a record header or a connection header, each after its uint32 length."""
    out, pos = {}, 0
    while pos < len(data):
        if pos + 4 > len(data):
            raise Damage(f"a header at byte {at:,} ends inside a field's length")
        (n,) = struct.unpack_from("<I", data, pos)
        pos += 4
        if pos + n > len(data):
            raise Damage(f"a header at byte {at:,} has a field of {n:,} bytes where {len(data) - pos:,} are left")
        name, sep, value = data[pos:pos + n].partition(b"=")
        if not sep:
            raise Damage(f"a header at byte {at:,} has a field without '='")
        out[_text(name)] = value
        pos += n
    return out


def _field(fields: dict, name: str, size: int, at: int) -> bytes:
    value = fields.get(name)
    if value is None or len(value) != size:
        raise Damage(f"the record at byte {at:,} has no {size}-byte {name} field")
    return value


def _int(fields: dict, name: str, size: int, at: int) -> int:
    return int.from_bytes(_field(fields, name, size, at), "little")


def _first(differences: list[str]) -> str:
    """The first LISTED differences, each shortened (a definition's line may be megabytes), and how many more."""
    more = len(differences) - LISTED
    return ", ".join(shorten(d) for d in differences[:LISTED]) + (f" (and {more} more)" if more > 0 else "")


def _text(raw: bytes) -> str:
    return raw.decode("utf-8", "replace")


def _decompressed(compression: bytes, data: bytes, size: int, at: int) -> bytes:
    """A chunk's records, decompressed to at most ``size`` bytes (what its header says they are)."""
    decoder = None
    if compression == b"none":
        out, whole = data, True
    elif compression == b"bz2":
        decoder = bz2.BZ2Decompressor()
        try:
            out = decoder.decompress(data, size + 1)
        except (OSError, ValueError, EOFError) as exc:
            raise Damage(f"the chunk at byte {at:,} is damaged bz2 data ({exc})") from None
        whole = decoder.eof
    elif compression == b"lz4":
        try:
            from lz4.frame import LZ4FrameDecompressor
        except ImportError:
            raise Damage(f"the chunk at byte {at:,} is lz4-compressed: reading it needs the lz4 package, which "
                         "the suite's ros extra installs") from None
        decoder = LZ4FrameDecompressor()
        try:
            out = decoder.decompress(data, size + 1)
        except (RuntimeError, ValueError, OSError) as exc:
            raise Damage(f"the chunk at byte {at:,} is damaged lz4 data ({exc})") from None
        whole = decoder.eof
    else:
        raise Damage(f"the chunk at byte {at:,} is compressed with {_text(compression)[:40]!r}, which no bag uses")
    if len(out) > size:
        raise Damage(_beyond(decoder, _text(compression), data, size, at))
    if len(out) < size or not whole:
        raise Damage(f"the chunk at byte {at:,} holds {len(out):,} bytes where its header says {size:,}, or its "
                     "compressed data is cut")
    return out


def _beyond(decoder, kind: str, data: bytes, size: int, at: int) -> str:
    """What is wrong with a chunk that decompresses to more than its header says: its compressed data, where the
    decoder, read on (its output unkept, bounded as a bomb is), says so; else its header."""
    made = size
    try:
        while decoder is not None and not decoder.eof and decoder.needs_input is False and \
                made <= max(streams.BOMB_FLOOR, streams.BOMB_RATIO * len(data)):
            made += len(decoder.decompress(b"", 1 << 20))
    except (OSError, ValueError, EOFError, RuntimeError) as exc:
        return f"the chunk at byte {at:,} is damaged {kind} data ({exc})"
    return f"the chunk at byte {at:,} holds more than the {size:,} bytes its header says"
