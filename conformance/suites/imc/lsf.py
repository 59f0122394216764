"""LSF, the mission log of DUNE (its Logging task), Neptus and imcjava: the IMC frames a system dispatched and
received, each whole (header, payload, CRC, in its sender's byte order), one after another with nothing between
(DUNE: ``IMC::Packet::serialize`` of each message into ``Data.lsf``, compressed as ``Data.lsf.gz`` or ``.bz2``;
``src/Transports/Logging/Task.cpp``). Sans-IO: ``LsfReader.units`` takes the decompressed bytes in pieces.

A frame's size field says where the next frame begins. A frame of an id IMC.xml does not define is taken as one
only where its CRC holds; elsewhere, and where no synchronization number is, the log is damaged: the reader skips to
the next place where a synchronization number is followed by an id IMC.xml defines, and says how many bytes it
skipped. A frame the end of the log cuts is said, not judged.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from itertools import chain
from pathlib import Path

from ...capture.logs import Logged
from ...capture.streams import GAP
from . import codec
from .crc16 import arc

SYNCS = (b"\x54\xfe", b"\xfe\x54")
HEAD = {b"\x54\xfe": struct.Struct("<HHHdH"), b"\xfe\x54": struct.Struct(">HHHdH")}  # sync, mgid, size, timestamp, src
LOOK = HEAD[SYNCS[0]].size  # bytes a frame's place needs before its size, time and sender can be read
OVERHEAD = codec.HEADER_SIZE + codec.FOOTER_SIZE
FRAME, MORE, CUT, NONE = "frame", "more", "cut", "none"  # what a place in a log holds (LsfReader._at)


class LsfReader:
    """Reads LSF logs for the IMC suite ``suite``: frames judged by its capture rules."""

    format = "LSF"
    addressed = True
    gaps = True

    def __init__(self, suite, edition: str | None):
        self.suite, self.rules = suite, suite.capture_rules()
        self.edition = edition or suite.editions[0]
        self.notes: list[str] = []
        known = suite.defs.by_id.keys() | suite.defs.ids_elsewhere  # where a frame may begin again after damage
        self.ids = {sync: frozenset(struct.pack(order + "H", i) for i in known) for sync, order in zip(SYNCS, "<>")}

    def recognises(self, head: bytes) -> bool:
        return head[:2] in HEAD

    def beside(self, path: Path, use: bool):
        from .log_xml import beside

        return beside(path, self.suite, use)

    def units(self, pieces: Iterator[bytes], damage: list[str], name: str) -> Iterator[Logged]:
        buf, pos, base, number = b"", 0, 0, 0  # base: the log's byte at buf[0]
        skipped, ids = _Skipped(), self.ids
        cut = False  # the bytes before the next frame are the rest of the one the stream's damage cut
        for piece in chain(pieces, (b"",)):  # then b"": the end of the log
            if piece is GAP:  # what follows does not follow (damage the stream said): the frame it cuts is dropped,
                buf, base, pos, cut = b"", base + len(buf), 0, True  # its rest too (the damage's line says so)
                continue
            last = not piece
            buf, base, pos = buf[pos:] + piece, base + pos, 0
            n = len(buf)
            while pos < n:
                order = buf[pos:pos + 2]
                head = HEAD.get(order)
                if head is not None and n - pos >= LOOK:  # the common case: a frame of a message IMC.xml defines
                    _, _, size, t, src = head.unpack_from(buf, pos)
                    end = pos + OVERHEAD + size
                    if end <= n and buf[pos + 2:pos + 4] in ids[order]:
                        number += 1
                        yield Logged(number, t, base + pos, buf[pos:end], None, None, src)  # positional: the hot path
                        pos, cut = end, False
                        continue
                what, end, t = self._at(buf, pos, n, last)
                if what is FRAME:
                    number += 1
                    yield Logged(number, t, base + pos, buf[pos:end], system=HEAD[buf[pos:pos + 2]].unpack_from(
                        buf, pos)[4])
                    pos, cut = end, False
                elif what is NONE:
                    found = self._next_frame(buf, pos, n, last)
                    if not cut:
                        skipped.add(base + pos, found - pos)
                    pos = found
                else:
                    break  # MORE: the rest is in the next piece; CUT: the log ends inside this frame
        if skipped.stretches:
            damage.append(f"{name}: {skipped.stretches:,} stretch{'es' if skipped.stretches != 1 else ''} of bytes "
                          f"that are no IMC frame ({skipped.count:,} bytes, the first at byte {skipped.first:,}): "
                          "skipped, each to the next synchronization number followed by a message id")
        if pos < len(buf):
            damage.append(f"{name}: {self._cut(buf[pos:], base + pos)}: cut short, judged up to it")

    def _at(self, buf: bytes, pos: int, n: int, last: bool) -> tuple[object, int, float]:
        """What begins at ``pos`` besides a whole frame of a defined message: (FRAME, its end, its time) for a frame
        of an id IMC.xml lacks whose CRC holds, MORE where the next piece must tell, CUT for a frame the end of the
        log cuts, NONE for bytes that are no frame (then the next frame is looked for)."""
        if n - pos < LOOK and not last:
            return MORE, 0, 0.0
        order = buf[pos:pos + 2]
        head = HEAD.get(order)
        if head is None:
            return NONE, 0, 0.0
        if n - pos < LOOK:
            return CUT, 0, 0.0
        _, _, size, t, _ = head.unpack_from(buf, pos)
        end = pos + OVERHEAD + size
        known = buf[pos + 2:pos + 4] in self.ids[order]
        if end > n:
            return (MORE if not last else CUT if known else NONE), 0, 0.0
        if known or _sound(buf[pos:end], order):
            return FRAME, end, t
        return NONE, 0, 0.0

    def _next_frame(self, buf: bytes, pos: int, n: int, last: bool) -> int:
        """Where the next frame may begin after the damage at ``pos``: a synchronization number followed by an id
        IMC.xml defines; else the end (of the log, or of the piece but for bytes that may begin a frame). Each
        synchronization number is searched for again only past the place rejected: one pass over the bytes, however
        many of them are numbers followed by ids IMC.xml lacks."""
        at = pos + 1
        ahead = [buf.find(sync, at) for sync in SYNCS]  # where each is next (-1: nowhere)
        while True:
            found = [i for i in ahead if i >= 0]
            if not found:
                return n if last else max(at, n - LOOK + 1)
            i = min(found)
            if i + 4 > n or buf[i + 2:i + 4] in self.ids[buf[i:i + 2]]:
                return i
            at = i + 1
            ahead = [buf.find(sync, at) if j == i else j for sync, j in zip(SYNCS, ahead)]

    def _cut(self, rest: bytes, offset: int) -> str:
        """What the end of the log cuts: a frame's header, or a frame of a message (how much of it is there)."""
        if len(rest) < 6:
            return f"the log ends {len(rest)} bytes into a frame's header at byte {offset:,}"
        _, mgid, size = struct.unpack_from(HEAD[rest[:2]].format[:4], rest)
        known = self.suite.defs.by_id.get(mgid)
        return (f"the log ends inside a frame of {known.abbrev if known else f'id {mgid}'} at byte {offset:,} "
                f"({len(rest):,} of its {size + OVERHEAD:,} bytes)")


def _sound(frame: bytes, order: bytes) -> bool:
    """Whether a whole frame's CRC holds (a little-endian frame and its CRC: their CRC is 0)."""
    if order == SYNCS[0]:
        return not arc(frame)
    return arc(frame[:-2]) == int.from_bytes(frame[-2:], "big")


class _Skipped:
    """The stretches of a log that are no frame: how many, their bytes, where the first began."""

    def __init__(self):
        self.stretches = self.count = 0
        self.first: int | None = None
        self.end: int | None = None  # where the last stretch ends (the next one may go on from there)

    def add(self, offset: int, count: int) -> None:
        if count <= 0:
            return
        if offset != self.end:
            self.stretches += 1
            self.first = offset if self.first is None else self.first
        self.count += count
        self.end = offset + count
