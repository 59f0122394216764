"""The bytes of a log file, read in bounded pieces and decompressed as they come: plain, gzip (every member of a
multi-member file, as loggers that flush write them) or bzip2 (every stream), told apart by their content, not
their name. Memory stays flat whatever the size: each piece is at most ``PIECE`` bytes before and after
decompression (a gzip member's output is held until its CRC checks, up to ``HOLD``). What cannot be read is said in
``damage`` (one line each, naming its byte), never raised, after the pieces before it: a stream cut short, a gzip
member cut where another begins, bytes after the last stream, damaged compressed data, and output beyond
``BOMB_RATIO`` times the compressed bytes consumed past ``BOMB_FLOOR`` (no real log compresses so well: a
decompression bomb is refused, not followed into the memory or the hours it asks for).

Hand-written around the standard library's zlib and bz2 rather than the gzip and bz2 modules' file objects: those
raise at trailing garbage and at a cut stream without saying how far they got.
"""

from __future__ import annotations

import bz2
import os
import stat
import zlib
from collections.abc import Iterator
from pathlib import Path

from ..limits import PIPE_LIMIT

PIECE = 1 << 20  # bytes read and decompressed at a time
SLICE = {"gzip": 64 << 10, "bzip2": 1 << 10}  # compressed bytes given to a decoder at a time (libbz2 cannot be
# copied to find the damage again a byte at a time, so its slices are small: the damage is named within one)
BOMB_RATIO = 200  # decompressed bytes per compressed byte beyond which a stream is refused (DUNE's gzip logs: about 2.5)
BOMB_FLOOR = 64 << 20  # decompressed bytes before the ratio is applied (a small stream may compress better)
GZIP, BZIP2 = b"\x1f\x8b", b"BZh"
MEMBER = b"\x1f\x8b\x08"  # a gzip member's header begins so (deflate)
HOLD = 16 << 20  # bytes of a gzip member's output held until its end checks it (DUNE's members: about 1 MB)
LOOKAHEAD = 1 << 20  # compressed bytes a member is read on from a header inside it, to tell whether it was cut there


class Stream:
    """A log file's decompressed bytes (``pieces()``), with what was found on the way: its ``compression``
    (None, "gzip" or "bzip2"), the bytes read from the file (``read``) and produced (``produced``), and ``damage``."""

    def __init__(self, path: Path, handle, limit: int, sized: bool = False):
        self.path, self.handle, self.limit, self.sized = path, handle, limit, sized  # sized: a file of that size
        self.compression: str | None = None
        self.read = self.produced = 0
        self.damage: list[str] = []
        self.ended = False  # no byte more is read (the end, the bound, or an error)
        self.failed = False  # the reading stopped short of the end (an error, or the bound), said in ``damage``
        self.broken = False  # the pieces stop at damage (said in ``damage``), not at the end of the log
        self.gaps = False  # the reader takes GAP among the pieces (LogReader.gaps): a gzip member cut where another
        # begins is then read on from there

    def pieces(self) -> Iterator[bytes]:
        """The decompressed bytes; where ``gaps``, GAP between two pieces that do not follow each other (a gzip
        member cut, and the next one read on) and after the last where the pieces stop at damage."""
        yield from self._pieces()
        if (self.broken or self.failed) and self.gaps and self.produced:
            yield GAP

    def _pieces(self) -> Iterator[bytes]:
        first = self._raw(PIECE)
        if first.startswith(GZIP):
            self.compression = "gzip"
            yield from self._decompressed(first, lambda: zlib.decompressobj(16 + zlib.MAX_WBITS), GZIP)
        elif first.startswith(BZIP2):
            self.compression = "bzip2"
            yield from self._decompressed(first, bz2.BZ2Decompressor, BZIP2)
        else:
            while first:
                self.produced += len(first)
                yield first
                first = self._raw(PIECE)

    def _raw(self, size: int) -> bytes:
        """At most ``size`` bytes more of the file, never past ``limit`` (a device or a pipe is a file; a regular
        file is read to the size it had when opened)."""
        if self.ended or size <= 0:
            return b""
        try:
            size = min(size, self.limit - self.read)
            data = self.handle.read(size) if size > 0 else b""
            if not data and not self.sized and self.read >= self.limit and self.handle.read(1):
                self.damage.append(f"{self.path}: more than {self.limit >> 20} MB through a pipe or device: judged "
                                   "up to there")
                self.failed = True
        except OSError as exc:
            self.damage.append(f"{self.path}: cannot read on after byte {self.read:,}: {exc.strerror or exc}")
            data, self.failed = b"", True
        self.read += len(data)
        self.ended = not data
        return data

    def _decompressed(self, pending: bytes, fresh, magic: bytes) -> Iterator[bytes]:
        """Every stream of the file decompressed, in pieces of at most PIECE bytes (each call bounded), the
        compressed bytes given a SLICE at a time. A gzip member's output is held until its CRC-32 (at its end) says
        it is whole, up to HOLD bytes: damaged deflate data decompresses on into garbage, found only there, and
        frames made of garbage would be judged as the log's. A member cut short, or cut where another begins, is
        found at the cut: its output up to there is the log's."""
        what, gz = self.compression, self.compression == "gzip"
        decoder, start, pos, size = fresh(), 0, 0, SLICE[what]  # start: the file's byte where the stream began
        held: list[bytes] = []  # the current gzip member's output, not yet checked
        holding, kept = gz, 0  # kept: the bytes held
        while True:
            tail = decoder.unconsumed_tail if gz else b""
            if tail or (not gz and not decoder.needs_input):
                feed = tail  # what the decoder has yet to turn into output
            else:
                if pos >= len(pending):
                    pending, pos = self._raw(PIECE), 0
                    if not pending:
                        yield from held
                        self.broken = True
                        if not self.failed:  # else it said where the reading stopped
                            self.damage.append(f"{self.path}: the {what} stream that begins at byte {start:,} is "
                                               f"cut short at byte {self.read:,}, the end of the file (no end marker):"
                                               " every frame before the cut judged")
                        return
                cut = self._member_begins(pending, pos, size, start) if gz else -1
                if cut == pos:  # a gzip header where the member, not ended, goes on: cut there?
                    cut, pending = self._cut_at(decoder, pending, pos)
                    if cut:
                        yield from held
                        at = self.read - len(pending) + pos
                        self.damage.append(f"{self.path}: the gzip member that begins at byte {start:,} is cut at "
                                           f"byte {at:,}, where another member begins: every frame before the cut "
                                           + ("judged, and the log read on from there (the frame the cut splits is "
                                              "not)" if self.gaps else "judged, nothing after it read"))
                        if not self.gaps:
                            self.broken = True
                            return
                        if self.produced:
                            yield GAP
                        decoder, start, held, holding, kept = fresh(), at, [], True, 0
                        continue
                    cut = self._member_begins(pending, pos + 1, size - 1, start)
                size_now = size if cut < 0 else cut - pos
                feed, pos = pending[pos:pos + size_now], pos + size_now
            given = self.read - len(pending) + min(pos, len(pending))  # the file's byte after what was given
            here = given - len(feed)  # the file's byte of feed[0]
            saved = decoder.copy() if gz else None  # to find the damage again, a byte at a time
            try:
                out = decoder.decompress(feed, PIECE)
            except (zlib.error, OSError, EOFError, ValueError) as exc:
                out, where = _salvage(saved, feed, here) if saved is not None else (b"", None)
                at = f"at byte {where:,}" if where is not None else f"between bytes {here:,} and {given:,}"
                if holding:
                    said = "what the member decompressed to is not judged (gzip checks a member whole, at its end, " \
                           "and damaged data decompresses on into garbage), every frame before the member judged"
                else:
                    said = "every frame before it judged"
                    if out:
                        self.produced += len(out)
                        yield out
                self.damage.append(f"{self.path}: damaged {what} data {at}, in the {'member' if gz else 'stream'} "
                                   f"that begins at byte {start:,} ({'zlib' if gz else 'libbz2'}: {exc}): {said}, "
                                   "nothing after it read")
                self.broken = True
                return
            if out:
                self.produced += len(out)
                consumed = given - len(decoder.unconsumed_tail if gz else b"") - len(decoder.unused_data)
                if self.produced > BOMB_FLOOR and self.produced > BOMB_RATIO * consumed:
                    yield from held
                    self.damage.append(f"{self.path}: {self.produced >> 20} MB out of its first {consumed:,} "
                                       f"compressed bytes, more than {BOMB_RATIO} times their size (no log compresses "
                                       "so well: a decompression bomb?): refused from there")
                    self.broken = True
                    return
                if holding:
                    held.append(out)
                    kept += len(out)
                    if kept > HOLD:  # a member too large to hold: judged as it comes
                        yield from held
                        held, holding = [], False
                else:
                    yield out
            if decoder.eof:
                yield from held
                held, holding, kept = [], gz, 0
                rest = decoder.unused_data + pending[pos:]
                pending, pos = rest + self._raw(max(0, len(magic) - len(rest))), 0
                if not pending:
                    return
                if not pending.startswith(magic):
                    after = len(pending) + self._skip()
                    self.damage.append(f"{self.path}: {after:,} bytes after the {what} data, at byte "
                                       f"{self.read - after:,}, are not {what}: ignored")
                    return
                decoder, start = fresh(), self.read - len(pending)

    def _member_begins(self, pending: bytes, pos: int, size: int, start: int) -> int:
        """Where in ``pending[pos:pos + size]`` a gzip member's header may begin (-1: nowhere), but the current one's
        (which begins at the file's byte ``start``)."""
        base = self.read - len(pending)
        at = pending.find(MEMBER, pos, pos + size + len(MEMBER) - 1)
        while at >= 0 and (base + at == start or not _header(pending[at:at + 10])):
            at = pending.find(MEMBER, at + 1, pos + size + len(MEMBER) - 1)
        return at if at < pos + size else -1

    def _cut_at(self, decoder, pending: bytes, pos: int) -> tuple[bool, bytes]:
        """Whether the member being decompressed (``decoder``, given every byte before ``pending[pos]``, where a gzip
        header is) was cut there: its data read on from there is damaged within LOOKAHEAD bytes. (A member cut and
        followed by the next one is read on as if it went on, and found damaged only at the next one's end, after
        frames made of the next one's bytes, which would be judged as the log's.) Decompressed on a copy, the output
        left unkept; and ``pending`` with what was read on for it."""
        while len(pending) - pos < LOOKAHEAD and not self.ended:  # at most a piece more, kept to go on with
            more = self._raw(PIECE)
            if not more:
                break
            pending += more
        test, ahead, made = decoder.copy(), pending[pos:pos + LOOKAHEAD], 0
        try:
            while ahead and not test.eof and made < BOMB_FLOOR:
                made += len(test.decompress(ahead, PIECE))
                ahead = test.unconsumed_tail
        except zlib.error:
            return True, pending
        return False, pending

    def _skip(self) -> int:
        """Read the rest of the file (bounded) without keeping it; how many bytes that was."""
        total = 0
        while True:
            piece = self._raw(PIECE)
            if not piece:
                return total
            total += len(piece)


def open_stream(path: Path) -> Stream:
    """The ``Stream`` of a log file (``-``: standard input); ValueError with one line if it cannot be opened. A
    regular file is read to the size it had when opened; a pipe or a device to ``PIPE_LIMIT`` bytes."""
    import sys

    try:
        if str(path) == "-":
            return Stream(path, sys.stdin.buffer, PIPE_LIMIT)
        handle = open(path, "rb")  # noqa: SIM115 - the caller closes it (Stream.handle)
        info = os.fstat(handle.fileno())
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {exc.strerror or exc}") from None
    regular = stat.S_ISREG(info.st_mode)
    return Stream(path, handle, info.st_size if regular else PIPE_LIMIT, sized=regular)


def _header(head: bytes) -> bool:
    """Whether 10 bytes are a gzip member's header (RFC 1952: deflate, no reserved flag, XFL 0, 2 or 4)."""
    return len(head) < 10 or (head[3] < 0x20 and head[8] in (0, 2, 4))


def _salvage(saved, feed: bytes, here: int) -> tuple[bytes, int]:
    """What a zlib decoder (``saved``, as it was before the call that found damage) gives of ``feed``, which begins
    at the file's byte ``here``, up to the damage, a byte at a time (the failing call's output is lost with it); the
    byte where the damage was found."""
    out = []
    for i in range(len(feed)):
        try:
            out.append(saved.decompress(feed[i:i + 1]))
        except zlib.error:
            return b"".join(out), here + i
    return b"".join(out), here + len(feed)


class _Gap:
    """Between two decompressed pieces that do not follow each other (``Stream.gaps``)."""

    def __repr__(self) -> str:
        return "GAP"


GAP = _Gap()


class Short(ValueError):
    """The bytes ended before ``take`` had what it asked for (``got`` of them were there)."""

    def __init__(self, got: int):
        super().__init__(f"{got} bytes left")
        self.got = got


class Reader:
    """Sequential reading of decompressed pieces: ``take(n)`` exactly ``n`` bytes (the caller bounds ``n``), and
    ``offset``, the byte of the log the next one comes from."""

    def __init__(self, pieces):
        self.pieces, self.buf, self.pos, self.offset = iter(pieces), b"", 0, 0

    def take(self, n: int) -> bytes:
        if len(self.buf) - self.pos < n:
            parts, have = [self.buf[self.pos:]], len(self.buf) - self.pos
            while have < n:
                piece = next(self.pieces, b"")
                if not piece:
                    self.buf, self.pos = b"".join(parts), 0
                    raise Short(have)
                parts.append(piece)
                have += len(piece)
            self.buf, self.pos = b"".join(parts), 0
        out = self.buf[self.pos:self.pos + n]
        self.pos += n
        self.offset += n
        return out

    def skip(self, n: int) -> None:
        """Pass over ``n`` bytes, holding at most a piece of them at a time; Short if fewer are left."""
        left = n
        while left:
            have = len(self.buf) - self.pos
            if not have:
                self.buf, self.pos = next(self.pieces, b""), 0
                if not self.buf:
                    raise Short(n - left)
                continue
            step = min(have, left)
            self.pos += step
            self.offset += step
            left -= step

    def at_end(self) -> bool:
        """Whether no byte is left."""
        if self.pos < len(self.buf):
            return False
        self.buf, self.pos = next(self.pieces, b""), 0
        return not self.buf
