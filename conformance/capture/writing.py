"""Writing captures: classic pcap of UDP datagrams over Ethernet and IPv4, fast enough for the benchmark's
million frames (scapy builds ~10,000 packets a second; this packs headers with struct)."""

from __future__ import annotations

import socket
import struct

PCAP_HEADER = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)  # microseconds, Ethernet
MACS = bytes.fromhex("020000000002" "020000000001")
OPTION_LIMIT = 0xFFFC  # bytes of a pcapng option value (its length is 16 bits; values are padded to 4)


def ethernet_udp(src: str, sport: int, dst: str, dport: int, payload: bytes, ident: int = 0) -> bytes:
    """An Ethernet frame carrying one IPv4 UDP datagram (IP header checksum computed, UDP checksum 0)."""
    udp = struct.pack("!HHHH", sport, dport, 8 + len(payload), 0) + payload
    head = struct.pack("!BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), ident & 0xFFFF, 0, 64, 17, 0,
                       socket.inet_aton(src), socket.inet_aton(dst))
    total = sum(struct.unpack("!10H", head))
    total = (total & 0xFFFF) + (total >> 16)
    head = head[:10] + struct.pack("!H", ~((total & 0xFFFF) + (total >> 16)) & 0xFFFF) + head[12:]
    return MACS + b"\x08\x00" + head + udp


def pcap_record(t: float, frame: bytes) -> bytes:
    seconds, micros = divmod(round(t * 1e6), 1_000_000)
    return struct.pack("<IIII", seconds, micros, len(frame), len(frame)) + frame


def ip_udp(src: str, sport: int, dst: str, dport: int, payload: bytes) -> bytes:
    """One IPv4 or IPv6 UDP datagram as it was on the wire (checksums left 0: "not computed")."""
    udp = struct.pack("!HHHH", sport, dport, 8 + len(payload), 0) + payload
    if ":" in src:  # a link-local address's zone (fe80::1%eth0) is not on the wire
        return struct.pack("!IHBB16s16s", 6 << 28, len(udp), 17, 64, socket.inet_pton(socket.AF_INET6, src.split("%")[0]),
                           socket.inet_pton(socket.AF_INET6, dst.split("%")[0])) + udp
    return ethernet_udp(src, sport, dst, dport, payload)[14:]


class PcapNgWriter:
    """A pcapng file of raw IP datagrams (link type 101) with nanosecond timestamps, a comment on the section
    (``about``), one on every packet and, at ``close``, one on the interface's statistics. Hand-written: scapy's
    writer cannot comment the section header."""

    def __init__(self, handle, about: str):
        self.handle = handle
        handle.write(_block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1) + _options([(1, about.encode())])))
        handle.write(_block(1, struct.pack("<HHI", 101, 0, 0) + _options([(9, b"\x09")])))

    def write(self, epoch: float, src: tuple, dst: tuple, payload: bytes, comment: str) -> None:
        packet = ip_udp(src[0], src[1], dst[0], dst[1], payload)
        ns = round(epoch * 1e9)
        body = struct.pack("<IIIII", 0, ns >> 32, ns & 0xFFFFFFFF, len(packet), len(packet))
        self.handle.write(_block(6, body + packet + bytes(-len(packet) % 4) + _options([(1, comment.encode())])))


    def close(self, epoch: float, comment: str) -> None:
        """End the file with the interface's statistics block, commented (how a reader knows the run ended)."""
        ns = round(epoch * 1e9)
        self.handle.write(_block(5, struct.pack("<III", 0, ns >> 32, ns & 0xFFFFFFFF) + _options([(1, comment.encode())])))


def _options(items) -> bytes:
    """Options of a block; a value longer than an option holds (65,535 bytes) goes in several of the same code
    (a reader joins a section's comments)."""
    out = b""
    for code, value in items:
        for start in range(0, max(len(value), 1), OPTION_LIMIT):
            part = value[start:start + OPTION_LIMIT]
            out += struct.pack("<HH", code, len(part)) + part + bytes(-len(part) % 4)
    return out + struct.pack("<HH", 0, 0)


def _block(kind: int, body: bytes) -> bytes:
    length = 12 + len(body)
    return struct.pack("<II", kind, length) + body + struct.pack("<I", length)
