"""The bytes of a log file, read in bounded pieces and decompressed as they come: plain, gzip (every member of a
multi-member file, as loggers that flush write them) or bzip2 (every stream), told apart by their content, not
their name. Memory stays flat whatever the size: each piece is at most ``PIECE`` bytes before and after
decompression. What cannot be read is said in ``damage`` (one line each), never raised, after the pieces before it:
a stream cut short, bytes after the last stream, damaged compressed data, and output beyond ``BOMB_RATIO`` times the
compressed input read (no real log compresses so well: a decompression bomb is refused, not followed into the
memory or the hours it asks for).

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
BOMB_RATIO = 200  # decompressed bytes per compressed byte beyond which a stream is refused (DUNE's gzip logs: about 2.5)
BOMB_FLOOR = 64 << 20  # decompressed bytes before the ratio is applied (a small stream may compress better)
GZIP, BZIP2 = b"\x1f\x8b", b"BZh"


class Stream:
    """A log file's decompressed bytes (``pieces()``), with what was found on the way: its ``compression``
    (None, "gzip" or "bzip2"), the bytes read from the file (``read``) and produced (``produced``), and ``damage``."""

    def __init__(self, path: Path, handle, limit: int, sized: bool = False):
        self.path, self.handle, self.limit, self.sized = path, handle, limit, sized  # sized: a file of that size
        self.compression: str | None = None
        self.read = self.produced = 0
        self.damage: list[str] = []
        self.ended = False  # no byte more is read (the end, the bound, or an error)

    def pieces(self) -> Iterator[bytes]:
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
        except OSError as exc:
            self.damage.append(f"{self.path}: cannot read on after byte {self.read:,}: {exc.strerror or exc}")
            data = b""
        self.read += len(data)
        self.ended = not data
        return data

    def _decompressed(self, data: bytes, fresh, magic: bytes) -> Iterator[bytes]:
        """Every stream of the file decompressed, in pieces of at most PIECE bytes (each call bounded)."""
        what = self.compression
        decoder, start = fresh(), 0  # start: where in the file the current stream began
        while True:
            try:
                out = decoder.decompress(data, PIECE)
            except (zlib.error, OSError, EOFError, ValueError) as exc:
                self.damage.append(f"{self.path}: damaged {what} data in the stream that begins at byte {start:,} "
                                   f"({exc}): judged up to it")
                return
            data = decoder.unconsumed_tail if what == "gzip" else b""
            if out:
                self.produced += len(out)
                if self.produced > BOMB_FLOOR and self.produced > BOMB_RATIO * self.read:
                    self.damage.append(f"{self.path}: {self.produced >> 20} MB out of the first {self.read:,} bytes, "
                                       f"more than {BOMB_RATIO} times their size (no log compresses so well: a "
                                       "decompression bomb?): refused from there")
                    return
                yield out
            if decoder.eof:
                rest = decoder.unused_data
                rest += self._raw(max(0, len(magic) - len(rest)))
                if not rest:
                    return
                if not rest.startswith(magic):
                    after = len(rest) + self._skip()
                    self.damage.append(f"{self.path}: {after:,} bytes after the {what} data, at byte "
                                       f"{self.read - after:,}, are not {what}: ignored")
                    return
                decoder, start, data = fresh(), self.read - len(rest), rest
            elif not (out or data or (what == "bzip2" and not decoder.needs_input)):
                data = self._raw(PIECE)  # the decoder wants more input
                if not data:
                    self.damage.append(f"{self.path}: the {what} stream that begins at byte {start:,} is cut short "
                                       f"(it ends without its end marker): judged up to the cut")
                    return

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
