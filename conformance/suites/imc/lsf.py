"""LSF, the mission log of DUNE (its Logging task), Neptus and imcjava: the IMC frames a system dispatched and
received, each whole (header, payload, CRC, in its sender's byte order), one after another with nothing between
(DUNE: ``IMC::Packet::serialize`` of each message into ``Data.lsf``, compressed as ``Data.lsf.gz`` or ``.bz2``;
``src/Transports/Logging/Task.cpp``). Sans-IO: ``LsfReader.units`` takes the decompressed bytes in pieces.

A frame's size field says where the next frame begins. Where no synchronization number is (the log is damaged
there), the reader skips to the next place where one is followed by a message id the definitions know, and says
how many bytes it skipped; a frame cut by the end of the log is said, not judged.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from pathlib import Path

from ...capture.logs import Logged
from . import codec

SYNCS = (b"\x54\xfe", b"\xfe\x54")
HEAD = {b"\x54\xfe": struct.Struct("<HHHd"), b"\xfe\x54": struct.Struct(">HHHd")}  # sync, mgid, size, timestamp
LOOK = HEAD[SYNCS[0]].size  # bytes a frame's place needs before its size and time can be read
OVERHEAD = codec.HEADER_SIZE + codec.FOOTER_SIZE


class LsfReader:
    """Reads LSF logs for the IMC suite ``suite``: frames judged by its capture rules."""

    format = "LSF"

    def __init__(self, suite, edition: str | None):
        self.suite, self.rules = suite, suite.capture_rules()
        self.edition = edition or suite.editions[0]
        self.notes: list[str] = []
        known = suite.defs.by_id.keys() | suite.defs.ids_elsewhere  # where a frame may begin again after damage
        self.ids = {order: frozenset(struct.pack(order + "H", i) for i in known) for order in "<>"}

    def recognises(self, head: bytes) -> bool:
        return head[:2] in HEAD

    def beside(self, path: Path, use: bool):
        from .log_xml import beside

        return beside(path, self.suite, use)

    def units(self, pieces: Iterator[bytes], damage: list[str], name: str) -> Iterator[Logged]:
        buf, pos, base, number = b"", 0, 0, 0  # base: the log's byte at buf[0]
        skipped = _Skipped()
        for piece in pieces:
            buf, base, pos = buf[pos:] + piece, base + pos, 0
            n = len(buf)
            while n - pos >= LOOK:
                head = HEAD.get(buf[pos:pos + 2])
                if head is None:
                    found = self._next_frame(buf, pos, n)
                    skipped.add(base + pos, found - pos)
                    pos = found
                    continue
                _, _, size, t = head.unpack_from(buf, pos)
                end = pos + OVERHEAD + size
                if end > n:
                    break  # the rest of the frame is in the next piece
                number += 1
                yield Logged(number, t, base + pos, buf[pos:end])
                pos = end
        self._ended(buf[pos:], base + pos, skipped, damage, name)

    def _next_frame(self, buf: bytes, pos: int, n: int) -> int:
        """Where the next frame may begin after the damage at ``pos``: a synchronization number followed by an id
        IMC.xml defines; else the last bytes, which may begin one (the next piece tells)."""
        at = pos + 1
        while True:
            found = [i for i in (buf.find(SYNCS[0], at), buf.find(SYNCS[1], at)) if i >= 0]
            if not found:
                return max(at, n - LOOK + 1)
            i = min(found)
            if i + 4 > n or buf[i + 2:i + 4] in self.ids["<" if buf[i] == 0x54 else ">"]:
                return i
            at = i + 1

    def _ended(self, rest: bytes, offset: int, skipped: _Skipped, damage: list[str], name: str) -> None:
        """What the end of the log says: bytes after the last whole frame (a cut frame, or not a frame)."""
        head = HEAD.get(rest[:2])
        if rest and head is None:
            skipped.add(offset, len(rest))
        if skipped.stretches:
            damage.append(f"{name}: {skipped.stretches:,} stretch{'es' if skipped.stretches != 1 else ''} of bytes "
                          f"that are no IMC frame ({skipped.count:,} bytes, the first at byte {skipped.first:,}): "
                          "skipped, each to the next synchronization number followed by a message id")
        if rest and head is not None:
            if len(rest) < 6:
                damage.append(f"{name}: the log ends {len(rest)} bytes into a frame's header at byte {offset:,} (cut "
                              f"short): judged up to it")
                return
            _, mgid, size = struct.unpack_from(head.format[:4], rest)
            known = self.suite.defs.by_id.get(mgid)
            damage.append(f"{name}: the log ends inside a frame of {known.abbrev if known else f'id {mgid}'} at byte "
                          f"{offset:,} ({len(rest):,} of its {size + OVERHEAD:,} bytes; cut short): judged up to it")


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
