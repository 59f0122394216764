"""The records of a pcap or pcapng capture, read from its bytes (sans-IO: the caller maps or reads the file).

Hand-written rather than scapy's readers: those stop with an exception at the first damaged record (losing
the frames before it in a generator the caller cannot resume) and cost ~20 µs a record; this reader yields
every whole record, then raises ``CaptureError`` naming the damage, at ~1 µs a record.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Iterator

PCAP_MAGICS = {b"\xd4\xc3\xb2\xa1": ("<", 1e-6), b"\xa1\xb2\xc3\xd4": (">", 1e-6),
               b"\x4d\x3c\xb2\xa1": ("<", 1e-9), b"\xa1\xb2\x3c\x4d": (">", 1e-9)}
PCAPNG_SHB = b"\x0a\x0d\x0d\x0a"
RECORD_LIMIT = 1 << 18  # bytes: no link layer captures more in one record (tcpdump's largest snaplen)
NUMBERED = (0x00000BAD, 0x40000BAD, 9)  # custom blocks and systemd journal entries: frames to Wireshark


class CaptureError(ValueError):
    """The capture is not one, or is damaged from ``record`` on (the records before it were read)."""


@dataclass(slots=True)
class Record:
    number: int  # 1-based, as Wireshark numbers frames
    time: float  # seconds since the epoch
    linktype: int
    data: bytes  # what was captured
    length: int  # the frame's length on the wire (more than len(data) when the snaplen cut it)
    comment: str | None = None  # pcapng opt_comment


def records(buf, sections: list[str] | None = None) -> Iterator[Record]:
    """Every record of the capture in ``buf``; raises CaptureError at the first damage. The comments of a pcapng
    section and of its interface statistics are appended to ``sections`` as they are read."""
    head = bytes(buf[:4])
    if head in PCAP_MAGICS:
        return _pcap(buf, *PCAP_MAGICS[head])
    if head == PCAPNG_SHB:
        return _pcapng(buf, [] if sections is None else sections)
    if len(buf) < 4:
        raise CaptureError(f"not a capture: {len(buf)} bytes")
    raise CaptureError(f"not a pcap or pcapng capture (it starts {head.hex()})")


def _pcap(buf, e: str, unit: float) -> Iterator[Record]:
    if len(buf) < 24:
        raise CaptureError(f"a truncated pcap header ({len(buf)} of 24 bytes)")
    linktype = struct.unpack_from(e + "I", buf, 20)[0] & 0xFFFF  # the upper bits say whether frames end in an FCS
    unpack, pos, end, number = struct.Struct(e + "IIII").unpack_from, 24, len(buf), 0
    while pos < end:
        number += 1
        if pos + 16 > end:
            raise CaptureError(f"record {number} is truncated (its header has {end - pos} of 16 bytes)")
        seconds, fraction, caplen, length = unpack(buf, pos)
        if caplen > RECORD_LIMIT:
            raise CaptureError(f"record {number} claims {caplen} bytes: the capture is damaged from there")
        pos += 16
        if pos + caplen > end:
            raise CaptureError(f"record {number} is truncated ({end - pos} of {caplen} bytes)")
        yield Record(number, seconds + fraction * unit, linktype, bytes(buf[pos:pos + caplen]), length)
        pos += caplen


def _pcapng(buf, sections: list[str]) -> Iterator[Record]:
    end, pos, number = len(buf), 0, 0
    e, interfaces = "<", []
    while pos < end:
        if pos + 12 > end:
            raise CaptureError(f"a pcapng block at byte {pos} is truncated")
        raw_type = bytes(buf[pos:pos + 4])
        if raw_type == PCAPNG_SHB:
            magic = bytes(buf[pos + 8:pos + 12])
            e = {b"\x4d\x3c\x2b\x1a": "<", b"\x1a\x2b\x3c\x4d": ">"}.get(magic)
            if e is None:
                raise CaptureError(f"a pcapng section at byte {pos} has no byte-order magic")
            interfaces = []
        btype, blen = struct.unpack_from(e + "II", buf, pos)
        if blen < 12 or blen % 4 or pos + blen > end:
            raise CaptureError(f"a pcapng block at byte {pos} is truncated or damaged (length {blen})")
        body = buf[pos + 8:pos + blen - 4]
        pos += blen
        if btype in (0x0A0D0D0A, 5):  # a section's or an interface statistics block's comments, each joined
            comments = [value for code, value in _options(body, 16 if btype == 0x0A0D0D0A else 12, e) if code == 1]
            if comments:
                sections.append(b"".join(comments).decode("utf-8", "replace"))
        elif btype == 1:  # interface description
            interfaces.append(_interface(number + 1, body, e))
        elif btype in (6, 3, 2):  # enhanced, simple, obsolete packet
            number += 1
            yield _packet(number, btype, body, e, interfaces)
        elif btype in NUMBERED:
            number += 1  # Wireshark numbers these blocks as frames too


def _interface(number: int, body, e: str) -> tuple[int, float, float]:
    """(link type, seconds per timestamp unit, offset in seconds) of an interface description block."""
    if len(body) < 8:
        raise CaptureError(f"an interface description before record {number} is damaged ({len(body)} bytes)")
    linktype = struct.unpack_from(e + "H", body, 0)[0]
    unit, offset = 1e-6, 0.0
    for code, value in _options(body, 8, e):
        if code == 9 and value:
            unit = 2.0 ** -(value[0] & 0x7F) if value[0] & 0x80 else 10.0 ** -value[0]
        elif code == 14 and len(value) == 8:
            offset = float(struct.unpack(e + "q", value)[0])
    return linktype, unit, offset


def _packet(number: int, btype: int, body, e: str, interfaces: list) -> Record:
    try:
        if btype == 3:  # simple: no interface id, no timestamp
            length = struct.unpack_from(e + "I", body, 0)[0]
            linktype, _, _ = interfaces[0]
            return Record(number, 0.0, linktype, bytes(body[4:4 + min(length, len(body) - 4)]), length)
        if btype == 6:
            iface, high, low, caplen, length = struct.unpack_from(e + "IIIII", body, 0)
        else:
            iface, _, high, low, caplen, length = struct.unpack_from(e + "HHIIII", body, 0)
        start = 20
        linktype, unit, offset = interfaces[iface]
    except (struct.error, IndexError):
        raise CaptureError(f"record {number} is damaged (a packet block without its interface or fields)") from None
    if start + caplen > len(body):
        raise CaptureError(f"record {number} is truncated ({len(body) - start} of {caplen} bytes)")
    comment = None
    after = start + caplen + (-caplen % 4)
    if after < len(body):
        comments = [value for code, value in _options(body, after, e) if code == 1]
        comment = b"".join(comments).decode("utf-8", "replace") if comments else None
    return Record(number, ((high << 32) | low) * unit + offset, linktype, bytes(body[start:start + caplen]), length, comment)


def _options(body, pos: int, e: str):
    """(code, value) of each option from ``pos`` (until opt_endofopt or the end of the block)."""
    while pos + 4 <= len(body):
        code, size = struct.unpack_from(e + "HH", body, pos)
        if code == 0:
            return
        value = bytes(body[pos + 4:pos + 4 + size])
        if len(value) < size:
            return  # a damaged option ends the options, not the capture
        yield code, value
        pos += 4 + size + (-size % 4)
