"""Byte-level edits of a frame that keep or deliberately break its consistency."""

from __future__ import annotations

import struct

from ..codec import FOOTER_SIZE, HEADER_SIZE, ORDERS
from ..crc16 import crc16


def u16(order: str, value: int) -> bytes:
    return struct.pack(ORDERS[order] + "H", value)


def read_u16(frame: bytes, order: str, offset: int) -> int:
    return struct.unpack_from(ORDERS[order] + "H", frame, offset)[0]


def payload_of(frame: bytes, order: str) -> bytes:
    size = read_u16(frame, order, 4)
    return frame[HEADER_SIZE:HEADER_SIZE + size]


def reframe(frame: bytes, order: str, *, payload: bytes | None = None, mgid: int | None = None,
            size: int | None = None) -> bytes:
    """A consistent frame (size and CRC recomputed unless ``size`` is forced) from ``frame``'s header."""
    payload = payload_of(frame, order) if payload is None else payload
    head = bytearray(frame[:HEADER_SIZE])
    if mgid is not None:
        head[2:4] = u16(order, mgid)
    head[4:6] = u16(order, len(payload) if size is None else size)
    body = bytes(head) + payload
    return body + u16(order, crc16(body))


def with_crc(frame: bytes, order: str) -> bytes:
    """The frame with its footer recomputed over everything before it, stored in ``order``."""
    return frame[:-2] + u16(order, crc16(frame[:-2]))


def flip(frame: bytes, offset: int, mask: int = 0x01) -> bytes:
    out = bytearray(frame)
    out[offset] ^= mask
    return bytes(out)


def swapped_crc(frame: bytes) -> bytes:
    """The frame with its footer's two bytes swapped (the CRC in the other byte order)."""
    return frame[:-FOOTER_SIZE] + frame[-1:] + frame[-2:-1]
