"""CRC-16/ARC (poly 0x8005 reflected, init 0, no final XOR), the IMC footer checksum.

Hand-written rather than a dependency: ``binascii.crc_hqx`` is CRC-CCITT, and a
table-driven CRC is twelve lines that the corpus pins with the standard check value.
"""

from __future__ import annotations


def _table() -> tuple[int, ...]:
    rows = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
        rows.append(crc)
    return tuple(rows)


_TABLE = _table()


def crc16(data: bytes, crc: int = 0) -> int:
    """Return the CRC-16/ARC of ``data`` (``crc16(b"123456789") == 0xBB3D``)."""
    for byte in data:
        crc = (crc >> 8) ^ _TABLE[(crc ^ byte) & 0xFF]
    return crc
