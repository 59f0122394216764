"""What the IMC suite judges in captures: the frame at the start of each datagram on the IMC ports (the first
only, as DUNE reads one frame a datagram), by the reference codec's rules, and the exchanges of exchanges.json.

A fast path checks what every frame needs (sync, header, size, a C-accelerated CRC-16/ARC) and decodes the
payload only where the frame's validity or an exchange depends on it: a message of fixed-size fields is valid
when its payload is at least their size.
"""

from __future__ import annotations

import struct

from ...capture.findings import Frame
from ...kinds.scenario.passive import PassiveExchanges
from ...kinds.vector.errors import FrameError, NotJudged
from . import codec
from .crc16 import arc  # fastcrc's, called without the wrapper: this is the hot path
from .definitions import Definitions
from .elsewhere import defined_elsewhere
from .wire import NOT_JUDGED_CLAUSE, UNKNOWN_SYSTEM, ImcWire, outside

PORTS = frozenset([*range(6001, 6031), *range(30100, 30105)])  # DUNE's node ports and its discovery ports
SEEN_LIMIT = 1 << 16  # decoded payloads remembered (repeated statuses and requests decode once)
SEEN_SIZE = 512  # bytes of a payload remembered at most (the memory stays flat whatever the frames)
UNIDENTIFIED = "unidentified"  # frames whose message id cannot be read or is the null id
LITTLE = b"\x54\xfe"
HEAD = {LITTLE: struct.Struct("<HHH"), b"\xfe\x54": struct.Struct(">HHH")}
ADDRESSING = {b"\x54\xfe": struct.Struct("<HBH"), b"\xfe\x54": struct.Struct(">HBH")}
FOOTER = {b"\x54\xfe": struct.Struct("<H"), b"\xfe\x54": struct.Struct(">H")}
HEADER_SIZE, FOOTER_SIZE = codec.HEADER_SIZE, codec.FOOTER_SIZE


class ImcCaptureRules:
    ports = PORTS
    outside = ImcWire.outside_judged

    def __init__(self, defs: Definitions, wire: ImcWire, rules: list[dict], behaviour: dict | None):
        self.defs, self.wire, self.behaviour = defs, wire, behaviour
        self.clauses = {r["id"]: r["clause"] for r in rules}
        self.ours = {m.id: m.abbrev for m in defs.suite_messages}
        self.keys = {m.abbrev: str(m.id) for m in defs.suite_messages} | {UNIDENTIFIED: "-"}
        self.max_payload = defs.max_payload
        self.fixed = {m.id: sum(f.size for f in m.fields) for m in defs.messages if all(f.is_scalar for f in m.fields)}
        self.watched: set[int] = set()
        self.seen: dict[bytes, dict] = {}  # decoded fields by payload, for the watched messages
        self.named: dict[int, tuple[str, bool]] = {}  # message id -> (name, undefined): messages outside the suite

    def exchanges(self, edition: str, scale: float) -> PassiveExchanges:
        known = self.defs.by_abbrev  # a folder's own definitions may lack the messages of some exchanges
        exchanges = [ex for ex in (self.behaviour or {}).get("exchanges", [])
                     if ex["request"]["message"] in known and ex["reply"] in known]
        behaviour = self.behaviour or {}
        tracker = PassiveExchanges(self.wire, exchanges, edition, scale, UNKNOWN_SYSTEM, behaviour.get("bounds"),
                                   nobody=0, silence=behaviour.get("silence", ()),  # 0: DUNE's Announce goes to it
                                   ambiguities=behaviour.get("ambiguities"))
        self.watched = {self.defs[m].id for m in tracker.messages}
        return tracker

    def frame(self, p: bytes) -> Frame | None:
        order = p[:2]
        head = HEAD.get(order)
        if head is None:
            return None  # no IMC synchronization number: not an IMC frame
        n = len(p)
        if n < 6:
            return self._decoded(p, UNIDENTIFIED)
        _, mgid, size = head.unpack_from(p)
        group = self.ours.get(mgid)
        end = HEADER_SIZE + size
        if n < end + FOOTER_SIZE or size > self.max_payload:
            sound = False
        elif n == end + FOOTER_SIZE and order == LITTLE:  # a frame and its little-endian CRC: their CRC is 0
            sound = not arc(p)
        else:
            sound = arc(p[:end]) == FOOTER[order].unpack_from(p, end)[0]
        if group is None:  # a message the suite does not cover: its framing is judged, not its fields
            if not sound or mgid == self.defs.null_id:
                return self._decoded(p, UNIDENTIFIED)
            named = self.named.get(mgid)
            if named is None:
                named = self.named[mgid] = outside(self.defs, mgid)
            return Frame(None, outside=named[0], undefined=named[1])
        if not sound:
            return self._decoded(p, group)
        src, _, dst = ADDRESSING[order].unpack_from(p, 14)
        fixed = self.fixed.get(mgid)
        if mgid not in self.watched and fixed is not None and size >= fixed:
            return Frame(group, src=src, dst=dst)  # fixed-size fields, all there: valid
        payload = p[:4] + p[HEADER_SIZE:end]  # what the fields' verdict depends on: byte order, id, payload
        known = self.seen.get(payload)
        if known is None:
            known = self._decoded(p, group)
            if known.rule is None and mgid not in self.watched:
                known = Frame(group)  # valid, and no exchange reads its fields: they need not be kept
            if size <= SEEN_SIZE:
                if len(self.seen) >= SEEN_LIMIT:
                    self.seen.clear()
                self.seen[payload] = known
        if known.rule is not None:
            return known
        return Frame(group, fields=known.fields if mgid in self.watched else None, src=src, dst=dst)

    def _decoded(self, p: bytes, group: str) -> Frame:
        try:
            decoded = codec.decode(self.defs, p, elsewhere=defined_elsewhere)
        except FrameError as exc:
            return Frame(group, exc.rule, exc.offset, exc.detail, self.clauses.get(exc.rule, ""))
        except NotJudged as exc:
            return Frame(group, exc.reason, exc.offset, exc.detail, NOT_JUDGED_CLAUSE, undecided=True)
        header = decoded["header"]
        return Frame(group, fields=decoded["fields"], src=header["src"], dst=header["dst"])

    def vector_case(self, group: str, data: bytes, number: int, edition: str) -> dict | None:
        """A captured frame as a vector case of the corpus's form (its verdict the reference codec's), to replay
        through an implementation's decode; None for a frame no message of the suite can be told in."""
        if group == UNIDENTIFIED:
            return None
        order = codec.byte_order_of(data)
        case = {"id": f"imc/{group}/capture/decode/{number}", "clause": "imc-wire#what-real-receivers-do",
                "checks": [f"decode-{order}"], "frames": {order: data.hex()}, "tags": ["capture"]}
        try:
            case["message"] = codec.decode(self.defs, data)
        except FrameError as exc:
            if exc.rule == "unknown-inline-id":
                return None  # an inline message outside the suite (a vehicle's other traffic): no verdict to compare with
            return case | {"expect": "invalid", "rule": exc.rule, "clause": self.clauses.get(exc.rule, case["clause"])}
        except NotJudged:
            return None  # beyond the reference codec's bounds: no verdict to compare with
        return case | {"expect": "valid"}
