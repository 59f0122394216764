"""UDP datagrams out of captured link-layer records: Ethernet (with VLAN tags), raw IP, Linux cooked (SLL and
SLL2, what ``tcpdump -i any`` writes), BSD loopback; IPv4 and IPv6, fragments reassembled. Sans-IO.

Hand-written rather than scapy's dissection, which costs ~100 µs a packet; a capture of a million frames
must be judged in seconds.
"""

from __future__ import annotations

import socket
import struct
from collections import OrderedDict
from dataclasses import dataclass

from .records import Record

ETHERNET, NULL, LOOP, RAW, SLL, SLL2, IPV4, IPV6 = 1, 0, 108, 101, 113, 276, 228, 229
LINKTYPES = {ETHERNET: "Ethernet", NULL: "BSD loopback", LOOP: "OpenBSD loopback", RAW: "raw IP", 12: "raw IP",
             14: "raw IP", SLL: "Linux cooked capture", SLL2: "Linux cooked capture v2", IPV4: "raw IPv4",
             IPV6: "raw IPv6"}
VLAN_TYPES = (0x8100, 0x88A8, 0x9100)
BSD_INET6 = (10, 24, 28, 30)  # AF_INET6 on Linux, NetBSD/OpenBSD, FreeBSD, macOS
IPV6_EXTENSIONS = (0, 43, 60)  # hop-by-hop, routing, destination options (fragment, 44, is handled apart)
UDP = 17
HELD_LIMIT = 1024  # datagrams awaiting fragments at once; the oldest is given up beyond that
ADDRESS_CACHE = 1024  # IPv4 addresses kept as text


@dataclass(slots=True)
class Datagram:
    number: int  # the record that completed it (Wireshark shows a reassembled datagram there)
    time: float
    src: str
    sport: int
    dst: str
    dport: int
    payload: bytes
    cut: bool = False  # the capture's snaplen cut it: the payload is only its start
    comment: str | None = None


class Dissector:
    """Turns records into UDP datagrams; keeps the fragments of datagrams not yet whole. ``datagram`` returns
    the datagram a record completes, or a string saying why there is none."""

    def __init__(self):
        self.held: OrderedDict[tuple, dict] = OrderedDict()
        self.given_up = 0

    def datagram(self, record: Record) -> Datagram | str:
        d = record.data
        if record.linktype == ETHERNET and len(d) >= 42:  # the common case, read with one struct call
            kind, version, total, flags, protocol, src, dst, sport, dport, length = _ETHERNET_IPV4_UDP(d)
            if kind == 0x0800 and version == 0x45 and protocol == UDP and not flags & 0x3FFF \
                    and total <= len(d) - 14 and 8 <= length <= total - 20:  # whole, unfragmented, no options
                return Datagram(record.number, record.time, _address(src), sport, _address(dst), dport,
                                d[42:34 + length], False, record.comment)
        return self.dissected(record)

    def dissected(self, record: Record) -> Datagram | str:
        """``datagram`` by the general path, every link layer and IP header the module reads."""
        found = _network(record.linktype, record.data)
        if isinstance(found, str):
            return found
        version, packet = found
        return self._ipv4(record, packet) if version == 4 else self._ipv6(record, packet)

    def _ipv4(self, record: Record, p: bytes) -> Datagram | str:
        if len(p) < 20 or p[0] >> 4 != 4:
            return "not IP"
        ihl = (p[0] & 15) * 4
        total, ident, flags = struct.unpack_from("!HHH", p, 2)
        if p[9] != UDP:
            return "not UDP"
        if ihl < 20 or len(p) < ihl:
            return "a damaged IPv4 header"
        src, dst = socket.inet_ntoa(p[12:16]), socket.inet_ntoa(p[16:20])
        cut = len(p) < total
        body = p[ihl:total]
        offset, more = (flags & 0x1FFF) * 8, bool(flags & 0x2000)
        if offset or more:
            if cut:
                return "a fragment cut by the capture"
            body = self._reassemble((src, dst, ident, 4), offset, more, body)
            if body is None:
                return "IP fragments (judged once their datagram is whole)"
        return _udp(record, src, dst, body, cut)

    def _ipv6(self, record: Record, p: bytes) -> Datagram | str:
        if len(p) < 40:
            return "not IP"
        (length,) = struct.unpack_from("!H", p, 4)
        nxt, pos = p[6], 40
        src, dst = socket.inet_ntop(socket.AF_INET6, p[8:24]), socket.inet_ntop(socket.AF_INET6, p[24:40])
        cut = len(p) < 40 + length
        end = 40 + length
        fragment = None
        while nxt in IPV6_EXTENSIONS or nxt == 44:
            if pos + 8 > len(p):
                return "a damaged IPv6 header"
            if nxt == 44:
                field, ident = struct.unpack_from("!HI", p, pos + 2)
                fragment = (field & 0xFFF8, bool(field & 1), ident)
                nxt, pos = p[pos], pos + 8
            else:
                nxt, pos = p[pos], pos + (p[pos + 1] + 1) * 8
        if nxt != UDP:
            return "not UDP"
        body = p[pos:end]
        if fragment is not None:
            if cut:
                return "a fragment cut by the capture"
            body = self._reassemble((src, dst, fragment[2], 6), fragment[0], fragment[1], body)
            if body is None:
                return "IP fragments (judged once their datagram is whole)"
        return _udp(record, src, dst, body, cut)

    def _reassemble(self, key: tuple, offset: int, more: bool, body: bytes) -> bytes | None:
        """The whole datagram once every fragment of ``key`` is in, else None."""
        held = self.held.setdefault(key, {"parts": {}, "end": None, "have": 0})
        if offset not in held["parts"]:
            held["have"] += len(body)
        held["parts"][offset] = body
        if not more:
            held["end"] = offset + len(body)
        if len(self.held) > HELD_LIMIT:
            self.held.popitem(last=False)
            self.given_up += 1
        if held["end"] is None or held["have"] < held["end"]:
            return None  # not every byte can be in yet: put it together only when it can be whole
        whole, pos = bytearray(), 0
        for start in sorted(held["parts"]):
            if start > pos:
                return None  # a hole: not every fragment is in yet
            whole[start:] = held["parts"][start]
            pos = max(pos, start + len(held["parts"][start]))
        if pos < held["end"]:
            return None
        del self.held[key]
        return bytes(whole[:held["end"]])


_ETHERNET_IPV4_UDP = struct.Struct("!12xHBxH2xHxB2x4s4sHHH").unpack_from  # ethertype, IPv4 header, UDP header
_ADDRESSES: dict[bytes, str] = {}  # IPv4 addresses as text, by their bytes (a capture has few hosts)


def _address(raw: bytes) -> str:
    text = _ADDRESSES.get(raw)
    if text is None:
        if len(_ADDRESSES) >= ADDRESS_CACHE:
            _ADDRESSES.clear()
        text = _ADDRESSES[raw] = socket.inet_ntoa(raw)
    return text


def _network(linktype: int, d: bytes) -> tuple[int, bytes] | str:
    """(IP version, packet) of a link-layer frame, or why it is not IP."""
    if linktype == ETHERNET:
        if len(d) < 14:
            return "a truncated Ethernet header"
        (kind,), pos = struct.unpack_from("!H", d, 12), 14
        while kind in VLAN_TYPES and len(d) >= pos + 4:
            (kind,), pos = struct.unpack_from("!H", d, pos + 2), pos + 4
        return _by_ethertype(kind, d[pos:])
    if linktype == SLL:
        return _by_ethertype(struct.unpack_from("!H", d, 14)[0], d[16:]) if len(d) >= 16 else "a truncated SLL header"
    if linktype == SLL2:
        return _by_ethertype(struct.unpack_from("!H", d, 0)[0], d[20:]) if len(d) >= 20 else "a truncated SLL2 header"
    if linktype in (NULL, LOOP):
        if len(d) < 4:
            return "a truncated loopback header"
        family = struct.unpack_from("!I" if linktype == LOOP or d[0] == 0 else "<I", d, 0)[0]
        return (4, d[4:]) if family == 2 else (6, d[4:]) if family in BSD_INET6 else "not IP"
    if linktype in (RAW, 12, 14, IPV4, IPV6):
        return (d[0] >> 4, d) if d and d[0] >> 4 in (4, 6) else "not IP"
    return f"link type {linktype}"


def _by_ethertype(kind: int, packet: bytes) -> tuple[int, bytes] | str:
    return (4, packet) if kind == 0x0800 else (6, packet) if kind == 0x86DD else "not IP"


def _udp(record: Record, src: str, dst: str, body: bytes, cut: bool) -> Datagram | str:
    if len(body) < 8:
        return "a truncated UDP header"
    sport, dport, length = struct.unpack_from("!HHH", body, 0)
    payload = body[8:length] if length >= 8 else body[8:]
    return Datagram(record.number, record.time, src, sport, dst, dport, payload, cut or len(body) < length,
                    record.comment)


def describe_linktype(linktype: int) -> str:
    return LINKTYPES.get(linktype, f"link type {linktype}")
